//! One of the three linked slice views beside the 3D view (3D Slicer's "four-up"). One crosshair is shared by all
//! three (and marked in the 3D view): a left click or drag in a slice moves it there, the wheel steps the slice
//! along its normal, a right drag changes window (horizontal) and level (vertical), and the value under the
//! cursor is shown in data units. The slab box and the clipping plane are drawn where they cut each slice.
//!
//! The images are resampled on the CPU from the volume the app keeps (`slice::render`) by whoever keeps their
//! textures ([`SliceImages`]), only when what they show ([`SliceImage`]) changed.

use crate::scene::layer_set::Layers;
use crate::scene::slice::{self, SliceFrame, SliceView, WindowLevel};
use crate::viewer::model::slices::{
    self as slice_state, PresetFit, Probe, SliceData, SliceImage, SliceSource, CT_PRESETS,
};
use crate::viewer::model::Model;
use crate::viewer::widgets::shown_slice::ShownSlice;
use crate::viewer::widgets::{clip_plane, marks, rects, ruler};
use crate::volume::Volume;
use egui::{Color32, Pos2, Stroke};
use glam::{DMat4, DVec3};

/// Where a slice view's image comes from: the texture showing a [`SliceImage`], made again from `volume` only
/// when the image changed; with no volume to resample, the last one made (if any).
pub type SliceImages<'a> = dyn FnMut(&egui::Context, &SliceImage, Option<SliceSource>) -> Option<egui::TextureId> + 'a;

/// Where a slice view's image is drawn in its rect: as large as fits, centred, square pixels.
pub fn image_rect(frame: &SliceFrame, rect: egui::Rect) -> egui::Rect {
    let (w, h) = (frame.width as f32, frame.height as f32);
    let scale = (rect.width() / w).min(rect.height() / h);
    egui::Rect::from_center_size(rect.center(), egui::vec2(w * scale, h * scale))
}

/// The frame a view shows now: through the crosshair, at most as many pixels as the view has.
pub fn frame_of(model: &Model, view: SliceView, rect: egui::Rect, pixels_per_point: f32) -> SliceFrame {
    let mm = slice::mm_from_index(&model.geometry, model.look.voxel_axes);
    let through = mm.transform_point3(model.slices.crosshair);
    let side = (rect.width().max(rect.height()) * pixels_per_point).clamp(16.0, 1024.0) as u32;
    SliceFrame::new(view, model.anatomical(), mm, model.dims, through, side)
}

/// One slice view in `rect`: its image, the crosshair, slab and clip plane over it, the probe, and its input.
/// `data` is what the image is resampled from and the probe reads.
pub fn slice_view(
    ui: &mut egui::Ui,
    rect: egui::Rect,
    model: &mut Model,
    view: SliceView,
    data: SliceData,
    images: &mut SliceImages<'_>,
) {
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, Color32::BLACK);
    let mm = slice::mm_from_index(&model.geometry, model.look.voxel_axes);
    let frame = frame_of(model, view, rect, ui.ctx().pixels_per_point());
    let wl = model.slices.window_level(model.volume.range);
    let image = SliceImage {
        generation: model.slices.generation,
        frame,
        mm_from_index: mm,
        wl,
        voxel_axes: model.look.voxel_axes,
        layers: model.layers.generation,
    };
    // Only the volume the model describes: never resample another one's grid.
    let volume = data.volume.filter(|v| v.dims == model.dims);
    let shown = image_rect(&frame, rect);
    let styles = model.layers.styles();
    let source = volume.map(|volume| SliceSource {
        volume,
        layers: data.layers,
        styles: &styles,
    });
    if let Some(texture) = images(ui.ctx(), &image, source) {
        let uv = egui::Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        painter.image(texture, shown, uv, Color32::WHITE);
    }
    let slice = ShownSlice {
        frame,
        mm,
        shown,
        scale: shown.width() / frame.width as f32,
    };
    paint_cuts(&painter, model, &slice);
    paint_labels(&painter, rect, model, view, mm.transform_point3(model.slices.crosshair));
    // Framed in its colour, as Slicer marks its views: which view a label or a click belongs to is never in doubt.
    let frame_stroke = Stroke::new(1.0, marks::view_color(view));
    painter.rect_stroke(rect, 0.0, frame_stroke, egui::StrokeKind::Inside);

    let response = ui.interact(
        rect,
        ui.id().with(("slice view", image.slot())),
        egui::Sense::click_and_drag(),
    );
    let ruler_took = ruler::take_input(model, &slice, &response);
    take_input(ui, model, &slice, wl, &response, ruler_took);
    probe(
        &painter,
        rect,
        model,
        &slice,
        volume.map(|v| (v, data.layers)),
        &response,
    );
    ruler::paint(&painter, model, &slice, response.hover_pos());
    tools(ui, rect, model, view);
}

