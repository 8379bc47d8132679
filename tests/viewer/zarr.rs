//! An OME-Zarr store is a folder: dropped on the viewer by a real XDND source (`common::xdnd`, what a file
//! manager is), the window must accept the drop, load the store (its log says so) and show it: the F12 screenshot
//! equals the headless render of the same store (opened by `volume::open`) under the screenshot's settings.

use crate::common;

use common::compare::diff;
use common::x11::{have, read_screenshot, type_keys, xvfb, Viewer, HOLD};
use std::path::Path;
use std::time::Duration;
use volcast::gpu::{Gpu, GpuOptions};
use volcast::render::headless::Headless;

#[test]
fn viewer_loads_a_dropped_zarr_folder() {
    let Some(x) = xvfb() else { return };
    if !have("xdotool", "version") {
        common::skip("xdotool not found; apt-get install xdotool");
        return;
    }
    let dir = common::scratch("viewer-zarr-drop");
    let store = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/zarr/napari_czyx.zarr");
    let script = format!("frames:3;{HOLD};exit");
    let mut viewer = Viewer::start(&x.display, &dir, &["--builtin", "box", "--builtin-size", "16"], &script);
    viewer.wait_for("script: Hold", Duration::from_secs(180));
    let window = viewer.window(&x.display);
    let id: u32 = window.parse().expect("window id");
    let accepted = common::xdnd::drop_file(&x.display, id, (600, 300), &store).expect("XDND drop");
    assert!(accepted, "the window accepts the drop (XdndFinished)");
    let loaded = viewer.wait_for("load", Duration::from_secs(60));
    assert!(
        loaded.starts_with("loaded ") && loaded.ends_with("tests/data/zarr/napari_czyx.zarr"),
        "{loaded}"
    );
    // The level shown is named (the store's finest fits the device, so level 0 of its two).
    let level = viewer.wait_for("showing", Duration::from_secs(10));
    assert_eq!(level, "showing level 0 of 2 (8x6x4)");
    type_keys(&x.display, &window, &["F12"]);
    let (shot, settings) = read_screenshot(&dir, &viewer.wait_for("saved screenshot ", Duration::from_secs(60)));

    let gpu = Gpu::new(&GpuOptions {
        validation: true,
        ..Default::default()
    })
    .expect("Vulkan");
    let mut headless = Headless::new(&gpu).expect("renderer");
    let volume = volcast::volume::open(&store, &Default::default()).expect("volume");
    assert_eq!(volume.format, "OME-Zarr");
    headless.set_volume(&gpu, &volume).expect("upload");
    let expected = headless.render(&gpu, &settings).expect("render").image;
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    assert!(log.problems().is_empty(), "{:#?}", log.problems());
    let d = diff(&shot, &expected);
    assert!(
        d.max <= 1.0,
        "the dropped store's view differs from its headless render: {d}"
    );
    viewer.finish_clean();
}
