//! Recent files through real X input (xdotool under Xvfb): a session that loads two files leaves them in
//! `$XDG_CONFIG_HOME/volcast/recent.json` (the test's own folder, never the user's), newest first; a viewer
//! started again with the same config offers them in the panel's Recent menu, and a click on the older one loads
//! it. A broken list is ignored with a warning. Validation reports 0 messages.

use crate::common;

use common::ui_wait::settled_rect;
use common::x11::{button, pointer, x_session, Viewer};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

#[test]
fn recent_files_survive_a_restart_and_open_from_the_menu() {
    let Some((x, dir)) = x_session("viewer-recent") else {
        return;
    };
    let list = dir.join("config/volcast/recent.json");
    std::fs::create_dir_all(list.parent().unwrap()).unwrap();
    std::fs::write(&list, "{ not json").unwrap();
    let (first, second) = (data("ramp.nhdr"), data("ramp.vtk"));

    // Two loads: the command line's file, then a dropped one.
    let script = format!("frames:3;drop:{};frames:3;exit", second.display());
    let mut viewer = Viewer::start(&x.display, &dir, &[first.to_str().unwrap()], &script);
    let line = viewer.wait_for("script: load", Duration::from_secs(120));
    assert!(line.contains("script: loaded"), "{line}");
    viewer.finish_clean();
    assert!(
        viewer.stderr.contains("is not a recent-files list"),
        "{}",
        viewer.stderr
    );
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&list).unwrap()).unwrap();
    let canonical = |p: &Path| std::fs::canonicalize(p).unwrap().to_string_lossy().into_owned();
    assert_eq!(
        json["recent"],
        serde_json::json!([canonical(&second), canonical(&first)])
    );

    // Again, with the same config: Recent offers both, newest first; the older one loads.
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "box", "--builtin-size", "16"]);
    let window = &window;
    let (d, w) = (x.display.as_str(), window.as_str());
    let mut combo = settled_rect(&mut viewer, "recent-combo");
    // The Volume section is below the fold of the 900x600 window: the wheel over the panel brings it up.
    let deadline = Instant::now() + Duration::from_secs(60);
    while combo.bottom() > 560.0 {
        assert!(
            Instant::now() < deadline,
            "the wheel never brought the menu up: {combo:?}"
        );
        pointer(d, w, egui::pos2(combo.center().x, 300.0));
        button(d, "click", "5");
        // The panel scrolls smoothly: read where the menu is once it stops.
        combo = settled_rect(&mut viewer, "recent-combo");
    }
    pointer(d, w, combo.center());
    button(d, "click", "1");
    let newest = settled_rect(&mut viewer, "recent-item-0");
    let older = settled_rect(&mut viewer, "recent-item-1");
    assert!(older.top() > newest.top(), "{newest:?} {older:?}");
    pointer(d, w, older.center());
    button(d, "click", "1");
    let loaded = viewer.wait_for("loaded ", Duration::from_secs(120));
    assert!(loaded.ends_with("ramp.nhdr"), "{loaded}");
    viewer.finish_clean();
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&list).unwrap()).unwrap();
    assert_eq!(
        json["recent"][0],
        serde_json::json!(canonical(&first)),
        "the pick moves to the front"
    );
}
