//! The clipping plane and the record button through real X input (xdotool under Xvfb), on an anatomical phantom
//! in the four-up layout:
//! - C shows a plane through the centre facing away from the viewer, and its line appears in each slice view it
//!   crosses;
//! - a drag on its ring turns it by the drag's length over the ring's radius, about the axis the drag implies;
//! - F12's screenshot equals `render --state` of its JSON to 1/255 (the GPU clips what the viewer showed), and
//!   differs from the same view unclipped;
//! - a drag of its handle along its arrow slides it by the arrow's length per arrow's screen length;
//! - F flips it;
//! - F9 records a GIF while the camera turns: every frame the view's size, the first and last different, the last
//!   near the still view F12 saves after it.
//!
//! Validation reports 0 messages.

use crate::common;

use common::x11::{
    capture, drag, four_up_rects, read_screenshot, render_state, type_keys, x_session, Rerendered, Viewer,
};
use image::RgbaImage;
use std::path::Path;
use std::time::Duration;
use volcast::scene::clip::ClipPlane;
use volcast::scene::slice::SliceView;
use volcast::scene::view_state::ViewState;
use volcast::viewer::model::Model;
use volcast::viewer::widgets::clip_plane::{self, ARROW, RING};
use volcast::viewer::widgets::slice_view;
use volcast::volume::Volume;

const SIZE: (f32, f32) = (900.0, 600.0);

/// The viewer's state for a saved session of `volume`, to say where its widgets are.
fn state_of(volume: &Volume, session: &ViewState) -> Model {
    let mut state = Model::new(volume.extent(), "phantom".into());
    state.set_volume(volume.extent(), volume.geometry, volume.dims, "phantom".into());
    state.restore(session);
    state
}

/// Pixels of the plane's colour (within 40/255 a channel) inside `r`.
fn plane_pixels(img: &RgbaImage, r: egui::Rect) -> usize {
    let c = clip_plane::COLOR;
    let mut n = 0;
    for y in r.top() as u32 + 1..r.bottom() as u32 - 1 {
        for x in r.left() as u32 + 1..r.right() as u32 - 1 {
            let p = img.get_pixel(x, y).0;
            if [c.r(), c.g(), c.b()].iter().zip(p).all(|(a, b)| a.abs_diff(b) <= 40) {
                n += 1;
            }
        }
    }
    n
}

fn plane(state: &ViewState) -> ClipPlane {
    state.settings.cut.clip_plane.expect("a clipping plane")
}

