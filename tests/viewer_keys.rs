//! Keyboard shortcuts through real X input (xdotool under Xvfb), as a user types them: after Tab hides the panel,
//! S still shades and Tab brings the panel back, with no Escape in between (egui's focus traversal used to take
//! Tab into a text field, which then swallowed every key). The panel's state is read from F12's screenshot width
//! and settings.

mod common;

use common::x11::{have, read_screenshot, type_keys, xvfb, Viewer, WAIT_MS};
use std::time::Duration;

#[test]
fn shortcuts_keep_working_after_tab_hides_the_panel() {
    if !(have("xdotool", "version") && have("xwd", "-help")) {
        common::skip("xdotool or xwd missing (apt install xdotool x11-apps)");
        return;
    }
    let Some(x) = xvfb() else { return };
    let dir = std::env::temp_dir().join(format!("volcast-viewer-keys-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let script = format!("frames:3;wait:{WAIT_MS};exit");
    let mut viewer = Viewer::start(
        &x.display,
        &dir,
        &["--builtin", "helix", "--builtin-size", "64"],
        &script,
    );
    viewer.wait_for("script: Wait(", Duration::from_secs(180));
    let window = &viewer.window(&x.display);
    let mut shot = |keys: &[&str]| {
        let mut all = keys.to_vec();
        all.push("F12");
        type_keys(&x.display, window, &all);
        let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
        read_screenshot(&dir, &saved)
    };

    let (with_panel, s0) = shot(&[]);
    assert!(with_panel.width() < 900, "the panel is shown at first");
    // Tab hides the panel: the view is the whole window.
    let (hidden, _) = shot(&["Tab"]);
    assert_eq!(hidden.width(), 900, "Tab hides the panel");
    // Shortcuts still work with the panel hidden: S shades.
    let (_, shaded) = shot(&["s"]);
    assert_ne!(
        shaded.shading.is_some(),
        s0.shading.is_some(),
        "S after Tab toggles shading"
    );
    // And Tab brings the panel back.
    let (back, _) = shot(&["Tab"]);
    assert!(back.width() < 900, "a second Tab shows the panel again");
    // With the panel back, keys still reach the shortcuts (no text field took the focus).
    let (_, unshaded) = shot(&["s"]);
    assert_eq!(
        unshaded.shading.is_some(),
        s0.shading.is_some(),
        "S with the panel back"
    );

    let status = viewer.finish();
    assert!(status.success(), "viewer exit: {status}\n{}", viewer.stderr);
    assert!(
        viewer.stderr.contains("validation: 0 errors, 0 warnings"),
        "validation summary:\n{}",
        viewer.stderr
    );
    let _ = std::fs::remove_dir_all(&dir);
}
