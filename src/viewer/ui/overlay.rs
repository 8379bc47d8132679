//! Over the 3D view: the bounding and slab boxes, the orientation gizmo and the patient-side labels; and the
//! camera's mouse input on the view.

use super::state::ViewerState;
use crate::scene::camera::edge_labels;
use crate::viewer::controls::{gizmo_axes, look_along, pick_axis, RotationAnimation};
use egui::{Color32, Pos2, Stroke};
use glam::{Mat4, Vec2, Vec3};

pub fn box_corners(tex_to_world: Mat4, lo: Vec3, hi: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        let t = Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
        tex_to_world.transform_point3(lo + (hi - lo) * t)
    })
}

use crate::scene::slice::BOX_EDGES;

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

/// Bounding box, slab box and origin gizmo over the volume view; handles camera input on it.
pub fn view_overlay(ui: &mut egui::Ui, state: &mut ViewerState) {
    let rect = ui.max_rect();
    state.view_rect = Some(rect);
    let response = ui.interact(rect, ui.id().with("volume view"), egui::Sense::click_and_drag());
    let viewport = Vec2::new(rect.width(), rect.height());
    let gizmo_center = Vec2::new(rect.right() - 60.0, rect.bottom() - 60.0);
    let gizmo_radius = 40.0;
    state.interacting = response.dragged();
    // A drag that starts on the light gizmo moves the light, not the camera.
    let moving_light = crate::viewer::light_gizmo::light_gizmo(ui, state, rect, &response);
    // So does one that starts on the clipping plane's handle or ring.
    let moving_plane = crate::viewer::clip_widget::clip_widget(ui, state, rect, &response);

    if let Some(pos) = response.interact_pointer_pos() {
        let p = Vec2::new(pos.x - rect.left(), pos.y - rect.top());
        let d = response.drag_delta();
        if response.dragged_by(egui::PointerButton::Primary) && d != egui::Vec2::ZERO && !moving_light && !moving_plane
        {
            state.animation = None;
            state.orbit.arcball(p - Vec2::new(d.x, d.y), p, viewport);
        }
        if response.dragged_by(egui::PointerButton::Secondary) || response.dragged_by(egui::PointerButton::Middle) {
            state.orbit.pan(Vec2::new(d.x, d.y), viewport);
        }
    }
    if response.clicked() {
        if let Some(pos) = response.interact_pointer_pos() {
            let axes = gizmo_axes(state.orbit.rotation);
            if let Some(a) = pick_axis(Vec2::new(pos.x, pos.y), gizmo_center, gizmo_radius, 10.0, &axes) {
                state.animation = Some(RotationAnimation::new(
                    state.orbit.rotation,
                    look_along(a.axis, a.positive),
                ));
            }
        }
    }
    if response.hovered() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            state.orbit.zoom(scroll / 50.0);
            state.interacting = true;
        }
    }

    let painter = ui.painter_at(rect);
    if state.show_boxes {
        let s = state.render_settings(rect.width() as u32, rect.height() as u32);
        let vp = state.view_projection(rect);
        let model = state.tex_to_world();
        let draw_box = |lo: Vec3, hi: Vec3, color: Color32| {
            let corners = box_corners(model, lo, hi).map(|c| project(vp, c, rect));
            for (a, b) in BOX_EDGES {
                if let (Some(pa), Some(pb)) = (corners[a], corners[b]) {
                    painter.line_segment([pa, pb], Stroke::new(1.0, color));
                }
            }
        };
        draw_box(Vec3::ZERO, Vec3::ONE, Color32::from_gray(160));
        if s.slab_lo != Vec3::ZERO || s.slab_hi != Vec3::ONE {
            draw_box(s.slab_lo, s.slab_hi, Color32::from_rgb(255, 200, 60));
        }
        if state.slices.shown {
            // The slice views' crosshair: a short segment along each world axis, in its view's colour.
            let d = glam::DVec3::new(
                f64::from(state.dims[0]),
                f64::from(state.dims[1]),
                f64::from(state.dims[2]),
            );
            let tex = ((state.slices.crosshair + 0.5) / d).as_vec3();
            let centre = model.transform_point3(tex);
            for view in crate::scene::slice::SliceView::ALL {
                let mut axis = Vec3::ZERO;
                axis[view.normal_axis()] = 0.04;
                if let (Some(a), Some(b)) = (project(vp, centre - axis, rect), project(vp, centre + axis, rect)) {
                    let color = crate::viewer::slice_views::view_color(view);
                    painter.line_segment([a, b], Stroke::new(2.0, color));
                }
            }
        }
    }

    if state.show_colorbar {
        // The transfer function's colour bar with data-unit ticks, top left of the view.
        let height = (rect.height() - 40.0).clamp(60.0, 220.0);
        let bar = egui::Rect::from_min_size(rect.left_top() + egui::vec2(8.0, 28.0), egui::vec2(78.0, height));
        let unit = (!state.value_unit.is_empty()).then_some(state.value_unit.as_str());
        crate::viewer::tf_editor::paint_colorbar(
            &painter,
            bar,
            &state.look.classification(),
            state.look.window,
            state.range,
            unit,
        );
    }

    let colors = [
        Color32::from_rgb(230, 70, 70),
        Color32::from_rgb(90, 200, 90),
        Color32::from_rgb(80, 130, 240),
    ];
    let c = Pos2::new(gizmo_center.x, gizmo_center.y);
    painter.circle_filled(c, gizmo_radius + 12.0, Color32::from_black_alpha(90));
    for a in gizmo_axes(state.orbit.rotation) {
        let end = Pos2::new(c.x + a.screen.x * gizmo_radius, c.y + a.screen.y * gizmo_radius);
        let color = if a.positive {
            colors[a.axis]
        } else {
            colors[a.axis].gamma_multiply(0.45)
        };
        if a.positive {
            painter.line_segment([c, end], Stroke::new(2.0, color));
        }
        painter.circle_filled(end, 8.0, color);
        // In patient space every end is named (R/L, A/P, S/I); otherwise the positive ends X, Y, Z.
        let label = if state.anatomical() {
            Some([['L', 'R'], ['P', 'A'], ['I', 'S']][a.axis][usize::from(a.positive)])
        } else {
            a.positive.then_some(['X', 'Y', 'Z'][a.axis])
        };
        if let Some(label) = label {
            painter.text(
                end,
                egui::Align2::CENTER_CENTER,
                label,
                egui::FontId::proportional(11.0),
                Color32::BLACK,
            );
        }
    }
    if state.anatomical() {
        // Which side of the patient each edge of the view faces.
        side_labels(
            &painter,
            rect,
            edge_labels(&state.orbit.camera()),
            16.0,
            egui::vec2(8.0, 8.0),
        );
    }
}

