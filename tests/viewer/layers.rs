//! Layers in the viewer through real X input (xdotool under Xvfb): a volume opened with `--overlay` and `--labels`
//! (each on its own 2 mm grid over a 1 mm volume) in four-up. The axial slice shows the label map in its table's
//! red; hovering there names the label; the Layers section's checkbox hides it (from the slices, and from the 3D
//! view's frames: F12's settings), its remove button drops the overlay, and a path typed into its field adds the
//! overlay again; the Session section's *Open session* on an earlier F12 view state brings its layers back with the
//! looks it saved. Validation reports nothing.

use crate::common;
use crate::panel::{click, scroll_to, type_text};

use common::ui_wait::settled_rect;
use common::x11::{
    capture, four_up_rects, pointer, read_screenshot, screenshot_png, type_keys, x_session, Viewer, HOLD,
};
use image::RgbaImage;
use std::path::{Path, PathBuf};
use std::time::Duration;
use volcast::scene::layers::LayerKind;
use volcast::scene::settings::RenderSettings;

const SIZE: (f32, f32) = (900.0, 600.0);

/// An NRRD of `dims` voxels of `spacing` mm, of `type_name` (one little-endian value per voxel from `value`).
fn nrrd(path: &Path, dims: usize, spacing: f64, type_name: &str, value: impl Fn([usize; 3]) -> Vec<u8>) {
    let mut out = format!(
        "NRRD0004\ntype: {type_name}\ndimension: 3\nsizes: {dims} {dims} {dims}\nspacings: {spacing} {spacing} \
         {spacing}\nencoding: raw\nendian: little\n\n"
    )
    .into_bytes();
    for z in 0..dims {
        for y in 0..dims {
            for x in 0..dims {
                out.extend(value([x, y, z]));
            }
        }
    }
    std::fs::write(path, out).expect("write the test volume");
}

/// The volume (24³ at 1 mm, grey), a label map over it (12³ at 2 mm: id 7, "Thalamus" in red, in its middle) with
/// its table beside it, and an overlay (12³ at 2 mm: 5 in one corner, 0 elsewhere).
fn files(dir: &Path) -> [String; 3] {
    let inside = |v: [usize; 3], lo: usize, hi: usize| v.iter().all(|&c| (lo..hi).contains(&c));
    nrrd(&dir.join("base.nrrd"), 24, 1.0, "uint8", |_| vec![60]);
    nrrd(&dir.join("atlas.nrrd"), 12, 2.0, "uint8", |v| {
        vec![if inside(v, 4, 8) { 7 } else { 0 }]
    });
    std::fs::write(dir.join("atlas.ctbl"), "0 Background 0 0 0 0\n7 Thalamus 255 0 0 255\n").expect("table");
    let z = |v| if inside(v, 1, 3) { 5.0f32 } else { 0.0 };
    nrrd(&dir.join("zmap.nrrd"), 12, 2.0, "float", |v| {
        z(v).to_le_bytes().to_vec()
    });
    ["base.nrrd", "atlas.nrrd", "zmap.nrrd"].map(|f| dir.join(f).to_string_lossy().into_owned())
}

/// Pixels of the label's red in `rect`: the outline (255, 0, 0) and the fill (red at half opacity over grey).
fn red_pixels(image: &RgbaImage, rect: egui::Rect) -> usize {
    let mut n = 0;
    for y in rect.top() as u32..rect.bottom() as u32 {
        for x in rect.left() as u32..rect.right() as u32 {
            let [r, g, b, _] = image.get_pixel(x, y).0;
            n += usize::from(r > 120 && r > g.saturating_add(60) && g.abs_diff(b) < 20);
        }
    }
    n
}

