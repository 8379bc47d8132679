//! Image fidelity as `bench` measures it: a frame's error against the same scene rendered converged, the way
//! the issue on fidelity and speed defines it. Converged is 1/8-voxel steps with every sampling approximation off
//! (brick strides); camera, transfer function, mode, shading, the gradient rule (rule 5: the filtered texture or
//! samples of the interpolant) and jitter stay the frame's, so the error measures sampling, not a choice of filter.
//! The error is taken over object pixels (where either image shows the volume, `compare::diff_stats`), so a
//! small object on a large background cannot dilute it.

use crate::measure::image_diff::{background_u8, diff_stats};
use crate::scene::quality::CONVERGED_STEP;
use crate::scene::settings::RenderSettings;
use image::RgbaImage;

/// `s` with the converged step and brick strides off.
pub fn converged(s: &RenderSettings) -> RenderSettings {
    let mut c = s.clone();
    c.sampling.step_length = CONVERGED_STEP;
    c.sampling.max_stride = 1;
    c
}

/// A frame's error against its converged image, in 1/255 of the largest channel difference per pixel.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Fidelity {
    pub mean: f64,
    pub p99: f64,
    pub max: f64,
    /// Pixels the statistics are taken over.
    pub object_pixels: usize,
}

impl Fidelity {
    /// `frame` against `converged`, both rendered with settings whose background is `s.background`.
    pub fn of(frame: &RgbaImage, converged: &RgbaImage, s: &RenderSettings) -> Fidelity {
        let d = diff_stats(frame, converged, background_u8(s));
        Fidelity {
            mean: d.mean,
            p99: d.p99,
            max: d.max,
            object_pixels: d.object_pixels,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Rgba;

    #[test]
    fn converged_settings_keep_the_view_and_the_gradient_rule_and_drop_strides() {
        let mut s = RenderSettings::new(8, 8, glam::Vec3::ONE);
        s.sampling.step_length = 2.0;
        s.sampling.max_stride = 4;
        s.lighting.gradient_texture = true;
        s.sampling.jitter = Some(7);
        let c = converged(&s);
        assert_eq!(
            (
                c.sampling.step_length,
                c.sampling.max_stride,
                c.lighting.gradient_texture
            ),
            (0.125, 1, true)
        );
        assert_eq!(
            (c.sampling.jitter, c.camera.eye, c.colour.window),
            (s.sampling.jitter, s.camera.eye, s.colour.window)
        );
    }

    #[test]
    fn errors_are_over_object_pixels() {
        // 100 pixels, one object pixel off by 10: a mean of 10 over the object, not 0.1 over the image.
        let s = RenderSettings::new(10, 10, glam::Vec3::ONE);
        let a = RgbaImage::from_pixel(10, 10, Rgba([0, 0, 0, 255]));
        let mut b = a.clone();
        b.put_pixel(3, 3, Rgba([10, 0, 0, 255]));
        let f = Fidelity::of(&b, &a, &s);
        assert_eq!((f.object_pixels, f.mean, f.max), (1, 10.0, 10.0));
    }
}
