//! "Export figure": the 3D view rendered offscreen from the session (camera, transfer function, clipping,
//! lighting) at any size up to the device's limit, with the colour bar if asked, into a PNG named by the date
//! and time. F12 saves the view at its size on screen (a quarter of the window in the four-up layout); this
//! is the high-resolution figure.

use super::ERROR_COLOR;
use crate::viewer::model::actions::UiAction;
use crate::viewer::model::Model;
use crate::viewer::widgets::rects;

pub fn export_section(ui: &mut egui::Ui, model: &mut Model, actions: &mut Vec<UiAction>) {
    egui::CollapsingHeader::new("Export figure")
        .default_open(true)
        .show(ui, |ui| {
            let export = &mut model.export;
            ui.horizontal(|ui| {
                let width = ui.add(egui::TextEdit::singleline(&mut export.width).desired_width(52.0));
                rects::log("export-width", width.rect);
                ui.label("×");
                let height = ui.add(egui::TextEdit::singleline(&mut export.height).desired_width(52.0));
                rects::log("export-height", height.rect);
                ui.label("pixels");
            });
            let colorbar = ui
                .checkbox(&mut export.colorbar, "colour bar")
                .on_hover_text("in data units, drawn inside the width");
            rects::log("export-colorbar", colorbar.rect);
            if colorbar.changed() {
                eprintln!(
                    "export figure: colour bar {}",
                    if export.colorbar { "on" } else { "off" }
                );
            }
            let scale_bar = ui
                .checkbox(&mut export.scale_bar, "scale bar")
                .on_hover_text("a round length in mm (µm under 1 mm) at the depth of the point the view orbits");
            rects::log("export-scale-bar", scale_bar.rect);
            if scale_bar.changed() {
                let on = if export.scale_bar { "on" } else { "off" };
                eprintln!("export figure: scale bar {on}");
            }
            let button = ui.button("Export");
            rects::log("export-button", button.rect);
            if button.clicked() {
                actions.push(UiAction::ExportFigure);
            }
            match &export.last {
                Some(Ok(path)) => {
                    ui.label(format!("saved {path}"));
                }
                Some(Err(e)) => {
                    ui.colored_label(ERROR_COLOR, e);
                }
                None => {}
            }
        });
}