/// F12: the 3D view's frame settings (what it marched with), its image's width, and the view state's file.
fn frame_settings(viewer: &mut Viewer, d: &str, w: &str, dir: &Path) -> (RenderSettings, u32, PathBuf) {
    viewer.drain();
    type_keys(d, w, &["F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (shot, settings) = read_screenshot(dir, &saved);
    (
        settings,
        shot.width(),
        screenshot_png(dir, &saved).with_extension("json"),
    )
}

#[test]
fn layers_show_hide_go_and_come_back_through_the_panel() {
    let Some((x, dir)) = x_session("viewer-layers") else {
        return;
    };
    let [base, atlas, zmap] = files(&dir);
    let args = [
        base.as_str(),
        "--labels",
        &atlas,
        "--overlay",
        &zmap,
        "--threshold",
        "2",
        "--slices",
    ];
    let mut viewer = Viewer::start(&x.display, &dir, &args, &format!("frames:3;{HOLD};exit"));
    viewer.wait_for("script: Hold", Duration::from_secs(180));
    let window = viewer.window(&x.display);
    let (d, w) = (x.display.as_str(), window.as_str());

    let (settings, width, first_state) = frame_settings(&mut viewer, d, w, &dir);
    let kinds: Vec<LayerKind> = settings.layers.iter().map(|l| l.kind).collect();
    assert_eq!(
        kinds,
        [LayerKind::Overlay, LayerKind::Labels],
        "the 3D view mixes both layers"
    );
    // The middle of the axial view, where the label lies: clear of the view's red frame and name.
    let view = four_up_rects(SIZE, width)[0];
    let axial = egui::Rect::from_center_size(view.center(), egui::Vec2::splat(view.width().min(view.height()) * 0.6));
    let red = red_pixels(&capture(d, w), axial);
    assert!(red > 100, "the axial slice shows the label map in red: {red} pixels");

    // The label under the pointer, named by its table (the crosshair, and the label, are in the middle).
    pointer(d, w, axial.center() + egui::vec2(3.0, 3.0));
    let probe = viewer.wait_for("ui label probe ", Duration::from_secs(60));
    let probe = if probe.contains("Thalamus") {
        probe
    } else {
        viewer.wait_for("atlas.nrrd: 7 Thalamus", Duration::from_secs(60))
    };
    assert!(
        probe.contains("zmap.nrrd: 0.000 | atlas.nrrd: 7 Thalamus | "),
        "{probe}"
    );

    let visible = scroll_to(&mut viewer, d, w, "layer-visible-1");
    click(d, w, egui::pos2(visible.left() + 8.0, visible.center().y));
    let (settings, _, _) = frame_settings(&mut viewer, d, w, &dir);
    assert!(!settings.layers[1].visible, "the 3D view's frames hide the label map");
    let hidden = red_pixels(&capture(d, w), axial);
    assert_eq!(hidden, 0, "the axial slice no longer shows the label map");

    let remove = scroll_to(&mut viewer, d, w, "layer-remove-0");
    click(d, w, remove.center());
    viewer.wait_for("ui gone layer-visible-1", Duration::from_secs(60));
    let (settings, _, _) = frame_settings(&mut viewer, d, w, &dir);
    assert_eq!(settings.layers.len(), 1, "the overlay is gone");
    assert_eq!(settings.layers[0].kind, LayerKind::Labels);

    let field = scroll_to(&mut viewer, d, w, "layer-path");
    click(d, w, field.center());
    type_text(d, w, &zmap);
    let add = settled_rect(&mut viewer, "layer-add-overlay");
    click(d, w, add.center());
    viewer.wait_for("layer added ", Duration::from_secs(60));
    let (settings, _, _) = frame_settings(&mut viewer, d, w, &dir);
    let kinds: Vec<LayerKind> = settings.layers.iter().map(|l| l.kind).collect();
    assert_eq!(
        kinds,
        [LayerKind::Overlay, LayerKind::Labels],
        "the overlay is back, before the label map"
    );
    assert!(!settings.layers[1].visible, "the label map kept its look");

    // The panel's Open session on the first F12's view state: its layers come back with the looks it saved.
    let remove = scroll_to(&mut viewer, d, w, "layer-remove-0");
    click(d, w, remove.center());
    viewer.wait_for("ui gone layer-visible-1", Duration::from_secs(60));
    let field = scroll_to(&mut viewer, d, w, "session-path");
    click(d, w, field.center());
    type_keys(d, w, &["ctrl+a"]);
    type_text(d, w, &first_state.display().to_string());
    let open = settled_rect(&mut viewer, "session-open");
    click(d, w, open.center());
    viewer.wait_for("layers restored 2", Duration::from_secs(60));
    let (settings, _, _) = frame_settings(&mut viewer, d, w, &dir);
    let kinds: Vec<LayerKind> = settings.layers.iter().map(|l| l.kind).collect();
    assert_eq!(kinds, [LayerKind::Overlay, LayerKind::Labels], "the session's layers");
    assert!(settings.layers[1].visible, "the label map as the session saved it");
    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
