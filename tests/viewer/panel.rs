//! The panel's Volume section through real X input (xdotool under Xvfb), as a first-time user meets it:
//! - a path typed into the path field loads when Enter is pressed (not only with the Load button);
//!
//! Where the widgets are comes from the viewer's `ui rect` lines (`VOLCAST_UI_RECTS`); the input is X's. The panel
//! is scrolled with the mouse wheel until the widget is in the 900×600 window.

use crate::common;

use common::x11::{button, pointer, type_keys, x_client, x_session, Viewer, WAIT_MS};
use std::path::Path;
use std::time::Duration;

/// The test windows' height (`Viewer::start` opens 900×600).
const WINDOW_HEIGHT: f32 = 600.0;

/// Scrolls the panel with the wheel until widget `name` is wholly in the window, and returns where it is then.
pub fn scroll_to(viewer: &mut Viewer, d: &str, w: &str, name: &str) -> egui::Rect {
    for _ in 0..60 {
        let r = viewer.ui_rect(name);
        if r.top() >= 0.0 && r.bottom() <= WINDOW_HEIGHT - 20.0 {
            // Let a smooth scroll come to rest, then read where it stopped.
            std::thread::sleep(Duration::from_millis(600));
            return viewer.ui_rect(name);
        }
        pointer(d, w, egui::pos2(130.0, 300.0));
        button(d, "click", if r.top() < 0.0 { "4" } else { "5" });
    }
    panic!("{name} never scrolled into view:\n{}", viewer.stderr);
}

/// Clicks `at` (window points) with the left button.
pub fn click(d: &str, w: &str, at: egui::Pos2) {
    pointer(d, w, at);
    button(d, "click", "1");
}

/// Types `text` as keystrokes into the focused widget of `window`.
pub fn type_text(d: &str, w: &str, text: &str) {
    x_client(d, "xdotool", &["windowfocus", "--sync", w]);
    x_client(d, "xdotool", &["type", "--delay", "30", text]);
}

#[test]
fn enter_in_the_path_field_loads_the_file() {
    let Some((x, dir)) = x_session("viewer-panel-enter") else {
        return;
    };
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk/vti_zlib.vti");
    let script = format!("frames:3;wait:{WAIT_MS};exit");
    let mut viewer = Viewer::start(&x.display, &dir, &["--builtin", "box", "--builtin-size", "16"], &script);
    viewer.wait_for("script: Wait(", Duration::from_secs(180));
    let window = &viewer.window(&x.display);
    let (d, w) = (x.display.as_str(), window.as_str());

    let field = scroll_to(&mut viewer, d, w, "load-path");
    click(d, w, field.center());
    type_text(d, w, file.to_str().expect("a UTF-8 path"));
    type_keys(d, w, &["Return"]);
    let loaded = viewer.wait_for("loaded ", Duration::from_secs(60));
    assert!(loaded.ends_with("tests/data/vtk/vti_zlib.vti"), "{loaded}");
    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
