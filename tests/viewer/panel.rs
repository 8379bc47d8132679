//! The panel's Volume section through real X input (xdotool under Xvfb), as a first-time user meets it:
//! - a path typed into the path field loads when Enter is pressed (not only with the Load button);
//!
//! Where the widgets are comes from the viewer's `ui rect` lines (`VOLCAST_UI_RECTS`); the input is X's. The panel
//! is scrolled with the mouse wheel until the widget is in the 900×600 window.

use crate::common;

use common::ui_wait::{labelled_rect, settled_rect};
use common::x11::{button, pointer, type_keys, x_client, x_session, Viewer, HOLD};
use std::path::Path;
use std::time::Duration;

/// The test windows' height (`Viewer::start` opens 900×600).
const WINDOW_HEIGHT: f32 = 600.0;

/// Scrolls the panel with the wheel until widget `name` is wholly in the window, and returns where it is then.
pub fn scroll_to(viewer: &mut Viewer, d: &str, w: &str, name: &str) -> egui::Rect {
    for _ in 0..60 {
        let r = viewer.ui_rect(name);
        if r.top() >= 0.0 && r.bottom() <= WINDOW_HEIGHT - 20.0 {
            // Where a smooth scroll comes to rest, however slowly the machine draws its frames.
            return settled_rect(viewer, name);
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
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "box", "--builtin-size", "16"]);
    let window = &window;
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

/// Pixels of `image` inside `rect` (window points, 1 pixel each under Xvfb) in the panel's error colour.
fn error_coloured_pixels(image: &image::RgbaImage, rect: egui::Rect) -> usize {
    let (x0, y0) = (rect.left().max(0.0) as u32, rect.top().max(0.0) as u32);
    let (x1, y1) = (rect.right() as u32, (rect.bottom() as u32).min(image.height()));
    (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let p = image.get_pixel(x, y);
            p[0] > 180 && p[1] < 140 && p[2] < 140 && p[0] > p[1] + 60
        })
        .count()
}

/// `volcast BAD_FILE`, no subcommand: the viewer opens (on the empty scene) and shows the load's error under the
/// path field, which names the file, as a load from the panel does; closing it exits 0. (It used to flash and exit
/// 1, and `volcast FILE` without `view` was refused.)
#[test]
fn a_bad_file_on_the_command_line_opens_the_viewer_with_its_error() {
    let Some((x, dir)) = x_session("viewer-panel-bad-file") else {
        return;
    };
    std::fs::create_dir_all(&dir).expect("scratch");
    let bad = dir.join("broken.nii");
    std::fs::write(&bad, b"not a NIfTI header at all").expect("write the bad file");
    let script = format!("frames:3;{HOLD};exit");
    let mut viewer = Viewer::launch(&x.display, &dir, &[bad.to_str().expect("UTF-8")], &script);
    let said = viewer.wait_for("could not load ", Duration::from_secs(180));
    assert!(said.contains("broken.nii"), "{said}");
    viewer.wait_for("script: Hold", Duration::from_secs(60));
    let window = &viewer.window(&x.display);
    let (d, w) = (x.display.as_str(), window.as_str());
    let error = scroll_to(&mut viewer, d, w, "load-error");
    // The reason first, the file named once.
    let text = viewer
        .stderr
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("ui label load-error "))
        .expect("its text");
    assert_eq!(text.matches("broken.nii").count(), 1, "{text}");
    assert!(!text.starts_with('/') && !text.starts_with("broken.nii"), "{text}");
    let field = viewer.ui_rect("load-path");
    assert!(
        error.top() >= field.bottom(),
        "the error {error:?} shows under the path field {field:?}"
    );
    let shown = common::x11::capture(d, w);
    let red = error_coloured_pixels(&shown, error);
    assert!(red > 50, "the error is drawn in the error colour ({red} pixels)");
    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}

/// Double-clicks `at` with the left button.
fn double_click(d: &str, w: &str, at: egui::Pos2) {
    pointer(d, w, at);
    x_client(d, "xdotool", &["click", "--repeat", "2", "--delay", "60", "1"]);
    std::thread::sleep(Duration::from_millis(800));
}

/// Open… with no desktop portal (none under Xvfb) opens the viewer's own chooser: a double click enters a folder,
/// Parent folder goes back, a double click on a file loads it. A load's error shows under the path field, so the
/// Open… button the user clicked has not moved (the panel's top used to show it and push everything down).
#[test]
fn open_without_a_portal_uses_the_built_in_chooser() {
    let Some((x, dir)) = x_session("viewer-panel-chooser") else {
        return;
    };
    let folder = dir.join("a-vols");
    std::fs::create_dir_all(&folder).expect("a folder to navigate to");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk/vti_zlib.vti");
    std::fs::copy(&data, folder.join("head.vti")).expect("copy a volume");
    std::fs::write(folder.join("bad.nii"), b"not a NIfTI header").expect("a broken file");
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "box", "--builtin-size", "16"]);
    let window = &window;
    let (d, w) = (x.display.as_str(), window.as_str());

    let open = scroll_to(&mut viewer, d, w, "open");
    click(d, w, open.center());
    // The chooser opens on the working folder: a-vols/ first (folders first), then xdg/ (the test's runtime dir).
    // Each step waits for the rows it expects, at rest: a new window's first frame is laid out invisibly and takes
    // no clicks (a double click there once went to the panel under it, and the rest of the test astray).
    let vols = "🗁 a-vols/";
    double_click(d, w, labelled_rect(&mut viewer, "chooser-0", vols).center());
    labelled_rect(&mut viewer, "chooser-0", "bad.nii");
    click(d, w, settled_rect(&mut viewer, "chooser-up").center());
    double_click(d, w, labelled_rect(&mut viewer, "chooser-0", vols).center());
    // a-vols/: bad.nii, then head.vti. The broken file's error shows under the path field; Open… stays put.
    double_click(d, w, labelled_rect(&mut viewer, "chooser-0", "bad.nii").center());
    let said = viewer.wait_for("could not load ", Duration::from_secs(60));
    assert!(said.contains("a-vols/bad.nii"), "{said}");
    assert_eq!(
        settled_rect(&mut viewer, "open"),
        open,
        "Open… stayed where it was clicked"
    );
    // The error shows in a frame after the one that said so.
    assert!(settled_rect(&mut viewer, "load-error").top() >= viewer.ui_rect("load-path").bottom());
    // Again: the chooser opens on the folder of the path field's file (its rows were forgotten when it closed).
    click(d, w, open.center());
    double_click(d, w, labelled_rect(&mut viewer, "chooser-1", "head.vti").center());
    let loaded = viewer.wait_for("loaded ", Duration::from_secs(60));
    assert!(loaded.ends_with("a-vols/head.vti"), "{loaded}");
    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
