//! The panel's View section: view presets, what is drawn over the volume, vsync, ray setup, reset, screenshot and
//! recording.

use crate::scene::camera::ViewPreset;
use crate::scene::settings::{PositionFormat, RaySetup};
use crate::viewer::model::actions::UiAction;
use crate::viewer::model::Model;
use crate::viewer::widgets::panel::ERROR_COLOR;

/// View presets, boxes, ray setup, reset and screenshot.
pub fn view_section(ui: &mut egui::Ui, model: &mut Model, actions: &mut Vec<UiAction>) {
    egui::CollapsingHeader::new("View").default_open(true).show(ui, |ui| {
        ui.horizontal(|ui| {
            ui.label("from");
            for preset in ViewPreset::ALL {
                let name = preset.name();
                let letter = name[..1].to_ascii_uppercase();
                if ui.button(letter).on_hover_text(name).clicked() {
                    model.look_from(preset);
                }
            }
        });
        if model.geometry.anatomical {
            let voxel_axes = model.look.voxel_axes;
            ui.checkbox(&mut model.look.voxel_axes, "voxel axes")
                .on_hover_text("ignore the file's orientation: show the voxel grid's own axes");
            if voxel_axes != model.look.voxel_axes {
                model.reset_view();
            }
        }
        ui.checkbox(&mut model.slices.shown, "slice views, four-up (L)");
        ui.checkbox(&mut model.display.show_boxes, "draw bounding box");
        ui.checkbox(&mut model.display.show_colorbar, "colour bar (data units)");
        ui.checkbox(&mut model.camera.auto_rotate, "auto-rotate (Space)");
        if ui.checkbox(&mut model.display.vsync, "vsync").changed() {
            actions.push(UiAction::VsyncChanged);
        }
        ui.horizontal(|ui| {
            ui.label("ray setup");
            ui.selectable_value(&mut model.look.pipeline.ray_setup, RaySetup::Faces, "faces");
            ui.selectable_value(&mut model.look.pipeline.ray_setup, RaySetup::Analytic, "analytic");
        });
        if model.look.pipeline.ray_setup == RaySetup::Faces {
            ui.horizontal(|ui| {
                ui.label("positions");
                ui.selectable_value(
                    &mut model.look.pipeline.position_format,
                    PositionFormat::Rgba32f,
                    "rgba32f",
                );
                ui.selectable_value(
                    &mut model.look.pipeline.position_format,
                    PositionFormat::Rgba16f,
                    "rgba16f",
                );
            });
        }
        ui.horizontal(|ui| {
            if ui.button("Reset view (R)").clicked() {
                model.reset_view();
            }
            if ui.button("Screenshot (F12)").clicked() {
                actions.push(UiAction::Screenshot);
            }
        });
        let record = if model.messages.recording.is_some() {
            "Stop recording (F9)"
        } else {
            "Record GIF (F9)"
        };
        if ui.button(record).clicked() {
            actions.push(UiAction::ToggleRecording);
        }
        if let Some(path) = &model.messages.recording {
            ui.colored_label(ERROR_COLOR, format!("recording {path}"));
        }
        super::messages_about(ui, &model.messages, crate::viewer::model::Topic::Capture);
        ui.label("Hide this panel: Tab");
    });
}
