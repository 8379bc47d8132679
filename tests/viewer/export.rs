//! "Export figure" through real X input (xdotool under Xvfb): typed into the panel's width and height fields,
//! the figure is the session's view rendered offscreen at that size — at the view's own size without the colour
//! bar and the scale bar (on by default, switched off) it is F12's screenshot, and at 1600×1000 with both it is
//! exactly 1600×1000 with the colour bar at its right and the scale bar at its bottom left.

use crate::common;

use common::ui_wait::settled_rect;
use common::x11::{button, pointer, read_screenshot, type_keys, worst_channel_diff, x_session, Viewer};
use image::RgbaImage;
use std::time::Duration;

/// Clicks field `name`, replaces its text with `text`.
pub(crate) fn type_into(viewer: &mut Viewer, display: &str, window: &str, name: &str, text: &str) {
    pointer(display, window, viewer.ui_rect(name).center());
    button(display, "click", "1");
    let mut keys = vec!["ctrl+a"];
    let digits: Vec<String> = text.chars().map(String::from).collect();
    keys.extend(digits.iter().map(String::as_str));
    type_keys(display, window, &keys);
}

/// Clicks the colour bar's checkbox and waits for the viewer to say it is `state` ("on" or "off").
pub(crate) fn toggle_colorbar(viewer: &mut Viewer, display: &str, window: &str, state: &str) {
    pointer(display, window, viewer.ui_rect("export-colorbar").center());
    button(display, "click", "1");
    let said = viewer.wait_for("export figure: colour bar ", Duration::from_secs(30));
    assert!(said.ends_with(state), "{said}");
}

/// Clicks the scale bar's checkbox and waits for the viewer to say it is `state` ("on" or "off").
pub(crate) fn toggle_scale_bar(viewer: &mut Viewer, display: &str, window: &str, state: &str) {
    pointer(display, window, viewer.ui_rect("export-scale-bar").center());
    button(display, "click", "1");
    let said = viewer.wait_for("export figure: scale bar ", Duration::from_secs(30));
    assert!(said.ends_with(state), "{said}");
}

/// Clicks Export and reads the figure the viewer says it wrote.
pub(crate) fn export(viewer: &mut Viewer, display: &str, window: &str, dir: &std::path::Path) -> RgbaImage {
    pointer(display, window, viewer.ui_rect("export-button").center());
    button(display, "click", "1");
    let line = viewer.wait_for("exported figure ", Duration::from_secs(120));
    let name = line
        .split_once("exported figure ")
        .unwrap()
        .1
        .split(" (")
        .next()
        .unwrap()
        .trim()
        .to_string();
    // The path is absolute, so the message says where the figure is.
    let path = std::path::Path::new(&name);
    let file = path.file_name().unwrap().to_string_lossy();
    assert!(
        path.is_absolute() && dir.join(&*file).exists(),
        "{line}: in the working folder, named absolutely"
    );
    assert!(file.starts_with("volcast-20") && file.ends_with(".png"), "{line}");
    image::open(path).unwrap_or_else(|e| panic!("{name}: {e}")).to_rgba8()
}

/// Scrolls the panel until the "Export figure" section is in view and still.
pub(crate) fn scroll_to_export(viewer: &mut Viewer, display: &str, window: &str) {
    // Bring the section into view: the panel scrolls.
    pointer(display, window, egui::pos2(100.0, 300.0));
    for _ in 0..25 {
        button(display, "click", "5");
    }
    // The scroll glides: wait until the viewer says it came to rest.
    let at = settled_rect(viewer, "export-button");
    assert!(at.bottom() < 600.0, "the section scrolled into view: {at:?}");
}

#[test]
fn export_figure_renders_the_view_at_the_typed_size_with_the_colour_bar() {
    let Some((x, dir)) = x_session("viewer-export") else {
        return;
    };
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "helix", "--builtin-size", "64"]);
    let window = &window;
    type_keys(&x.display, window, &["F12"]);
    let (shot, _) = read_screenshot(&dir, &viewer.wait_for("saved screenshot ", Duration::from_secs(60)));
    let (w, h) = shot.dimensions();

    scroll_to_export(&mut viewer, &x.display, window);

    // At the view's size and without the bar, the figure is the view: F12's screenshot within 1/255.
    type_into(&mut viewer, &x.display, window, "export-width", &w.to_string());
    type_into(&mut viewer, &x.display, window, "export-height", &h.to_string());
    toggle_colorbar(&mut viewer, &x.display, window, "off");
    // The scale bar is on until switched off.
    toggle_scale_bar(&mut viewer, &x.display, window, "off");
    let same = export(&mut viewer, &x.display, window, &dir);
    assert_eq!(same.dimensions(), (w, h));
    let worst = worst_channel_diff(&same, &shot);
    assert!(worst <= 1, "the figure differs from the view by up to {worst}/255");

    // 1600×1000 with the colour bar: that size exactly, the bar's light ink (ticks, labels) at the right only.
    type_into(&mut viewer, &x.display, window, "export-width", "1600");
    type_into(&mut viewer, &x.display, window, "export-height", "1000");
    toggle_colorbar(&mut viewer, &x.display, window, "on");
    toggle_scale_bar(&mut viewer, &x.display, window, "on");
    let figure = export(&mut viewer, &x.display, window, &dir);
    assert_eq!(figure.dimensions(), (1600, 1000));
    // The scale bar: white, 6 rows ending 18 pixels above the bottom, from 18 pixels in (render/scale_bar.rs at
    // 1000 pixels high), at most a fifth of the render's width.
    let white = |x_: u32, y: u32| figure.get_pixel(x_, y).0[..3] == [255, 255, 255];
    let run = (18..1600).take_while(|&x_| white(x_, 980)).count();
    assert!((20..=1300 / 5).contains(&run), "a scale bar {run} pixels long");
    assert!(white(18, 976) && !white(18, 973) && !white(18, 982));
    let ink = |x0: u32, x1: u32| {
        (x0..x1)
            .flat_map(|x_| (0..1000).map(move |y| (x_, y)))
            .filter(|&(x_, y)| figure.get_pixel(x_, y).0[..3] == [235, 235, 235])
            .count()
    };
    assert!(ink(1500, 1600) > 100, "tick labels at the right: {}", ink(1500, 1600));
    assert_eq!(ink(0, 1300), 0, "no bar over the render");
    let lit = |x0: u32, x1: u32| {
        (x0..x1)
            .flat_map(|x_| (0..1000).map(move |y| (x_, y)))
            .filter(|&(x_, y)| figure.get_pixel(x_, y).0[..3] != [0, 0, 0])
            .count()
    };
    assert!(lit(200, 1300) > 10_000, "the volume is rendered left of the bar");
    viewer.finish_clean();
    let _ = std::fs::remove_dir_all(&dir);
}