/// The patient's sides at a view's left, right, top and bottom edges, `inset` in from them.
pub fn side_labels(
    painter: &egui::Painter,
    rect: egui::Rect,
    labels: [impl ToString; 4],
    size: f32,
    inset: egui::Vec2,
) {
    let [left, right, top, bottom] = labels;
    let font = egui::FontId::proportional(size);
    let color = Color32::from_rgb(255, 220, 120);
    let mid = rect.center();
    for (text, pos, align) in [
        (
            left.to_string(),
            Pos2::new(rect.left() + inset.x, mid.y),
            egui::Align2::LEFT_CENTER,
        ),
        (
            right.to_string(),
            Pos2::new(rect.right() - inset.x, mid.y),
            egui::Align2::RIGHT_CENTER,
        ),
        (
            top.to_string(),
            Pos2::new(mid.x, rect.top() + inset.y),
            egui::Align2::CENTER_TOP,
        ),
        (
            bottom.to_string(),
            Pos2::new(mid.x, rect.bottom() - inset.y),
            egui::Align2::CENTER_BOTTOM,
        ),
    ] {
        painter.text(pos, align, text, font.clone(), color);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projected_box_corners_land_in_the_view() {
        let state = ViewerState::new(Vec3::ONE, "x".into());
        let s = state.render_settings(100, 100);
        let vp = s.camera.projection(1.0) * s.camera.view();
        let rect = egui::Rect::from_min_size(Pos2::ZERO, egui::vec2(100.0, 100.0));
        for c in box_corners(state.tex_to_world(), Vec3::ZERO, Vec3::ONE) {
            let p = project(vp, c, rect).expect("in front of the camera");
            assert!(rect.contains(p), "{p:?}");
        }
    }
}