/// The view's tool row, top right: the ruler tool's toggle and the window/level presets.
fn tools(ui: &mut egui::Ui, rect: egui::Rect, model: &mut Model, view: SliceView) {
    let row = egui::Rect::from_min_size(rect.right_top() + egui::vec2(-132.0, 2.0), egui::vec2(130.0, 20.0));
    let mut tools_ui = ui.new_child(
        egui::UiBuilder::new()
            .max_rect(row)
            .layout(egui::Layout::right_to_left(egui::Align::Center)),
    );
    let ui = &mut tools_ui;
    // The tests click the axial view's tools; the other two views' are the same.
    let logged = view == SliceView::Axial;
    let menu = ui.menu_button("W/L", |ui| wl_presets(ui, model, logged)).response;
    let ruler = ui
        .selectable_label(model.slices.ruler.active, "ruler")
        .on_hover_text("M: click two points to measure (mm); right click or Esc clears");
    if ruler.clicked() {
        model.slices.ruler.toggle_tool();
    }
    if logged {
        rects::log("wl-menu", menu.rect);
        rects::log("ruler-tool", ruler.rect);
    }
}

/// The window/level presets: "auto" (the percentile window a volume opens with) and the CT presets in HU,
/// disabled with a note for a modality whose values are not HU.
fn wl_presets(ui: &mut egui::Ui, model: &mut Model, logged: bool) {
    let auto = ui.button("auto (0.5–99.5th percentile)");
    if auto.clicked() {
        model.slices.wl = Some(slice_state::percentile_window(
            &model.volume.histogram,
            model.volume.range,
        ));
        ui.close();
    }
    let modality = model.tf_editor.volume.as_ref().and_then(|(f, _)| f.modality.clone());
    let fit = slice_state::preset_fit(modality.as_deref(), &model.volume.unit);
    if let PresetFit::NotHounsfield(note) = &fit {
        ui.weak(note);
    }
    let suffix = if fit == PresetFit::Unknown { " (HU)" } else { "" };
    for p in CT_PRESETS {
        let text = format!("{}  W{} L{}{suffix}", p.name, p.wl.window, p.wl.level);
        let item = ui.add_enabled(!matches!(fit, PresetFit::NotHounsfield(_)), egui::Button::new(text));
        if item.clicked() {
            model.slices.wl = Some(p.wl);
            ui.close();
        }
        if logged {
            rects::log(p.id, item.rect);
        }
    }
    if logged {
        rects::log("wl-auto", auto.rect);
    }
}

