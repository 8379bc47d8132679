//! Screenshots and recordings through real X input (xdotool under Xvfb): their files are named by the local date
//! and time (`volcast-2026-11-26_12-03-45.png`, `-2` for a second one in the same second), the window's title
//! names the volume shown (and follows a dropped file), and Shift+F12 / Shift+F9 capture the view as shown — the
//! orientation gizmo and box outline over the render that F12 and F9 capture clean.

use crate::common;

use common::x11::{read_screenshot, type_keys, x_client, x_session, Viewer};
use image::RgbaImage;
use std::path::Path;
use std::time::Duration;

/// `volcast-YYYY-MM-DD_HH-MM-SS` (and `-N` when that second was taken) with extension `ext`: the stem, or None.
fn readable_stem<'a>(name: &'a str, ext: &str) -> Option<&'a str> {
    let stem = name.strip_prefix("volcast-")?.strip_suffix(&format!(".{ext}"))?;
    let (time, _) = stem.split_at_checked(19)?;
    let shape = time.bytes().enumerate().all(|(i, b)| match i {
        4 | 7 | 13 | 16 => b == b'-',
        10 => b == b'_',
        _ => b.is_ascii_digit(),
    });
    let rest = &stem[19..];
    let numbered = rest.is_empty()
        || rest
            .strip_prefix('-')
            .is_some_and(|n| n.parse::<u32>().is_ok_and(|n| n >= 2));
    (shape && numbered).then_some(time)
}

fn window_name(display: &str, window: &str) -> String {
    String::from_utf8_lossy(&x_client(display, "xdotool", &["getwindowname", window]))
        .trim()
        .to_string()
}

/// The file name in a "saved screenshot PATH" line. PATH is absolute: a relative one does not say where it is.
fn saved_name(line: &str) -> String {
    let path = Path::new(line.split_once("saved screenshot ").expect("a saved line").1.trim());
    assert!(path.is_absolute(), "{line}: the path is absolute");
    path.file_name().expect("a file name").to_string_lossy().into_owned()
}

/// Pixels within `tolerance` of `rgb` in every channel.
fn count_colour(image: &RgbaImage, rgb: [u8; 3], tolerance: u8) -> usize {
    image
        .pixels()
        .filter(|p| (0..3).all(|c| p.0[c].abs_diff(rgb[c]) <= tolerance))
        .count()
}

