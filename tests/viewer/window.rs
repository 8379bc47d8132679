//! The desktop viewer in a real window under its own Xvfb, driven with real X input (xdotool, through the XTEST
//! extension: the same path as a keyboard), and what the X server shows in the window read back with `xwd`.
//!
//! The claim proven: the window shows exactly the image `volcast render` makes. The viewer starts on the helix
//! under validation, survives a resize, a 0×0 size and a minimize/restore (scripted: X has no deterministic way
//! to make a window 0×0), then waits while the test types Space (auto-rotate: the window must change), Space, R
//! and F12 with the panel shown, and Tab and F12 with it hidden. Each F12 writes the
//! view as a PNG with its `RenderSettings` as JSON. The window's pixels must equal the headless render of those
//! settings, and the PNG, within 1/255 (same `Renderer`, same shaders, same settings; the swapchain must add
//! nothing), everywhere except where egui draws over the view (bounding box lines, orientation gizmo). An sRGB
//! swapchain would encode the colours a second time: the check that the window is far from that image says the
//! bound would see it.
//! Validation with synchronization validation, swapchain included, reports 0 messages.
//!
//! Needs Xvfb (`xvfb`), xdotool (`xdotool`) and xwd (`x11-apps`); a missing one is a skip (a failure with CI=true).
//! A DISPLAY that is already set is not used: the test types keys, which must not land in someone's desktop.

use crate::common;

use common::x11::{capture, have, read_screenshot, type_keys, xvfb, Viewer, HOLD};

use image::RgbaImage;
use std::time::{Duration, Instant};
use volcast::gpu::{Gpu, GpuOptions};
use volcast::render::headless::Headless;
use volcast::scene::quality::Quality;
use volcast::scene::settings::RenderSettings;

/// Which pixels of the view (`view` in window pixels; 1 pixel per point under Xvfb) show the volume alone, and
/// not egui's overlay (`widgets::overlay::view_overlay`): the bounding box's 1-point lines (plus anti-aliasing
/// feather, hence 3 px), the orientation gizmo's disc (`framing::gizmo_place`: radius 52 centred 60 px from the
/// bottom-right corner at full size, smaller in small views) and the light
/// gizmo's from the top-right. The box is projected as the overlay projects it, from the frame's own camera.
pub(crate) fn volume_only(settings: &RenderSettings, extent: glam::Vec3, view: egui::Rect) -> Vec<bool> {
    let cam = &settings.camera;
    let view_proj = cam.projection(view.width() / view.height()) * cam.view();
    let corners: [Option<egui::Pos2>; 8] = std::array::from_fn(|i| {
        let t = glam::Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
        volcast::viewer::widgets::screen::project(view_proj, (t - glam::Vec3::splat(0.5)) * extent, view)
    });
    assert_eq!(
        (settings.cut.slab_lo, settings.cut.slab_hi),
        (glam::Vec3::ZERO, glam::Vec3::ONE),
        "no slab box is drawn"
    );
    let mut edges = Vec::new();
    for a in 0..8 {
        for bit in [1, 2, 4] {
            if a & bit == 0 {
                if let (Some(p), Some(q)) = (corners[a], corners[a | bit]) {
                    edges.push((p, q));
                }
            }
        }
    }
    let distance = |p: egui::Pos2, (a, b): (egui::Pos2, egui::Pos2)| {
        let ab = b - a;
        let t = ((p - a).dot(ab) / ab.length_sq().max(1e-6)).clamp(0.0, 1.0);
        (p - (a + t * ab)).length()
    };
    // The orientation gizmo where the viewer places it (smaller in small views), plus 3 px of feather.
    let place = volcast::viewer::model::framing::gizmo_place(view);
    let (gizmo, gizmo_radius) = (egui::pos2(place.centre.x, place.centre.y), place.disc + 3.0);
    // The light gizmo (`light_gizmo`, shown on lit frames): a disc of radius 36 in the top-right corner.
    let light = egui::pos2(view.right() - 60.0, view.top() + 60.0);
    let (w, h) = (view.width() as u32, view.height() as u32);
    (0..w * h)
        .map(|i| {
            let p = egui::pos2(view.left() + (i % w) as f32 + 0.5, view.top() + (i / w) as f32 + 0.5);
            (p - gizmo).length() > gizmo_radius
                && (p - light).length() > 52.0
                && edges.iter().all(|&e| distance(p, e) > 3.0)
        })
        .collect()
}

/// The image a swapchain that encodes to sRGB would show: the renderer's output, already display-encoded,
/// encoded once more.
fn encoded_twice(image: &RgbaImage) -> RgbaImage {
    let again = |c: u8| {
        let v = f64::from(c) / 255.0;
        let e = if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (e * 255.0).round() as u8
    };
    RgbaImage::from_fn(image.width(), image.height(), |x, y| {
        let p = image.get_pixel(x, y);
        image::Rgba([again(p[0]), again(p[1]), again(p[2]), 255])
    })
}

