//! The Recent menu beside the path field: the files opened last, newest first; one that is no longer there is
//! shown disabled. Picking one loads it as a typed path would.

use crate::viewer::model::actions::UiAction;
use crate::viewer::model::Model;
use crate::viewer::widgets::rects;

/// Names the entries' rectangles are logged under (`VOLCAST_UI_RECTS`), for tests that click them.
const ITEM_NAMES: [&str; crate::viewer::model::recent::RECENT_CAP] = [
    "recent-item-0",
    "recent-item-1",
    "recent-item-2",
    "recent-item-3",
    "recent-item-4",
    "recent-item-5",
    "recent-item-6",
    "recent-item-7",
    "recent-item-8",
    "recent-item-9",
];

/// A "Recent" drop-down; disabled while the list is empty or a volume loads.
pub fn recent_menu(ui: &mut egui::Ui, model: &mut Model, actions: &mut Vec<UiAction>) {
    let entries = model.recent.entries();
    let idle = model.messages.loading.is_none();
    let mut picked = None;
    let combo = ui.add_enabled_ui(!entries.is_empty() && idle, |ui| {
        egui::ComboBox::from_id_salt("recent files")
            .selected_text("Recent")
            .width(ui.available_width().min(250.0))
            .show_ui(ui, |ui| {
                for (i, e) in entries.iter().enumerate() {
                    let name = e
                        .path
                        .file_name()
                        .map_or_else(|| e.path.display().to_string(), |n| n.to_string_lossy().into_owned());
                    let text = if e.exists { name } else { format!("{name} (missing)") };
                    let item = ui
                        .add_enabled(e.exists, egui::Button::selectable(false, text))
                        .on_hover_text(e.path.display().to_string());
                    if let Some(n) = ITEM_NAMES.get(i) {
                        rects::log(n, item.rect);
                    }
                    if item.clicked() {
                        picked = Some(e.path.clone());
                    }
                }
            })
    });
    rects::log("recent-combo", combo.inner.response.rect);
    if let Some(path) = picked {
        actions.push(model.files.load_action(path));
    }
}
