//! The transfer-function section of the panel: a preset menu (the simple model, the presets, and "auto (by
//! modality)"), the editor with the axis in the volume's units, the colormap when there are no colour points,
//! and JSON save/load with a path field (errors beside the buttons).

use super::editor_with_unit;
use crate::transfer::auto::{auto_transfer_function, VolumeFacts};
use crate::transfer::function::{TransferFunction, PRESET_NAMES};
use crate::transfer::Colormap;
use std::path::Path;

/// The name the menu shows for the automatic choice.
pub const AUTO: &str = "auto (by modality)";

/// What the panel keeps between frames. The viewer makes it once and calls [`TfEditorState::set_volume`]
/// whenever a volume is installed.
#[derive(Clone, Debug, Default)]
pub struct TfEditorState {
    /// The opacity point being dragged.
    pub dragging: Option<usize>,
    /// The path field of save/load.
    pub path: String,
    /// The last save/load's outcome: `Ok(message)` or `Err(error)`, shown beside the buttons.
    pub message: Option<Result<String, String>>,
    /// The shown volume's facts and histogram (for "auto" and the axis unit); `None` before a volume.
    pub volume: Option<(VolumeFacts, Vec<u64>)>,
}

impl TfEditorState {
    /// Remembers what "auto" and the axis need of a newly installed volume (its value histogram over the
    /// normalised range, any bin count).
    pub fn set_volume(&mut self, volume: &crate::volume::Volume, histogram: &[u64]) {
        self.volume = Some((VolumeFacts::of(volume), histogram.to_vec()));
    }

    /// The values' unit ("HU" for CT).
    pub fn unit(&self) -> Option<&'static str> {
        self.volume.as_ref().and_then(|(f, _)| f.kind().unit())
    }

    /// The automatic transfer function for the shown volume.
    pub fn auto(&self) -> Option<TransferFunction> {
        self.volume.as_ref().map(|(f, h)| auto_transfer_function(f, h))
    }
}

/// Writes `tf` as JSON to `path`; the message names the file.
pub fn save_tf(tf: &TransferFunction, path: &str) -> Result<String, String> {
    let path = path.trim();
    if path.is_empty() {
        return Err("enter a file name to save to".into());
    }
    std::fs::write(path, tf.to_json()).map_err(|e| format!("cannot write {path}: {e}"))?;
    Ok(format!("saved {path}"))
}

/// Reads a transfer function from `path` (validated; the error names the file and the problem).
pub fn load_tf(path: &str) -> Result<TransferFunction, String> {
    let path = path.trim();
    if path.is_empty() {
        return Err("enter a file name to load".into());
    }
    TransferFunction::load(Path::new(path)).map_err(|e| e.to_string())
}

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
    let mut changed = false;
    let current = transfer_function
        .as_ref()
        .map(|t| t.name.clone())
        .unwrap_or_else(|| "simple (Qt)".into());
    egui::ComboBox::from_label("preset")
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
            for name in PRESET_NAMES {
                if ui.selectable_label(current == *name, *name).clicked() {
                    *transfer_function = TransferFunction::preset(name).ok();
                    *window = [0.0, 1.0];
                    changed = true;
                }
            }
        });
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
    ui.horizontal(|ui| {
        let field = ui.add(
            egui::TextEdit::singleline(&mut state.path)
                .hint_text("transfer function .json")
                .desired_width(150.0),
        );
        crate::viewer::ui::rects::log("tf-path", field.rect);
        let save = ui.button("Save");
        crate::viewer::ui::rects::log("tf-save", save.rect);
        if save.clicked() {
            state.message = Some(save_tf(tf, &state.path));
        }
        let load = ui.button("Load");
        crate::viewer::ui::rects::log("tf-load", load.rect);
        if load.clicked() {
            state.message = Some(load_tf(&state.path).map(|loaded| {
                *tf = loaded;
                changed = true;
                format!("loaded {}", state.path.trim())
            }));
        }
    });
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn save_and_load_name_the_file_and_round_trip() {
        let dir = std::env::temp_dir().join(format!("volcast-tf-panel-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let tf = TransferFunction::preset("ct-lung").unwrap();
        let path = dir.join("lung.json").display().to_string();
        assert!(save_tf(&tf, &path).unwrap().contains("lung.json"));
        assert_eq!(load_tf(&format!("  {path} ")).unwrap(), tf);
        assert!(save_tf(&tf, " ").unwrap_err().contains("file name"));
        let missing = dir.join("nope/x.json").display().to_string();
        assert!(save_tf(&tf, &missing).unwrap_err().contains("nope/x.json"));
        assert!(load_tf(&missing).unwrap_err().contains("nope/x.json"));
        std::fs::write(dir.join("bad.json"), "{\"opacity\": []}").unwrap();
        let err = load_tf(&dir.join("bad.json").display().to_string()).unwrap_err();
        assert!(err.contains("at least one opacity point"), "{err}");
    }

    #[test]
    fn auto_and_unit_follow_the_volume() {
        let mut state = TfEditorState::default();
        assert!(state.auto().is_none() && state.unit().is_none());
        let data: Vec<u16> = (0..8u32).map(|i| (32768 - 1024 + i * 500) as u16).collect();
        let v = crate::volume::Volume::new(
            "ct",
            [2, 2, 2],
            [1.0; 3],
            crate::volume::VoxelType::I16,
            crate::volume::VoxelData::U16(data),
        )
        .unwrap();
        state.set_volume(&v, &[1, 1, 1, 1]);
        assert_eq!(state.unit(), Some("HU"));
        assert!(state.auto().unwrap().name.contains("ct-bone"));
    }
}
