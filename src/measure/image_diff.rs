//! Differences between two images, as every comparison in volcast measures them (`compare`, fidelity, the
//! tests): per pixel the largest RGB channel difference in 1/255, over the pixels that show the volume. Pure code.

use crate::scene::settings::RenderSettings;
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
pub fn background_u8(s: &RenderSettings) -> [u8; 3] {
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
}
