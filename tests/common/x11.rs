//! The viewer under its own Xvfb, driven by real X input (xdotool through XTEST) and read back with `xwd`:
//! shared by the viewer tests.

use image::RgbaImage;
use std::io::BufRead;
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};
use volcast::scene::settings::RenderSettings;
use volcast::scene::view_state::ViewState;

/// The script step that keeps the viewer's window open for the test's input: `hold` lasts until the viewer's
/// standard input ends, which [`Viewer::finish`] brings about once the test's input is done. (A fixed `wait:`
/// ran out under the test's hands on a loaded machine; xdotool 3.2016 cannot close a window gracefully, and
/// there is no window manager to ask.)
pub const HOLD: &str = "hold";

pub struct Xvfb {
    child: Child,
    pub display: String,
    /// Held while the X server runs: see [`X_TESTS`]. A field, so it is let go after `drop` has stopped Xvfb.
    _turn: MutexGuard<'static, ()>,
}

/// One X test at a time in a test binary. libtest runs a binary's tests on several threads, but these type
/// through XTEST, click and time their input against a viewer's scripted `wait:`; run side by side on a small
/// machine they starve each other's viewers (and before they shared a binary, cargo ran them one after another).
/// A test that fails while holding it only poisons it: the next takes it all the same, see [`xvfb`].
static X_TESTS: Mutex<()> = Mutex::new(());

impl Drop for Xvfb {
    fn drop(&mut self) {
        // SIGTERM first, so Xvfb removes its lock file and socket; SIGKILL only if that failed.
        let terminated = Command::new("kill")
            .arg(self.child.id().to_string())
            .status()
            .is_ok_and(|s| s.success());
        if !terminated {
            let _ = self.child.kill();
        }
        let _ = self.child.wait();
    }
}

/// A fresh Xvfb, or None after a skip where it cannot start. Waits until no other X test of this binary runs
/// ([`X_TESTS`]), and keeps the others waiting until the returned server is dropped at the end of the test.
pub fn xvfb() -> Option<Xvfb> {
    // A poisoned lock says only that an earlier X test failed; its server was stopped as it unwound.
    let turn = X_TESTS.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    // -displayfd: Xvfb picks a free display itself and writes its number once it accepts connections (a fixed
    // number can collide with another server or a stale lock, and a socket file can exist before it is ready).
    // -noreset: by default the server resets when its last client leaves, and a test that starts a second
    // viewer after the first has exited raced that reset ("no display to open a window on" under load).
    let mut child = match Command::new("Xvfb")
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            "1280x1024x24",
            "-nolisten",
            "tcp",
            "-noreset",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
    {
        Ok(c) => c,
        Err(e) => {
            super::skip(&format!("Xvfb could not start ({e}); apt-get install xvfb"));
            return None;
        }
    };
    let stdout = child.stdout.take().expect("piped stdout");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        let _ = std::io::BufReader::new(stdout).read_line(&mut line);
        let _ = tx.send(line);
    });
    let number = rx.recv_timeout(Duration::from_secs(20)).unwrap_or_default();
    let number = number.trim();
    if number.is_empty() || number.parse::<u32>().is_err() {
        let _ = child.kill();
        let _ = child.wait();
        panic!("Xvfb did not report a display within 20 s (got {number:?})");
    }
    Some(Xvfb {
        child,
        display: format!(":{number}"),
        _turn: turn,
    })
}

/// What a viewer test driven by xdotool needs: xdotool and xwd, a fresh Xvfb, and an empty working folder
/// named after the test (None after a skip where a tool is missing).
pub fn x_session(name: &str) -> Option<(Xvfb, std::path::PathBuf)> {
    if !(have("xdotool", "version") && have("xwd", "-help")) {
        super::skip("xdotool or xwd missing (apt install xdotool x11-apps)");
        return None;
    }
    let x = xvfb()?;
    Some((x, super::scratch(name).to_path_buf()))
}

/// Whether `program` can be started at all (its exit status does not matter).
pub fn have(program: &str, arg: &str) -> bool {
    Command::new(program)
        .arg(arg)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok()
}

