//! The last step of a sort-last frame, on rank 0: the composited shares become the image the single-process march
//! writes. The march's output rule (shaders/march.glsl `finish`, `classify`) restated on the CPU in f32: over the
//! background in linear light, sRGB-encoded once, rounded to 8 bits as a UNORM store rounds. Pure code.

use crate::scene::settings::{CompositeMode, RenderSettings};
use crate::transfer::function::{bake, linear_to_srgb, srgb_to_linear};

/// How the ranks' shares are merged, by compositing mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Merge {
    /// Premultiplied colour and opacity, blended front to back in the k-d tree's order (IceT's ordered blend):
    /// emission, density and iso-surfaces.
    Over,
    /// The largest (MIP) or smallest (MinIP) value: IceT's depth test on a depth that orders the values.
    Closest,
    /// Sums and counts, added (MPI_Reduce): the mean of all visible samples.
    Sum,
}

impl Merge {
    pub fn of(mode: CompositeMode) -> Merge {
        match mode {
            CompositeMode::Mip | CompositeMode::MinIp => Merge::Closest,
            CompositeMode::Average => Merge::Sum,
            _ => Merge::Over,
        }
    }
}

/// The depth IceT compares for a MIP or MinIP share's value `m` (the nearest depth wins): the largest value
/// nearest for MIP, the smallest for MinIP, all in [0, 0.5] so that none reads as IceT's background depth 1.
pub fn depth_of(mode: CompositeMode, m: f32) -> f32 {
    let m = m.clamp(0.0, 1.0);
    if mode == CompositeMode::MinIp {
        0.5 * m
    } else {
        0.5 * (1.0 - m)
    }
}

/// The march's classification on the CPU: the baked table at `v`, interpolated between its two nearest entries.
fn classify(lut: &[[f32; 4]], v: f32) -> [f32; 4] {
    let u = v.clamp(0.0, 1.0) * 4095.0;
    let i0 = (u as usize).min(4094);
    let f = u - i0 as f32;
    let (a, b) = (lut[i0], lut[i0 + 1]);
    [0, 1, 2, 3].map(|c| a[c] + (b[c] - a[c]) * f)
}

/// What the pixels of the frame `s` become: per pixel the merged share (see [`Merge`]), for a volume whose values
/// span `range`.
pub struct Finisher {
    lut: Vec<[f32; 4]>,
    background: [f32; 3],
    mode: CompositeMode,
}

impl Finisher {
    pub fn new(s: &RenderSettings, range: [f64; 2]) -> Finisher {
        Finisher {
            lut: bake(&s.classification(), s.colour.window, range),
            background: [s.background.x, s.background.y, s.background.z].map(srgb_to_linear),
            mode: s.compositing.mode,
        }
    }

    /// Shader `finish`: `color` (premultiplied, linear) at `opacity` over the background, encoded.
    fn finish(&self, color: [f32; 3], opacity: f32) -> [u8; 4] {
        let c = [0, 1, 2].map(|i| (color[i] + (1.0 - opacity) * self.background[i]).clamp(0.0, 1.0));
        let e = c.map(|x| (linear_to_srgb(x) * 255.0).round() as u8);
        [e[0], e[1], e[2], 255]
    }

    /// One pixel from its merged share: Over (colour, opacity); Closest (value, 0, 0, 1 where any rank saw a visible
    /// sample); Sum (sum, count, 0, 0).
    pub fn pixel(&self, p: [f32; 4]) -> [u8; 4] {
        match Merge::of(self.mode) {
            Merge::Over => self.finish([p[0], p[1], p[2]], p[3]),
            Merge::Closest if p[3] > 0.0 => self.finish_value(p[0]),
            Merge::Sum if p[1] > 0.0 => self.finish_value(p[0] / p[1]),
            _ => self.finish([0.0; 3], 0.0),
        }
    }

    fn finish_value(&self, v: f32) -> [u8; 4] {
        let c = classify(&self.lut, v);
        self.finish([c[0], c[1], c[2]], 1.0)
    }

    /// The image of `width` x `height` merged shares (RGBA f32, rows top down).
    pub fn image(&self, width: u32, height: u32, merged: &[f32]) -> image::RgbaImage {
        let mut img = image::RgbaImage::new(width, height);
        for (px, p) in img.pixels_mut().zip(merged.chunks_exact(4)) {
            px.0 = self.pixel([p[0], p[1], p[2], p[3]]);
        }
        img
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depths_order_values_as_the_modes_want() {
        assert!(depth_of(CompositeMode::Mip, 0.9) < depth_of(CompositeMode::Mip, 0.2));
        assert!(depth_of(CompositeMode::MinIp, 0.2) < depth_of(CompositeMode::MinIp, 0.9));
        assert!(depth_of(CompositeMode::Mip, 0.0) < 1.0 && depth_of(CompositeMode::MinIp, 1.0) < 1.0);
    }

    #[test]
    fn nothing_composited_is_the_background_and_opaque_colour_covers_it() {
        let mut s = RenderSettings::new(4, 4, glam::Vec3::ONE);
        s.background = glam::Vec3::new(1.0, 0.0, 0.0);
        let f = Finisher::new(&s, [0.0, 1.0]);
        assert_eq!(f.pixel([0.0; 4]), [255, 0, 0, 255]);
        assert_eq!(f.pixel([0.0, 0.0, 1.0, 1.0]), [0, 0, 255, 255]);
        // Half of linear white over black is sRGB 188.
        s.background = glam::Vec3::ZERO;
        let f = Finisher::new(&s, [0.0, 1.0]);
        assert_eq!(f.pixel([0.5, 0.5, 0.5, 0.5]), [188, 188, 188, 255]);
    }
}
