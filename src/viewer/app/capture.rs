//! What the viewer captures of its view: the F12 screenshot (the view image's pixels, and beside it the view
//! state that `volcast render --state` renders again; Shift+F12 the view as shown, overlays included), the
//! session saved with a frame's settings (Ctrl+S), and the GIF recording (F9, Shift+F9 as shown). Captures are
//! requested here and served after a frame is presented; their files are named by [`file_names`].

use super::file_names;
use super::recording::Recorder;
use crate::scene::view_state::ViewState;
use crate::viewer::model::measurements::{self, Format};
use crate::viewer::model::{Messages, Model};
use crate::viewer::present::{Pixels, Wanted};
use crate::viewer::session::write_session;
use crate::viewer::ViewerError;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A screenshot asked for: where, and whether of the view as shown (else the clean render).
pub(super) struct Shot {
    pub(super) path: PathBuf,
    pub(super) as_shown: bool,
}

/// The captures asked for.
#[derive(Default)]
pub(super) struct Capture {
    /// Save the next full frame here (each press its own file, even when two come within one frame).
    screenshots: Vec<Shot>,
    /// Save the session here with the next frame's settings.
    session: Option<PathBuf>,
    /// The GIF being recorded, and whether of the view as shown.
    recorder: Option<(Recorder, bool)>,
    /// Names handed out this session (a screenshot's file does not exist until its frame is read back).
    named: Vec<PathBuf>,
}

impl Capture {
    pub(super) fn request_screenshot(&mut self, path: PathBuf, as_shown: bool) {
        self.screenshots.push(Shot { path, as_shown });
    }

    /// F12 (clean) or Shift+F12 (as shown): a screenshot under a new readable name.
    pub(super) fn screenshot_now(&mut self, as_shown: bool) {
        let path = self.new_name("png");
        self.request_screenshot(path, as_shown);
    }

    /// `volcast-<local date and time>.EXT`, unused on disk and in this session.
    pub(super) fn new_name(&mut self, ext: &str) -> PathBuf {
        let path = file_names::capture_path(ext, |p| p.exists() || self.named.iter().any(|n| n == p));
        self.named.push(path.clone());
        path
    }

    pub(super) fn request_session(&mut self, path: PathBuf) {
        self.session = Some(path);
    }

    /// Which pixels the next frame must read back; any: it is captured, so it must be a full-detail one.
    pub(super) fn wants(&self) -> Wanted {
        let recording = self.recorder.as_ref().map(|(_, shown)| *shown);
        Wanted {
            clean: self.screenshots.iter().any(|s| !s.as_shown) || recording == Some(false),
            shown: self.screenshots.iter().any(|s| s.as_shown) || recording == Some(true),
        }
    }

    pub(super) fn wants_pixels(&self) -> bool {
        self.wants().any()
    }

    pub(super) fn take_session(&mut self) -> Option<PathBuf> {
        self.session.take()
    }

    pub(super) fn take_screenshots(&mut self) -> Vec<Shot> {
        std::mem::take(&mut self.screenshots)
    }

    /// F9 (clean) or Shift+F9 (as shown): starts a recording into `volcast-<date and time>.gif`, or stops the
    /// one running and writes it.
    pub(super) fn toggle_recording(&mut self, as_shown: bool, messages: &mut Messages) {
        if self.recorder.is_some() {
            self.stop_recording(messages);
            return;
        }
        let path = self.new_name("gif");
        let kind = if as_shown { " (as shown)" } else { "" };
        eprintln!("recording {}{kind}", path.display());
        messages.recording = Some(path.display().to_string());
        self.recorder = Some((Recorder::new(path), as_shown));
    }

