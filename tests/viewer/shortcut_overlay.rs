//! The shortcut overlay through real X input (xdotool under Xvfb): F1 shows the list of keyboard and mouse
//! shortcuts over the window, F1 hides it; ? shows it too and Esc closes it. Whether it is shown is read from
//! its rect in the viewer's widget log (`ui rect shortcuts`, empty while hidden). Validation reports 0 messages.

use crate::common;

use common::x11::{type_keys, x_session, Viewer};
use std::time::Duration;

/// Presses `key` and returns the overlay's rect once the frames after it logged it (egui sizes a new area in
/// its first frame and places it in the next).
fn press(viewer: &mut Viewer, display: &str, window: &str, key: &str) -> egui::Rect {
    viewer.drain();
    type_keys(display, window, &[key]);
    viewer.wait_for("ui rect shortcuts ", Duration::from_secs(30));
    std::thread::sleep(Duration::from_millis(800));
    viewer.ui_rect("shortcuts")
}

#[test]
fn f1_and_question_mark_show_the_shortcuts_and_f1_or_esc_hide_them() {
    let Some((x, dir)) = x_session("viewer-shortcut-overlay") else {
        return;
    };
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "helix", "--builtin-size", "64"]);
    let window = &window;
    let d = x.display.as_str();

    let shown = press(&mut viewer, d, window, "F1");
    assert!(
        shown.width() > 200.0 && shown.height() > 200.0,
        "F1 shows the list: {shown:?}"
    );
    assert!(
        egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(900.0, 600.0)).contains_rect(shown),
        "inside the window: {shown:?}"
    );
    assert_eq!(
        press(&mut viewer, d, window, "F1"),
        egui::Rect::ZERO,
        "F1 again hides it"
    );
    assert_eq!(press(&mut viewer, d, window, "question"), shown, "? shows it");
    assert_eq!(
        press(&mut viewer, d, window, "Escape"),
        egui::Rect::ZERO,
        "Esc hides it"
    );

    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
