//! The series chooser through real X input (xdotool under Xvfb): a DICOM folder holding three series (made at run
//! time from the shared MRI series, `common::dicom_series`) opens with the series `--series` names, the panel
//! shows a combo box of the three, and a click on another series in it loads that one. Where the combo box and
//! its items are comes from the viewer's `ui rect` lines; the input is X's. Validation reports 0 messages.

use crate::common;

use common::dicom_series;
use common::ui_wait::settled_rect;
use common::x11::{button, pointer, x_session, Viewer, HOLD};
use std::time::Duration;

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
    let script = format!("frames:3;{HOLD};exit");
    let mut viewer = Viewer::start(&x.display, &dir, &[&folder, "--series", "903"], &script);
    let first = viewer.wait_for("loaded ", Duration::from_secs(180));
    assert!(first.ends_with("mixed (series 903)"), "{first}");
    viewer.wait_for("script: Hold", Duration::from_secs(60));
    let window = &viewer.window(&x.display);
    let (d, w) = (x.display.as_str(), window.as_str());

    let combo = settled_rect(&mut viewer, "series-combo");
    // Series 903's description is 64 characters: the box cuts it short within the panel, and the transfer
    // function's editor below keeps its place inside the panel too (it was pushed past the window's edge).
    let panel = volcast::viewer::widgets::layout::PANEL_WIDTH;
    assert!(
        combo.right() <= panel,
        "the series box {combo:?} runs past the panel ({panel})"
    );
    let plot = settled_rect(&mut viewer, "tf-plot");
    assert!(
        plot.right() <= panel,
        "the transfer function editor {plot:?} runs past the panel ({panel})"
    );
    pointer(d, w, combo.center());
    button(d, "click", "1");
    // Items in the series' number order: 901 (4 slices), 902 (6), 903 (2).
    let item = settled_rect(&mut viewer, "series-item-0");
    assert!(
        item.top() >= combo.bottom() - 1.0,
        "the list opens below the box: {item:?} {combo:?}"
    );
    assert!(settled_rect(&mut viewer, "series-item-2").top() > item.top());
    pointer(d, w, item.center());
    button(d, "click", "1");
    let picked = viewer.wait_for("loaded ", Duration::from_secs(120));
    assert!(picked.ends_with("mixed (series 901)"), "{picked}");
    viewer.finish_clean();
}

/// A file of a series given alone (as Open…, a drop or `volcast FILE` give it) loads its whole series, and the panel
/// lists the folder's others. Slice 2 belongs to series 901 (4 slices), not the largest.
#[test]
fn one_file_of_a_series_loads_the_series() {
    let Some((x, dir)) = x_session("viewer-series-one-file") else {
        return;
    };
    let Some(folder) = dicom_series::make(&dir.join("mixed")) else {
        common::skip("no shared DICOM series (../shared/data/native/brain_pd_mr)");
        return;
    };
    let file = folder.join("slice_002.dcm").to_string_lossy().into_owned();
    let script = format!("frames:3;{HOLD};exit");
    let mut viewer = Viewer::launch(&x.display, &dir, &[&file], &script);
    viewer.wait_for("loaded ", Duration::from_secs(180));
    let holds = viewer.wait_for("holds ", Duration::from_secs(10));
    assert!(holds.ends_with("256x256x4 voxels"), "{holds}");
    viewer.wait_for("script: Hold", Duration::from_secs(60));
    let combo = settled_rect(&mut viewer, "series-combo");
    assert!(combo.width() > 0.0, "the panel lists the folder's series");
    viewer.finish_clean();
}