/// What cuts the slice: the other two views' planes through the crosshair (in their colours), the slab box and
/// the clipping plane.
fn paint_cuts(painter: &egui::Painter, model: &Model, slice: &ShownSlice) {
    let (frame, mm) = (&slice.frame, slice.mm);
    let through = mm.transform_point3(model.slices.crosshair);
    for other in SliceView::ALL.into_iter().filter(|&o| o != frame.view) {
        let (r, d) = other.screen_axes(model.anatomical());
        if let Some((a, b)) = frame.line_of_plane(through, r.cross(d)) {
            painter.line_segment(
                [slice.to_screen(a), slice.to_screen(b)],
                Stroke::new(1.0, marks::view_color(other)),
            );
        }
    }
    let s = model.render_settings(1, 1);
    if s.cut.slab_lo != glam::Vec3::ZERO || s.cut.slab_hi != glam::Vec3::ONE {
        let outline = frame.section(&slab_corners_mm(mm, model.dims, s.cut.slab_lo, s.cut.slab_hi));
        if outline.len() >= 3 {
            let points: Vec<Pos2> = outline.iter().map(|&p| slice.to_screen(p)).collect();
            painter.add(egui::Shape::closed_line(
                points,
                Stroke::new(1.5, Color32::from_rgb(255, 200, 60)),
            ));
        }
    }
    if let Some(plane) = model.look.cut.clip_plane {
        let (point, normal) = clip_plane::plane_in_slices(model, &plane, mm);
        if let Some((a, b)) = frame.line_of_plane(point, normal) {
            painter.line_segment(
                [slice.to_screen(a), slice.to_screen(b)],
                Stroke::new(1.5, clip_plane::COLOR),
            );
        }
    }
}

/// A left click or drag moves the crosshair there (unless the ruler took it), a right drag changes window/level,
/// the wheel steps the slice.
fn take_input(
    ui: &egui::Ui,
    model: &mut Model,
    slice: &ShownSlice,
    wl: WindowLevel,
    response: &egui::Response,
    ruler_took: bool,
) {
    let (frame, mm) = (&slice.frame, slice.mm);
    let index_from_mm = mm.inverse();
    if let Some(pos) = response.interact_pointer_pos() {
        if !ruler_took && (response.dragged_by(egui::PointerButton::Primary) || response.clicked()) {
            let w = slice.world_at(pos);
            model.slices.crosshair = index_from_mm.transform_point3(w);
        }
        if response.dragged_by(egui::PointerButton::Secondary) {
            let d = response.drag_delta();
            model.slices.wl = Some(wl.dragged(f64::from(d.x), f64::from(d.y), model.volume.range));
        }
    }
    if response.hovered() {
        // Wheel events (not egui's smoothed scroll), one voxel's depth along the normal per frame that has any: X11
        // delivers each notch twice (measured under Xvfb: two MouseWheel events of one line for one `click 4`).
        let notches: f32 = ui.input(|i| {
            i.events
                .iter()
                .filter_map(|e| match e {
                    egui::Event::MouseWheel { delta, .. } if delta.y != 0.0 => Some(delta.y.signum()),
                    _ => None,
                })
                .sum::<f32>()
        });
        let notches = if notches == 0.0 { 0.0 } else { notches.signum() };
        if notches != 0.0 {
            let step = frame.normal() * frame.pixel.min(smallest_spacing(mm)) * f64::from(notches);
            let moved = mm.transform_point3(model.slices.crosshair) + step;
            model.slices.crosshair = index_from_mm.transform_point3(moved);
        }
    }
}

/// The value under the pointer: kept in the model while it hovers this view, written at its bottom left, with each
/// layer's value (a label map's id and name) above it.
fn probe(
    painter: &egui::Painter,
    rect: egui::Rect,
    model: &mut Model,
    shown: &ShownSlice,
    data: Option<(&Volume, &Layers)>,
    response: &egui::Response,
) {
    let view = shown.frame.view;
    if let (Some(pos), Some((volume, _))) = (response.hover_pos(), data) {
        let w = shown.world_at(pos);
        model.slices.probe = slice::voxel_at(model.dims, shown.mm.inverse(), w).map(|voxel| Probe {
            view,
            world: w,
            voxel,
            value: volume.value(voxel[0], voxel[1], voxel[2]),
        });
    } else if model.slices.probe.is_some_and(|p| p.view == view) {
        model.slices.probe = None;
    }
    let Some(p) = model.slices.probe.filter(|p| p.view == view) else {
        return;
    };
    let mut lines = match data {
        Some((volume, layers)) => crate::scene::slice_layers::values_at(&volume.geometry, shown.mm, p.world, layers),
        None => Vec::new(),
    };
    lines.push(probe_text(&p, model.anatomical(), &model.volume.unit));
    let text = lines.join("\n");
    let at = Pos2::new(rect.left() + 6.0, rect.bottom() - 6.0);
    let font = egui::FontId::monospace(11.0);
    let drawn = painter.text(at, egui::Align2::LEFT_BOTTOM, &text, font, Color32::WHITE);
    rects::log_labelled("probe", drawn, Some(&text.replace('\n', " | ")));
}

