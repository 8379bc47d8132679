//! The settings panel: the volume's label, the time controls, then one collapsing section per concern (a module
//! each); a message shows in the section of the action that caused it. Sections edit the [`Model`] and push [`UiAction`]s for what needs the app.

pub mod chooser;
pub mod export;
pub mod layers;
pub mod lighting;
pub mod recent;
pub mod rendering;
pub mod series;
pub mod slicing;
pub mod time;
pub mod transfer;
pub mod view;
pub mod volume;

use crate::viewer::model::actions::UiAction;
use crate::viewer::model::{Messages, Model, Topic};
use crate::viewer::widgets::rects;
use egui::Color32;
use std::path::PathBuf;

/// The colour of errors in the panel.
pub const ERROR_COLOR: Color32 = Color32::from_rgb(255, 110, 110);

/// The settings panel. Returns what the viewer must do beyond editing `model`.
pub fn settings_panel(ui: &mut egui::Ui, model: &mut Model) -> Vec<UiAction> {
    let mut actions = Vec::new();
    // A slider's label sits right of it and never wraps: egui's default 100-point slider left too little of the
    // panel's width for labels such as "i (R->L) position", and the widest row widened every row, so that
    // wrapped text ran past the panel's edge too (tests.rs lays the panel out and finds no text cut).
    ui.spacing_mut().slider_width = 80.0;
    ui.heading("volcast");
    volume_label(ui, &model.volume.label);
    series::series_chooser(ui, model, &mut actions);
    time::time_controls(ui, &mut model.time);
    ui.separator();

    transfer::transfer_function_section(ui, model);
    rendering::rendering_section(ui, model);
    lighting::lighting_section(ui, &mut model.look);
    slicing::slicing_section(ui, model, &mut actions);
    view::view_section(ui, model, &mut actions);
    export::export_section(ui, model, &mut actions);
    volume::volume_section(ui, model, &mut actions);
    layers::layers_section(ui, model, &mut actions);
    session_section(ui, model, &mut actions);
    performance_section(ui, model);
    actions
}

/// `slider` over a place in the data's range (0–1, as the renderer takes it) showing and taking the value in the
/// data's units (HU for a CT), or a percentage typed as one (`40%`).
pub fn in_data_units(slider: egui::Slider<'_>, range: [f64; 2]) -> egui::Slider<'_> {
    let span = range[1] - range[0];
    let decimals = if span >= 100.0 {
        0
    } else if span >= 1.0 {
        2
    } else {
        4
    };
    slider
        .custom_formatter(move |f, _| format!("{:.*}", decimals, range[0] + f * span))
        .custom_parser(move |text| {
            crate::scene::values::DataValue::parse(text)
                .ok()
                .map(|v| f64::from(v.fraction(range)))
        })
}

/// The last error and status line if they are about `topic`: shown beside the controls of the action that
/// caused them, so that nothing above those controls changes height (the panel used to show them at its top, and
/// every message moved the whole panel under the pointer).
pub fn messages_about(ui: &mut egui::Ui, messages: &Messages, topic: Topic) -> Option<egui::Response> {
    if messages.about != topic {
        return None;
    }
    let error = messages.error.as_ref().map(|err| ui.colored_label(ERROR_COLOR, err));
    if let Some(status) = &messages.status {
        ui.label(status);
    }
    error
}

/// The volume's description at the top of the panel, in a space of fixed height (three lines; a longer one is
/// cut, whole on hover), so that loading another volume does not move what is below.
fn volume_label(ui: &mut egui::Ui, label: &str) {
    let rows = 3;
    let height = rows as f32 * ui.text_style_height(&egui::TextStyle::Body) + (rows - 1) as f32 * 2.0;
    let size = egui::vec2(ui.available_width(), height);
    ui.allocate_ui_with_layout(size, egui::Layout::top_down(egui::Align::Min), |ui| {
        ui.set_min_size(size);
        let mut text = egui::text::LayoutJob::single_section(label.to_string(), Default::default());
        text.wrap = egui::text::TextWrapping {
            max_rows: rows,
            ..Default::default()
        };
        ui.add(egui::Label::new(text)).on_hover_text(label);
    });
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
            if let Some(streaming) = &model.streaming {
                ui.label(format!("streamed through a pool of {} bricks", streaming.capacity));
                if let Some(p) = &streaming.progress {
                    let state = if p.done { "refined" } else { "refining" };
                    ui.label(format!(
                        "{state}: {} of {} wanted bricks resident",
                        p.resident, p.wanted
                    ))
                    .on_hover_text(format!("level-0 bricks showing each level: {}", p.levels_shown()));
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
            rects::log("session-path", ui.add(field).rect);
            ui.horizontal(|ui| {
                let named = !path.trim().is_empty();
                if ui
                    .add_enabled(named, egui::Button::new("Save session (Ctrl+S)"))
                    .clicked()
                {
                    actions.push(UiAction::SaveSession);
                }
                let open = ui.add_enabled(named, egui::Button::new("Open session"));
                rects::log("session-open", open.rect);
                if open.clicked() {
                    actions.push(UiAction::OpenSession(PathBuf::from(path.trim())));
                }
            });
            messages_about(ui, &model.messages, Topic::Session);
        });
}

#[cfg(test)]
mod tests;