    /// Ends a recording (if one runs): writes its GIF, or says why not.
    pub(super) fn stop_recording(&mut self, messages: &mut Messages) {
        let Some((r, _)) = self.recorder.take() else { return };
        let path = r.path().display().to_string();
        messages.recording = None;
        match r.finish(Instant::now()) {
            Ok(frames) => {
                eprintln!("saved recording {path} ({frames} frames)");
                messages.status = Some(format!("saved {path} ({frames} frames)"));
            }
            Err(e) => {
                eprintln!("recording: {e}");
                messages.error = Some(format!("recording: {e}"));
            }
        }
    }

    /// Adds a frame shown at `at` (`width`×`height` RGBA8, of the kind it records) to the recording, if one runs;
    /// an error stops it.
    pub(super) fn record(&mut self, pixels: Pixels, (width, height): (u32, u32), at: Instant, messages: &mut Messages) {
        let Some((recorder, as_shown)) = self.recorder.as_mut() else {
            return;
        };
        let pixels = if *as_shown { pixels.shown } else { pixels.clean };
        let pixels = pixels.unwrap_or_else(|| Err("the frame was not read back".into()));
        if let Err(e) = pixels.and_then(|p| recorder.push(width, height, p, at)) {
            messages.error = Some(format!("recording: {e}"));
            self.stop_recording(messages);
        }
    }
}

/// Saves a screenshot (and its view state beside it), saying in `messages` where or why not.
pub(super) fn screenshot(
    path: &Path,
    pixels: Result<Vec<u8>, String>,
    state: &ViewState,
    step: Option<u32>,
    messages: &mut Messages,
) {
    let saved = pixels
        .map_err(ViewerError::Other)
        .and_then(|p| save_screenshot(path, p, state, step));
    match saved {
        Ok(()) => messages.status = Some(format!("saved {}", path.display())),
        Err(e) => messages.error = Some(format!("screenshot: {e}")),
    }
}

/// Writes the ruler's measurements into the working folder (`volcast-<date and time>.csv` or `.json`), saying in
/// the model's messages where or why not.
pub(super) fn save_measurements(model: &mut Model, format: Format) {
    let path = file_names::capture_path(format.extension(), |p| p.exists());
    let name = model.volume.label.split(" — ").next().unwrap_or_default().to_string();
    let text = measurements::write(format, &name, model.anatomical(), &model.slices.ruler.measured);
    let messages = &mut model.messages;
    match std::fs::write(&path, text) {
        Ok(()) => {
            eprintln!("saved measurements {}", path.display());
            messages.status = Some(format!("saved {}", path.display()));
        }
        Err(e) => messages.error = Some(format!("cannot write {}: {e}", path.display())),
    }
}

/// Writes the session file, saying in `messages` where (by its absolute path, whatever the working folder) or why
/// not.
pub(super) fn save_session(path: &Path, state: &ViewState, messages: &mut Messages) {
    let path = &std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    match write_session(path, state) {
        Ok(()) => {
            eprintln!("saved session {}", path.display());
            messages.status = Some(format!("saved session {}", path.display()));
        }
        Err(e) => messages.error = Some(e),
    }
}

/// Writes the view image's pixels (RGBA8, exactly what the view shows without the panel) and the settings; a
/// series' shown step is logged after the file name.
fn save_screenshot(path: &Path, pixels: Vec<u8>, state: &ViewState, step: Option<u32>) -> Result<(), ViewerError> {
    let settings = &state.settings;
    let img = image::RgbaImage::from_raw(settings.width, settings.height, pixels)
        .ok_or_else(|| ViewerError::Other("screenshot size mismatch".into()))?;
    crate::render::save::save(&img, path).map_err(ViewerError::Other)?;
    // The view state: the settings (still readable as plain `RenderSettings`), the volume's origin and the
    // viewer's own state, so that `volcast render --state` renders this view again and `view --state` restores it.
    write_session(&path.with_extension("json"), state).map_err(ViewerError::Other)?;
    match step {
        Some(t) => eprintln!("saved screenshot {} (time step {t})", path.display()),
        None => eprintln!("saved screenshot {}", path.display()),
    }
    Ok(())
}
