//! Over the 3D view: the camera's mouse input, and what is drawn on the volume — the light gizmo, the clipping
//! plane, the bounding and slab boxes, the slice views' crosshair, the colour bar, the orientation gizmo and the
//! patient-side labels (in that order, later ones on top).

use crate::scene::camera::edge_labels;
use crate::scene::slice::{SliceView, BOX_EDGES};
use crate::viewer::model::Model;
use crate::viewer::widgets::screen::{box_corners, project};
use crate::viewer::widgets::{clip_plane, colorbar, keys, light_gizmo, marks, orientation, rects};
use egui::{Color32, Stroke};
use glam::{Vec2, Vec3};

/// The 3D view filling `ui`: its input (camera, gizmos, clipping plane) and everything drawn over it.
pub fn view_overlay(ui: &mut egui::Ui, model: &mut Model) {
    let rect = ui.max_rect();
    model.interaction.view_rect = Some(rect);
    let response = ui.interact(rect, ui.id().with("volume view"), egui::Sense::click_and_drag());
    model.interaction.interacting = response.dragged();
    // A drag that starts on the light gizmo moves the light, not the camera.
    let moving_light = light_gizmo::light_gizmo(ui, model, rect, &response);
    // So does one that starts on the clipping plane's handle or ring.
    let moving_plane = clip_plane::clip_widget(ui, model, rect, &response);
    camera_input(ui, model, rect, &response, moving_light || moving_plane);

    let painter = ui.painter_at(rect);
    if model.display.show_boxes {
        paint_boxes(&painter, model, rect);
    }
    if model.display.show_colorbar {
        paint_colorbar(&painter, model, rect);
    }
    orientation::paint(&painter, model, rect);
    paint_refining(&painter, model, rect);
    if model.anatomical() {
        // Which side of the patient each edge of the view faces.
        marks::side_labels(
            &painter,
            rect,
            edge_labels(&model.camera.orbit.camera()),
            16.0,
            egui::vec2(8.0, 8.0),
        );
    }
}

/// While a streamed volume refines, how far it has come, at the view's bottom left.
fn paint_refining(painter: &egui::Painter, model: &Model, rect: egui::Rect) {
    let Some(streaming) = model.streaming.as_ref().filter(|s| s.refining()) else {
        return;
    };
    let text = match &streaming.progress {
        Some(p) => format!("refining: {} of {} bricks at their level", p.resident, p.wanted),
        None => "refining".to_string(),
    };
    painter.text(
        rect.left_bottom() + egui::vec2(8.0, -8.0),
        egui::Align2::LEFT_BOTTOM,
        text,
        egui::FontId::proportional(13.0),
        Color32::from_rgb(230, 230, 140),
    );
}

/// Left drag turns (arcball) unless a gizmo took it, right or middle drag pans, the wheel zooms, a click on the
/// orientation gizmo flies to its axis.
fn camera_input(ui: &egui::Ui, model: &mut Model, rect: egui::Rect, response: &egui::Response, gizmo_dragged: bool) {
    let viewport = Vec2::new(rect.width(), rect.height());
    if let Some(pos) = response.interact_pointer_pos() {
        let p = Vec2::new(pos.x - rect.left(), pos.y - rect.top());
        let d = response.drag_delta();
        if response.dragged_by(egui::PointerButton::Primary) && d != egui::Vec2::ZERO && !gizmo_dragged {
            model.camera.animation = None;
            model.camera.orbit.arcball(p - Vec2::new(d.x, d.y), p, viewport);
        }
        if response.dragged_by(egui::PointerButton::Secondary) || response.dragged_by(egui::PointerButton::Middle) {
            model.camera.orbit.pan(Vec2::new(d.x, d.y), viewport);
        }
    }
    orientation::take_click(model, rect, response);
    if response.hovered() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            model.camera.orbit.zoom(scroll / 50.0);
            model.interaction.interacting = true;
        }
    }
}

