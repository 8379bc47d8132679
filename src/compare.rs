//! The two ray setups side by side: the same frames rendered with entry/exit faces and with analytic ray/box
//! intersection, their difference, their GPU time per pass and the memory each needs. Used by `volcast compare`
//! and by the tests.

use crate::camera::Camera;
use crate::gpu::{Gpu, GpuError};
use crate::headless::Headless;
use crate::render::{PassTimings, Renderer};
use crate::settings::{RaySetup, RenderSettings};
use glam::Vec3;
use image::{Rgba, RgbaImage};
use serde::Serialize;

/// Agreement bound between the two methods over the object pixels (units of 1/255): the GPU-vs-reference bound
/// of the tests (tests/common/bounds.rs), since each method is held to it.
pub const AGREE_MEAN: f64 = 0.5;
pub const AGREE_P99: f64 = 3.0;

/// Differences between two images of the same size, per pixel the largest RGB channel difference, in 1/255.
/// Mean, p99 and the share over 1/255 are taken over the *object pixels*, those where either image is not the
/// background, so that empty parts of the view do not dilute them; max and PSNR over the whole image.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DiffStats {
    pub max: f64,
    pub mean: f64,
    pub p99: f64,
    /// Peak signal-to-noise ratio over RGB in dB (infinite for identical images).
    pub psnr_db: f64,
    /// Pixels where either image shows the volume (what mean, p99 and over_1 are taken over).
    pub object_pixels: usize,
    /// Share (0..1) of the object pixels differing by more than 1/255.
    pub over_1: f64,
    /// Pixels differing by more than 1/255.
    pub pixels_over_1: usize,
    /// Of those, how many lie on the box's silhouette (background in one image, not in the other).
    pub silhouette_over_1: usize,
    /// Bounding box [x0, y0, x1, y1] of the pixels over 1/255, if any.
    pub region: Option<[u32; 4]>,
}

impl DiffStats {
    pub fn agrees(&self) -> bool {
        self.mean < AGREE_MEAN && self.p99 < AGREE_P99
    }
}

fn channel_diff(a: &Rgba<u8>, b: &Rgba<u8>) -> u8 {
    (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0)
}

/// The 8-bit background colour a frame with settings `s` shows where no volume is (`s.background` is sRGB).
pub fn background_u8(s: &crate::settings::RenderSettings) -> [u8; 3] {
    let to_u8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    [to_u8(s.background.x), to_u8(s.background.y), to_u8(s.background.z)]
}

/// Compares `a` and `b` (same size); `background` marks silhouette pixels.
pub fn diff_stats(a: &RgbaImage, b: &RgbaImage, background: [u8; 3]) -> DiffStats {
    assert_eq!(
        a.dimensions(),
        b.dimensions(),
        "compared images must have the same size"
    );
    let pixels = (a.width() * a.height()).max(1) as usize;
    let mut errors: Vec<u8> = Vec::with_capacity(pixels);
    let mut squared = 0.0f64;
    let (mut max, mut over, mut silhouette) = (0u8, 0usize, 0usize);
    let mut region: Option<[u32; 4]> = None;
    let is_bg = |p: &Rgba<u8>| p[0] == background[0] && p[1] == background[1] && p[2] == background[2];
    for (x, y, p) in a.enumerate_pixels() {
        let q = b.get_pixel(x, y);
        let e = channel_diff(p, q);
        max = max.max(e);
        squared += (0..3).map(|c| (p[c] as f64 - q[c] as f64).powi(2)).sum::<f64>();
        if is_bg(p) && is_bg(q) {
            continue;
        }
        errors.push(e);
        if e > 1 {
            over += 1;
            if is_bg(p) != is_bg(q) {
                silhouette += 1;
            }
            let r = region.get_or_insert([x, y, x, y]);
            *r = [r[0].min(x), r[1].min(y), r[2].max(x), r[3].max(y)];
        }
    }
    let n = errors.len().max(1);
    let mean = errors.iter().map(|&e| e as f64).sum::<f64>() / n as f64;
    errors.sort_unstable();
    let p99 = errors.get((99 * n).div_ceil(100) - 1).copied().unwrap_or(0) as f64;
    let mse = squared / (3 * pixels) as f64;
    DiffStats {
        max: max as f64,
        mean,
        p99,
        psnr_db: if mse == 0.0 {
            f64::INFINITY
        } else {
            10.0 * (255.0f64 * 255.0 / mse).log10()
        },
        object_pixels: errors.len(),
        over_1: over as f64 / n as f64,
        pixels_over_1: over,
        silhouette_over_1: silhouette,
        region,
    }
}

