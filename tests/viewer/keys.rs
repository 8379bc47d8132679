//! Keyboard shortcuts through real X input (xdotool under Xvfb), as a user types them: after Tab hides the panel,
//! S still shades and Tab brings the panel back, with no Escape in between (egui's focus traversal used to take
//! Tab into a text field, which then swallowed every key). The panel's state is read from F12's screenshot width
//! and settings. A quick drag, all of it within one slow frame, still turns the camera.

use crate::common;

use common::x11::{read_screenshot, type_keys, x_client, x_session, Viewer, HOLD};
use glam::Vec2;
use std::time::Duration;
use volcast::viewer::model::orbit::OrbitView;

#[test]
fn shortcuts_keep_working_after_tab_hides_the_panel() {
    let Some((x, dir)) = x_session("viewer-keys") else {
        return;
    };
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "helix", "--builtin-size", "64"]);
    let window = &window;
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
        shaded.lighting.shading.is_some(),
        s0.lighting.shading.is_some(),
        "S after Tab toggles shading"
    );
    // And Tab brings the panel back.
    let (back, _) = shot(&["Tab"]);
    assert!(back.width() < 900, "a second Tab shows the panel again");
    // With the panel back, keys still reach the shortcuts (no text field took the focus).
    let (_, unshaded) = shot(&["s"]);
    assert_eq!(
        unshaded.lighting.shading.is_some(),
        s0.lighting.shading.is_some(),
        "S with the panel back"
    );

    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}

/// A file named on the command line loads behind an open window (the background loader, with its progress in the
/// panel; a 1 GiB volume used to keep the window away for 20 s): the loader's "loaded" line comes, the script waits
/// for it, and F12 then shows the file's volume. A file that cannot be read leaves the window open on an empty scene
/// with its error (on stderr too), and the session then ends cleanly.
#[test]
fn a_file_from_the_command_line_loads_behind_the_window() {
    let Some(ct) = common::shared_data("raw/cranium_ct_256x256x108_int16.raw") else {
        return;
    };
    let Some((x, dir)) = x_session("viewer-cli-load") else {
        return;
    };
    let script = format!("frames:2;{HOLD};exit");
    let ct = ct.to_str().unwrap();
    let mut viewer = Viewer::start(&x.display, &dir, &[ct], &script);
    let loaded = viewer.wait_for("loaded ", Duration::from_secs(180));
    assert!(loaded.contains("cranium_ct"), "{loaded}");
    viewer.wait_for("script: Hold", Duration::from_secs(60));
    let window = &viewer.window(&x.display);
    // F12's JSON is a view state: `render --state` renders the same view again, volume included.
    let f12 = common::x11::Rerendered::take(&mut viewer, &x.display, window, &dir);
    assert!(
        f12.shot.pixels().filter(|p| p.0[..3] != [0, 0, 0]).count() > 1000,
        "the CT shows once loaded"
    );
    let worst = f12.worst();
    assert!(
        worst <= 1,
        "render --state differs from the F12 screenshot by up to {worst}/255"
    );
    let status = viewer.finish();
    assert!(status.success(), "{}", viewer.stderr);

    let mut missing = Viewer::start(&x.display, &dir, &["/nonexistent/scan.nrrd"], "frames:2;exit");
    let status = missing.finish();
    assert!(status.success(), "{}", missing.stderr);
    assert!(
        missing.stderr.contains("could not load /nonexistent/scan.nrrd"),
        "{}",
        missing.stderr
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_quick_drag_within_one_frame_turns_the_camera() {
    let Some((x, dir)) = x_session("viewer-quick-drag") else {
        return;
    };
    // The full-size helix: frames of tens of milliseconds on lavapipe, and the drag below takes a few.
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "helix"]);
    let window = &window;
    type_keys(&x.display, window, &["F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (shot, before) = read_screenshot(&dir, &saved);
    let (w, h) = shot.dimensions();
    let view_left = (900 - w) as f32;

    // Press, six moves and the release in one xdotool call: no pause anywhere, as a flick of the hand.
    let from = Vec2::new(w as f32 * 0.3, h as f32 * 0.5);
    let to = from + Vec2::new(180.0, 0.0);
    let move_to = |p: Vec2| {
        let at = [format!("{}", (p.x + view_left).round()), format!("{}", p.y.round())];
        ["mousemove", "--window", window.as_str(), &at[0], &at[1]]
            .map(String::from)
            .to_vec()
    };
    let mut args = move_to(from);
    args.extend(["mousedown", "1"].map(String::from));
    for k in 1..=6 {
        args.extend(move_to(from + (to - from) * (k as f32 / 6.0)));
    }
    args.extend(["mouseup", "1"].map(String::from));
    x_client(
        &x.display,
        "xdotool",
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    std::thread::sleep(Duration::from_millis(800));

    type_keys(&x.display, window, &["F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (_, after) = read_screenshot(&dir, &saved);
    // What the whole drag does as one arcball turn (as it does when the motion comes in one frame).
    let mut expected = OrbitView::from_camera(&before.camera);
    expected.arcball(from, to, Vec2::new(w as f32, h as f32));
    let turned = OrbitView::from_camera(&after.camera);
    let angle = |a: glam::Quat, b: glam::Quat| a.angle_between(b).to_degrees();
    let start = OrbitView::from_camera(&before.camera).rotation;
    assert!(angle(start, expected.rotation) > 20.0, "the drag is a real turn");
    assert!(
        angle(turned.rotation, expected.rotation) < 3.0,
        "a quick drag turns the camera as a slow one: {:.1}° from the expected turn, {:.1}° from the start",
        angle(turned.rotation, expected.rotation),
        angle(turned.rotation, start)
    );
    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
