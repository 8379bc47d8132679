//! Undo and redo through real X input (xdotool under Xvfb), on a CT: a point added to the transfer function and
//! then dragged is two steps (the whole drag is one); Ctrl+Z takes the drag back, Ctrl+Z again the point, and
//! Ctrl+Shift+Z and Ctrl+Y redo them. A camera drag in the 3D view is one step too: Ctrl+Z puts the camera back,
//! Ctrl+Shift+Z turns it again. The state is read from the session Ctrl+S writes. Validation reports 0 messages.

use crate::common;

use common::x11::{button, drag, pointer, tf_of, type_keys, x_session, Viewer};
use std::path::Path;
use std::time::Duration;
use volcast::scene::camera::Camera;
use volcast::viewer::model::tf::to_normalized;

fn same_camera(a: &Camera, b: &Camera) -> bool {
    a.eye.distance(b.eye) < 1e-4 && a.up.distance(b.up) < 1e-4 && a.target.distance(b.target) < 1e-4
}

#[test]
fn ctrl_z_undoes_a_point_a_drag_and_a_turn_and_ctrl_shift_z_redoes_them() {
    let ct = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dicom/enhanced_ct_native.dcm");
    let volume = volcast::formats::open(&ct, &Default::default()).expect("the CT");
    let range = volume.range;
    let Some((x, dir)) = x_session("viewer-history") else {
        return;
    };
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &[ct.to_str().unwrap()]);
    let window = &window;
    let (d, w) = (x.display.as_str(), window.as_str());
    let state = |viewer: &mut Viewer, keys: &[&str]| {
        if !keys.is_empty() {
            type_keys(d, w, keys);
        }
        viewer.save_session(d, w, &dir)
    };

    let opened = state(&mut viewer, &[]);
    let tf0 = tf_of(&opened);
    std::thread::sleep(Duration::from_millis(600));
    let plot = viewer.ui_rect("tf-plot");
    let at = |u: f32, a: f32| egui::pos2(plot.left() + u * plot.width(), plot.bottom() - a * plot.height());
    // A point clear of the preset's, then a drag of it upwards.
    let (u, a) = (0.12, 0.6);
    pointer(d, w, at(u, a));
    button(d, "click", "1");
    let added = tf_of(&state(&mut viewer, &[]));
    assert_eq!(added.opacity.len(), tf0.opacity.len() + 1, "{:?}", added.opacity);
    let new = *added
        .opacity
        .iter()
        .find(|p| !tf0.opacity.contains(p))
        .expect("the new point");
    drag(
        d,
        w,
        "1",
        at(to_normalized(&added, new[0], range), new[1]),
        egui::vec2(0.0, -8.0),
        3,
    );
    let dragged = tf_of(&state(&mut viewer, &[]));
    assert_ne!(dragged, added, "the drag moved the point");

    // Back through the drag (one step, however many frames it took), then the point.
    assert_eq!(
        tf_of(&state(&mut viewer, &["ctrl+z"])),
        added,
        "Ctrl+Z undoes the whole drag"
    );
    assert_eq!(
        tf_of(&state(&mut viewer, &["ctrl+z"])),
        tf0,
        "Ctrl+Z again removes the point"
    );
    assert_eq!(
        tf_of(&state(&mut viewer, &["ctrl+shift+z"])),
        added,
        "Ctrl+Shift+Z redoes the point"
    );
    assert_eq!(
        tf_of(&state(&mut viewer, &["ctrl+y"])),
        dragged,
        "Ctrl+Y redoes the drag"
    );

    // A turn of the camera: a left drag in the 3D view (right of the panel).
    let before = state(&mut viewer, &[]).settings.camera;
    drag(d, w, "1", egui::pos2(560.0, 300.0), egui::vec2(20.0, 0.0), 6);
    let turned = state(&mut viewer, &[]).settings.camera;
    assert!(!same_camera(&before, &turned), "the drag turned the camera");
    let undone = state(&mut viewer, &["ctrl+z"]);
    assert!(
        same_camera(&undone.settings.camera, &before),
        "Ctrl+Z puts the camera back"
    );
    assert_eq!(tf_of(&undone), dragged, "and leaves the transfer function");
    let redone = state(&mut viewer, &["ctrl+shift+z"]).settings.camera;
    assert!(same_camera(&redone, &turned), "Ctrl+Shift+Z turns it again");

    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