fn is_lit(p: &image::Rgba<u8>) -> bool {
    u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]) > 30
}

/// Captures the view (`view` of the window) until it equals the F12 screenshot outside the overlay, for at
/// most a few seconds (the frame F12 saved was presented before the file was written, but the X server may put it
/// a moment later; later frames draw the same). Returns the last capture.
pub(crate) fn capture_view(
    display: &str,
    window: &str,
    view: egui::Rect,
    shot: &RgbaImage,
    mask: &[bool],
) -> RgbaImage {
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        let whole = capture(display, window);
        let (x, y) = (view.left() as u32, view.top() as u32);
        let (w, h) = (view.width() as u32, view.height() as u32);
        assert!(
            x + w <= whole.width() && y + h <= whole.height(),
            "view {view:?} in a {}x{} window",
            whole.width(),
            whole.height()
        );
        let region = image::imageops::crop_imm(&whole, x, y, w, h).to_image();
        if common::compare::diff_where(&region, shot, mask).max <= 1.0 || Instant::now() > deadline {
            return region;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// The window's view must be the headless render and the F12 PNG, within 1/255, outside the overlay; and far from
/// what an sRGB swapchain would show.
pub(crate) fn assert_window_shows(
    name: &str,
    window: &RgbaImage,
    shot: &RgbaImage,
    expected: &RgbaImage,
    mask: &[bool],
) {
    let compared = mask.iter().filter(|&&m| m).count();
    assert!(
        compared > mask.len() * 3 / 4,
        "{name}: the overlay mask leaves only {compared} of {} pixels",
        mask.len()
    );
    for (what, other) in [("the F12 screenshot", shot), ("the headless render", expected)] {
        let d = common::compare::diff_where(window, other, mask);
        if d.max > 1.0 {
            common::compare::write_failure_images(&format!("viewer-{name}"), window, other);
            panic!("{name}: the window differs from {what} outside the overlay: {d}");
        }
    }
    let lit: Vec<bool> = expected.pixels().zip(mask).map(|(p, &m)| m && is_lit(p)).collect();
    let lit_count = lit.iter().filter(|&&l| l).count();
    assert!(
        lit_count > mask.len() / 20,
        "{name}: the helix is visible ({lit_count} pixels lit)"
    );
    let twice = common::compare::diff_where(window, &encoded_twice(expected), &lit);
    assert!(
        twice.mean > 10.0,
        "{name}: the window is not far from the doubly sRGB-encoded image ({twice}), so the check above could \
         not tell an sRGB swapchain from a UNORM one"
    );
    eprintln!("{name}: window = headless render outside the overlay ({compared} px); doubly encoded would be {twice}");
}

#[test]
fn viewer_window_shows_the_headless_render_and_survives_resizes() {
    let Some(x) = xvfb() else { return };
    for (tool, arg, package) in [("xdotool", "version", "xdotool"), ("xwd", "-help", "x11-apps")] {
        if !have(tool, arg) {
            common::skip(&format!("{tool} not found; apt-get install {package}"));
            return;
        }
    }
    let dir = common::scratch("viewer");
    let started = Instant::now();

    // Scripted: what X cannot do deterministically (a 0×0 size) and the frames in between; then the window stays
    // open for the test's input, and the script ends the session so that the validation summary is printed.
    let script = format!(
        "frames:3;screenshot:with-panel.png;resize:640x480;frames:2;zero-size;frames:2;restore;minimize;frames:2;\
         restore;frames:2;{HOLD};exit"
    );
    let mut viewer = Viewer::start(&x.display, &dir, &["--builtin", "helix"], &script);
    let helix = volcast::volume::builtin("helix", None).unwrap();
    viewer.wait_for("script: Hold", Duration::from_secs(180));
    let waiting = Instant::now();
    let window = &viewer.window(&x.display);

    // Space starts auto-rotation, which must show: the same key path as a user's.
    let before = capture(&x.display, window);
    assert_eq!(before.dimensions(), (640, 480), "the window after resize:640x480");
    type_keys(&x.display, window, &["space"]);
    // The first turned frame shows when the machine gets to it: watched for, not slept for.
    let deadline = Instant::now() + Duration::from_secs(60);
    while capture(&x.display, window).as_raw() == before.as_raw() {
        assert!(Instant::now() < deadline, "Space (auto-rotate) changes the window");
        std::thread::sleep(Duration::from_millis(100));
    }

    // Panel shown: the view is the part of the window right of it.
    type_keys(&x.display, window, &["space", "r", "F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (shot_panel, settings_panel) = read_screenshot(&dir, &saved);
    let (w, h) = shot_panel.dimensions();
    assert!(w > 200 && w < 640 && h == 480, "the view right of the panel is {w}x{h}");
    let view_panel = egui::Rect::from_min_size(egui::pos2((640 - w) as f32, 0.0), egui::vec2(w as f32, h as f32));
    let mask_panel = volume_only(&settings_panel, helix.extent(), view_panel);
    let window_panel = capture_view(&x.display, window, view_panel, &shot_panel, &mask_panel);
    // The viewer starts at `render`'s default quality; Q lowers it one level, and the next frame takes that
    // level's step (resolved from the transfer function, as `render --quality fast` resolves it).
    let normal = Quality::Normal.step_length(&settings_panel, helix.range);
    assert_eq!(
        settings_panel.sampling.step_length, normal,
        "the viewer's default quality is normal"
    );
    type_keys(&x.display, window, &["q", "F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (_, settings_fast) = read_screenshot(&dir, &saved);
    let fast = Quality::Fast.step_length(&settings_fast, helix.range);
    assert!(fast > normal, "fast {fast} against normal {normal}");
    assert_eq!(settings_fast.sampling.step_length, fast, "Q: normal → fast");
    // S shades, with gradients from the texture (`render --gradients auto`): the window must show what the
    // headless renderer makes of those settings. S again turns shading off for the rest.
    type_keys(&x.display, window, &["s", "F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (shot_shaded, settings_shaded) = read_screenshot(&dir, &saved);
    assert!(settings_shaded.lighting.shading.is_some(), "S: shading on");
    assert!(
        settings_shaded.lighting.gradient_texture,
        "shaded frames take the gradient texture"
    );
    let mask_shaded = volume_only(&settings_shaded, helix.extent(), view_panel);
    let window_shaded = capture_view(&x.display, window, view_panel, &shot_shaded, &mask_shaded);
    type_keys(&x.display, window, &["s"]);

    // Tab hides the panel, and F12 right after it works (keys.rs: Tab no longer moves egui's focus).
    type_keys(&x.display, window, &["Tab", "F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (shot_full, settings_full) = read_screenshot(&dir, &saved);
    assert_eq!(
        shot_full.dimensions(),
        (640, 480),
        "the whole window once Tab hid the panel"
    );
    let view_full = egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(640.0, 480.0));

    let mask_full = volume_only(&settings_full, helix.extent(), view_full);
    let window_full = capture_view(&x.display, window, view_full, &shot_full, &mask_full);
    eprintln!(
        "input and captures took {:.1} s while the viewer held its window open",
        waiting.elapsed().as_secs_f64()
    );

    // Rendered while the viewer still waits (both on one lavapipe, so slower, but the wait is spent anyway).
    let gpu = Gpu::new(&GpuOptions {
        validation: true,
        ..Default::default()
    })
    .expect("Vulkan");
    let mut headless = Headless::new(&gpu).expect("renderer");
    headless.set_volume(&gpu, &helix).unwrap();
    let expected_panel = headless.render(&gpu, &settings_panel).expect("render").image;
    let expected_full = headless.render(&gpu, &settings_full).expect("render").image;
    headless
        .renderer
        .enable_gradient_texture(&gpu, &helix)
        .expect("gradients");
    let expected_shaded = headless.render(&gpu, &settings_shaded).expect("render").image;
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    assert!(log.problems().is_empty(), "{:#?}", log.problems());

    assert_window_shows("with-panel", &window_panel, &shot_panel, &expected_panel, &mask_panel);
    assert_window_shows("panel-hidden", &window_full, &shot_full, &expected_full, &mask_full);
    assert_window_shows("shaded", &window_shaded, &shot_shaded, &expected_shaded, &mask_shaded);
    let defaults = RenderSettings::new(640, 480, helix.extent());
    assert!(
        (settings_full.camera.eye - defaults.camera.eye).length() < 1e-4,
        "R resets the view after auto-rotating"
    );

    viewer.finish_clean();
    // The scripted screenshot at 900x600, before the resize: the view right of the panel.
    let with_panel = image::open(dir.join("with-panel.png"))
        .expect("scripted screenshot")
        .to_rgba8();
    assert!(
        with_panel.width() < 900 && with_panel.width() > 400 && with_panel.height() == 600,
        "{:?}",
        with_panel.dimensions()
    );
    eprintln!("viewer test took {:.1} s", started.elapsed().as_secs_f64());
}

#[test]
fn viewer_without_a_display_says_so_and_points_to_render() {
    let out = common::volcast_command()
        .args(["view", "--builtin", "box", "--builtin-size", "8"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("run volcast");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains("volcast render"), "{stderr}");
}