/// Runs an X client on `display` and returns its stdout; any failure fails the test.
pub fn x_client(display: &str, program: &str, args: &[&str]) -> Vec<u8> {
    let out = Command::new(program)
        .args(args)
        .env("DISPLAY", display)
        .output()
        .unwrap_or_else(|e| panic!("{program}: {e}"));
    assert!(
        out.status.success(),
        "{program} {args:?}: {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// Types `keys` into `window` as a user would: focus it, then key events through XTEST. (`xdotool key --window`
/// sends synthetic events with XSendEvent instead; the viewer did not react to them when tried.)
pub fn type_keys(display: &str, window: &str, keys: &[&str]) {
    x_client(display, "xdotool", &["windowfocus", "--sync", window]);
    let mut args = vec!["key", "--delay", "50"];
    args.extend_from_slice(keys);
    x_client(display, "xdotool", &args);
}

/// What the X server shows in `window` now.
pub fn capture(display: &str, window: &str) -> RgbaImage {
    let xwd = x_client(display, "xwd", &["-id", window, "-silent"]);
    parse_xwd(&xwd).unwrap_or_else(|e| panic!("xwd output: {e}"))
}

/// Decodes an XWD dump (X11 `XWDFileHeader`: 25 big-endian u32, the window name, the colormap, then the image
/// as the server sent it). Only what Xvfb at depth 24 produces is accepted: ZPixmap, 32 bits per pixel, true
/// colour with 8-bit masks.
pub fn parse_xwd(b: &[u8]) -> Result<RgbaImage, String> {
    let field = |i: usize| -> Result<u32, String> {
        b.get(4 * i..4 * i + 4)
            .map(|s| u32::from_be_bytes([s[0], s[1], s[2], s[3]]))
            .ok_or_else(|| format!("truncated header ({} bytes)", b.len()))
    };
    let (header_size, version, format) = (field(0)? as usize, field(1)?, field(2)?);
    let (width, height) = (field(4)?, field(5)?);
    let (little_endian, bits_per_pixel, bytes_per_line) = (field(7)? == 0, field(11)?, field(12)? as usize);
    let masks = [field(14)?, field(15)?, field(16)?];
    let colors = field(19)? as usize;
    if version != 7 || format != 2 || bits_per_pixel != 32 {
        return Err(format!(
            "version {version}, format {format}, {bits_per_pixel} bpp (expected 7, ZPixmap = 2, 32)"
        ));
    }
    if masks.iter().any(|m| m.count_ones() != 8) {
        return Err(format!("colour masks {masks:x?} are not 8 bits each"));
    }
    // Colormap entries (XWDColor) are 12 bytes each.
    let start = header_size + 12 * colors;
    let pixels = b
        .get(start..start + bytes_per_line * height as usize)
        .ok_or_else(|| format!("{} bytes, {width}x{height} needs more", b.len()))?;
    Ok(RgbaImage::from_fn(width, height, |x, y| {
        let at = y as usize * bytes_per_line + 4 * x as usize;
        let p = [pixels[at], pixels[at + 1], pixels[at + 2], pixels[at + 3]];
        let v = if little_endian {
            u32::from_le_bytes(p)
        } else {
            u32::from_be_bytes(p)
        };
        let channel = |m: u32| ((v & m) >> m.trailing_zeros()) as u8;
        image::Rgba([channel(masks[0]), channel(masks[1]), channel(masks[2]), 255])
    }))
}

/// The viewer process, its stderr read line by line as it comes. Killed if the test fails before it ends.
pub struct Viewer {
    child: Child,
    /// Closed by [`Viewer::finish`] to end the script's `hold`.
    stdin: Option<std::process::ChildStdin>,
    lines: Receiver<String>,
    pub stderr: String,
}

impl Viewer {
    /// Starts `volcast view VOLUME... --validate --size 900x600 --script SCRIPT` in `dir` on `display`.
    pub fn start(display: &str, dir: &Path, volume: &[&str], script: &str) -> Viewer {
        Viewer::launch(display, dir, &[&["view"], volume].concat(), script)
    }

    /// As [`Viewer::start`], with `args` in place of `view VOLUME...` (`volcast FILE` names no subcommand).
    pub fn launch(display: &str, dir: &Path, args: &[&str], script: &str) -> Viewer {
        let runtime = dir.join("xdg");
        std::fs::create_dir_all(&runtime).expect("XDG_RUNTIME_DIR");
        let mut child = super::volcast_command()
            // Held open by the test: the end of stdin ends a script's `hold`.
            .stdin(Stdio::piped())
            .args(args)
            .args(["--validate", "--size", "900x600", "--script", script])
            // F12 writes its screenshot into the working directory.
            .current_dir(dir)
            .env("DISPLAY", display)
            .env("XDG_RUNTIME_DIR", &runtime)
            // Its own config (the recent-files list) in the test's folder: a second start in it sees the first's.
            .env("XDG_CONFIG_HOME", dir.join("config"))
            .env("XDG_CACHE_HOME", dir.join("cache"))
            // The panel's widgets say where they are (`ui rect NAME L T R B`), for tests that click them.
            .env("VOLCAST_UI_RECTS", "1")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run the viewer");
        let stdin = child.stdin.take();
        let stderr = child.stderr.take().expect("piped stderr");
        let (tx, lines) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(stderr).lines().map_while(Result::ok) {
                let _ = tx.send(line);
            }
        });
        Viewer {
            child,
            stdin,
            lines,
            stderr: String::new(),
        }
    }

    /// Starts the viewer on `volume` with its window held open for the test's input (`frames:3;hold;exit`), waits
    /// until it holds, and returns it with its window.
    pub fn held(display: &str, dir: &Path, volume: &[&str]) -> (Viewer, String) {
        let mut viewer = Viewer::start(display, dir, volume, &format!("frames:3;{HOLD};exit"));
        viewer.wait_for("script: Hold", Duration::from_secs(180));
        let window = viewer.window(display);
        (viewer, window)
    }

    /// Waits for a stderr line containing `needle` and returns it.
    pub fn wait_for(&mut self, needle: &str, timeout: Duration) -> String {
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    self.stderr.push_str(&line);
                    self.stderr.push('\n');
                    if line.contains(needle) {
                        return line;
                    }
                }
                Err(RecvTimeoutError::Timeout) => {
                    panic!(
                        "no '{needle}' from the viewer within {timeout:?}; stderr so far:\n{}",
                        self.stderr
                    )
                }
                Err(RecvTimeoutError::Disconnected) => panic!(
                    "the viewer ended before '{needle}' (it failed, or its script ended); stderr:\n{}",
                    self.stderr
                ),
            }
        }
    }

    /// Ends the script's `hold` (closes the viewer's stdin), waits for the viewer to exit (the script ends the
    /// session) and collects the rest of its stderr.
    pub fn finish(&mut self) -> ExitStatus {
        drop(self.stdin.take());
        let status = self.child.wait().expect("wait for the viewer");
        while let Ok(line) = self.lines.recv_timeout(Duration::from_secs(10)) {
            self.stderr.push_str(&line);
            self.stderr.push('\n');
        }
        status
    }

    /// Waits for the viewer to exit and asserts what every viewer test ends on: a clean exit and a validation
    /// layer (with synchronization validation) that reported nothing, leaks at device destruction included.
    pub fn finish_clean(&mut self) {
        let status = self.finish();
        let stderr = &self.stderr;
        assert!(status.success(), "viewer exit: {status}\n{stderr}");
        assert!(stderr.contains("validation: 0 errors, 0 warnings"), "{stderr}");
        assert!(!stderr.contains("[validation"), "{stderr}");
    }

    /// Saves the session (Ctrl+S into `dir`, the viewer's working directory) and reads it back.
    pub fn save_session(&mut self, display: &str, window: &str, dir: &Path) -> ViewState {
        type_keys(display, window, &["ctrl+s"]);
        let line = self.wait_for("saved session ", Duration::from_secs(60));
        // Named by its absolute path (issue 60: "saved" messages gave relative ones).
        let named = line.trim().trim_start_matches("saved session ");
        let path = dir.join("volcast-session.json");
        let same = std::fs::canonicalize(named).ok() == std::fs::canonicalize(&path).ok();
        assert!(Path::new(named).is_absolute() && same, "{line}");
        read_state(&path)
    }

    /// Reads the stderr lines that have arrived so far, without waiting.
    pub fn drain(&mut self) {
        while let Ok(line) = self.lines.try_recv() {
            self.stderr.push_str(&line);
            self.stderr.push('\n');
        }
    }

    /// The latest rectangle the viewer logged for widget `name` (see `VOLCAST_UI_RECTS`).
    pub fn ui_rect(&mut self, name: &str) -> egui::Rect {
        self.drain();
        let prefix = format!("ui rect {name} ");
        let line = self
            .stderr
            .lines()
            .rev()
            .find_map(|l| l.strip_prefix(&prefix))
            .unwrap_or_else(|| panic!("the viewer logged no rect for {name}:\n{}", self.stderr));
        let v: Vec<f32> = line.split_whitespace().map(|x| x.parse().expect("a number")).collect();
        egui::Rect::from_min_max(egui::pos2(v[0], v[1]), egui::pos2(v[2], v[3]))
    }

    pub fn pid(&self) -> String {
        self.child.id().to_string()
    }

    /// The viewer's one window on `display` (xdotool's id), asserting there is exactly one: the window of its
    /// process whose title ends in "volcast" (`helix — volcast`; the title names the volume shown).
    pub fn window(&self, display: &str) -> String {
        let found = x_client(
            display,
            "xdotool",
            &["search", "--all", "--pid", &self.pid(), "--name", "volcast$"],
        );
        let found = String::from_utf8_lossy(&found);
        let windows: Vec<&str> = found.split_whitespace().collect();
        assert_eq!(windows.len(), 1, "one volcast window: {windows:?}");
        windows[0].to_string()
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
        // A failing test shows what the viewer said (its widget rectangles left out), so a failure in CI can be
        // read without running it again.
        if std::thread::panicking() {
            self.drain();
            let said: Vec<&str> = self
                .stderr
                .lines()
                .filter(|l| {
                    !l.starts_with("ui rect ")
                        && !l.starts_with("ui label ")
                        && !l.starts_with("ui gone ")
                        && *l != "ui still"
                })
                .collect();
            let from = said.len().saturating_sub(120);
            eprintln!("--- the viewer's stderr (last {} lines) ---", said.len() - from);
            for line in &said[from..] {
                eprintln!("{line}");
            }
        }
    }
}

