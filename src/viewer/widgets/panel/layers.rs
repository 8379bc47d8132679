//! The panel's Layers section (rule 13's layers): each layer shown with the volume — its visibility, opacity, an
//! overlay's threshold, and a button to remove it — and a path to add a file as an overlay or as labels.

use crate::scene::layers::LayerKind;
use crate::viewer::model::actions::UiAction;
use crate::viewer::model::layers::LayerEntry;
use crate::viewer::model::{Model, Topic};
use crate::viewer::widgets::panel::messages_about;
use crate::viewer::widgets::rects;
use std::path::PathBuf;

/// The rects' names of the first layers' controls (`VOLCAST_UI_RECTS`): visibility, opacity and removal.
const VISIBLE: [&str; 4] = [
    "layer-visible-0",
    "layer-visible-1",
    "layer-visible-2",
    "layer-visible-3",
];
const OPACITY: [&str; 4] = [
    "layer-opacity-0",
    "layer-opacity-1",
    "layer-opacity-2",
    "layer-opacity-3",
];
const REMOVE: [&str; 4] = ["layer-remove-0", "layer-remove-1", "layer-remove-2", "layer-remove-3"];

/// The layer list, then the field and buttons that add one.
pub fn layers_section(ui: &mut egui::Ui, model: &mut Model, actions: &mut Vec<UiAction>) {
    egui::CollapsingHeader::new("Layers").default_open(true).show(ui, |ui| {
        if let Some(why) = model.layers.hidden_by(&model.look) {
            ui.weak(why);
        }
        let mut changed = false;
        for (i, entry) in model.layers.entries.iter_mut().enumerate() {
            changed |= layer_row(ui, i, entry, actions);
        }
        if changed {
            model.layers.generation += 1;
        }
        add_row(ui, model, actions);
        messages_about(ui, &model.messages, Topic::Layers);
    });
    settle_after_change(ui.ctx(), model.layers.entries.len());
}

/// Two more frames after the list changed length: the panel's scroll area clamps its offset to the new height a
/// frame later, and without them it moved only at the next input (under the pointer of whoever clicks next).
fn settle_after_change(ctx: &egui::Context, count: usize) {
    let id = egui::Id::new("layer list length");
    let (seen, frames) = ctx.data(|d| d.get_temp::<(usize, u8)>(id)).unwrap_or((count, 0));
    let frames = if seen == count { frames.saturating_sub(1) } else { 2 };
    if frames > 0 {
        ctx.request_repaint();
    }
    ctx.data_mut(|d| d.insert_temp(id, (count, frames)));
}

/// Layer `i`'s controls; whether its look changed.
fn layer_row(ui: &mut egui::Ui, i: usize, entry: &mut LayerEntry, actions: &mut Vec<UiAction>) -> bool {
    let style = &mut entry.style;
    let file = crate::scene::layer_set::short_name(&entry.name);
    let kind = match style.kind {
        LayerKind::Overlay => "overlay",
        LayerKind::Labels => "labels",
    };
    let mut changed = false;
    ui.horizontal(|ui| {
        let visible = ui.checkbox(&mut style.visible, format!("{file} ({kind})"));
        changed |= visible.changed();
        let visible = visible.on_hover_text(&entry.name);
        let remove = ui.small_button("remove");
        if let Some(&name) = VISIBLE.get(i) {
            rects::log(name, visible.rect);
            rects::log(REMOVE[i], remove.rect);
        }
        if remove.clicked() {
            actions.push(UiAction::RemoveLayer(i));
        }
    });
    let opacity = ui.add(egui::Slider::new(&mut style.opacity, 0.0..=1.0).text("opacity"));
    if let Some(&name) = OPACITY.get(i) {
        rects::log(name, opacity.rect);
    }
    changed |= opacity.changed();
    if style.kind == LayerKind::Overlay {
        let top = entry.range[0].abs().max(entry.range[1].abs()).max(f64::MIN_POSITIVE);
        let mut on = style.threshold.is_some();
        ui.horizontal(|ui| {
            changed |= ui
                .checkbox(&mut on, if style.signed { "|value| ≥" } else { "value ≥" })
                .changed();
            let mut t = style
                .threshold
                .unwrap_or(if style.signed { top / 2.0 } else { entry.range[0] });
            let lo = if style.signed { 0.0 } else { entry.range[0] };
            let slider = egui::Slider::new(&mut t, lo..=top.max(lo)).max_decimals(2);
            changed |= ui.add_enabled(on, slider).changed();
            style.threshold = on.then_some(t);
        });
    }
    changed
}

/// A path, and whether to add it as an overlay or as labels.
fn add_row(ui: &mut egui::Ui, model: &mut Model, actions: &mut Vec<UiAction>) {
    let field = egui::TextEdit::singleline(&mut model.layers.path)
        .hint_text("a file to add")
        .desired_width(ui.available_width().min(250.0));
    let field = ui.add(field);
    rects::log("layer-path", field.rect);
    let path = model.layers.path.trim();
    ui.horizontal(|ui| {
        for (label, kind, name) in [
            ("Add overlay", LayerKind::Overlay, "layer-add-overlay"),
            ("Add labels", LayerKind::Labels, "layer-add-labels"),
        ] {
            let button = ui.add_enabled(!path.is_empty(), egui::Button::new(label));
            rects::log(name, button.rect);
            if button.clicked() {
                actions.push(UiAction::AddLayer(PathBuf::from(path), kind));
            }
        }
    });
}
