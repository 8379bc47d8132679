//! Scripted sessions (`--script`): the steps a test gives the viewer, parsed, and how they advance after each
//! frame. Real input (xdotool under Xvfb) is what the viewer tests drive; the script only sets up, waits and
//! captures. The script keeps its own counters and waits; steps that need the window or the app come back as a
//! [`Command`] for the app to carry out.

use crate::viewer::model::Model;
use crate::viewer::ViewerError;
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::event_loop::EventLoopProxy;

/// Reads standard input to its end on a thread of its own, then sets the flag it returns and wakes the loop.
fn watch_stdin(waker: EventLoopProxy<()>) -> Arc<AtomicBool> {
    let ended = Arc::new(AtomicBool::new(false));
    let flag = ended.clone();
    std::thread::spawn(move || {
        let _ = std::io::copy(&mut std::io::stdin().lock(), &mut std::io::sink());
        flag.store(true, Ordering::Release);
        let _ = waker.send_event(());
    });
    ended
}

/// One step of a scripted session (`--script`, used by the tests to drive a real window under Xvfb).
#[derive(Clone, Debug, PartialEq)]
pub enum ScriptStep {
    /// Render this many frames.
    Frames(u32),
    /// Keep the window open for this long, so that a test can drive it with real X input meanwhile (the viewer
    /// draws as it would untouched: when input or an animation asks for a frame).
    Wait(Duration),
    /// Keep the window open until standard input ends (the test closes its end when its input is done): the
    /// test, not a clock, decides when the window may go, so a slow machine cannot end it under a test's hands.
    /// The viewer sleeps meanwhile as it would untouched.
    Hold,
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

/// Parses `frames:3;wait:500;hold;resize:320x240;minimize;restore;zero-size;key:tab;screenshot:PATH;drop:PATH;exit` (wait in
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
                "hold" if arg.is_empty() => ScriptStep::Hold,
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

/// A step the app carries out.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Command {
    Dialog,
    /// Load a file as if dropped on the window.
    Drop(PathBuf),
    Resize(u32, u32),
    Minimize,
    Restore,
    Key(egui::Key),
    Screenshot(PathBuf),
}

/// What the script wants after a frame.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Next {
    /// Keep drawing.
    Continue,
    /// Carry out this step, then keep drawing.
    Run(Command),
    /// The session ends.
    Exit,
}

/// What the script needs to know of the window and the app.
#[derive(Clone, Copy, Debug)]
pub(super) struct Seen {
    /// The window's size now.
    pub(super) window_size: winit::dpi::PhysicalSize<u32>,
    /// A load is under way.
    pub(super) loading: bool,
}

pub(super) struct Script {
    steps: VecDeque<ScriptStep>,
    frames_left: u32,
    drag_left: u32,
    /// A resize asked for: width, height, frames left to wait for it.
    waiting_for_size: Option<(u32, u32, u32)>,
    wait_until: Option<Instant>,
    /// A `hold` under way: set when standard input has ended.
    hold: Option<Arc<AtomicBool>>,
    /// Wakes the event loop when a hold ends.
    waker: EventLoopProxy<()>,
    started: Instant,
    /// A load (the command line's, or a `drop:` step's) is under way.
    pub(super) waiting_for_load: bool,
    /// Behave as if the window were 0×0 (`zero-size`, until `restore`).
    pub(super) zero_size: bool,
    /// Frame times (ms) of scripted drags, reported when the script ends.
    drag_frames: Vec<f64>,
}

impl Script {
    pub(super) fn new(steps: &[ScriptStep], waker: EventLoopProxy<()>) -> Script {
        Script {
            steps: steps.iter().cloned().collect(),
            frames_left: 0,
            drag_left: 0,
            waiting_for_size: None,
            wait_until: None,
            hold: None,
            waker,
            started: Instant::now(),
            waiting_for_load: false,
            zero_size: false,
            drag_frames: Vec::new(),
        }
    }

    /// When the script only waits for time to pass (a `wait:` step with nothing else under way), until when: the
    /// viewer then sleeps until that time or input, like an untouched viewer, instead of drawing frame after frame.
    pub(super) fn waiting_until(&self) -> Option<Instant> {
        let busy =
            self.frames_left > 0 || self.drag_left > 0 || self.waiting_for_size.is_some() || self.waiting_for_load;
        let until = match self.holding() {
            // Until input or the end of the hold (whose thread wakes the loop) asks for a frame.
            true => Some(Instant::now() + Duration::from_secs(3600)),
            false => self.wait_until,
        };
        until.filter(|_| !busy)
    }

    /// A `hold` step waits for standard input to end.
    fn holding(&self) -> bool {
        self.hold.as_ref().is_some_and(|ended| !ended.load(Ordering::Acquire))
    }

    /// A scripted drag is turning the view.
    pub(super) fn dragging(&self) -> bool {
        self.drag_left > 0
    }

    /// A frame of a scripted drag took `ms`.
    pub(super) fn drag_frame(&mut self, ms: f64) {
        self.drag_frames.push(ms);
    }