/// The volume's bounding box, the slab box when it cuts, and (four-up) the slice views' crosshair.
fn paint_boxes(painter: &egui::Painter, model: &Model, rect: egui::Rect) {
    let s = model.render_settings(rect.width() as u32, rect.height() as u32);
    let vp = model.view_projection(rect);
    let to_world = model.tex_to_world();
    let draw_box = |lo: Vec3, hi: Vec3, color: Color32| {
        let corners = box_corners(to_world, lo, hi).map(|c| project(vp, c, rect));
        for (a, b) in BOX_EDGES {
            if let (Some(pa), Some(pb)) = (corners[a], corners[b]) {
                painter.line_segment([pa, pb], Stroke::new(1.0, color));
            }
        }
    };
    draw_box(Vec3::ZERO, Vec3::ONE, Color32::from_gray(160));
    if s.cut.slab_lo != Vec3::ZERO || s.cut.slab_hi != Vec3::ONE {
        draw_box(s.cut.slab_lo, s.cut.slab_hi, Color32::from_rgb(255, 200, 60));
    }
    if model.slices.shown {
        // The slice views' crosshair: a short segment along each world axis, in its view's colour.
        let d = glam::DVec3::new(
            f64::from(model.dims[0]),
            f64::from(model.dims[1]),
            f64::from(model.dims[2]),
        );
        let tex = ((model.slices.crosshair + 0.5) / d).as_vec3();
        let centre = to_world.transform_point3(tex);
        for view in SliceView::ALL {
            let mut axis = Vec3::ZERO;
            axis[view.normal_axis()] = 0.04;
            if let (Some(a), Some(b)) = (project(vp, centre - axis, rect), project(vp, centre + axis, rect)) {
                painter.line_segment([a, b], Stroke::new(2.0, marks::view_color(view)));
            }
        }
    }
}

/// The transfer function's colour bar with data-unit ticks, top left of the view.
fn paint_colorbar(painter: &egui::Painter, model: &Model, rect: egui::Rect) {
    let height = (rect.height() - 40.0).clamp(60.0, 220.0);
    let bar = egui::Rect::from_min_size(rect.left_top() + egui::vec2(8.0, 28.0), egui::vec2(78.0, height));
    let unit = (!model.volume.unit.is_empty()).then_some(model.volume.unit.as_str());
    colorbar::paint_colorbar(
        painter,
        bar,
        &model.look.classification(),
        model.look.colour.window,
        model.volume.range,
        unit,
    );
}

/// The list of every keyboard shortcut ([`keys::KEYS`]) and mouse gesture ([`keys::MOUSE`]), over the middle of
/// the window while `model.display.show_shortcuts` (F1 or ?; Esc closes it). Its rect is logged as `shortcuts`
/// (empty while hidden) for the tests.
pub fn shortcut_overlay(ctx: &egui::Context, model: &Model) {
    if !model.display.show_shortcuts {
        rects::log("shortcuts", egui::Rect::ZERO);
        return;
    }
    // A box of one size, centred, placed where it belongs from its first frame (egui places an area anchored
    // by its size only a frame later); however small the window, the list fits it and scrolls.
    let screen = ctx.content_rect();
    let size = egui::vec2(600.0, 520.0)
        .min(screen.size() - egui::vec2(40.0, 40.0))
        .max(egui::vec2(120.0, 80.0));
    let shown = egui::Area::new(egui::Id::new("shortcut overlay"))
        .order(egui::Order::Foreground)
        .fixed_pos(screen.center() - size / 2.0)
        .show(ctx, |ui| {
            egui::Frame::popup(ui.style()).inner_margin(8.0).show(ui, |ui| {
                ui.set_width(size.x - 16.0);
                egui::ScrollArea::vertical()
                    .max_height(size.y - 16.0)
                    .min_scrolled_height(size.y - 16.0)
                    .show(ui, shortcut_list);
            });
        });
    let rect = shown.response.rect;
    rects::log("shortcuts", rect);
}

/// The overlay's content: the keys, then the mouse gestures by where they are made.
fn shortcut_list(ui: &mut egui::Ui) {
    ui.strong("Keyboard (F1, ? or Esc closes this)");
    egui::Grid::new("shortcut keys").num_columns(2).show(ui, |ui| {
        for binding in keys::listed_keys() {
            ui.monospace(binding.label);
            ui.label(binding.does);
            ui.end_row();
        }
    });
    ui.separator();
    ui.strong("Mouse");
    egui::Grid::new("shortcut mouse").num_columns(2).show(ui, |ui| {
        for (place, gesture, does) in keys::MOUSE {
            ui.monospace(format!("{place}: {gesture}"));
            ui.label(*does);
            ui.end_row();
        }
    });
}
