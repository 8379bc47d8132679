//! The transfer-function editor through real X input (xdotool under Xvfb), on a CT (DICOM, Modality CT):
//! - the CT opens with the automatic preset for its modality (ct-bone, in HU);
//! - a click on the opacity plot adds a point there (data units on x, opacity on y), a drag moves it, a right
//!   click deletes it;
//! - a click on the colour strip adds a colour point with the colour already there;
//! - Save writes the function to the typed path (the same function the session holds), and Load reads it back
//!   after another edit;
//! - F12 equals `render --state` of its JSON to 1/255: the GPU renders the edited function.
//!
//! Where the editor's widgets are comes from the viewer's `ui rect` lines (`VOLCAST_UI_RECTS`); the input is X's.
//! Validation reports 0 messages.

use crate::common;

use common::x11::{button, drag, pointer, tf_of, x_client, x_session, Rerendered, Viewer};
use std::path::Path;
use std::time::Duration;
use volcast::transfer::function::TransferFunction;
use volcast::viewer::model::tf::to_normalized;

#[test]
fn the_editor_adds_moves_deletes_saves_and_loads_points() {
    let ct = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dicom/enhanced_ct_native.dcm");
    let volume = volcast::formats::open(&ct, &Default::default()).expect("the CT");
    let range = volume.range;
    let Some((x, dir)) = x_session("viewer-tf") else {
        return;
    };
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &[ct.to_str().unwrap()]);
    let window = &window;
    let (d, w) = (x.display.as_str(), window.as_str());

    // The CT's own preset, in HU.
    let opened = viewer.save_session(d, w, &dir);
    let tf0 = tf_of(&opened);
    assert_eq!(tf0.name, "auto: ct-bone", "the CT opens with its modality's preset");

    // A click on the plot, away from the existing points: a point at that value and opacity. (The session's
    // message shows under the Session buttons, below the editor, so saving moves nothing above it.)
    let plot = viewer.ui_rect("tf-plot");
    let at = |u: f32, a: f32| egui::pos2(plot.left() + u * plot.width(), plot.bottom() - a * plot.height());
    let (u, a) = (0.12, 0.6);
    for p in &tf0.opacity {
        let q = at(to_normalized(&tf0, p[0], range), p[1]);
        assert!(q.distance(at(u, a)) > 20.0, "the click is clear of the preset's points");
    }
    pointer(d, w, at(u, a));
    button(d, "click", "1");
    let added = tf_of(&viewer.save_session(d, w, &dir));
    assert_eq!(added.opacity.len(), tf0.opacity.len() + 1, "{:?}", added.opacity);
    assert_eq!(added.name, "custom");
    let new = added
        .opacity
        .iter()
        .find(|p| !tf0.opacity.contains(p))
        .copied()
        .expect("the new point");
    let px = (range[1] - range[0]) as f32 / plot.width();
    let target = (range[0] as f32) + u * (range[1] - range[0]) as f32;
    assert!(
        (new[0] - target).abs() <= 1.5 * px,
        "x {} HU, expected {target}",
        new[0]
    );
    assert!((new[1] - a).abs() <= 1.5 / plot.height(), "opacity {}", new[1]);

    // Dragged up 24 points: 24 / height more opaque, at the same value.
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(viewer.ui_rect("tf-plot"), plot, "the editor stayed put");
    let on = at(to_normalized(&added, new[0], range), new[1]);
    drag(d, w, "1", on, egui::vec2(0.0, -8.0), 3);
    let moved = tf_of(&viewer.save_session(d, w, &dir));
    let dragged = moved
        .opacity
        .iter()
        .find(|p| !tf0.opacity.contains(p))
        .copied()
        .expect("the point");
    assert!((dragged[0] - new[0]).abs() <= 1.5 * px, "{dragged:?}");
    let rise = dragged[1] - new[1];
    assert!(
        (rise - 24.0 / plot.height()).abs() <= 1.5 / plot.height(),
        "rose {rise}"
    );

    // A right click on it deletes it.
    pointer(d, w, at(to_normalized(&moved, dragged[0], range), dragged[1]));
    button(d, "click", "3");
    let deleted = tf_of(&viewer.save_session(d, w, &dir));
    assert_eq!(deleted.opacity, tf0.opacity, "back to the preset's points");

    // A click on the colour strip, clear of its markers: one more colour point there.
    let strip = viewer.ui_rect("tf-strip");
    let markers: Vec<f32> = tf0.colors.iter().map(|c| to_normalized(&tf0, c[0], range)).collect();
    let su = (1..20)
        .map(|k| k as f32 / 20.0)
        .find(|s| markers.iter().all(|m| (m - s).abs() * strip.width() > 16.0))
        .expect("a place on the strip without a marker");
    pointer(d, w, egui::pos2(strip.left() + su * strip.width(), strip.center().y));
    button(d, "click", "1");
    let coloured = tf_of(&viewer.save_session(d, w, &dir));
    assert_eq!(coloured.colors.len(), tf0.colors.len() + 1, "{:?}", coloured.colors);
    let c = coloured
        .colors
        .iter()
        .find(|c| !tf0.colors.contains(c))
        .expect("the new colour point");
    let target = (range[0] as f32) + su * (range[1] - range[0]) as f32;
    assert!((c[0] - target).abs() <= 1.5 * (range[1] - range[0]) as f32 / strip.width());

    // Save to a typed path: the file holds the function the session does.
    std::thread::sleep(Duration::from_millis(300));
    let field = viewer.ui_rect("tf-path");
    pointer(d, w, field.center());
    button(d, "click", "1");
    x_client(d, "xdotool", &["type", "--delay", "30", "edited.json"]);
    std::thread::sleep(Duration::from_millis(300));
    let save = viewer.ui_rect("tf-save");
    pointer(d, w, save.center());
    button(d, "click", "1");
    let saved_file = dir.join("edited.json");
    let deadline = std::time::Instant::now() + Duration::from_secs(10);
    while !saved_file.exists() && std::time::Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(100));
    }
    let on_disk = TransferFunction::load(&saved_file).expect("the saved function");
    assert_eq!(on_disk, coloured, "Save writes the function shown");

    // Another edit, then Load: the saved function is back.
    pointer(d, w, at(0.05, 0.3));
    button(d, "click", "1");
    let load = viewer.ui_rect("tf-load");
    pointer(d, w, load.center());
    button(d, "click", "1");
    // Out of the text field, so that the keys below are shortcuts again.
    pointer(d, w, egui::pos2(850.0, 300.0));
    button(d, "click", "1");
    let loaded = tf_of(&viewer.save_session(d, w, &dir));
    assert_eq!(loaded, coloured, "Load reads it back");

    // The GPU renders the edited function as the viewer shows it.
    let worst = Rerendered::take(&mut viewer, d, w, &dir).worst();
    assert!(worst <= 1, "render --state differs from F12 by up to {worst}/255");

    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}