    /// The session ends: what its frames cost is said on stderr.
    fn end(&mut self, model: &Model) -> Next {
        self.report_drag(model.sampling.lod);
        let stats = &model.stats;
        eprintln!(
            "frames: {} drawn, {} of them marched (the rest showed the view unchanged)",
            stats.drawn, stats.marched
        );
        Next::Exit
    }

    /// Prints the frame times of scripted drags (the first frame of each drag includes the switch of detail).
    fn report_drag(&mut self, lod: bool) {
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
            if lod { "on" } else { "off" }
        );
    }

    /// Advances the script after a frame: counts down frames and drags (a drag turns `model`'s view), waits for a
    /// time, a resize or a load, then takes the next step.
    pub(super) fn advance(&mut self, model: &mut Model, seen: Seen) -> Result<Next, ViewerError> {
        if self.holding() {
            return Ok(Next::Continue);
        }
        self.hold = None;
        if self.started.elapsed() > Duration::from_secs(300) {
            return Err(ViewerError::Other(format!(
                "script timed out with steps left: {:?}",
                self.steps
            )));
        }
        if self.frames_left > 0 {
            self.frames_left -= 1;
            return Ok(Next::Continue);
        }
        if self.wait_until.is_some_and(|t| Instant::now() < t) {
            return Ok(Next::Continue);
        }
        self.wait_until = None;
        if self.drag_left > 0 {
            self.drag_left -= 1;
            model.camera.orbit.turn(0.03);
            return Ok(Next::Continue);
        }
        if !self.waited_for_size(seen.window_size)? || !self.waited_for_load(model, seen.loading) {
            return Ok(Next::Continue);
        }
        let Some(step) = self.steps.pop_front() else {
            return Ok(self.end(model));
        };
        eprintln!("script: {step:?}");
        self.take(step, model)
    }

    /// Whether a resize asked for has arrived (an error once it took too many frames).
    fn waited_for_size(&mut self, size: winit::dpi::PhysicalSize<u32>) -> Result<bool, ViewerError> {
        let Some((w, h, tries)) = self.waiting_for_size else {
            return Ok(true);
        };
        if (size.width, size.height) == (w, h) {
            self.waiting_for_size = None;
            Ok(true)
        } else if tries == 0 {
            Err(ViewerError::Other(format!(
                "window did not resize to {w}x{h} (it is {size:?})"
            )))
        } else {
            self.waiting_for_size = Some((w, h, tries - 1));
            Ok(false)
        }
    }

    /// Whether a load waited for has ended (then says on stderr how).
    fn waited_for_load(&mut self, model: &Model, loading: bool) -> bool {
        if !self.waiting_for_load {
            return true;
        }
        if loading {
            return false;
        }
        self.waiting_for_load = false;
        match &model.messages.error {
            Some(e) => eprintln!("script: load failed: {e}"),
            None => eprintln!("script: loaded {}", model.volume.label),
        }
        true
    }

    /// Starts `step`: the script's own steps here, the rest as a command for the app.
    fn take(&mut self, step: ScriptStep, model: &mut Model) -> Result<Next, ViewerError> {
        let command = match step {
            ScriptStep::Frames(n) => {
                self.frames_left = n;
                return Ok(Next::Continue);
            }
            ScriptStep::Wait(d) => {
                self.wait_until = Some(Instant::now() + d);
                return Ok(Next::Continue);
            }
            ScriptStep::Hold => {
                self.hold = Some(watch_stdin(self.waker.clone()));
                return Ok(Next::Continue);
            }
            ScriptStep::Drag(n) => {
                self.drag_left = n;
                return Ok(Next::Continue);
            }
            ScriptStep::Lod(on) => {
                self.report_drag(model.sampling.lod);
                model.sampling.lod = on;
                return Ok(Next::Continue);
            }
            ScriptStep::ZeroSize => {
                self.zero_size = true;
                return Ok(Next::Continue);
            }
            ScriptStep::Exit => return Ok(self.end(model)),
            ScriptStep::Dialog => Command::Dialog,
            ScriptStep::Drop(path) => {
                self.waiting_for_load = true;
                Command::Drop(path)
            }
            ScriptStep::Resize(w, h) => {
                self.waiting_for_size = Some((w, h, 200));
                Command::Resize(w, h)
            }
            ScriptStep::Minimize => Command::Minimize,
            ScriptStep::Restore => {
                self.zero_size = false;
                Command::Restore
            }
            ScriptStep::Key(k) => Command::Key(match k.as_str() {
                "r" => egui::Key::R,
                "space" => egui::Key::Space,
                "tab" => egui::Key::Tab,
                "f12" => egui::Key::F12,
                _ => return Err(ViewerError::Other(format!("script: unknown key {k}"))),
            }),
            ScriptStep::Screenshot(path) => Command::Screenshot(path),
        };
        Ok(Next::Run(command))
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
            parse_script("drag:5;lod:off;wait:1500;hold").unwrap(),
            vec![
                ScriptStep::Drag(5),
                ScriptStep::Lod(false),
                ScriptStep::Wait(Duration::from_millis(1500)),
                ScriptStep::Hold
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
            "hold:5",
        ] {
            assert!(parse_script(bad).is_err(), "{bad}");
        }
    }
}