#[test]
fn captures_have_readable_names_and_the_title_names_the_volume() {
    let Some((x, dir)) = x_session("viewer-capture-names") else {
        return;
    };
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "helix", "--builtin-size", "64"]);
    let window = &window;
    assert_eq!(window_name(&x.display, window), "helix — volcast");

    // Two quick presses: two files, both named by the time, the second numbered when in the same second.
    type_keys(&x.display, window, &["F12", "F12"]);
    let first = saved_name(&viewer.wait_for("saved screenshot ", Duration::from_secs(60)));
    let second = saved_name(&viewer.wait_for("saved screenshot ", Duration::from_secs(60)));
    let t1 = readable_stem(&first, "png").unwrap_or_else(|| panic!("{first} is not volcast-<date>_<time>.png"));
    let t2 = readable_stem(&second, "png").unwrap_or_else(|| panic!("{second} is not volcast-<date>_<time>.png"));
    assert_ne!(first, second, "each press its own file");
    if t1 == t2 {
        assert_eq!(second, format!("volcast-{t1}-2.png"), "the same second gets -2");
    }
    for name in [&first, &second] {
        assert!(
            dir.join(name).exists() && dir.join(name).with_extension("json").exists(),
            "{name}"
        );
    }

    // The recording too.
    type_keys(&x.display, window, &["F9"]);
    let started = viewer.wait_for("recording ", Duration::from_secs(30));
    std::thread::sleep(Duration::from_millis(500));
    type_keys(&x.display, window, &["F9"]);
    viewer.wait_for("saved recording ", Duration::from_secs(60));
    let gif = Path::new(started.split_once("recording ").unwrap().1.trim());
    assert!(gif.is_absolute(), "{started}: the path is absolute");
    let gif = gif.file_name().unwrap().to_str().unwrap();
    assert!(
        readable_stem(gif, "gif").is_some(),
        "{gif} is not volcast-<date>_<time>.gif"
    );
    assert!(dir.join(gif).exists(), "{gif}");

    // Another volume dropped on the window: the title follows it.
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk/vti_zlib.vti");
    let id: u32 = window.parse().expect("window id");
    assert!(common::xdnd::drop_file(&x.display, id, (600, 300), &file).expect("XDND drop"));
    viewer.wait_for("loaded ", Duration::from_secs(60));
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(window_name(&x.display, window), "vti_zlib.vti — volcast");
    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn shift_captures_the_view_as_shown() {
    let Some((x, dir)) = x_session("viewer-capture-shown") else {
        return;
    };
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "helix", "--builtin-size", "64"]);
    let window = &window;
    type_keys(&x.display, window, &["F12", "shift+F12"]);
    let clean_line = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let shown_line = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let (clean, _) = read_screenshot(&dir, &clean_line);
    let (shown, _) = read_screenshot(&dir, &shown_line);
    assert!(readable_stem(&saved_name(&shown_line), "png").is_some(), "{shown_line}");
    assert_eq!(clean.dimensions(), shown.dimensions(), "both are the 3D view");

    // The orientation gizmo (60 points in from the bottom-right corner; the X axis end in its red) is in the
    // shown image only; elsewhere only the box outline's thin lines differ.
    let (w, h) = (clean.width() as f32, clean.height() as f32);
    let centre = egui::pos2(w - 60.0, h - 60.0);
    let red = [230, 70, 70];
    assert!(
        count_colour(&shown, red, 6) > 20,
        "the gizmo's red X axis is in the view as shown"
    );
    assert_eq!(count_colour(&clean, red, 6), 0, "and not in the clean render");
    let (mut in_gizmo, mut gizmo_area, mut outside) = (0, 0, 0);
    for (x_, y_, p) in shown.enumerate_pixels() {
        let differs = (0..3).any(|c| p.0[c].abs_diff(clean.get_pixel(x_, y_).0[c]) > 2);
        if egui::pos2(x_ as f32 + 0.5, y_ as f32 + 0.5).distance(centre) < 50.0 {
            gizmo_area += 1;
            in_gizmo += usize::from(differs);
        } else {
            outside += usize::from(differs);
        }
    }
    assert!(
        in_gizmo > 300,
        "the gizmo's axes are drawn: {in_gizmo} of {gizmo_area} pixels differ"
    );
    let rest = (clean.width() * clean.height()) as usize - gizmo_area;
    assert!(
        outside > 50,
        "the box outline is drawn in the view as shown ({outside} pixels differ)"
    );
    assert!(
        outside * 10 < rest,
        "outside the gizmo only thin lines differ: {outside} of {rest}"
    );

    // Shift+F9 records the view as shown: the gizmo's red is in its frames.
    type_keys(&x.display, window, &["shift+F9"]);
    let started = viewer.wait_for("recording ", Duration::from_secs(30));
    assert!(started.ends_with("(as shown)"), "{started}");
    std::thread::sleep(Duration::from_millis(400));
    type_keys(&x.display, window, &["shift+F9"]);
    viewer.wait_for("saved recording ", Duration::from_secs(60));
    let gif = started
        .split_once("recording ")
        .unwrap()
        .1
        .trim_end_matches(" (as shown)")
        .trim();
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options
        .read_info(std::fs::File::open(dir.join(gif)).expect("the GIF"))
        .expect("a GIF");
    let (gw, gh) = (u32::from(decoder.width()), u32::from(decoder.height()));
    let frame = decoder.read_next_frame().expect("a frame").expect("one frame at least");
    let first = RgbaImage::from_raw(gw, gh, frame.buffer.to_vec()).expect("RGBA");
    // The view is still: the frame is the view as shown, up to the GIF's palette, around the gizmo most of all.
    let near = |a: &RgbaImage, b: &RgbaImage| {
        let mut sum = 0u64;
        for (x_, y_, p) in a.enumerate_pixels() {
            if egui::pos2(x_ as f32, y_ as f32).distance(centre) < 50.0 {
                sum += (0..3)
                    .map(|c| u64::from(p.0[c].abs_diff(b.get_pixel(x_, y_).0[c])))
                    .sum::<u64>();
            }
        }
        sum
    };
    let (to_shown, to_clean) = (near(&first, &shown), near(&first, &clean));
    assert!(
        to_shown * 3 < to_clean,
        "the recording shows the gizmo: off the view as shown by {to_shown}, off the clean one by {to_clean}"
    );
    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
