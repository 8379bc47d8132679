//! Rule 12's spaced rays in the reference: the size of the image rays are marched for, and that image stretched
//! over the output by bilinear filtering, written from the rule (and the Vulkan specification's blit), not from the
//! renderer.

use image::{Rgba, RgbaImage};
use volcast::scene::settings::RenderSettings;

/// The image size rules 1–8 are applied at: one ray per k² output pixels, k the ray spacing (1 for a frame that
/// counts samples), each side rounded up.
pub fn marched(s: &RenderSettings) -> (u32, u32) {
    let k = if s.pipeline.count_samples {
        1
    } else {
        s.sampling.ray_spacing.max(1)
    };
    (s.width.div_ceil(k), s.height.div_ceil(k))
}

/// The two source pixels along one axis that output coordinate `x` (of `out` pixels) reads from a `src`-pixel
/// axis, and the second's weight: the pixel centre `x + 0.5` scaled to the source, centres at `i + 0.5`, the edge
/// repeated beyond the outer centres.
pub fn taps(x: u32, out: u32, src: u32) -> (u32, u32, f64) {
    let u = (f64::from(x) + 0.5) * f64::from(src) / f64::from(out) - 0.5;
    let i = u.floor();
    let w = u - i;
    let clamp = |j: f64| j.clamp(0.0, f64::from(src - 1)) as u32;
    (clamp(i), clamp(i + 1.0), w)
}

/// `small` stretched over `width`×`height`: each channel of each output pixel the bilinear mix of its four taps,
/// rounded to 8 bits.
pub fn stretch(small: &RgbaImage, width: u32, height: u32) -> RgbaImage {
    let (sw, sh) = small.dimensions();
    RgbaImage::from_fn(width, height, |x, y| {
        let (x0, x1, wx) = taps(x, width, sw);
        let (y0, y1, wy) = taps(y, height, sh);
        let at = |x: u32, y: u32, c: usize| f64::from(small.get_pixel(x, y)[c]);
        Rgba(std::array::from_fn(|c| {
            let top = at(x0, y0, c) * (1.0 - wx) + at(x1, y0, c) * wx;
            let bottom = at(x0, y1, c) * (1.0 - wx) + at(x1, y1, c) * wx;
            (top * (1.0 - wy) + bottom * wy).round() as u8
        }))
    })
}

/// A per-pixel mark of the marched image (shows the volume, samples taken) at the output's pixels: the nearest
/// marched pixel's.
pub fn nearest<T: Copy>(marks: &[T], (sw, sh): (u32, u32), width: u32, height: u32) -> Vec<T> {
    let near = |x: u32, out: u32, src: u32| ((u64::from(x) * 2 + 1) * u64::from(src) / (2 * u64::from(out))) as u32;
    (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| marks[(near(y, height, sh) * sw + near(x, width, sw)) as usize])
        .collect()
}
