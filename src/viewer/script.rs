//! Scripted sessions (`--script`): the steps a test gives the viewer, parsed, and how the viewer advances them
//! after each frame. Real input (xdotool under Xvfb) is what the viewer tests drive; the script only sets up,
//! waits and captures.

use super::model::actions::UiAction;
use super::widgets::keys;
use super::{Flow, Running, ViewerError};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// One step of a scripted session (`--script`, used by the tests to drive a real window under Xvfb).
#[derive(Clone, Debug, PartialEq)]
pub enum ScriptStep {
    /// Render this many frames.
    Frames(u32),
    /// Keep the window open and drawing for this long, so that a test can drive it with real X input meanwhile.
    Wait(Duration),
    /// Rotate the view a little each frame for this many frames, as a drag would, and report the frame times.
    Drag(u32),
    /// Interactive level of detail on or off.
    Lod(bool),
    /// Press "Open…" (the platform file dialog; without a desktop portal it reports that none is available).
    Dialog,
    /// Ask the window system for a new size and wait (a bounded number of frames) until it arrives.
    Resize(u32, u32),
    Minimize,
    Restore,
    /// Behave as if the window system reported a 0×0 size (what minimising does on most platforms).
    ZeroSize,
    /// Press a key (through the same path as the keyboard): r, space, tab or f12.
    Key(String),
    /// Save the current view through the screenshot path (PNG, plus the settings as JSON beside it).
    Screenshot(PathBuf),
    /// Load a file as if it were dropped on the window (the `DroppedFile` handler's path), then wait until the
    /// load ends and say on stderr whether it loaded.
    Drop(PathBuf),
    Exit,
}

/// Parses `frames:3;wait:500;resize:320x240;minimize;restore;zero-size;key:tab;screenshot:PATH;drop:PATH;exit` (wait in
/// milliseconds).
pub fn parse_script(s: &str) -> Result<Vec<ScriptStep>, String> {
    s.split(';')
        .filter(|p| !p.trim().is_empty())
        .map(|part| {
            let part = part.trim();
            let (cmd, arg) = part.split_once(':').unwrap_or((part, ""));
            let bad = || format!("bad script step '{part}'");
            Ok(match cmd {
                "frames" => ScriptStep::Frames(arg.parse().map_err(|_| bad())?),
                "wait" => ScriptStep::Wait(Duration::from_millis(arg.parse().map_err(|_| bad())?)),
                "drag" => ScriptStep::Drag(arg.parse().map_err(|_| bad())?),
                "lod" if arg == "on" || arg == "off" => ScriptStep::Lod(arg == "on"),
                "dialog" => ScriptStep::Dialog,
                "resize" => {
                    let (w, h) = arg.split_once('x').ok_or_else(bad)?;
                    ScriptStep::Resize(w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?)
                }
                "minimize" => ScriptStep::Minimize,
                "restore" => ScriptStep::Restore,
                "zero-size" => ScriptStep::ZeroSize,
                "key" => ScriptStep::Key(arg.to_lowercase()),
                "screenshot" if !arg.is_empty() => ScriptStep::Screenshot(PathBuf::from(arg)),
                "drop" if !arg.is_empty() => ScriptStep::Drop(PathBuf::from(arg)),
                "exit" => ScriptStep::Exit,
                _ => return Err(bad()),
            })
        })
        .collect()
}

pub(super) struct Script {
    pub(super) steps: VecDeque<ScriptStep>,
    pub(super) frames_left: u32,
    pub(super) drag_left: u32,
    pub(super) waiting_for_size: Option<(u32, u32, u32)>,
    pub(super) wait_until: Option<Instant>,
    pub(super) started: Instant,
    /// A `drop:` step's load is under way.
    pub(super) waiting_for_load: bool,
}

impl Running {
    /// Prints the frame times of scripted drags (the first frame of each drag includes the switch of detail).
    pub(super) fn report_drag(&mut self) {
        if self.drag_frames.len() < 3 {
            return;
        }
        let mut t: Vec<f64> = self.drag_frames.drain(..).skip(2).collect();
        t.sort_by(|a, b| a.total_cmp(b));
        let median = t[t.len() / 2];
        eprintln!(
            "drag: median frame {median:.1} ms ({:.1} fps) over {} frames, level of detail {}",
            1e3 / median,
            t.len(),
            if self.state.sampling.lod { "on" } else { "off" }
        );
    }

