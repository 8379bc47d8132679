//! The desktop viewer opens every format of issue 12 the way a dropped file is opened: the script's `drop:PATH`
//! step calls the window's `DroppedFile` handler path (`FileFields::load_action`, then the background load),
//! under its own Xvfb and validation. For each file the viewer must say it loaded, and its F12-path screenshot
//! must equal, within 1/255, the headless render of the same file (opened by `formats::open`) under the
//! screenshot's own settings; a time series opens on step 0.
//!
//! A second test drops a file for real: `common::xdnd` is an XDND drag source (what a file manager is), so the
//! drop goes through the X server and the window's own XDND handling, which xdotool cannot drive.

use crate::common;

use common::compare::diff;
use common::x11::{have, read_screenshot, type_keys, xvfb, Viewer, HOLD};
use std::path::Path;
use std::time::Duration;
use volcast::gpu::{Gpu, GpuOptions};
use volcast::render::headless::Headless;
use volcast::scene::settings::RenderSettings;

const FILES: &[&str] = &[
    "vtk/vti_zlib.vti",
    "vtk/legacy_u8_binary.vtk",
    "tiff/u16_imagej_lzw.tif",
    "tiff/stack",
    "dicom/u16_j2k",
    "dicom/enhanced_ct_rle.dcm",
    "time/fmri_f32.nii.gz",
];

#[test]
fn viewer_opens_every_new_format_as_a_dropped_file() {
    let Some(x) = xvfb() else { return };
    if !have("xdotool", "version") {
        common::skip("xdotool not found; apt-get install xdotool");
        return;
    }
    let dir = common::scratch("viewer-formats");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut script = String::from("frames:2;");
    for (i, f) in FILES.iter().enumerate() {
        script += &format!("drop:{};frames:2;screenshot:shot{i}.png;", data.join(f).display());
    }
    script += "exit";
    let mut viewer = Viewer::start(&x.display, &dir, &["--builtin", "box", "--builtin-size", "16"], &script);
    for f in FILES {
        let line = viewer.wait_for("script: load", Duration::from_secs(120));
        assert!(line.contains("script: loaded"), "{f}: {line}");
    }
    viewer.finish_clean();

    let gpu = Gpu::new(&GpuOptions {
        validation: true,
        ..Default::default()
    })
    .expect("Vulkan");
    let mut headless = Headless::new(&gpu).expect("renderer");
    for (i, f) in FILES.iter().enumerate() {
        let png = dir.join(format!("shot{i}.png"));
        let shot = image::open(&png).unwrap_or_else(|e| panic!("{f}: {e}")).to_rgba8();
        let json = std::fs::read_to_string(png.with_extension("json")).expect("settings beside the screenshot");
        let settings: RenderSettings = serde_json::from_str(&json).expect("settings JSON");
        let volume = volcast::formats::open(&data.join(f), &Default::default()).expect("volume");
        assert_eq!(volume.shown_step(), 0);
        headless.set_volume(&gpu, &volume).expect("upload");
        let expected = headless.render(&gpu, &settings).expect("render").image;
        let d = diff(&shot, &expected);
        assert!(
            d.max <= 1.0,
            "{f}: the viewer's view differs from the headless render: {d}"
        );
        let lit = shot
            .pixels()
            .filter(|p| u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]) > 30)
            .count();
        // Step 0 of the series lies at the bottom of the series' range (its values rise 40 a step), below the
        // default window: transparent, as the shared range says it must be. Every other file shows itself.
        if !f.starts_with("time/") {
            assert!(lit > 100, "{f}: the view shows the volume ({lit} lit pixels)");
        }
    }
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    assert!(log.problems().is_empty(), "{:#?}", log.problems());
}

/// A `.vti` dropped on the window by a real XDND source: the viewer must accept the drop, load the file (its log
/// says so) and show it: the F12 screenshot equals the headless render of the file within 1/255.
#[test]
fn viewer_loads_a_file_dropped_by_xdnd() {
    let Some(x) = xvfb() else { return };
    if !have("xdotool", "version") {
        common::skip("xdotool not found; apt-get install xdotool");
        return;
    }
    let dir = common::scratch("viewer-xdnd");
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk/vti_zlib.vti");
    let (mut viewer, window) = drop_for_real(&x.display, &dir, &file, "tests/data/vtk/vti_zlib.vti");
    type_keys(&x.display, &window, &["F12"]);
    let (shot, settings) = read_screenshot(&dir, &viewer.wait_for("saved screenshot ", Duration::from_secs(60)));
    let volume = volcast::formats::open(&file, &Default::default()).expect("volume");
    let d = diff(&shot, &headless_render(&volume, &settings));
    assert!(
        d.max <= 1.0,
        "the dropped file's view differs from its headless render: {d}"
    );
    viewer.finish_clean();
}

/// Starts a viewer on a tiny box, drops `path` on its window with a real XDND source (`common::xdnd`, what a file
/// manager is) and waits until it says it loaded the path ending in `suffix`; returns the viewer and its window.
pub(crate) fn drop_for_real(display: &str, dir: &Path, path: &Path, suffix: &str) -> (Viewer, String) {
    let script = format!("frames:3;{HOLD};exit");
    let mut viewer = Viewer::start(display, dir, &["--builtin", "box", "--builtin-size", "16"], &script);
    viewer.wait_for("script: Hold", Duration::from_secs(180));
    let window = viewer.window(display);
    let id: u32 = window.parse().expect("window id");
    let accepted = common::xdnd::drop_file(display, id, (600, 300), path).expect("XDND drop");
    assert!(accepted, "the window accepts the drop (XdndFinished)");
    let loaded = viewer.wait_for("load", Duration::from_secs(60));
    assert!(loaded.starts_with("loaded ") && loaded.ends_with(suffix), "{loaded}");
    (viewer, window)
}

/// `volume` rendered headless under `settings`, with validation, which must report nothing.
pub(crate) fn headless_render(volume: &volcast::volume::Volume, settings: &RenderSettings) -> image::RgbaImage {
    headless_render_within(volume, settings, None)
}

/// [`headless_render`] with the volume placed within a GPU budget of `gpu_budget` bytes (`None`: whole), as the
/// viewer places it: over it whole, streamed through a pool and refined for `settings`' view.
pub(crate) fn headless_render_within(
    volume: &volcast::volume::Volume,
    settings: &RenderSettings,
    gpu_budget: Option<u64>,
) -> image::RgbaImage {
    let gpu = Gpu::new(&GpuOptions {
        validation: true,
        ..Default::default()
    })
    .expect("Vulkan");
    let mut headless = Headless::new(&gpu).expect("renderer");
    match gpu_budget {
        None => headless.set_volume(&gpu, volume).expect("upload"),
        Some(bytes) => {
            let budgets = volcast::pyramid::budget::Budgets::host(None).with_gpu(volcast::pyramid::budget::GpuBudget {
                bytes,
                max_dim: gpu.properties.limits.max_image_dimension3_d,
            });
            headless.renderer.place_volume(&gpu, volume, &budgets).expect("placed");
            headless.renderer.refine(&gpu, volume, settings).expect("refined");
        }
    }
    let expected = headless.render(&gpu, settings).expect("render").image;
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    assert!(log.problems().is_empty(), "{:#?}", log.problems());
    expected
}
