//! The desktop viewer in a real window under Xvfb: it starts on the helix, renders frames, survives a resize,
//! a 0×0 size, a minimize/restore and hiding the panel, and writes a screenshot through its own screenshot path.
//! The screenshot must equal the headless render of the settings it was taken with (saved beside it as JSON):
//! both come from the same `Renderer` and shaders, so the bound is 1/255 (no pixel may differ by more).
//! All under validation with synchronization validation, swapchain included: 0 messages.
//!
//! Xvfb: a DISPLAY that is already set is used; otherwise the test starts its own Xvfb (installed by .ci/run).

mod common;

use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::Duration;
use volcast::gpu::{Gpu, GpuOptions};
use volcast::headless::Headless;
use volcast::settings::RenderSettings;

struct Xvfb {
    child: Option<Child>,
    display: String,
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        if let Some(c) = &mut self.child {
            // SIGTERM first, so Xvfb removes its lock file and socket; SIGKILL only if that failed.
            let terminated = Command::new("kill")
                .arg(c.id().to_string())
                .status()
                .is_ok_and(|s| s.success());
            if !terminated {
                let _ = c.kill();
            }
            let _ = c.wait();
        }
    }
}

/// A display to open windows on, or None (with a note) where none can be had outside CI.
fn display() -> Option<Xvfb> {
    if let Ok(d) = std::env::var("DISPLAY") {
        if !d.is_empty() {
            return Some(Xvfb {
                child: None,
                display: d,
            });
        }
    }
    // -displayfd: Xvfb picks a free display itself and writes its number once it accepts connections (a fixed
    // number can collide with another server or a stale lock, and a socket file can exist before it is ready).
    let mut child = match Command::new("Xvfb")
        .args(["-displayfd", "1", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
    {
        Ok(c) => c,
        Err(e) => {
            assert_ne!(
                std::env::var("CI").as_deref(),
                Ok("true"),
                "Xvfb is required in CI: {e}"
            );
            eprintln!("skipped: no DISPLAY and Xvfb could not start ({e}); apt-get install xvfb");
            return None;
        }
    };
    let stdout = child.stdout.take().expect("piped stdout");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        let _ = std::io::BufRead::read_line(&mut std::io::BufReader::new(stdout), &mut line);
        let _ = tx.send(line);
    });
    let number = rx.recv_timeout(Duration::from_secs(20)).unwrap_or_default();
    let number = number.trim();
    if number.is_empty() || number.parse::<u32>().is_err() {
        let _ = child.kill();
        let _ = child.wait();
        panic!("Xvfb did not report a display within 20 s (got {number:?})");
    }
    let display = format!(":{number}");
    Some(Xvfb {
        child: Some(child),
        display,
    })
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("viewer");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir.join(name)
}

#[test]
fn viewer_survives_resizes_and_its_screenshot_matches_the_headless_render() {
    let Some(x) = display() else { return };
    let shot_panel = scratch("with-panel.png");
    let shot = scratch("shot.png");
    let script = format!(
        "frames:3;screenshot:{};resize:640x480;frames:2;zero-size;frames:2;restore;minimize;frames:2;restore;\
         key:space;frames:3;key:space;key:r;key:tab;frames:2;screenshot:{};exit",
        shot_panel.display(),
        shot.display()
    );
    let runtime = scratch("xdg");
    std::fs::create_dir_all(&runtime).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_volcast"))
        .args([
            "view",
            "--builtin",
            "helix",
            "--validate",
            "--size",
            "900x600",
            "--script",
            &script,
        ])
        .env("DISPLAY", &x.display)
        .env("XDG_RUNTIME_DIR", &runtime)
        .output()
        .expect("run the viewer");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "viewer failed:\n{stderr}");
    assert!(stderr.contains("validation: 0 errors, 0 warnings"), "{stderr}");
    assert!(!stderr.contains("[validation"), "{stderr}");

    // With the panel, the view is the part of the window right of it.
    let with_panel = image::open(&shot_panel).expect("first screenshot").to_rgba8();
    assert!(
        with_panel.width() < 900 && with_panel.width() > 400,
        "{}",
        with_panel.width()
    );
    assert_eq!(with_panel.height(), 600);

    // Resized, panel hidden (Tab), view reset (R) after auto-rotating: the whole 640x480 window.
    let actual = image::open(&shot).expect("screenshot").to_rgba8();
    assert_eq!(actual.dimensions(), (640, 480));
    let json = std::fs::read_to_string(shot.with_extension("json")).expect("settings beside the screenshot");
    let settings: RenderSettings = serde_json::from_str(&json).expect("settings JSON");
    let helix = volcast::volume::builtin("helix", None).unwrap();
    let defaults = RenderSettings::new(640, 480, helix.extent());
    assert!(
        (settings.camera.eye - defaults.camera.eye).length() < 1e-4,
        "R resets the view"
    );

    let gpu = Gpu::new(&GpuOptions {
        validation: true,
        ..Default::default()
    })
    .expect("Vulkan");
    let mut headless = Headless::new(&gpu).expect("renderer");
    headless.set_volume(&gpu, &helix).unwrap();
    let expected = headless.render(&gpu, &settings).expect("render").image;
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    assert!(log.problems().is_empty(), "{:#?}", log.problems());
    let d = common::compare::diff(&actual, &expected);
    if d.max > 1.0 {
        common::compare::write_failure_images("viewer-screenshot", &actual, &expected);
        panic!("the screenshot differs from the headless render: {d}");
    }
    let lit = actual
        .pixels()
        .filter(|p| p[0] as u32 + p[1] as u32 + p[2] as u32 > 30)
        .count();
    assert!(lit > 640 * 480 / 20, "the helix is visible ({lit} pixels lit)");
}

#[test]
fn viewer_without_a_display_says_so_and_points_to_render() {
    let out = Command::new(env!("CARGO_BIN_EXE_volcast"))
        .args(["view", "--builtin", "box", "--builtin-size", "8"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("run volcast");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains("volcast render"), "{stderr}");
}
