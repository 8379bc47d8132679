//! The viewer's own file chooser window (see `model::chooser`): the folder's entries, the parent folder, a path
//! field, Open and Cancel. A double click opens a file or enters a folder.

use crate::viewer::model::actions::UiAction;
use crate::viewer::model::chooser::FileChooser;
use crate::viewer::model::files::FileFields;
use crate::viewer::widgets::panel::ERROR_COLOR;
use crate::viewer::widgets::{clicks, rects};
use std::path::PathBuf;

/// What the user did in the chooser this frame.
enum Chosen {
    Nothing,
    Enter(PathBuf),
    Up,
    Open(PathBuf),
    Cancel,
}

/// Shows the chooser while `files.chooser` is open; a file chosen becomes a load (or a session opened).
pub fn chooser_window(ctx: &egui::Context, files: &mut FileFields, actions: &mut Vec<UiAction>) {
    let Some(chooser) = &mut files.chooser else { return };
    let mut chosen = Chosen::Nothing;
    egui::Window::new("Open a volume")
        .collapsible(false)
        .resizable(false)
        .default_width(420.0)
        .show(ctx, |ui| chosen = chooser_ui(ui, chooser));
    match chosen {
        Chosen::Nothing => {}
        Chosen::Enter(folder) => chooser.enter(&folder),
        Chosen::Up => chooser.up(),
        Chosen::Open(path) if path.is_dir() => chooser.enter(&path),
        Chosen::Open(path) => {
            files.chooser = None;
            actions.push(files.load_action(path));
        }
        Chosen::Cancel => files.chooser = None,
    }
}

fn chooser_ui(ui: &mut egui::Ui, chooser: &mut FileChooser) -> Chosen {
    let mut chosen = Chosen::Nothing;
    ui.horizontal(|ui| {
        let up = ui.button("⬆ Parent folder");
        rects::log("chooser-up", up.rect);
        if up.clicked() {
            chosen = Chosen::Up;
        }
        ui.label(chooser.folder.display().to_string());
    });
    if let Some(err) = &chooser.error {
        ui.colored_label(ERROR_COLOR, err);
    }
    egui::ScrollArea::vertical().max_height(300.0).show(ui, |ui| {
        for (i, entry) in chooser.entries.iter().enumerate() {
            let name = if entry.is_dir {
                format!("🗁 {}/", entry.name)
            } else {
                entry.name.clone()
            };
            let path = chooser.path_of(&entry.name);
            let selected = chooser.typed == path.display().to_string();
            let row = ui.selectable_label(selected, name.as_str());
            if let Some(id) = ["chooser-0", "chooser-1"].get(i) {
                rects::log_labelled(id, row.rect, Some(&name));
            }
            // Open… clicked and a file double-clicked quickly is a "triple click" to egui (`clicks`).
            if clicks::double_clicked(&row) {
                chosen = if entry.is_dir {
                    Chosen::Enter(path.clone())
                } else {
                    Chosen::Open(path.clone())
                };
            } else if row.clicked() {
                chooser.typed = path.display().to_string();
            }
        }
    });
    let field = ui.add(egui::TextEdit::singleline(&mut chooser.typed).desired_width(f32::INFINITY));
    let entered = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
    ui.horizontal(|ui| {
        if ui.button("Open").clicked() || entered {
            chosen = Chosen::Open(PathBuf::from(chooser.typed.trim()));
        }
        if ui.button("Cancel").clicked() {
            chosen = Chosen::Cancel;
        }
    });
    chosen
}
