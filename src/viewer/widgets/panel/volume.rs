//! The panel's Volume section: the built-in volumes, a path (typed, picked or dropped) and the raw format's
//! fields (shown only while the path is one read as raw).

use crate::viewer::model::actions::UiAction;
use crate::viewer::model::Model;
use crate::viewer::model::Topic;
use crate::viewer::widgets::panel::{chooser, messages_about};
use crate::viewer::widgets::rects;
use crate::volume::{VoxelType, BUILTIN_NAMES};

/// The raw format's dims, type and scale (the path typed is a raw file).
fn raw_fields(ui: &mut egui::Ui, model: &mut Model) {
    egui::Grid::new("raw").num_columns(2).show(ui, |ui| {
        ui.label("dims");
        ui.horizontal(|ui| {
            for d in &mut model.files.raw_dims {
                ui.add(egui::DragValue::new(d).range(1..=crate::volume::MAX_DIM));
            }
        });
        ui.end_row();
        ui.label("type");
        egui::ComboBox::from_id_salt("raw type")
            .selected_text(model.files.raw_type.name())
            .show_ui(ui, |ui| {
                for t in VoxelType::ALL {
                    ui.selectable_value(&mut model.files.raw_type, t, t.name());
                }
            });
        ui.end_row();
        ui.label("scale");
        ui.horizontal(|ui| {
            for s in &mut model.files.raw_spacing {
                ui.add(egui::DragValue::new(s).speed(0.01).range(0.001..=1000.0));
            }
        });
        ui.end_row();
    });
}

/// Built-ins, a path or dialog, and the raw fields.
pub fn volume_section(ui: &mut egui::Ui, model: &mut Model, actions: &mut Vec<UiAction>) {
    egui::CollapsingHeader::new("Volume").default_open(true).show(ui, |ui| {
        ui.horizontal_wrapped(|ui| {
            for name in BUILTIN_NAMES {
                if ui.button(*name).clicked() {
                    actions.push(UiAction::LoadBuiltin(name.to_string()));
                }
            }
        });
        ui.horizontal(|ui| {
            let open = ui.button("Open…");
            rects::log("open", open.rect);
            if open.clicked() {
                actions.push(UiAction::OpenDialog);
            }
            // Open…'s own message on its row, in place of the hint: nothing below moves.
            match &model.files.open_note {
                Some(note) => ui.label(note),
                None => ui.label("or a path:"),
            }
        });
        super::recent::recent_menu(ui, model, actions);
        // A fixed width: a long path scrolls inside the field instead of widening the panel for good.
        let path_field =
            egui::TextEdit::singleline(&mut model.files.load_path).desired_width(ui.available_width().min(250.0));
        let field = ui.add(path_field);
        rects::log("load-path", field.rect);
        if field.changed() {
            model.files.path_edited();
        }
        // Enter in the field loads, as the button does (a single-line field gives up the focus on Enter).
        let entered = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        if model.files.path_is_raw {
            raw_fields(ui, model);
        }
        let can_load = !model.files.load_path.trim().is_empty() && model.messages.loading.is_none();
        if ui.add_enabled(can_load, egui::Button::new("Load volume")).clicked() || (entered && can_load) {
            actions.push(model.files.load_field_action());
        }
        // A load's progress, error and result under the button (and the field) that started it.
        if let Some((label, progress)) = &model.messages.loading {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label(format!("loading {label}"));
            });
            ui.add(egui::ProgressBar::new(*progress).show_percentage());
        }
        if let Some(error) = messages_about(ui, &model.messages, Topic::Volume) {
            rects::log_labelled("load-error", error.rect, model.messages.error.as_deref());
        }
        ui.weak("or drop a file on the window");
    });
    chooser::chooser_window(ui.ctx(), &mut model.files, actions);
}
