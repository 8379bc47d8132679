//! The series chooser: shown under the volume's label while a DICOM folder holding several series is open, it
//! lists them (number, description, modality, slices) and loads the one picked.

use crate::viewer::model::actions::UiAction;
use crate::viewer::model::Model;
use crate::viewer::widgets::rects;

/// Names the items' rectangles are logged under (`VOLCAST_UI_RECTS`), for tests that click them.
const ITEM_NAMES: [&str; 8] = [
    "series-item-0",
    "series-item-1",
    "series-item-2",
    "series-item-3",
    "series-item-4",
    "series-item-5",
    "series-item-6",
    "series-item-7",
];

/// A combo box of the folder's series; nothing for a volume that is not one of several.
pub fn series_chooser(ui: &mut egui::Ui, model: &Model, actions: &mut Vec<UiAction>) {
    let series = &model.volume.series;
    if series.len() < 2 {
        return;
    }
    let short = |s: &crate::volume::SeriesInfo| {
        let number = s.number.map_or_else(|| "-".to_string(), |n| n.to_string());
        let description = if s.description.is_empty() {
            "(no description)"
        } else {
            &s.description
        };
        format!("{number}: {description}, {} slices", s.slices)
    };
    let loaded = series.iter().find(|s| s.loaded);
    // The label on its own line and the box as wide as the panel, its text cut short (whole on hover): a long
    // description must never widen the panel past the window.
    ui.label(format!("series ({} in the folder):", series.len()));
    let combo = egui::ComboBox::from_id_salt("dicom series")
        .selected_text(loaded.map(short).unwrap_or_default())
        .width(ui.available_width())
        .truncate()
        .show_ui(ui, |ui| {
            for (i, s) in series.iter().enumerate() {
                let item = ui.selectable_label(s.loaded, short(s)).on_hover_text(s.line());
                if let Some(name) = ITEM_NAMES.get(i) {
                    rects::log(name, item.rect);
                }
                let busy = model.messages.loading.is_some();
                if item.clicked() && !s.loaded && !busy {
                    actions.push(UiAction::LoadSeries(s.selector(series)));
                }
            }
        });
    let combo = match loaded {
        Some(s) => combo.response.on_hover_text(s.line()),
        None => combo.response,
    };
    rects::log("series-combo", combo.rect);
}