/// |a − b| per channel × `gain`, opaque: small differences made visible.
pub fn amplified_diff(a: &RgbaImage, b: &RgbaImage, gain: u32) -> RgbaImage {
    RgbaImage::from_fn(a.width(), a.height(), |x, y| {
        let (p, q) = (a.get_pixel(x, y), b.get_pixel(x, y));
        let d = |c: usize| (p[c].abs_diff(q[c]) as u32 * gain).min(255) as u8;
        Rgba([d(0), d(1), d(2), 255])
    })
}

/// Images placed left to right with a 4-pixel grey gap.
pub fn side_by_side(images: &[&RgbaImage]) -> RgbaImage {
    let gap = 4;
    let h = images.iter().map(|i| i.height()).max().unwrap_or(0);
    let w = images.iter().map(|i| i.width()).sum::<u32>() + gap * images.len().saturating_sub(1) as u32;
    let mut out = RgbaImage::from_pixel(w, h, Rgba([64, 64, 64, 255]));
    let mut x0 = 0;
    for img in images {
        image::imageops::replace(&mut out, *img, x0 as i64, 0);
        x0 += img.width() + gap;
    }
    out
}

/// A named viewpoint: the settings to render it with.
#[derive(Clone, Debug)]
pub struct View {
    pub name: String,
    pub settings: RenderSettings,
}

/// The built-in viewpoints, derived from `base` (which carries size, transfer function and so on) for a box of
/// side lengths `extent`: oblique, two axis-aligned, grazing, close-up, near plane cutting the box, inside, on a
/// face, and a slab seen from inside it.
pub fn builtin_views(base: &RenderSettings, extent: Vec3) -> Vec<View> {
    let fit = Camera::fit_distance(extent.length() * 0.5, base.camera.fov_y_deg);
    let fov = base.camera.fov_y_deg;
    let view = |name: &str, camera: Camera| {
        let mut s = base.clone();
        s.camera = Camera {
            fov_y_deg: fov,
            ..camera
        };
        View {
            name: name.to_string(),
            settings: s,
        }
    };
    let e = extent;
    let mut views = vec![
        view("oblique", Camera::orbit(35.0, 25.0, fit, Vec3::ZERO)),
        view("axis-y", Camera::orbit(0.0, 0.0, fit, Vec3::ZERO)),
        view("axis-z", Camera::orbit(0.0, 90.0, fit, Vec3::ZERO)),
        // Just above the +z face, looking across it at a shallow angle.
        view(
            "grazing",
            Camera::looking_at(
                Vec3::new(-0.9 * e.x, -0.2 * e.y, 0.5 * e.z + 0.01),
                Vec3::new(0.5 * e.x, 0.3 * e.y, 0.4 * e.z),
            ),
        ),
        view("close-up", Camera::orbit(-50.0, 15.0, 0.45 * fit, Vec3::ZERO)),
        view(
            "inside",
            Camera::looking_at(Vec3::new(0.1, -0.15, 0.05) * e, Vec3::new(0.3, 0.35, 0.1) * e),
        ),
        view(
            "on-face",
            Camera::looking_at(Vec3::new(0.1 * e.x, 0.5 * e.y, 0.05 * e.z), Vec3::ZERO),
        ),
    ];
    let mut near_cut = view("near-plane-cut", Camera::orbit(120.0, 30.0, fit, Vec3::ZERO));
    near_cut.settings.camera.near = fit - 0.1 * e.length();
    views.push(near_cut);
    let mut slab = view(
        "slab-inside",
        Camera::looking_at(Vec3::new(0.05, 0.0, 0.05) * e, Vec3::new(-0.3, 0.4, 0.0) * e),
    );
    slab.settings.set_slab(0, 0.45, 0.5);
    slab.settings.set_slab(1, 0.5, 0.4);
    views.push(slab);
    views
}

/// One method's result for one view.
#[derive(Clone, Debug)]
pub struct MethodRun {
    pub image: RgbaImage,
    /// Median per-pass GPU times over the timed frames (None when none were timed).
    pub timings: Option<PassTimings>,
    /// Bytes of extra render targets this method needs at this resolution.
    pub extra_bytes: u64,
}