fn smallest_spacing(mm: DMat4) -> f64 {
    (0..3).map(|a| mm.col(a).truncate().length()).fold(f64::MAX, f64::min)
}

/// The texture-space box [lo, hi] as world millimetres (texture coordinate t is voxel index t·dims − ½).
pub fn slab_corners_mm(mm: DMat4, dims: [u32; 3], lo: glam::Vec3, hi: glam::Vec3) -> [DVec3; 8] {
    let d = DVec3::new(f64::from(dims[0]), f64::from(dims[1]), f64::from(dims[2]));
    std::array::from_fn(|c| {
        let pick = |bit: usize, a: usize| f64::from(if c >> bit & 1 == 1 { hi[a] } else { lo[a] });
        let t = DVec3::new(pick(0, 0), pick(1, 1), pick(2, 2));
        mm.transform_point3(t * d - 0.5)
    })
}

/// "R 12.3 A −4.0 S 30.1 mm  [i j k]  value unit" (x, y, z for a volume without orientation).
pub fn probe_text(p: &Probe, anatomical: bool, unit: &str) -> String {
    let coords = if anatomical {
        let letter = |v: f64, pos: char, neg: char| format!("{}{:.1}", if v >= 0.0 { pos } else { neg }, v.abs());
        format!(
            "{} {} {} mm",
            letter(p.world.x, 'R', 'L'),
            letter(p.world.y, 'A', 'P'),
            letter(p.world.z, 'S', 'I')
        )
    } else {
        format!("x {:.1} y {:.1} z {:.1}", p.world.x, p.world.y, p.world.z)
    };
    let value = if p.value.fract() == 0.0 && p.value.abs() < 1e9 {
        format!("{}", p.value)
    } else {
        format!("{:.4}", p.value)
    };
    let [i, j, k] = p.voxel;
    format!("{coords}  [{i} {j} {k}]  {value} {unit}")
        .trim_end()
        .to_string()
}

/// The view's name and position (top left) and, in patient space, the sides at its edges.
fn paint_labels(painter: &egui::Painter, rect: egui::Rect, model: &Model, view: SliceView, through: DVec3) {
    let anatomical = model.anatomical();
    let axis = view.normal_axis();
    let position = through[axis];
    let name = view.name(anatomical);
    let title = if anatomical {
        let (pos, neg) = [('R', 'L'), ('A', 'P'), ('S', 'I')][axis];
        format!(
            "{name}  {}{:.1} mm",
            if position >= 0.0 { pos } else { neg },
            position.abs()
        )
    } else {
        format!("{name}  {}{:.1}", ['x', 'y', 'z'][axis], position)
    };
    painter.text(
        rect.left_top() + egui::vec2(6.0, 4.0),
        egui::Align2::LEFT_TOP,
        title,
        egui::FontId::proportional(13.0),
        marks::view_color(view),
    );
    if anatomical {
        marks::side_labels(painter, rect, view.edge_labels(), 14.0, egui::vec2(6.0, 22.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probe_text_names_sides_and_units() {
        let p = Probe {
            view: SliceView::Axial,
            world: DVec3::new(-12.34, 4.0, -30.0),
            voxel: [1, 2, 3],
            value: 53.0,
        };
        assert_eq!(probe_text(&p, true, "HU"), "L12.3 A4.0 I30.0 mm  [1 2 3]  53 HU");
        assert_eq!(probe_text(&p, false, ""), "x -12.3 y 4.0 z -30.0  [1 2 3]  53");
    }

    #[test]
    fn slab_corners_are_the_voxel_faces_of_the_texture_box() {
        let c = slab_corners_mm(DMat4::IDENTITY, [10, 10, 10], glam::Vec3::ZERO, glam::Vec3::ONE);
        assert_eq!(c[0], DVec3::splat(-0.5));
        assert_eq!(c[7], DVec3::splat(9.5));
    }
}
