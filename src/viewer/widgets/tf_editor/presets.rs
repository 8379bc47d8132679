//! The transfer-function section's body: a preset menu (the simple model, the presets, and "auto (by
//! modality)"), the editor with the axis in the volume's units, the colormap when there are no colour points,
//! and JSON save/load with a path field (errors beside the buttons).

use super::editor_with_unit;
use crate::transfer::function::TransferFunction;
use crate::transfer::Colormap;
use crate::viewer::model::tf::{load_tf, save_tf, TfEditorState};
use crate::viewer::widgets::rects;

/// Names the preset items' rectangles and labels are logged under (`VOLCAST_UI_RECTS`), for tests.
const PRESET_ITEMS: [&str; 5] = [
    "tf-preset-0",
    "tf-preset-1",
    "tf-preset-2",
    "tf-preset-3",
    "tf-preset-4",
];

/// The name the menu shows for the automatic choice.
pub const AUTO: &str = "auto (by modality)";

/// The section: returns true when the transfer function or the window changed. `transfer_function: None` is
/// the simple model (then only the menu is drawn; its colormap stays with the caller).
pub fn panel(
    ui: &mut egui::Ui,
    transfer_function: &mut Option<TransferFunction>,
    window: &mut [f32; 2],
    range: [f64; 2],
    histogram: &[u64],
    state: &mut TfEditorState,
) -> bool {
    let mut changed = preset_menu(ui, transfer_function, window, state);
    let Some(tf) = transfer_function else {
        return changed;
    };
    ui.label("Opacity (click: add, drag: move, right-click: delete); colours on the strip below");
    let unit = state.unit();
    changed |= editor_with_unit(ui, tf, *window, range, histogram, &mut state.dragging, unit);
    if tf.colors.is_empty() {
        egui::ComboBox::from_label("Colormap")
            .selected_text(tf.colormap.name())
            .show_ui(ui, |ui| {
                for c in Colormap::ALL {
                    changed |= ui.selectable_value(&mut tf.colormap, c, c.name()).changed();
                }
            });
    }
    changed |= save_and_load(ui, tf, state);
    match &state.message {
        Some(Ok(m)) => {
            ui.label(m);
        }
        Some(Err(e)) => {
            ui.colored_label(egui::Color32::from_rgb(255, 110, 90), e);
        }
        None => {}
    }
    changed
}

/// The preset menu; true when it replaced the transfer function (and set the window to match).
fn preset_menu(
    ui: &mut egui::Ui,
    transfer_function: &mut Option<TransferFunction>,
    window: &mut [f32; 2],
    state: &TfEditorState,
) -> bool {
    let mut changed = false;
    let current = transfer_function
        .as_ref()
        .map(|t| t.name.clone())
        .unwrap_or_else(|| "simple (Qt)".into());
    let menu = egui::ComboBox::from_label("preset")
        .selected_text(&current)
        .show_ui(ui, |ui| {
            if ui
                .selectable_label(transfer_function.is_none(), "simple (Qt)")
                .clicked()
            {
                *transfer_function = None;
                *window = crate::scene::settings::DEFAULT_WINDOW;
                changed = true;
            }
            let auto = state.auto();
            if ui
                .add_enabled(
                    auto.is_some(),
                    egui::Button::selectable(current.starts_with("auto"), AUTO),
                )
                .clicked()
            {
                *transfer_function = auto;
                *window = [0.0, 1.0];
                changed = true;
            }
            // The presets of the volume's kind: no Hounsfield-unit window on an MRI.
            for (i, name) in state.presets().into_iter().enumerate() {
                let item = ui.selectable_label(current == name, name);
                rects::log_labelled(PRESET_ITEMS[i.min(PRESET_ITEMS.len() - 1)], item.rect, Some(name));
                if item.clicked() {
                    *transfer_function = TransferFunction::preset(name).ok();
                    *window = [0.0, 1.0];
                    changed = true;
                }
            }
        });
    rects::log("tf-preset", menu.response.rect);
    changed
}

/// The path field with Save and Load; true when a load replaced `tf`.
fn save_and_load(ui: &mut egui::Ui, tf: &mut TransferFunction, state: &mut TfEditorState) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        let field = ui.add(
            egui::TextEdit::singleline(&mut state.path)
                .hint_text("transfer function .json")
                .desired_width(150.0),
        );
        rects::log("tf-path", field.rect);
        let save = ui.button("Save");
        rects::log("tf-save", save.rect);
        if save.clicked() {
            state.message = Some(save_tf(tf, &state.path));
        }
        let load = ui.button("Load");
        rects::log("tf-load", load.rect);
        if load.clicked() {
            state.message = Some(load_tf(&state.path).map(|loaded| {
                *tf = loaded;
                changed = true;
                format!("loaded {}", state.path.trim())
            }));
        }
    });
    changed
}