/// Both methods on one view.
pub struct Comparison {
    pub view: View,
    pub faces: MethodRun,
    pub analytic: MethodRun,
    pub diff: DiffStats,
}

impl Comparison {
    /// One line: agree within the bound, or where they differ.
    pub fn verdict(&self) -> String {
        let d = &self.diff;
        if d.agrees() {
            return format!(
                "agree within the bound (mean {:.3} < {AGREE_MEAN}, p99 {:.0} < {AGREE_P99}; {} pixels over 1/255, {} of them on the silhouette)",
                d.mean, d.p99, d.pixels_over_1, d.silhouette_over_1
            );
        }
        let region = d
            .region
            .map(|r| format!(" in x {}..{}, y {}..{}", r[0], r[2], r[1], r[3]))
            .unwrap_or_default();
        format!(
            "differ: mean {:.3}, p99 {:.0}; {} pixels over 1/255 ({} on the silhouette){region}",
            d.mean, d.p99, d.pixels_over_1, d.silhouette_over_1
        )
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Renders `s` with `method`: one warm-up frame (lavapipe compiles pipelines on first use), then `frames` timed
/// frames whose per-pass medians are reported.
pub fn run_method(
    gpu: &Gpu,
    headless: &mut Headless,
    s: &RenderSettings,
    method: RaySetup,
    frames: u32,
) -> Result<MethodRun, GpuError> {
    let mut s = s.clone();
    s.ray_setup = method;
    let mut frame = headless.render(gpu, &s)?;
    let mut all = Vec::new();
    for _ in 0..frames {
        frame = headless.render(gpu, &s)?;
        all.extend(frame.timings);
    }
    let timings = (!all.is_empty()).then(|| {
        let pick = |f: &dyn Fn(&PassTimings) -> Option<f64>| {
            let v: Vec<f64> = all.iter().filter_map(f).collect();
            (!v.is_empty()).then(|| median(v))
        };
        PassTimings {
            entry_ms: pick(&|t| t.entry_ms),
            exit_ms: pick(&|t| t.exit_ms),
            march_ms: pick(&|t| Some(t.march_ms)).unwrap_or(0.0),
            total_ms: pick(&|t| Some(t.total_ms)).unwrap_or(0.0),
        }
    });
    Ok(MethodRun {
        image: frame.image,
        timings,
        extra_bytes: Renderer::extra_target_bytes(&s),
    })
}

/// Both methods on `view`.
pub fn compare_view(gpu: &Gpu, headless: &mut Headless, view: &View, frames: u32) -> Result<Comparison, GpuError> {
    let faces = run_method(gpu, headless, &view.settings, RaySetup::Faces, frames)?;
    let analytic = run_method(gpu, headless, &view.settings, RaySetup::Analytic, frames)?;
    let diff = diff_stats(&faces.image, &analytic.image, background_u8(&view.settings));
    Ok(Comparison {
        view: view.clone(),
        faces,
        analytic,
        diff,
    })
}

/// A row of the comparison table (what the JSON file holds).
#[derive(Serialize)]
pub struct Row {
    pub view: String,
    pub width: u32,
    pub height: u32,
    pub diff: DiffStats,
    pub faces_ms: Option<PassTimings>,
    pub analytic_ms: Option<PassTimings>,
    pub faces_extra_bytes: u64,
    pub analytic_extra_bytes: u64,
    pub agree: bool,
    pub verdict: String,
}

impl From<&Comparison> for Row {
    fn from(c: &Comparison) -> Row {
        Row {
            view: c.view.name.clone(),
            width: c.view.settings.width,
            height: c.view.settings.height,
            diff: c.diff,
            faces_ms: c.faces.timings,
            analytic_ms: c.analytic.timings,
            faces_extra_bytes: c.faces.extra_bytes,
            analytic_extra_bytes: c.analytic.extra_bytes,
            agree: c.diff.agrees(),
            verdict: c.verdict(),
        }
    }
}

fn ms(v: Option<f64>) -> String {
    v.map(|x| format!("{x:.2}")).unwrap_or_else(|| "–".into())
}

/// The comparison as a Markdown table (also what `compare` prints).
pub fn markdown_table(rows: &[Row]) -> String {
    let mut out = String::from(
        "| view | max | mean | PSNR dB | >1/255 | faces: entry + exit + march = total ms | analytic: march ms | faces extra MiB | analytic extra MiB | verdict |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let f = r.faces_ms;
        let faces = match f {
            Some(t) => format!(
                "{} + {} + {} = {}",
                ms(t.entry_ms),
                ms(t.exit_ms),
                ms(Some(t.march_ms)),
                ms(Some(t.total_ms))
            ),
            None => "–".into(),
        };
        let psnr = if r.diff.psnr_db.is_finite() {
            format!("{:.1}", r.diff.psnr_db)
        } else {
            "∞".into()
        };
        out += &format!(
            "| {} | {:.0} | {:.3} | {} | {:.2}% | {} | {} | {:.1} | {:.1} | {} |\n",
            r.view,
            r.diff.max,
            r.diff.mean,
            psnr,
            r.diff.over_1 * 100.0,
            faces,
            ms(r.analytic_ms.map(|t| t.total_ms)),
            r.faces_extra_bytes as f64 / (1u64 << 20) as f64,
            r.analytic_extra_bytes as f64 / (1u64 << 20) as f64,
            if r.agree { "agree" } else { "differ" }
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_infinite_psnr_and_no_region() {
        let a = RgbaImage::from_pixel(4, 3, Rgba([10, 20, 30, 255]));
        let d = diff_stats(&a, &a, [0, 0, 0]);
        assert_eq!((d.max, d.mean, d.p99, d.pixels_over_1), (0.0, 0.0, 0.0, 0));
        assert!(d.psnr_db.is_infinite() && d.region.is_none() && d.agrees());
    }

    #[test]
    fn differences_are_measured_and_located() {
        let a = RgbaImage::from_pixel(10, 10, Rgba([0, 0, 0, 255]));
        let mut b = a.clone();
        b.put_pixel(2, 3, Rgba([0, 51, 0, 255]));
        b.put_pixel(7, 5, Rgba([1, 0, 0, 255]));
        let d = diff_stats(&a, &b, [0, 0, 0]);
        assert_eq!(d.max, 51.0);
        assert_eq!(
            d.object_pixels, 2,
            "only pixels showing something in either image are compared"
        );
        assert!((d.mean - 52.0 / 2.0).abs() < 1e-9);
        assert_eq!(d.pixels_over_1, 1, "a 1/255 difference is rounding, not counted");
        assert_eq!(d.silhouette_over_1, 1, "background in one image only");
        assert_eq!(d.region, Some([2, 3, 2, 3]));
        let mse = (51.0f64 * 51.0 + 1.0) / 300.0;
        assert!((d.psnr_db - 10.0 * (255.0f64 * 255.0 / mse).log10()).abs() < 1e-9);
        assert_eq!(amplified_diff(&a, &b, 10).get_pixel(2, 3)[1], 255);
        assert_eq!(amplified_diff(&a, &b, 10).get_pixel(7, 5)[0], 10);
    }

    #[test]
    fn side_by_side_places_images_with_a_gap() {
        let a = RgbaImage::from_pixel(3, 2, Rgba([255, 0, 0, 255]));
        let b = RgbaImage::from_pixel(2, 4, Rgba([0, 255, 0, 255]));
        let s = side_by_side(&[&a, &b]);
        assert_eq!(s.dimensions(), (3 + 4 + 2, 4));
        assert_eq!(s.get_pixel(0, 0)[0], 255);
        assert_eq!(s.get_pixel(7, 3)[1], 255);
        assert_eq!(s.get_pixel(4, 0)[0], 64);
    }

    #[test]
    fn builtin_views_cover_the_hard_cases() {
        let e = Vec3::new(1.0, 1.0, 0.5);
        let base = RenderSettings::new(64, 64, e);
        let views = builtin_views(&base, e);
        let names: Vec<&str> = views.iter().map(|v| v.name.as_str()).collect();
        for n in [
            "oblique",
            "axis-y",
            "grazing",
            "close-up",
            "inside",
            "on-face",
            "near-plane-cut",
            "slab-inside",
        ] {
            assert!(names.contains(&n), "{n} missing");
        }
        let inside = &views[names.iter().position(|n| *n == "inside").unwrap()]
            .settings
            .camera;
        assert!(
            inside.eye.abs().cmplt(e * 0.5).all(),
            "the inside view's eye is inside the box"
        );
        let on_face = &views[names.iter().position(|n| *n == "on-face").unwrap()]
            .settings
            .camera;
        assert_eq!(on_face.eye.y, 0.5 * e.y);
        for v in &views {
            v.settings.validate().unwrap_or_else(|m| panic!("{}: {m}", v.name));
        }
    }
}
