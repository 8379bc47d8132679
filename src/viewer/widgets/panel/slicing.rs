//! The panel's Slicing section: the axis slabs, the clipping plane (which is dragged in the 3D view) and the ruler's
//! measurements.

use crate::scene::clip::ClipPlane;
use crate::viewer::model::actions::UiAction;
use crate::viewer::model::measurements::Format;
use crate::viewer::model::{Model, Topic};
use crate::viewer::widgets::{clip_plane, rects};
use crate::volume::geometry::index_axis_names;

/// The axis slabs, the clipping plane and the measurements.
pub fn slicing_section(ui: &mut egui::Ui, model: &mut Model, actions: &mut Vec<UiAction>) {
    egui::CollapsingHeader::new("Slicing")
        .default_open(true)
        .show(ui, |ui| {
            let names = if model.anatomical() {
                index_axis_names(&model.geometry)
            } else {
                ["x", "y", "z"].map(String::from)
            };
            for (axis, name) in names.iter().enumerate() {
                let (pos, width) = &mut model.slabs[axis];
                ui.add(egui::Slider::new(pos, 0.0..=1.0).text(format!("{name} position")));
                ui.add(egui::Slider::new(width, 0.0..=1.0).text(format!("{name} width")));
            }
            if ui.button("Reset slices").clicked() {
                model.slabs = [(0.5, 1.0); 3];
            }
            ui.separator();
            clip_plane_controls(ui, model);
            ui.separator();
            measurements(ui, model, actions);
        });
}

/// The ruler's measurements on this volume (the last few listed), saved as CSV or JSON with their ends in world
/// millimetres, or cleared.
fn measurements(ui: &mut egui::Ui, model: &mut Model, actions: &mut Vec<UiAction>) {
    let measured = &model.slices.ruler.measured;
    ui.label(format!("measurements: {} (ruler: M in a slice view)", measured.len()));
    let first = measured.len().saturating_sub(4);
    for (i, m) in measured.iter().enumerate().skip(first) {
        ui.weak(format!("{}. {:.1} mm ({})", i + 1, m.length_mm, m.view));
    }
    ui.add_enabled_ui(!measured.is_empty(), |ui| {
        ui.horizontal(|ui| {
            let formats = [
                (Format::Csv, "Save CSV", "measurements-csv"),
                (Format::Json, "Save JSON", "measurements-json"),
            ];
            for (format, text, name) in formats {
                let button = ui.button(text);
                rects::log(name, button.rect);
                if button.clicked() {
                    actions.push(UiAction::SaveMeasurements(format));
                }
            }
            if ui.button("Clear").clicked() {
                model.slices.ruler.measured.clear();
            }
        });
    });
    super::messages_about(ui, &model.messages, Topic::Measurements);
}

/// The arbitrary clipping plane: on/off, offset, flip, face the camera (dragged in the 3D view).
fn clip_plane_controls(ui: &mut egui::Ui, model: &mut Model) {
    let mut on = model.look.cut.clip_plane.is_some();
    if ui.checkbox(&mut on, "clip plane (C)").changed() {
        model.look.cut.clip_plane = on.then(|| clip_plane::facing_away(model));
    }
    let Some(plane) = model.look.cut.clip_plane else {
        return;
    };
    let reach = clip_plane::half_diagonal_mm(model);
    let mut offset = plane.offset();
    if ui
        .add(egui::Slider::new(&mut offset, -reach..=reach).text("offset (mm)"))
        .changed()
    {
        model.look.cut.clip_plane = plane.with_offset(offset).ok().or(Some(plane));
    }
    ui.horizontal(|ui| {
        if ui.button("Flip (F)").clicked() {
            model.look.cut.clip_plane = Some(plane.flipped());
        }
        if ui.button("Face the camera").clicked() {
            let forward = model.camera.orbit.camera().forward();
            model.look.cut.clip_plane = ClipPlane::through(forward, plane.point()).ok().or(Some(plane));
        }
    });
    let n = plane.normal();
    let frame = if model.anatomical() { "RAS" } else { "xyz" };
    ui.label(format!("normal {frame} {:.2} {:.2} {:.2}", n.x, n.y, n.z));
    ui.weak("Drag its handle to slide it, its ring to turn it.");
}