/// The preset menu offers the presets of the volume's kind, clicked open through X: Hounsfield-unit windows for a
/// CT and never the MR one; for an MRI (a NIfTI whose values are not HU) the MR one and never a CT window. The
/// generic qt-example is offered to both.
#[test]
fn the_preset_menu_offers_the_presets_of_the_volume_s_kind() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let cases = [
        (data.join("dicom/enhanced_ct_native.dcm"), "ct-bone", "mr-default"),
        (data.join("nibabel/example_nifti2.nii.gz"), "mr-default", "ct-bone"),
    ];
    for (i, (file, offered, never)) in cases.iter().enumerate() {
        let Some((x, dir)) = x_session(&format!("viewer-tf-presets-{i}")) else {
            return;
        };
        let (mut viewer, window) = Viewer::held(&x.display, &dir, &[file.to_str().unwrap()]);
        let (d, w) = (x.display.as_str(), window.as_str());
        let menu = common::ui_wait::settled_rect(&mut viewer, "tf-preset");
        pointer(d, w, menu.center());
        button(d, "click", "1");
        common::ui_wait::settled_rect(&mut viewer, "tf-preset-0");
        let names: Vec<String> = viewer
            .stderr
            .lines()
            .filter_map(|l| l.strip_prefix("ui label tf-preset-"))
            .filter_map(|l| l.split_once(' ').map(|(_, name)| name.to_string()))
            .collect();
        assert!(names.iter().any(|n| n == offered), "{}: {names:?}", file.display());
        assert!(names.iter().any(|n| n == "qt-example"), "{}: {names:?}", file.display());
        assert!(!names.iter().any(|n| n == never), "{}: {names:?}", file.display());
        viewer.finish_clean();
    }
}
