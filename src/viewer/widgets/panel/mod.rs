//! The settings panel: the volume's label and the messages, the time controls, then one collapsing section per
//! concern (a module each). Sections edit the [`Model`] and push [`UiAction`]s for what needs the app.

pub mod lighting;
pub mod rendering;
pub mod slicing;
pub mod time;
pub mod transfer;
pub mod view;
pub mod volume;

use crate::viewer::model::actions::UiAction;
use crate::viewer::model::Model;
use egui::Color32;
use std::path::PathBuf;

/// The colour of errors in the panel.
pub const ERROR_COLOR: Color32 = Color32::from_rgb(255, 110, 110);

/// The settings panel. Returns what the viewer must do beyond editing `model`.
pub fn settings_panel(ui: &mut egui::Ui, model: &mut Model) -> Vec<UiAction> {
    let mut actions = Vec::new();
    ui.heading("volcast");
    ui.label(&model.volume.label);
    messages(ui, model);
    time::time_controls(ui, &mut model.time);
    ui.separator();

    transfer::transfer_function_section(ui, model);
    rendering::rendering_section(ui, model);
    lighting::lighting_section(ui, &mut model.look);
    slicing::slicing_section(ui, model);
    view::view_section(ui, model, &mut actions);
    volume::volume_section(ui, model, &mut actions);
    session_section(ui, model, &mut actions);
    performance_section(ui, model);
    actions
}

/// A load's progress, the last error and the last status line.
fn messages(ui: &mut egui::Ui, model: &Model) {
    let messages = &model.messages;
    if let Some((label, progress)) = &messages.loading {
        ui.horizontal(|ui| {
            ui.spinner();
            ui.label(format!("loading {label}"));
        });
        ui.add(egui::ProgressBar::new(*progress).show_percentage());
    }
    if let Some(err) = &messages.error {
        ui.colored_label(ERROR_COLOR, err);
    }
    if let Some(status) = &messages.status {
        ui.label(status);
    }
}

/// Frame and GPU times.
fn performance_section(ui: &mut egui::Ui, model: &Model) {
    egui::CollapsingHeader::new("Performance")
        .default_open(true)
        .show(ui, |ui| {
            ui.label(format!("frame {:.1} ms", model.stats.frame_ms));
            if let Some(t) = model.stats.gpu {
                match (t.entry_ms, t.exit_ms) {
                    (Some(a), Some(b)) => {
                        ui.label(format!("GPU entry {a:.2} + exit {b:.2} + march {:.2} ms", t.march_ms));
                    }
                    _ => {
                        ui.label(format!("GPU march {:.2} ms", t.march_ms));
                    }
                }
            }
        });
}

/// Save and open sessions (the whole viewer state as JSON).
fn session_section(ui: &mut egui::Ui, model: &mut Model, actions: &mut Vec<UiAction>) {
    egui::CollapsingHeader::new("Session")
        .default_open(true)
        .show(ui, |ui| {
            let path = &mut model.files.session_path;
            let field = egui::TextEdit::singleline(path).desired_width(ui.available_width().min(250.0));
            ui.add(field);
            ui.horizontal(|ui| {
                let named = !path.trim().is_empty();
                if ui
                    .add_enabled(named, egui::Button::new("Save session (Ctrl+S)"))
                    .clicked()
                {
                    actions.push(UiAction::SaveSession);
                }
                if ui.add_enabled(named, egui::Button::new("Open session")).clicked() {
                    actions.push(UiAction::OpenSession(PathBuf::from(path.trim())));
                }
            });
        });
}

#[cfg(test)]
mod tests;
