//! The series chooser through real X input (xdotool under Xvfb): a DICOM folder holding three series (made at run
//! time from the shared MRI series, `common::dicom_series`) opens with the series `--series` names, the panel
//! shows a combo box of the three, and a click on another series in it loads that one. Where the combo box and
//! its items are comes from the viewer's `ui rect` lines; the input is X's. Validation reports 0 messages.

use crate::common;

use common::dicom_series;
use common::x11::{button, pointer, x_session, Viewer, WAIT_MS};
use std::time::{Duration, Instant};

/// The rectangle of `name` once the viewer has drawn it (the popup's items come a frame after the click).
fn rect_when_drawn(viewer: &mut Viewer, name: &str) -> egui::Rect {
    let deadline = Instant::now() + Duration::from_secs(30);
    let prefix = format!("ui rect {name} ");
    loop {
        viewer.drain();
        if viewer.stderr.lines().any(|l| l.starts_with(&prefix)) {
            return viewer.ui_rect(name);
        }
        assert!(Instant::now() < deadline, "{name} was never drawn:\n{}", viewer.stderr);
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn the_chooser_lists_the_series_and_loads_the_one_clicked() {
    let Some((x, dir)) = x_session("viewer-series") else {
        return;
    };
    let Some(folder) = dicom_series::make(&dir.join("mixed")) else {
        common::skip("no shared DICOM series (../shared/data/native/brain_pd_mr)");
        return;
    };
    let folder = folder.to_string_lossy().into_owned();
    let script = format!("frames:3;wait:{};exit", WAIT_MS * 2);
    let mut viewer = Viewer::start(&x.display, &dir, &[&folder, "--series", "903"], &script);
    let first = viewer.wait_for("loaded ", Duration::from_secs(180));
    assert!(first.ends_with("mixed (series 903)"), "{first}");
    viewer.wait_for("script: Wait(", Duration::from_secs(60));
    let window = &viewer.window(&x.display);
    let (d, w) = (x.display.as_str(), window.as_str());

    let combo = rect_when_drawn(&mut viewer, "series-combo");
    pointer(d, w, combo.center());
    button(d, "click", "1");
    // Items in the series' number order: 901 (4 slices), 902 (6), 903 (2).
    let item = rect_when_drawn(&mut viewer, "series-item-0");
    assert!(
        item.top() >= combo.bottom() - 1.0,
        "the list opens below the box: {item:?} {combo:?}"
    );
    assert!(rect_when_drawn(&mut viewer, "series-item-2").top() > item.top());
    pointer(d, w, item.center());
    button(d, "click", "1");
    let picked = viewer.wait_for("loaded ", Duration::from_secs(120));
    assert!(picked.ends_with("mixed (series 901)"), "{picked}");
    viewer.finish_clean();
}