/// A view state (a session, or F12's JSON) from its file.
pub fn read_state(path: &Path) -> ViewState {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    ViewState::from_json(&text, &path.display().to_string()).expect("a view state")
}

/// The transfer function a saved view holds (it must hold one).
pub fn tf_of(state: &ViewState) -> volcast::transfer::function::TransferFunction {
    state
        .settings
        .colour
        .transfer_function
        .clone()
        .expect("a transfer function")
}

/// A series' step that the "saved screenshot NAME (time step N)" line names.
pub fn screenshot_step(saved_line: &str) -> Option<u32> {
    let rest = saved_line.split_once(" (time step ")?.1;
    rest.split(')').next()?.parse().ok()
}

/// The PNG that F12 wrote into `dir`, named by the viewer's "saved screenshot NAME [(time step N)]" line; its view
/// state is the JSON beside it.
pub fn screenshot_png(dir: &Path, saved_line: &str) -> std::path::PathBuf {
    let name = saved_line
        .split_once("saved screenshot ")
        .map(|(_, n)| n.split(" (time step ").next().unwrap_or(n).trim())
        .expect("file name");
    dir.join(name)
}

/// The PNG and settings that F12 wrote, named by the viewer's "saved screenshot NAME" line.
pub fn read_screenshot(dir: &Path, saved_line: &str) -> (RgbaImage, RenderSettings) {
    let png = screenshot_png(dir, saved_line);
    let image = image::open(&png)
        .unwrap_or_else(|e| panic!("{}: {e}", png.display()))
        .to_rgba8();
    let json = std::fs::read_to_string(png.with_extension("json")).expect("settings beside the screenshot");
    (image, serde_json::from_str(&json).expect("settings JSON"))
}

