//! The light gizmo: a disc in the view's top-right corner showing the hemisphere that faces the viewer, with the
//! light as a sun on it (filled in front, hollow behind). Dragging on the disc places a directional light there
//! (rule 5's `light.direction`, fixed to the volume: it stays put when the camera turns); a double click gives
//! the headlight back. Pure geometry here; the drawing and input are in [`light_gizmo`].

use crate::scene::settings::CompositeMode;
use crate::viewer::model::Model;
use crate::viewer::widgets::clicks;
use egui::{Color32, Pos2, Stroke};
use glam::{Quat, Vec2, Vec3};

/// The disc's radius, points.
pub const RADIUS: f32 = 36.0;

/// The disc's centre for a view `rect`: 60 points in from its top-right corner.
pub fn center(rect: egui::Rect) -> Vec2 {
    Vec2::new(rect.right() - 60.0, rect.top() + 60.0)
}

/// The camera-space direction (x right, y up, z towards the viewer) under pointer `p` on the disc: the front
/// hemisphere inside it, the rim beyond.
pub fn camera_direction(p: Vec2, center: Vec2) -> Vec3 {
    let x = (p.x - center.x) / RADIUS;
    let y = (center.y - p.y) / RADIUS;
    let d2 = x * x + y * y;
    if d2 <= 1.0 {
        Vec3::new(x, y, (1.0 - d2).sqrt())
    } else {
        Vec3::new(x, y, 0.0).normalize()
    }
}

/// The world direction towards the light for pointer `p`, with the camera turned by `rotation` (the orbit view's:
/// camera axes to world axes).
pub fn world_direction(p: Vec2, center: Vec2, rotation: Quat) -> Vec3 {
    (rotation * camera_direction(p, center)).normalize()
}

/// Where world direction `d` shows on the disc, and whether it is on the front hemisphere.
pub fn disc_position(d: Vec3, center: Vec2, rotation: Quat) -> (Vec2, bool) {
    let c = rotation.inverse() * d.normalize();
    (Vec2::new(center.x + c.x * RADIUS, center.y - c.y * RADIUS), c.z >= 0.0)
}

/// Whether a frame of `model` is lit (the gizmo is shown and takes input only then).
pub fn shown(model: &Model) -> bool {
    let look = &model.look;
    look.compositing.mode == CompositeMode::Isosurface
        || (look.lighting.shading.is_some()
            && matches!(look.compositing.mode, CompositeMode::Emission | CompositeMode::Density))
}

/// Draws the gizmo over the view `rect` and handles its input: returns true while a drag on it moves the light
/// (the caller then leaves the camera alone).
pub fn light_gizmo(ui: &egui::Ui, model: &mut Model, rect: egui::Rect, response: &egui::Response) -> bool {
    if !shown(model) {
        return false;
    }
    let c = center(rect);
    let on_disc = |p: Pos2| (Vec2::new(p.x, p.y) - c).length() <= RADIUS + 4.0;
    let pressed_on_disc = ui.input(|i| i.pointer.press_origin()).is_some_and(on_disc);
    let mut dragging = false;
    if response.dragged_by(egui::PointerButton::Primary) && pressed_on_disc {
        if let Some(p) = response.interact_pointer_pos() {
            model.look.lighting.light.direction =
                Some(world_direction(Vec2::new(p.x, p.y), c, model.camera.orbit.rotation));
            dragging = true;
        }
    }
    if clicks::double_clicked(response) && response.interact_pointer_pos().is_some_and(on_disc) {
        model.look.lighting.light.direction = None;
    }
    let painter = ui.painter_at(rect);
    let centre = Pos2::new(c.x, c.y);
    painter.circle(
        centre,
        RADIUS,
        Color32::from_black_alpha(90),
        Stroke::new(1.0, Color32::from_gray(150)),
    );
    let sun = Color32::from_rgb(255, 210, 80);
    match model.look.lighting.light.direction {
        Some(d) => {
            let (p, front) = disc_position(d, c, model.camera.orbit.rotation);
            let p = Pos2::new(p.x, p.y);
            painter.line_segment([centre, p], Stroke::new(1.0, sun));
            if front {
                painter.circle_filled(p, 6.0, sun);
            } else {
                painter.circle_stroke(p, 6.0, Stroke::new(1.5, sun));
            }
        }
        // The headlight: a ring at the centre (the light comes from the eye).
        None => {
            painter.circle_stroke(centre, 6.0, Stroke::new(1.5, sun));
        }
    }
    dragging
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_disc_maps_to_the_front_hemisphere_and_back() {
        let c = Vec2::new(100.0, 100.0);
        // The centre is towards the viewer; the right edge is the camera's right.
        assert!((camera_direction(c, c) - Vec3::Z).length() < 1e-6);
        assert!((camera_direction(c + Vec2::new(RADIUS, 0.0), c) - Vec3::X).length() < 1e-6);
        assert!((camera_direction(c + Vec2::new(0.0, -RADIUS), c) - Vec3::Y).length() < 1e-6);
        let turn = Quat::from_rotation_z(0.7) * Quat::from_rotation_x(0.3);
        let p = c + Vec2::new(12.0, -20.0);
        let d = world_direction(p, c, turn);
        let (back, front) = disc_position(d, c, turn);
        assert!(front && (back - p).length() < 1e-3, "{back} vs {p}");
    }
}
