//! The slice views' tools through real X input (xdotool under Xvfb), on a CT (DICOM, Modality CT):
//! - the W/L menu's CT presets set the slices' window/level in Hounsfield units (Bone: 3D Slicer's W1000 L400),
//!   and "auto" brings back the window the CT opened with;
//! - with the ruler tool on (M), two clicks in the axial view measure the distance between them in world
//!   millimetres (the length the viewer logs equals the one computed here from the volume's affine) and leave
//!   the crosshair where it was; a right click clears the ruler;
//! - the panel's "Save CSV" writes the measurement with its ends in world millimetres.
//!
//! Validation reports 0 messages.

use crate::common;

use common::ui_wait::settled_rect;
use common::x11::{button, four_up_rects, pointer, read_screenshot, type_keys, x_session, Viewer};
use glam::{DVec2, DVec3};
use std::path::Path;
use std::time::Duration;
use volcast::scene::slice::{SliceView, WindowLevel};
use volcast::viewer::model::Model;
use volcast::viewer::widgets::slice_view;

/// Moves the pointer onto the widget `name` once the viewer has drawn it and come to rest: egui lays out a new
/// popup in a first, invisible frame and places it in the next.
fn point_at(viewer: &mut Viewer, display: &str, window: &str, name: &str) {
    pointer(display, window, settled_rect(viewer, name).center());
}

#[test]
fn window_level_presets_and_the_ruler_in_the_slice_views() {
    let ct = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dicom/enhanced_ct_native.dcm");
    let volume = volcast::formats::open(&ct, &Default::default()).expect("the CT");
    let Some((x, dir)) = x_session("viewer-slice-tools") else {
        return;
    };
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &[ct.to_str().unwrap(), "--slices"]);
    let window = &window;
    let (d, w) = (x.display.as_str(), window.as_str());
    let opened = viewer.save_session(d, w, &dir).viewer.expect("the viewer's part");
    let wl0 = opened.window_level.expect("the CT's own window");

    // W/L ▸ Bone: 3D Slicer's CT-Bone, in HU.
    point_at(&mut viewer, d, w, "wl-menu");
    button(d, "click", "1");
    point_at(&mut viewer, d, w, "wl-bone");
    button(d, "click", "1");
    let bone = viewer.save_session(d, w, &dir).viewer.unwrap().window_level;
    let expected = WindowLevel {
        window: 1000.0,
        level: 400.0,
    };
    assert_eq!(bone, Some(expected), "the Bone preset");
    // W/L ▸ auto: the window the CT opened with.
    point_at(&mut viewer, d, w, "wl-menu");
    button(d, "click", "1");
    point_at(&mut viewer, d, w, "wl-auto");
    button(d, "click", "1");
    let auto = viewer.save_session(d, w, &dir).viewer.unwrap().window_level.unwrap();
    assert!(
        (auto.window - wl0.window).abs() < 1e-9 && (auto.level - wl0.level).abs() < 1e-9,
        "auto {auto:?}, opened with {wl0:?}"
    );

    // Where the axial view's image is, as the slices test finds it.
    type_keys(d, w, &["F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (shot, _) = read_screenshot(&dir, &saved);
    let [axial_rect, ..] = four_up_rects((900.0, 600.0), shot.width());
    let session = viewer.save_session(d, w, &dir).viewer.unwrap();
    let mut state = Model::new(volume.extent(), "ct".into());
    state.set_volume(volume.extent(), volume.geometry, volume.dims, "ct".into());
    state.slices.crosshair = DVec3::from_array(session.crosshair);
    let frame = slice_view::frame_of(&state, SliceView::Axial, axial_rect, 1.0);
    let shown = slice_view::image_rect(&frame, axial_rect);
    let (a, b) = (
        shown.lerp_inside(egui::vec2(0.25, 0.4)),
        shown.lerp_inside(egui::vec2(0.7, 0.75)),
    );
    let world = |p: egui::Pos2| {
        let scale = f64::from(shown.width()) / f64::from(frame.width);
        frame.world(DVec2::new(
            f64::from(p.x.round() - shown.left()) / scale,
            f64::from(p.y.round() - shown.top()) / scale,
        ))
    };
    let expected_mm = world(a).distance(world(b));

    // M, then two clicks: the ruler's length in mm.
    pointer(d, w, a);
    type_keys(d, w, &["m"]);
    pointer(d, w, a);
    button(d, "click", "1");
    pointer(d, w, b);
    button(d, "click", "1");
    let line = viewer.wait_for("ruler: ", Duration::from_secs(30));
    let mm: f64 = line
        .split_whitespace()
        .nth(1)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("a length in {line}"));
    assert!(
        (mm - expected_mm).abs() < 1e-3 + 1e-6 * expected_mm,
        "ruler {mm} mm, expected {expected_mm} mm"
    );
    assert!(expected_mm > 2.0, "a real distance: {expected_mm}");
    let after = viewer.save_session(d, w, &dir).viewer.unwrap();
    assert_eq!(
        after.crosshair, session.crosshair,
        "the ruler's clicks leave the crosshair"
    );

    // A right click clears it.
    button(d, "click", "3");
    viewer.wait_for("ruler: cleared", Duration::from_secs(30));

    // The panel's Slicing section saves the measurement (it outlives the line on screen) as CSV: the view, its ends
    // in world millimetres (RAS), its length.
    let save = super::panel::scroll_to(&mut viewer, d, w, "measurements-csv");
    super::panel::click(d, w, save.center());
    let saved = viewer.wait_for("saved measurements ", Duration::from_secs(30));
    let path = saved.trim().trim_start_matches("saved measurements ");
    let csv = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows.len(), 2, "{csv}");
    assert_eq!(rows[0], "view,r1_mm,a1_mm,s1_mm,r2_mm,a2_mm,s2_mm,length_mm");
    let fields: Vec<&str> = rows[1].split(',').collect();
    assert_eq!(fields[0], "axial");
    let number = |i: usize| fields[i].parse::<f64>().unwrap_or_else(|_| panic!("{}", rows[1]));
    let (start, end) = (world(a), world(b));
    for axis in 0..3 {
        assert!(
            (number(1 + axis) - start[axis]).abs() < 1e-3,
            "start {} against {start}",
            rows[1]
        );
        assert!(
            (number(4 + axis) - end[axis]).abs() < 1e-3,
            "end {} against {end}",
            rows[1]
        );
    }
    assert!((number(7) - mm).abs() < 1e-3, "length {} against {mm}", rows[1]);

    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
