//! The light gizmo through real X input (xdotool under Xvfb): S turns shading on and shows the gizmo; a drag
//! that starts on its disc places a directional light where the pointer ends (and leaves the camera alone); a
//! double click gives the headlight back. Each state is read from F12's settings JSON, and the window must change
//! with the light. Validation reports 0 messages.

use crate::common;

use common::x11::{capture, read_screenshot, type_keys, x_client, x_session, Viewer};
use glam::Vec2;
use std::time::Duration;
use volcast::viewer::model::orbit::OrbitView;
use volcast::viewer::widgets::light_gizmo;

fn pointer(display: &str, window: &str, args: &[&str]) {
    let mut all = vec!["mousemove", "--window", window];
    all.extend_from_slice(args);
    x_client(display, "xdotool", &all);
}

fn button(display: &str, action: &str) {
    x_client(display, "xdotool", &[action, "1"]);
    std::thread::sleep(Duration::from_millis(150));
}

#[test]
fn dragging_the_light_gizmo_places_a_directional_light() {
    let Some((x, dir)) = x_session("viewer-light") else {
        return;
    };
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "helix"]);
    let window = &window;

    // Shading on: the gizmo shows; the headlight is the default.
    type_keys(&x.display, window, &["s", "F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (shot, before) = read_screenshot(&dir, &saved);
    assert!(
        before.lighting.shading.is_some() && before.lighting.light.direction.is_none(),
        "S: shaded under the headlight"
    );
    let (w, h) = shot.dimensions();
    let view = egui::Rect::from_min_size(egui::pos2((900 - w) as f32, 0.0), egui::vec2(w as f32, h as f32));
    let c = light_gizmo::center(view);
    let window_before = capture(&x.display, window);

    // Drag from the disc's centre to a point up and to the left on it.
    let end = c + Vec2::new(-20.0, -18.0);
    let at = |p: Vec2| [format!("{}", p.x.round()), format!("{}", p.y.round())];
    let [cx, cy] = at(c);
    pointer(&x.display, window, &[&cx, &cy]);
    button(&x.display, "mousedown");
    for k in 1..=6 {
        let [px, py] = at(c + (end - c) * (k as f32 / 6.0));
        pointer(&x.display, window, &[&px, &py]);
        std::thread::sleep(Duration::from_millis(100));
    }
    button(&x.display, "mouseup");
    std::thread::sleep(Duration::from_millis(600));
    type_keys(&x.display, window, &["F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (_, after) = read_screenshot(&dir, &saved);
    assert_eq!(
        after.camera.eye, before.camera.eye,
        "a drag on the gizmo leaves the camera alone"
    );
    let rotation = OrbitView::from_camera(&after.camera).rotation;
    let expected = light_gizmo::world_direction(Vec2::new(end.x.round(), end.y.round()), c, rotation);
    let got = after
        .lighting
        .light
        .direction
        .expect("a directional light after the drag");
    assert!(
        got.normalize().dot(expected) > 0.995,
        "light {got} where the pointer ended, {expected}"
    );
    assert_ne!(
        capture(&x.display, window).as_raw(),
        window_before.as_raw(),
        "the window changes with the light"
    );

    // A double click on the disc: the headlight again.
    pointer(&x.display, window, &[&cx, &cy]);
    x_client(&x.display, "xdotool", &["click", "--repeat", "2", "--delay", "80", "1"]);
    std::thread::sleep(Duration::from_millis(600));
    type_keys(&x.display, window, &["F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (_, reset) = read_screenshot(&dir, &saved);
    assert!(reset.lighting.light.direction.is_none(), "double click: the headlight");

    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
