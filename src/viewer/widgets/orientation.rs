//! The orientation gizmo in the 3D view's bottom-right corner: the world axes as the camera sees them (named R/L,
//! A/P, S/I in patient space); a click on an axis end flies the view to look along it. It shrinks in small views,
//! and the view frames the volume clear of it ([`framing`]).

use crate::viewer::model::framing::{self, gizmo_place};
use crate::viewer::widgets::rects;

use crate::viewer::model::orbit::{look_along, RotationAnimation};
use crate::viewer::model::Model;
use egui::{Color32, Pos2, Stroke};
use glam::{Quat, Vec2, Vec3};

/// The axes' arm length at full size, points.
pub const RADIUS: f32 = 40.0;

/// The gizmo's centre for a view `rect`: 60 points in from its bottom-right corner at full size.
pub fn center(rect: egui::Rect) -> Vec2 {
    gizmo_place(rect).centre
}

/// One of the gizmo's six axis ends (±x, ±y, ±z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GizmoAxis {
    /// 0 = x, 1 = y, 2 = z.
    pub axis: usize,
    pub positive: bool,
    /// Screen direction from the gizmo centre (y down), length ≤ 1 (shorter when the axis points at the viewer).
    pub screen: Vec2,
    /// Towards the viewer is positive: draw back to front.
    pub depth: f32,
}

/// The world axes as seen by a camera with `rotation` (see [`OrbitView`](crate::viewer::model::orbit::OrbitView)), back to front.
pub fn gizmo_axes(rotation: Quat) -> Vec<GizmoAxis> {
    let to_camera = rotation.inverse();
    let mut axes: Vec<GizmoAxis> = (0..6)
        .map(|i| {
            let axis = i / 2;
            let positive = i % 2 == 0;
            let mut w = Vec3::ZERO;
            w[axis] = if positive { 1.0 } else { -1.0 };
            let c = to_camera * w;
            GizmoAxis {
                axis,
                positive,
                screen: Vec2::new(c.x, -c.y),
                depth: c.z,
            }
        })
        .collect();
    axes.sort_by(|a, b| a.depth.total_cmp(&b.depth));
    axes
}

/// The axis end under `click` (pixels) for a gizmo drawn at `center` with arm length `radius`: the nearest end
/// within `pick_radius`, preferring the one closer to the viewer.
pub fn pick_axis(click: Vec2, center: Vec2, radius: f32, pick_radius: f32, axes: &[GizmoAxis]) -> Option<GizmoAxis> {
    axes.iter()
        .filter(|a| (center + a.screen * radius).distance(click) <= pick_radius)
        .max_by(|a, b| a.depth.total_cmp(&b.depth))
        .copied()
}

/// A click on an axis end starts the fly-to that looks along it.
pub fn take_click(model: &mut Model, rect: egui::Rect, response: &egui::Response) {
    if !response.clicked() {
        return;
    }
    let Some(pos) = response.interact_pointer_pos() else {
        return;
    };
    let rotation = model.camera.orbit.rotation;
    let axes = gizmo_axes(rotation);
    let g = gizmo_place(rect);
    if let Some(a) = pick_axis(Vec2::new(pos.x, pos.y), g.centre, g.arm, 10.0, &axes) {
        model.camera.animation = Some(RotationAnimation::new(rotation, look_along(a.axis, a.positive)));
    }
}

/// Paints the gizmo: the positive ends bright with a stem, the negative ones dimmed, back to front.
pub fn paint(painter: &egui::Painter, model: &Model, rect: egui::Rect) {
    let colors = [
        Color32::from_rgb(230, 70, 70),
        Color32::from_rgb(90, 200, 90),
        Color32::from_rgb(80, 130, 240),
    ];
    let g: framing::GizmoPlace = gizmo_place(rect);
    let c = Pos2::new(g.centre.x, g.centre.y);
    rects::log("view-3d", rect);
    rects::log(
        "orientation-gizmo",
        egui::Rect::from_center_size(c, egui::Vec2::splat(2.0 * g.disc)),
    );
    painter.circle_filled(c, g.disc, Color32::from_black_alpha(90));
    for a in gizmo_axes(model.camera.orbit.rotation) {
        let end = Pos2::new(c.x + a.screen.x * g.arm, c.y + a.screen.y * g.arm);
        let color = if a.positive {
            colors[a.axis]
        } else {
            colors[a.axis].gamma_multiply(0.45)
        };
        if a.positive {
            painter.line_segment([c, end], Stroke::new(2.0, color));
        }
        painter.circle_filled(end, 8.0 * g.scale, color);
        // In patient space every end is named (R/L, A/P, S/I); otherwise the positive ends X, Y, Z.
        let label = if model.anatomical() {
            Some([['L', 'R'], ['P', 'A'], ['I', 'S']][a.axis][usize::from(a.positive)])
        } else {
            a.positive.then_some(['X', 'Y', 'Z'][a.axis])
        };
        if let Some(label) = label {
            painter.text(
                end,
                egui::Align2::CENTER_CENTER,
                label,
                egui::FontId::proportional(11.0 * g.scale.max(0.8)),
                Color32::BLACK,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::Camera;
    use crate::viewer::model::orbit::OrbitView;

    #[test]
    fn gizmo_projects_and_picks_axes() {
        let v = OrbitView::from_camera(&Camera::orbit(0.0, 0.0, 2.0, Vec3::ZERO));
        let axes = gizmo_axes(v.rotation);
        let find = |axis, positive| *axes.iter().find(|a| a.axis == axis && a.positive == positive).unwrap();
        // From +y with +z up: +z points up on screen (negative y), -x points right, +y points at the viewer.
        assert!((find(2, true).screen - Vec2::new(0.0, -1.0)).length() < 1e-5);
        assert!((find(0, false).screen - Vec2::new(1.0, 0.0)).length() < 1e-5);
        assert!(
            find(1, true).depth > 0.99 && axes.last().unwrap().depth > 0.99,
            "sorted back to front"
        );
        let center = Vec2::new(50.0, 50.0);
        let hit = pick_axis(Vec2::new(50.0, 20.0), center, 30.0, 8.0, &axes).unwrap();
        assert_eq!((hit.axis, hit.positive), (2, true));
        assert!(pick_axis(Vec2::new(80.0, 80.0), center, 30.0, 8.0, &axes).is_none());
    }
}
