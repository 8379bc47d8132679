//! The scale bar of a figure (`render --scale-bar`, the viewer's "Export figure"): a bar at the bottom left whose
//! length is a round number of millimetres (or micrometres, under 1 mm) at the depth of the camera's target, the
//! point the view orbits. In an orthographic view that holds at every depth; in a perspective view nearer things
//! look larger, and the bar holds at the target only (3D Slicer shows its 3D ruler only in orthographic views;
//! ParaView and napari draw theirs at the focal point, as here).
//!
//! The view is `2·d·tan(fov/2)` world units high at the target's distance `d` (perspective and orthographic
//! alike, `Camera`), and the world is the volume's millimetres times `world_per_mm` (its longest side is 1).

use crate::scene::settings::RenderSettings;
use crate::transfer::colorbar::GLYPH_HEIGHT;
use image::{Rgba, RgbaImage};

/// Image pixels per millimetre at the camera target's depth, in an image `height` pixels high.
pub fn pixels_per_mm(s: &RenderSettings, world_per_mm: f64, height: u32) -> f64 {
    let c = &s.camera;
    let distance = f64::from((c.eye - c.target).length());
    let half = (f64::from(c.fov_y_deg) / 2.0).to_radians().tan();
    f64::from(height) / (2.0 * distance * half) * world_per_mm
}

/// The longest round length (1, 2 or 5 times a power of ten, in mm) whose bar is at most `max_px` pixels at
/// `px_per_mm`, and its length in pixels; `None` where nothing sensible fits (a degenerate view).
pub fn choose(px_per_mm: f64, max_px: f64) -> Option<(f64, f64)> {
    if !(px_per_mm.is_finite() && px_per_mm > 0.0 && max_px >= 1.0) {
        return None;
    }
    let limit = max_px / px_per_mm;
    let decade = 10f64.powf(limit.log10().floor());
    let mm = [5.0, 2.0, 1.0].into_iter().map(|m| m * decade).find(|&m| m <= limit)?;
    Some((mm, mm * px_per_mm))
}

/// "50 mm", or "200 µm" under a millimetre.
pub fn label(mm: f64) -> String {
    if mm >= 1.0 {
        format!("{} mm", crate::volume::geometry::shortest(mm))
    } else {
        format!("{} µm", crate::volume::geometry::shortest(mm * 1000.0))
    }
}

/// Draws the bar onto `image` (a render of `s`): at most a fifth of its width, its label above it, white on a dark
/// background and black on a light one. Returns the bar's length in mm, or `None` where none fits.
pub fn draw(image: &mut RgbaImage, s: &RenderSettings, world_per_mm: f64) -> Option<f64> {
    let (w, h) = image.dimensions();
    let (mm, px) = choose(pixels_per_mm(s, world_per_mm, h), f64::from(w) / 5.0)?;
    let scale = (h / 256).clamp(1, 4);
    let thick = 2 * scale;
    let margin = 6 * scale;
    let bg = s.background;
    let ink = if 0.2126 * bg.x + 0.7152 * bg.y + 0.0722 * bg.z > 0.5 {
        0
    } else {
        255
    };
    let colour = Rgba([ink, ink, ink, 255]);
    let (x0, bottom) = (i64::from(margin), i64::from(h) - i64::from(margin));
    let mut put = |x: i64, y: i64| {
        if (0..i64::from(w)).contains(&x) && (0..i64::from(h)).contains(&y) {
            image.put_pixel(x as u32, y as u32, colour);
        }
    };
    let length = px.round() as i64;
    for y in bottom - i64::from(thick)..bottom {
        for x in x0..x0 + length {
            put(x, y);
        }
    }
    let text_top = bottom - i64::from(thick + 2 * scale + GLYPH_HEIGHT * scale);
    crate::transfer::colorbar::for_each_text_pixel(&label(mm), x0, text_top, scale, put);
    Some(mm)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::Camera;
    use glam::Vec3;

    /// 400×300 from 1 unit at 90°: tan(45°) = 1, so the view is 2 units high at the target.
    fn unit_view() -> RenderSettings {
        let mut s = RenderSettings::new(400, 300, Vec3::ONE);
        s.camera = Camera {
            eye: Vec3::new(0.0, 0.0, 1.0),
            target: Vec3::ZERO,
            fov_y_deg: 90.0,
            ..s.camera
        };
        s
    }

    #[test]
    fn a_view_two_units_high_at_the_target_shows_height_over_two_pixels_per_unit() {
        let mut s = unit_view();
        let per_mm = pixels_per_mm(&s, 0.01, 300);
        assert!((per_mm - 150.0 * 0.01).abs() < 1e-9, "{per_mm}");
        s.camera.ortho = true;
        assert!(
            (pixels_per_mm(&s, 0.01, 300) - per_mm).abs() < 1e-12,
            "orthographic alike"
        );
    }

    #[test]
    fn the_bar_is_the_longest_round_length_within_its_room() {
        assert_eq!(choose(1.5, 80.0), Some((50.0, 75.0)));
        assert_eq!(choose(1.0, 80.0), Some((50.0, 50.0)));
        assert_eq!(choose(1.0, 30.0), Some((20.0, 20.0)));
        assert_eq!(choose(0.1, 15.0), Some((100.0, 10.0)));
        let (mm, px) = choose(4000.0, 100.0).unwrap();
        assert!((mm - 0.02).abs() < 1e-12 && (px - 80.0).abs() < 1e-9, "{mm} {px}");
        assert_eq!(choose(0.0, 100.0), None);
        assert_eq!(choose(f64::NAN, 100.0), None);
        assert_eq!(
            (label(50.0), label(0.02), label(2.0)),
            ("50 mm".into(), "20 µm".into(), "2 mm".into())
        );
    }

    #[test]
    fn the_bar_is_drawn_at_the_bottom_left_at_its_length() {
        let s = unit_view();
        let mut image = RgbaImage::from_pixel(400, 300, Rgba([0, 0, 0, 255]));
        // 1.5 px per mm, room for 80 px: a 50 mm bar, 75 px long, 2 px thick, 6 px in from the edges.
        assert_eq!(draw(&mut image, &s, 0.01), Some(50.0));
        let lit = |x: u32, y: u32| image.get_pixel(x, y)[0] == 255;
        let row: Vec<u32> = (0..400).filter(|&x| lit(x, 293)).collect();
        assert_eq!((row.first(), row.last(), row.len()), (Some(&6), Some(&80), 75));
        assert!(lit(6, 292) && !lit(6, 294) && !lit(6, 291));
        assert!((0..400).any(|x| (276..285).any(|y| lit(x, y))), "the label above it");
    }
}
