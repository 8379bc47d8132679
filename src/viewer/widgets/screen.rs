//! From the render world to the screen: the volume's box corners and the projection of a point into a view's
//! rectangle (points), as every overlay draws its shapes.

use egui::Pos2;
use glam::{Mat4, Vec3};

/// The corners of the texture-space box [`lo`, `hi`] in the render world (`tex_to_world`), x fastest.
pub fn box_corners(tex_to_world: Mat4, lo: Vec3, hi: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        let t = Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
        tex_to_world.transform_point3(lo + (hi - lo) * t)
    })
}

/// Screen position (points) of a world point, or None behind the near plane.
pub fn project(view_proj: Mat4, p: Vec3, rect: egui::Rect) -> Option<Pos2> {
    let c = view_proj * p.extend(1.0);
    if c.w <= 1e-6 || c.z < 0.0 {
        return None;
    }
    let ndc = c.truncate() / c.w;
    Some(Pos2::new(
        rect.left() + (ndc.x * 0.5 + 0.5) * rect.width(),
        rect.top() + (ndc.y * 0.5 + 0.5) * rect.height(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewer::model::Model;

    #[test]
    fn projected_box_corners_land_in_the_view() {
        let model = Model::new(Vec3::ONE, "x".into());
        let s = model.render_settings(100, 100);
        let vp = s.camera.projection(1.0) * s.camera.view();
        let rect = egui::Rect::from_min_size(Pos2::ZERO, egui::vec2(100.0, 100.0));
        for c in box_corners(model.tex_to_world(), Vec3::ZERO, Vec3::ONE) {
            let p = project(vp, c, rect).expect("in front of the camera");
            assert!(rect.contains(p), "{p:?}");
        }
    }
}
