//! A time series in the desktop viewer, driven by real X input under its own Xvfb (xdotool through XTEST, as a
//! keyboard would): `view FILE --time 2` opens on step 2, the P key plays the series (the window changes while it
//! plays, each step after the first uploaded ahead of display) and P again pauses it. Each F12 screenshot must
//! equal, within 1/255, the headless render of exactly the step the viewer logs with it, under the screenshot's
//! own settings: step 2 at the start, and the step reached after playing. `--tf` opens it with a given transfer
//! function, which the load keeps. Validation with
//! synchronization validation reports nothing.
//!
//! Needs Xvfb, xdotool and xwd like tests/viewer/window.rs; a missing one is a skip (a failure with CI=true).

use crate::common;

use common::compare::diff;
use common::x11::{capture, have, read_screenshot, screenshot_step, type_keys, xvfb, Viewer, WAIT_MS};
use std::path::Path;
use std::time::Duration;
use volcast::gpu::{Gpu, GpuOptions};
use volcast::render::headless::Headless;

#[test]
fn viewer_opens_plays_and_pauses_a_series_from_real_keys() {
    let Some(x) = xvfb() else { return };
    for (tool, arg, package) in [("xdotool", "version", "xdotool"), ("xwd", "-help", "x11-apps")] {
        if !have(tool, arg) {
            common::skip(&format!("{tool} not found; apt-get install {package}"));
            return;
        }
    }
    let dir = common::scratch("viewer-time");
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/time/sim_u16.nrrd");
    let script = format!("frames:3;wait:{WAIT_MS};exit");
    // A transfer function over the whole range (3..293), so that every step looks different: the automatic one
    // (a faint ramp over the upper percentiles of all steps) leaves the early steps of this tiny series clear.
    let tf = dir.join("tf.json");
    std::fs::write(
        &tf,
        r#"{"name": "all steps", "units": "data", "colors": [[3, 0, 0, 1], [293, 1, 0.2, 0]],
            "opacity": [[3, 0.2], [293, 0.9]]}"#,
    )
    .unwrap();
    let args = [file.to_str().unwrap(), "--time", "2", "--tf", tf.to_str().unwrap()];
    let mut viewer = Viewer::start(&x.display, &dir, &args, &script);
    viewer.wait_for("script: Wait(", Duration::from_secs(180));
    let window = viewer.window(&x.display);

    type_keys(&x.display, &window, &["F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    assert_eq!(screenshot_step(&saved), Some(2), "{saved}");
    let (start, start_settings) = read_screenshot(&dir, &saved);
    // Play: the window must change while the series plays.
    type_keys(&x.display, &window, &["p"]);
    let mut frames = Vec::new();
    for _ in 0..4 {
        std::thread::sleep(Duration::from_millis(350));
        frames.push(capture(&x.display, &window));
    }
    assert!(
        frames.windows(2).any(|w| w[0].as_raw() != w[1].as_raw()),
        "P (play) changes the window"
    );
    type_keys(&x.display, &window, &["p"]);
    std::thread::sleep(Duration::from_millis(300));
    let paused = capture(&x.display, &window);
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(paused.as_raw(), capture(&x.display, &window).as_raw(), "P again pauses");
    type_keys(&x.display, &window, &["F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    let after_step = screenshot_step(&saved).expect("the screenshot line names the step");
    let (after, after_settings) = read_screenshot(&dir, &saved);

    // Which steps each screenshot equals, rendered headless from the same file and settings.
    let gpu = Gpu::new(&GpuOptions {
        validation: true,
        ..Default::default()
    })
    .expect("Vulkan");
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut series = volcast::volume::open(&file, &Default::default()).expect("series");
    let (mut start_matches, mut after_matches) = (Vec::new(), Vec::new());
    for t in 0..series.timesteps() {
        series.show_step(t).unwrap();
        headless.set_volume(&gpu, &series).unwrap();
        if diff(&start, &headless.render(&gpu, &start_settings).expect("render").image).max <= 1.0 {
            start_matches.push(t);
        }
        if diff(&after, &headless.render(&gpu, &after_settings).expect("render").image).max <= 1.0 {
            after_matches.push(t);
        }
    }
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    assert!(log.problems().is_empty(), "{:#?}", log.problems());
    assert_eq!(
        start_matches,
        vec![2],
        "--time 2 opens on step 2 (and only step 2 looks like it)"
    );
    assert_eq!(
        after_matches,
        vec![after_step],
        "after playing (steps uploaded ahead of display), the view is exactly the step the viewer says it shows"
    );

    viewer.finish_clean();
}