/// What F12 saved, beside the headless render of the view state it saved with it.
pub struct Rerendered {
    pub shot: RgbaImage,
    /// `render --state` of F12's JSON.
    pub again: RgbaImage,
    pub json: std::path::PathBuf,
}

impl Rerendered {
    /// F12 in the viewer's `window`, then `render --state` of its JSON (the screenshot lies in `dir`).
    pub fn take(viewer: &mut Viewer, display: &str, window: &str, dir: &Path) -> Rerendered {
        type_keys(display, window, &["F12"]);
        let saved = viewer.wait_for("saved screenshot ", Duration::from_secs(60));
        let (shot, _) = read_screenshot(dir, &saved);
        let json = screenshot_png(dir, &saved).with_extension("json");
        let again = render_state(dir, &json);
        assert_eq!(again.dimensions(), shot.dimensions(), "F12 and its render");
        Rerendered { shot, again, json }
    }

    /// The largest channel difference between the screenshot and its render.
    pub fn worst(&self) -> u8 {
        worst_channel_diff(&self.again, &self.shot)
    }
}

/// Moves the pointer to `p` (window points) and lets the viewer see it.
pub fn pointer(display: &str, window: &str, p: egui::Pos2) {
    let (x, y) = (format!("{}", p.x.round()), format!("{}", p.y.round()));
    x_client(display, "xdotool", &["mousemove", "--window", window, &x, &y]);
    std::thread::sleep(Duration::from_millis(120));
}

