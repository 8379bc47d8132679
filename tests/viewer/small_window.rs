//! A small window (700×500) in the four-up layout, through real X input: the 3D view is a quarter of what the
//! panel leaves, narrower than tall. The CT head must lie wholly inside that view and clear of the orientation
//! gizmo (it ran past the view's sides and under the gizmo): the view frames the volume for its shape and the
//! gizmo shrinks.

use crate::common;

use common::x11::{read_screenshot, type_keys, x_session, Viewer, HOLD};
use std::time::Duration;

#[test]
fn a_small_four_up_view_frames_the_head_clear_of_the_gizmo() {
    let Some(ct) = common::shared_data("raw/cranium_ct_256x256x108_int16.raw") else {
        return;
    };
    let Some((x, dir)) = x_session("viewer-small-window") else {
        return;
    };
    let script = format!("frames:2;resize:700x500;frames:2;{HOLD};exit");
    let mut viewer = Viewer::start(&x.display, &dir, &[ct.to_str().unwrap()], &script);
    viewer.wait_for("script: Hold", Duration::from_secs(180));
    let window = &viewer.window(&x.display);
    type_keys(&x.display, window, &["l"]);
    std::thread::sleep(Duration::from_millis(500));
    type_keys(&x.display, window, &["F12"]);
    let (shot, settings) = read_screenshot(&dir, &viewer.wait_for("saved screenshot ", Duration::from_secs(60)));
    let view = viewer.ui_rect("view-3d");
    let gizmo = viewer.ui_rect("orientation-gizmo");
    let (w, h) = shot.dimensions();
    assert_eq!(
        (w as f32, h as f32),
        (view.width().round(), view.height().round()),
        "F12 is the 3D quarter"
    );
    assert!(w < h + 40 && w < 300, "a small quarter: {w}x{h} ({settings:?})");

    // The head's pixels: their bounding box inside the view (not touching its edges), none in the gizmo's square.
    let lit: Vec<(u32, u32)> = shot
        .enumerate_pixels()
        .filter(|(_, _, p)| p.0[..3].iter().any(|&c| c > 12))
        .map(|(x_, y_, _)| (x_, y_))
        .collect();
    assert!(lit.len() > 2000, "the head is shown ({} pixels)", lit.len());
    let (x0, x1) = (
        lit.iter().map(|p| p.0).min().unwrap(),
        lit.iter().map(|p| p.0).max().unwrap(),
    );
    let (y0, y1) = (
        lit.iter().map(|p| p.1).min().unwrap(),
        lit.iter().map(|p| p.1).max().unwrap(),
    );
    assert!(
        x0 > 0 && y0 > 0 && x1 < w - 1 && y1 < h - 1,
        "the head's box x {x0}..{x1}, y {y0}..{y1} runs to the edge of the {w}x{h} view"
    );
    let local = gizmo.translate(-view.min.to_vec2());
    let under: Vec<_> = lit
        .iter()
        .filter(|&&(x_, y_)| local.contains(egui::pos2(x_ as f32 + 0.5, y_ as f32 + 0.5)))
        .collect();
    assert!(
        under.is_empty(),
        "{} head pixels under the gizmo {local:?}, e.g. {:?}",
        under.len(),
        under.first()
    );
    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
