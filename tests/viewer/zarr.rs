//! An OME-Zarr store is a folder: dropped on the viewer by a real XDND source (`common::xdnd`, what a file
//! manager is), the window must accept the drop, load the store (its log says so) and show it: the F12 screenshot
//! equals the headless render of the same store (opened by `formats::open`) under the screenshot's settings.

use crate::common;

use super::formats::{drop_for_real, headless_render};
use common::compare::diff;
use common::x11::{have, read_screenshot, type_keys, xvfb};
use std::path::Path;
use std::time::Duration;

#[test]
fn viewer_loads_a_dropped_zarr_folder() {
    let Some(x) = xvfb() else { return };
    if !have("xdotool", "version") {
        common::skip("xdotool not found; apt-get install xdotool");
        return;
    }
    let dir = common::scratch("viewer-zarr-drop");
    let store = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/zarr/napari_czyx.zarr");
    let (mut viewer, window) = drop_for_real(&x.display, &dir, &store, "tests/data/zarr/napari_czyx.zarr");
    // The level shown is named (the store's finest fits the device, so level 0 of its two).
    let level = viewer.wait_for("showing", Duration::from_secs(10));
    assert_eq!(level, "showing level 0 of 2 (8x6x4)");
    type_keys(&x.display, &window, &["F12"]);
    let (shot, settings) = read_screenshot(&dir, &viewer.wait_for("saved screenshot ", Duration::from_secs(60)));
    let volume = volcast::formats::open(&store, &Default::default()).expect("volume");
    assert_eq!(volume.format, "OME-Zarr");
    let d = diff(&shot, &headless_render(&volume, &settings));
    assert!(
        d.max <= 1.0,
        "the dropped store's view differs from its headless render: {d}"
    );
    viewer.finish_clean();
}