#[test]
fn the_clip_plane_is_dragged_flipped_and_drawn_and_f9_records() {
    let phantom = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/world/nifti_coronal.nii.gz");
    let volume = volcast::formats::open(&phantom, &Default::default()).expect("phantom");
    let Some((x, dir)) = x_session("viewer-clip") else {
        return;
    };
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &[phantom.to_str().unwrap(), "--slices"]);
    let window = &window;
    type_keys(&x.display, window, &["F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (shot, _) = read_screenshot(&dir, &saved);
    let [axial, three_d, sagittal, coronal] = four_up_rects(SIZE, shot.width());
    let views = [
        (SliceView::Axial, axial),
        (SliceView::Sagittal, sagittal),
        (SliceView::Coronal, coronal),
    ];
    let before = capture(&x.display, window);
    assert!(views.iter().all(|&(_, r)| plane_pixels(&before, r) < 5), "no plane yet");

    // C: a plane through the centre, facing away from the viewer.
    type_keys(&x.display, window, &["c"]);
    let shown = viewer.save_session(&x.display, window, &dir);
    let camera = shown.settings.camera;
    let forward = (camera.target - camera.eye).normalize();
    let p0 = plane(&shown);
    assert!(p0.normal().dot(forward) > 0.9999 && p0.offset() == 0.0, "{p0:?}");
    // Its line is in every slice view it is not parallel to (the window polled: the frame may still be coming).
    let mut state = state_of(&volume, &shown);
    let mm = volcast::scene::slice::mm_from_index(&state.geometry, state.look.voxel_axes);
    let (point, normal) = clip_plane::plane_in_slices(&state, &p0, mm);
    let crossing: Vec<_> = views
        .iter()
        .filter(|(view, rect)| {
            let frame = slice_view::frame_of(&state, *view, *rect, 1.0);
            frame.line_of_plane(point, normal).is_some()
        })
        .collect();
    let crossed = crossing.len();
    let polled = std::time::Instant::now();
    loop {
        let window_now = capture(&x.display, window);
        let counts: Vec<usize> = crossing.iter().map(|(_, r)| plane_pixels(&window_now, *r)).collect();
        if counts.iter().all(|&c| c > 40) {
            break;
        }
        assert!(
            polled.elapsed() < Duration::from_secs(5),
            "the plane's line in the {:?} views: {counts:?} pixels",
            crossing.iter().map(|(v, _)| v).collect::<Vec<_>>()
        );
        std::thread::sleep(Duration::from_millis(200));
    }
    assert!(crossed >= 2, "the plane crosses at least two slice views");

    // A drag to the right on the ring, from its top: a turn about the camera's up by length / RING.
    let h = clip_plane::handles(&state, three_d).expect("the widget");
    let handle = h.handle.expect("the handle on screen");
    drag(
        &x.display,
        window,
        "1",
        handle - egui::vec2(0.0, RING),
        egui::vec2(8.0, 0.0),
        4,
    );
    let turned = viewer.save_session(&x.display, window, &dir);
    let p1 = plane(&turned);
    let angle = p1.normal().angle_between(p0.normal());
    assert!((angle - 32.0 / RING).abs() <= 2.0 / RING, "turned by {angle} rad");
    let up = camera.up.normalize();
    assert!(
        p1.normal().dot(up).abs() < 0.02,
        "about the camera's up: {}",
        p1.normal()
    );
    assert!(turned.settings.camera == camera, "the camera stayed");

    // The GPU clips what the viewer showed: F12 equals `render --state`, and the unclipped view differs.
    let f12 = Rerendered::take(&mut viewer, &x.display, window, &dir);
    let (clipped, json) = (&f12.shot, &f12.json);
    let worst = f12.worst();
    assert!(worst <= 1, "render --state differs from F12 by up to {worst}/255");
    let mut unclipped = ViewState::from_json(&std::fs::read_to_string(json).unwrap(), "F12's JSON").unwrap();
    unclipped.settings.cut.clip_plane = None;
    let unclipped_json = dir.join("unclipped.json");
    std::fs::write(&unclipped_json, unclipped.to_json()).unwrap();
    let whole = render_state(&dir, &unclipped_json);
    assert!(
        common::x11::worst_channel_diff(&whole, clipped) > 20,
        "the plane cuts the volume"
    );

    // A drag of the handle along the arrow: the plane slides by ARROW per arrow's screen length.
    state = state_of(&volume, &turned);
    let h = clip_plane::handles(&state, three_d).expect("the widget");
    let (handle, tip) = (h.handle.unwrap(), h.tip.unwrap());
    let arrow = tip - handle;
    assert!(arrow.length() > 12.0, "the turned plane's arrow shows: {arrow:?}");
    let step = arrow.normalized() * 8.0;
    drag(&x.display, window, "1", handle, step, 4);
    let slid = viewer.save_session(&x.display, window, &dir);
    let p2 = plane(&slid);
    let wpm = volume.geometry.world_per_mm(volume.dims) as f32;
    let expected = ARROW * 32.0 / arrow.length() / wpm;
    let tolerance = ARROW * 2.0 / arrow.length() / wpm;
    assert!((p2.normal() - p1.normal()).length() < 1e-4, "sliding keeps the normal");
    let moved = p2.offset() - p1.offset();
    assert!(
        (moved - expected).abs() <= tolerance,
        "slid {moved} mm, expected {expected}"
    );

    // F flips it.
    type_keys(&x.display, window, &["f"]);
    let flipped = viewer.save_session(&x.display, window, &dir);
    let p3 = plane(&flipped);
    assert!((p3.normal() + p2.normal()).length() < 1e-6 && (p3.offset() + p2.offset()).abs() < 1e-4);

    // F9 records while the camera turns (a drag left of the plane's ring), F9 again writes the GIF.
    type_keys(&x.display, window, &["F9"]);
    let started = viewer.wait_for("recording ", Duration::from_secs(30));
    let from = egui::pos2(three_d.left() + 0.15 * three_d.width(), three_d.center().y);
    assert!(
        from.distance(h.handle.unwrap()) > RING + 10.0,
        "the camera drag misses the plane's widget"
    );
    drag(&x.display, window, "1", from, egui::vec2(10.0, 0.0), 6);
    std::thread::sleep(Duration::from_millis(800));
    type_keys(&x.display, window, &["F9"]);
    let saved_gif = viewer.wait_for("saved recording ", Duration::from_secs(60));
    let gif_name = started.split_once("recording ").unwrap().1.trim();
    assert!(saved_gif.contains(gif_name), "{saved_gif} names {gif_name}");
    type_keys(&x.display, window, &["F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (still, _) = read_screenshot(&dir, &saved);

    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let file = std::fs::File::open(dir.join(gif_name)).expect("the recording");
    let mut decoder = options.read_info(file).expect("a GIF");
    let (w, h) = (decoder.width(), decoder.height());
    assert_eq!(
        (u32::from(w), u32::from(h)),
        still.dimensions(),
        "frames are the view's size"
    );
    let mut frames = Vec::new();
    while let Some(f) = decoder.read_next_frame().expect("a frame") {
        assert_eq!((f.width, f.height, f.left, f.top), (w, h, 0, 0));
        assert!(f.delay >= 2, "delay {}", f.delay);
        frames.push(RgbaImage::from_raw(w.into(), h.into(), f.buffer.to_vec()).unwrap());
    }
    assert!(frames.len() >= 3, "{} frames", frames.len());
    let mean = |a: &RgbaImage, b: &RgbaImage| {
        let sum: u64 = a
            .pixels()
            .zip(b.pixels())
            .map(|(p, q)| (0..3).map(|c| u64::from(p.0[c].abs_diff(q.0[c]))).sum::<u64>())
            .sum();
        sum as f64 / (3.0 * f64::from(a.width() * a.height()))
    };
    let (first, last) = (&frames[0], frames.last().unwrap());
    assert!(mean(first, last) > 1.0, "the camera turned while recording");
    let quantised = mean(last, &still);
    assert!(
        quantised < 3.0,
        "the last frame is the still view, up to the GIF's palette: {quantised}"
    );

    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
