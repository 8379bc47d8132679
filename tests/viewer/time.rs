//! A time series in the desktop viewer, driven by real X input under its own Xvfb (xdotool through XTEST, as a
//! keyboard would): `view FILE --time 2` opens on step 2, the P key plays the series (the step shown advances,
//! each step after the first uploaded ahead of display) and P again pauses it (the step stays). Each F12 screenshot must
//! equal, within 1/255, the headless render of exactly the step the viewer logs with it, under the screenshot's
//! own settings: step 2 at the start, and the step reached after playing. `--tf` opens it with a given transfer
//! function, which the load keeps. Validation with
//! synchronization validation reports nothing.
//!
//! Needs Xvfb, xdotool and xwd like tests/viewer/window.rs; a missing one is a skip (a failure with CI=true).

use crate::common;

use common::compare::diff;
use common::x11::{have, read_screenshot, screenshot_step, type_keys, xvfb, Viewer, HOLD};
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
    let script = format!("frames:3;{HOLD};exit");
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
    viewer.wait_for("script: Hold", Duration::from_secs(180));
    let window = viewer.window(&x.display);

    type_keys(&x.display, &window, &["F12"]);
    let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
    assert_eq!(screenshot_step(&saved), Some(2), "{saved}");
    let (start, start_settings) = read_screenshot(&dir, &saved);
    // Play, then pause. Each F12 names the step of the frame it saved, so the test reads what the viewer did,
    // whatever its frame rate: playback takes at most one step a frame at 10 steps/s, so 0.3 s apart two
    // screenshots lie 1 to ~4 steps apart while playing (of 12), and the same step once paused, however long after.
    let f12_step = |viewer: &mut Viewer| {
        type_keys(&x.display, &window, &["F12"]);
        let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
        let step = screenshot_step(&saved).expect("the screenshot line names the step");
        (step, saved)
    };
    type_keys(&x.display, &window, &["p"]);
    let (playing, _) = f12_step(&mut viewer);
    std::thread::sleep(Duration::from_millis(300));
    let (later, _) = f12_step(&mut viewer);
    assert_ne!(
        playing, later,
        "P plays: the step advances (step {playing}, then {later} 0.3 s later)"
    );
    type_keys(&x.display, &window, &["p"]);
    let (paused, _) = f12_step(&mut viewer);
    std::thread::sleep(Duration::from_millis(1000));
    let (after_step, saved) = f12_step(&mut viewer);
    assert_eq!(
        after_step, paused,
        "P again pauses: step {paused}, then {after_step} a second later"
    );
    let (after, after_settings) = read_screenshot(&dir, &saved);

    // Which steps each screenshot equals, rendered headless from the same file and settings.
    let gpu = Gpu::new(&GpuOptions {
        validation: true,
        ..Default::default()
    })
    .expect("Vulkan");
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut series = volcast::formats::open(&file, &Default::default()).expect("series");
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
