//! `draft`'s spaced rays (rule 12: one ray per 2×2 pixels, stretched) in the viewer's window, through real X
//! input: the helix opens at `normal`; a click on the panel's "multiplied alpha" makes its opacity rise from 0 at
//! the window's edge (a soft classification), Q twice lowers the quality to `draft`, Tab hides the panel and F12
//! saves the view with its settings. Those settings must space the rays, and the window must show the headless
//! render of them within 1/255 outside egui's overlay, and not the unspaced render (which differs by more).
//! Validation reports 0 messages.

use crate::common;
use crate::panel::{click, scroll_to};
use crate::window::{assert_window_shows, capture_view, volume_only};

use common::x11::{read_screenshot, type_keys, x_session, Viewer};
use std::time::Duration;
use volcast::render::headless::Headless;
use volcast::scene::quality::Quality;

#[test]
fn draft_on_a_soft_classification_shows_its_spaced_rays_as_rendered_headless() {
    let Some((x, dir)) = x_session("viewer-spaced") else {
        return;
    };
    let helix = volcast::volume::builtin("helix", None).unwrap();
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "helix"]);
    let window = &window;
    let (d, w) = (x.display.as_str(), window.as_str());

    let multiplied = scroll_to(&mut viewer, d, w, "multiplied-alpha");
    click(d, w, multiplied.center());
    type_keys(d, w, &["q", "q", "Tab", "F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (shot, settings) = read_screenshot(&dir, &saved);
    assert!(settings.colour.multiplied_alpha, "the click turned multiplied alpha on");
    assert_eq!(
        settings.sampling.step_length,
        Quality::Draft.step_length(&settings, helix.range),
        "Q twice: normal → fast → draft"
    );
    assert_eq!(
        settings.sampling.ray_spacing, 2,
        "draft spaces its rays on a soft classification"
    );
    let (width, height) = shot.dimensions();
    let view = egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(width as f32, height as f32));
    let mask = volume_only(&settings, helix.extent(), view);
    let shown = capture_view(d, w, view, &shot, &mask);

    let gpu = common::gpu::validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    headless.set_volume(&gpu, &helix).unwrap();
    let spaced = headless.render(&gpu, &settings).expect("render").image;
    let mut every_pixel = settings.clone();
    every_pixel.sampling.ray_spacing = 1;
    let unspaced = headless.render(&gpu, &every_pixel).expect("render").image;
    common::gpu::close(gpu, headless);

    assert_window_shows("spaced", &shown, &shot, &spaced, &mask);
    let apart = common::compare::diff_where(&shown, &unspaced, &mask);
    assert!(
        apart.max > 1.0,
        "the window is as close to the unspaced render ({apart}), so the check above could not tell spaced rays"
    );
    eprintln!("spaced: window = headless spaced render; the unspaced render differs by {apart}");

    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