/// An xdotool button action ("click", "mousedown", "mouseup") on button "1".."5".
pub fn button(display: &str, action: &str, button: &str) {
    x_client(display, "xdotool", &[action, button]);
    std::thread::sleep(Duration::from_millis(200));
}

/// A drag with `button` from `from` through `steps` moves of `step` points each (steps above egui's 6-point click
/// distance, so no motion is lost before the drag starts).
pub fn drag(display: &str, window: &str, button_name: &str, from: egui::Pos2, step: egui::Vec2, steps: u32) {
    pointer(display, window, from);
    button(display, "mousedown", button_name);
    for k in 1..=steps {
        pointer(display, window, from + step * k as f32);
    }
    button(display, "mouseup", button_name);
}

/// The four-up quadrants (axial, 3D, sagittal, coronal) of a `size` window whose F12 image is `shot_width` wide: the
/// area right of the panel, found as the one whose 3D quadrant has that width.
pub fn four_up_rects(size: (f32, f32), shot_width: u32) -> [egui::Rect; 4] {
    let panel_right = (0..size.0 as i32)
        .map(|p| p as f32)
        .find(|&left| {
            let area = egui::Rect::from_min_max(egui::pos2(left, 0.0), egui::pos2(size.0, size.1));
            (volcast::viewer::widgets::layout::four_up(area)[1].width().round() - shot_width as f32).abs() <= 0.5
        })
        .expect("a layout that gives F12's width");
    let area = egui::Rect::from_min_max(egui::pos2(panel_right, 0.0), egui::pos2(size.0, size.1));
    volcast::viewer::widgets::layout::four_up(area)
}

/// The largest difference of any colour channel between two images of one size, in 1/255.
pub fn worst_channel_diff(a: &RgbaImage, b: &RgbaImage) -> u8 {
    assert_eq!(a.dimensions(), b.dimensions());
    a.pixels()
        .zip(b.pixels())
        .map(|(p, q)| (0..3).map(|c| p.0[c].abs_diff(q.0[c])).max().unwrap_or(0))
        .max()
        .unwrap_or(0)
}

/// `volcast render --validate --state JSON` into `dir`: the image a view state renders headless.
pub fn render_state(dir: &Path, json: &Path) -> RgbaImage {
    let out = dir.join("render-state.png");
    let path = |p: &Path| p.to_str().expect("a UTF-8 path").to_string();
    super::volcast_ok(&["render", "--validate", "--state", &path(json), "-o", &path(&out)]);
    image::open(&out)
        .unwrap_or_else(|e| panic!("{}: {e}", out.display()))
        .to_rgba8()
}
