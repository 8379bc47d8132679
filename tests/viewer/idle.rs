//! An untouched viewer costs nothing: once its first frames are drawn, and again after a key changed the view, it
//! sleeps until input comes (it used to draw full frame after full frame with nothing changed: a core busy).
//! Measured as the process's CPU time (/proc/PID/stat) over seconds of idleness. And a frame in which only the
//! panel changed shows the last march's image again instead of marching.

use crate::common::x11::{pointer, type_keys, x_session, Rerendered, Viewer, HOLD};
use std::time::Duration;

/// CPU seconds (user + system) the process has used so far.
fn cpu_seconds(pid: &str) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("the viewer's /proc stat");
    // Fields after the command name (which may hold spaces) in parentheses: utime and stime are the 12th and 13th.
    let after = &stat[stat.rfind(')').expect("a stat line") + 2..];
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks: f64 = fields[11].parse::<f64>().unwrap() + fields[12].parse::<f64>().unwrap();
    let out = std::process::Command::new("getconf")
        .arg("CLK_TCK")
        .output()
        .expect("getconf");
    let per_second: f64 = String::from_utf8_lossy(&out.stdout).trim().parse().expect("CLK_TCK");
    ticks / per_second
}

/// CPU seconds the viewer uses over `quiet` of doing nothing.
fn cpu_over(viewer: &Viewer, quiet: Duration) -> f64 {
    let before = cpu_seconds(&viewer.pid());
    std::thread::sleep(quiet);
    cpu_seconds(&viewer.pid()) - before
}

/// Waits until the viewer has been quiet (under 0.02 CPU-seconds) for half a second: its last frames drawn,
/// however long the machine takes over them. A viewer that keeps drawing may have such gaps between frames, but
/// then uses a frame's CPU in the seconds measured after it.
fn settle(viewer: &Viewer) {
    let deadline = std::time::Instant::now() + Duration::from_secs(120);
    while cpu_over(viewer, Duration::from_millis(500)) >= 0.02 {
        assert!(
            std::time::Instant::now() < deadline,
            "the viewer never went quiet for 0.5 s"
        );
    }
}

#[test]
fn an_untouched_viewer_uses_no_cpu() {
    let Some((x, dir)) = x_session("viewer-idle") else {
        return;
    };
    let script = format!("frames:3;{HOLD};exit");
    let mut viewer = Viewer::start(&x.display, &dir, &["--builtin", "helix"], &script);
    viewer.wait_for("script: Hold", Duration::from_secs(180));
    let window = viewer.window(&x.display);
    // The last frames (a full-detail one after the first) finish; then nothing should run. A frame here costs
    // about 0.2-1 s of CPU, so 0.1 s over 3 s allows stray wake-ups but not a single frame.
    settle(&viewer);
    let idle = cpu_over(&viewer, Duration::from_secs(3));
    assert!(idle < 0.1, "untouched, the viewer used {idle:.2} CPU-seconds in 3 s");

    // A key that changes the view (the panel hidden and shown) draws frames, then the viewer is idle again.
    let before_key = cpu_seconds(&viewer.pid());
    type_keys(&x.display, &window, &["Tab", "Tab"]);
    settle(&viewer);
    let busy = cpu_seconds(&viewer.pid()) - before_key;
    let idle_again = cpu_over(&viewer, Duration::from_secs(3));
    assert!(
        busy > idle_again,
        "the key drew frames ({busy:.2} s) where idleness costs {idle_again:.2} s"
    );
    assert!(
        idle_again < 0.1,
        "after the key, the viewer used {idle_again:.2} CPU-seconds in 3 s"
    );

    viewer.finish_clean();
}

/// The viewer's count of frames from the line it ends a script with: (drawn, marched).
fn frames_counted(stderr: &str) -> (u64, u64) {
    let line = stderr
        .lines()
        .find_map(|l| l.strip_prefix("frames: "))
        .unwrap_or_else(|| panic!("no 'frames:' line:\n{stderr}"));
    let numbers: Vec<u64> = line.split_whitespace().filter_map(|w| w.parse().ok()).collect();
    (numbers[0], numbers[1])
}

/// The pointer moved over the panel (on and off a checkbox, which lights up under it) draws frames, but the view is
/// unchanged: those frames show the last march's image again. On lavapipe a march of this view costs some 0.4 s of
/// both cores; each such frame used to march anew. The image shown is still the view's: F12 then equals the
/// headless render of its state.
#[test]
fn frames_that_change_only_the_panel_do_not_march_the_view() {
    let Some((x, dir)) = x_session("viewer-reuse") else {
        return;
    };
    let (mut viewer, window) = Viewer::held(&x.display, &dir, &["--builtin", "helix"]);
    let (d, w) = (x.display.as_str(), window.as_str());
    settle(&viewer);
    let checkbox = viewer.ui_rect("multiplied-alpha");
    let moves = 16;
    for k in 0..moves {
        let off = if k % 2 == 0 { 0.0 } else { 3.0 * checkbox.height() };
        pointer(d, w, checkbox.center() + egui::vec2(0.0, off));
    }
    let worst = Rerendered::take(&mut viewer, d, w, &dir).worst();
    assert!(
        worst <= 1,
        "the view shown again differs from its render by up to {worst}/255"
    );
    viewer.finish_clean();

    let (drawn, marched) = frames_counted(&viewer.stderr);
    assert!(
        drawn >= marched + moves / 4,
        "of {drawn} frames {marched} marched: moving over the panel {moves} times marched the unchanged view again"
    );
}
