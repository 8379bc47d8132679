//! The panel's transfer-function section: presets, the value window, the editor or the simple model's colormap,
//! and the sampling quality.

use crate::scene::quality::Quality;
use crate::transfer::Colormap;
use crate::viewer::model::Model;
use crate::viewer::widgets::{rects, tf_editor};
use egui::{Color32, Pos2};

fn color_of(rgba: [u8; 4]) -> Color32 {
    Color32::from_rgb(rgba[0], rgba[1], rgba[2])
}

/// The colormap as a strip, with the value window marked.
fn colormap_strip(ui: &mut egui::Ui, colormap: Colormap, window: [f32; 2]) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(ui.available_width(), 16.0), egui::Sense::hover());
    let lut = colormap.lut();
    let painter = ui.painter();
    let n = 64;
    for i in 0..n {
        let t0 = i as f32 / n as f32;
        let t1 = (i + 1) as f32 / n as f32;
        // The strip spans the value range; inside the window the colormap is stretched over it.
        let c = ((t0 - window[0]) / (window[1] - window[0]).max(1e-6)).clamp(0.0, 1.0);
        let inside = t0 >= window[0] && t0 <= window[1];
        let color = if inside {
            color_of(lut[(c * 255.0) as usize])
        } else {
            Color32::from_gray(30)
        };
        let r = egui::Rect::from_min_max(
            Pos2::new(egui::lerp(rect.left()..=rect.right(), t0), rect.top()),
            Pos2::new(egui::lerp(rect.left()..=rect.right(), t1), rect.bottom()),
        );
        painter.rect_filled(r, 0.0, color);
    }
}

/// Presets, window, editor, quality.
pub fn transfer_function_section(ui: &mut egui::Ui, model: &mut Model) {
    egui::CollapsingHeader::new("Transfer function")
        .default_open(true)
        .show(ui, |ui| {
            let look = &mut model.look;
            tf_editor::presets::panel(
                ui,
                &mut look.colour.transfer_function,
                &mut look.colour.window,
                model.volume.range,
                &model.volume.histogram,
                &mut model.tf_editor,
            );
            ui.checkbox(&mut model.tf_editor.locked, "keep when another volume loads");
            let look = &mut model.look;
            ui.label("Visible values");
            let range = model.volume.range;
            let min = egui::Slider::new(&mut look.colour.window[0], 0.0..=1.0).text("min");
            ui.add(super::in_data_units(min, range));
            let max = egui::Slider::new(&mut look.colour.window[1], 0.0..=1.0).text("max");
            ui.add(super::in_data_units(max, range));
            if look.colour.window[0] > look.colour.window[1] {
                look.colour.window.swap(0, 1);
            }
            if look.colour.transfer_function.is_none() {
                colormap_strip(ui, look.colour.colormap, look.colour.window);
                egui::ComboBox::from_label("Colormap")
                    .selected_text(look.colour.colormap.name())
                    .show_ui(ui, |ui| {
                        for c in Colormap::ALL {
                            ui.selectable_value(&mut look.colour.colormap, c, c.name());
                        }
                    });
                ui.add(egui::Slider::new(&mut look.colour.step_alpha, 0.0..=1.0).text("step alpha"));
                let multiplied = ui.checkbox(&mut look.colour.multiplied_alpha, "multiplied alpha");
                rects::log("multiplied-alpha", multiplied.rect);
            }
            let name = |q: Option<Quality>| q.map_or("custom step", Quality::name);
            egui::ComboBox::from_label("quality (Q)")
                .selected_text(name(model.sampling.quality))
                .show_ui(ui, |ui| {
                    for q in Quality::ALL.into_iter().map(Some).chain([None]) {
                        ui.selectable_value(&mut model.sampling.quality, q, name(q));
                    }
                });
            ui.add_enabled(
                model.sampling.quality.is_none(),
                egui::Slider::new(&mut model.look.sampling.step_length, 0.1..=4.0)
                    .logarithmic(true)
                    .text("step (voxels)"),
            );
        });
}
