//! The two ray setups side by side: the same frames rendered with entry/exit faces and with analytic ray/box
//! intersection, their difference, their GPU time per pass and the memory each needs. Used by `volcast compare`
//! and by the tests.

use crate::gpu::{Gpu, GpuError};
use crate::measure::image_diff::{background_u8, diff_stats, DiffStats, AGREE_MEAN, AGREE_P99};
use crate::render::headless::Headless;
use crate::render::{PassTimings, Renderer};
use crate::scene::camera::Camera;
use crate::scene::settings::{RaySetup, RenderSettings};
use glam::Vec3;
use image::RgbaImage;
use serde::Serialize;

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
    slab.settings.cut.set_slab(0, 0.45, 0.5);
    slab.settings.cut.set_slab(1, 0.5, 0.4);
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
    s.pipeline.ray_setup = method;
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