    /// Advances the script after a frame; returns Exit when it ends the session.
    pub(super) fn step_script(&mut self) -> Result<Flow, ViewerError> {
        let Some(script) = &mut self.script else {
            return Ok(Flow::Continue);
        };
        if script.started.elapsed() > Duration::from_secs(300) {
            return Err(ViewerError::Other(format!(
                "script timed out with steps left: {:?}",
                script.steps
            )));
        }
        if script.frames_left > 0 {
            script.frames_left -= 1;
            return Ok(Flow::Continue);
        }
        if script.wait_until.is_some_and(|t| Instant::now() < t) {
            return Ok(Flow::Continue);
        }
        script.wait_until = None;
        if script.drag_left > 0 {
            script.drag_left -= 1;
            self.state.camera.orbit.turn(0.03);
            return Ok(Flow::Continue);
        }
        if let Some((w, h, tries)) = script.waiting_for_size {
            let size = self.window.inner_size();
            if (size.width, size.height) == (w, h) {
                script.waiting_for_size = None;
            } else if tries == 0 {
                return Err(ViewerError::Other(format!(
                    "window did not resize to {w}x{h} (it is {size:?})"
                )));
            } else {
                script.waiting_for_size = Some((w, h, tries - 1));
                return Ok(Flow::Continue);
            }
        }
        if script.waiting_for_load {
            if self.loading.is_some() {
                return Ok(Flow::Continue);
            }
            script.waiting_for_load = false;
            match &self.state.messages.error {
                Some(e) => eprintln!("script: load failed: {e}"),
                None => eprintln!("script: loaded {}", self.state.volume.label),
            }
        }
        let Some(step) = script.steps.pop_front() else {
            self.report_drag();
            return Ok(Flow::Exit);
        };
        eprintln!("script: {step:?}");
        match step {
            ScriptStep::Frames(n) => script.frames_left = n,
            ScriptStep::Wait(d) => script.wait_until = Some(Instant::now() + d),
            ScriptStep::Drag(n) => script.drag_left = n,
            ScriptStep::Dialog => self.apply(vec![UiAction::OpenDialog]),
            ScriptStep::Drop(path) => {
                script.waiting_for_load = true;
                let action = self.state.files.load_action(path);
                self.apply(vec![action]);
            }
            ScriptStep::Lod(on) => {
                self.report_drag();
                self.state.sampling.lod = on;
            }
            ScriptStep::Resize(w, h) => {
                let _ = self.window.request_inner_size(winit::dpi::PhysicalSize::new(w, h));
                script.waiting_for_size = Some((w, h, 200));
            }
            ScriptStep::Minimize => self.window.set_minimized(true),
            ScriptStep::Restore => {
                self.window.set_minimized(false);
                self.zero_size = false;
            }
            ScriptStep::ZeroSize => self.zero_size = true,
            ScriptStep::Key(k) => {
                let key = match k.as_str() {
                    "r" => egui::Key::R,
                    "space" => egui::Key::Space,
                    "tab" => egui::Key::Tab,
                    "f12" => egui::Key::F12,
                    _ => return Err(ViewerError::Other(format!("script: unknown key {k}"))),
                };
                self.egui_ctx.input_mut(|i| {
                    i.events.push(egui::Event::Key {
                        key,
                        physical_key: None,
                        pressed: true,
                        repeat: false,
                        modifiers: Default::default(),
                    });
                    i.keys_down.insert(key);
                });
                let actions = keys::shortcuts(&self.egui_ctx, &mut self.state);
                self.egui_ctx.input_mut(|i| {
                    i.keys_down.remove(&key);
                    i.events.clear();
                });
                self.apply(actions);
            }
            ScriptStep::Screenshot(path) => self.pending_screenshot = Some(path),
            ScriptStep::Exit => {
                self.report_drag();
                return Ok(Flow::Exit);
            }
        }
        Ok(Flow::Continue)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scripts_parse_and_reject_nonsense() {
        let steps =
            parse_script("frames:3; resize:320x240;minimize;restore;zero-size;key:Tab;screenshot:/tmp/a.png;exit")
                .expect("valid");
        assert_eq!(
            steps,
            vec![
                ScriptStep::Frames(3),
                ScriptStep::Resize(320, 240),
                ScriptStep::Minimize,
                ScriptStep::Restore,
                ScriptStep::ZeroSize,
                ScriptStep::Key("tab".into()),
                ScriptStep::Screenshot(PathBuf::from("/tmp/a.png")),
                ScriptStep::Exit
            ]
        );
        assert_eq!(
            parse_script("drag:5;lod:off;wait:1500").unwrap(),
            vec![
                ScriptStep::Drag(5),
                ScriptStep::Lod(false),
                ScriptStep::Wait(Duration::from_millis(1500))
            ]
        );
        for bad in [
            "frames:x",
            "resize:10",
            "dance",
            "screenshot:",
            "lod:maybe",
            "drag:",
            "wait:",
            "wait:-1",
            "wait:2s",
        ] {
            assert!(parse_script(bad).is_err(), "{bad}");
        }
    }
}
