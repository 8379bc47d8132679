//! What the viewer captures of its view: the F12 screenshot (the view image's pixels, and beside it the view
//! state that `volcast render --state` renders again), the session saved with a frame's settings (Ctrl+S), and
//! the GIF recording (F9). Captures are requested here and served after a frame is presented.

use super::recording::Recorder;
use crate::scene::view_state::ViewState;
use crate::viewer::model::Messages;
use crate::viewer::session::write_session;
use crate::viewer::ViewerError;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The captures asked for.
#[derive(Default)]
pub(super) struct Capture {
    /// Save the next full frame here.
    screenshot: Option<PathBuf>,
    /// Save the session here with the next frame's settings.
    session: Option<PathBuf>,
    /// The GIF being recorded.
    recorder: Option<Recorder>,
}

impl Capture {
    pub(super) fn request_screenshot(&mut self, path: PathBuf) {
        self.screenshot = Some(path);
    }

    pub(super) fn request_session(&mut self, path: PathBuf) {
        self.session = Some(path);
    }

    /// The next frame is captured (so it must be a full-detail one) and its view image read back.
    pub(super) fn wants_pixels(&self) -> bool {
        self.screenshot.is_some() || self.recorder.is_some()
    }

    pub(super) fn take_session(&mut self) -> Option<PathBuf> {
        self.session.take()
    }

    pub(super) fn take_screenshot(&mut self) -> Option<PathBuf> {
        self.screenshot.take()
    }

    /// F9: starts a recording into `volcast-<time>.gif`, or stops the one running and writes it.
    pub(super) fn toggle_recording(&mut self, messages: &mut Messages) {
        if self.recorder.is_some() {
            self.stop_recording(messages);
            return;
        }
        let path = PathBuf::from(format!("volcast-{}.gif", time_stamp()));
        eprintln!("recording {}", path.display());
        messages.recording = Some(path.display().to_string());
        self.recorder = Some(Recorder::new(path));
    }

    /// Ends a recording (if one runs): writes its GIF, or says why not.
    pub(super) fn stop_recording(&mut self, messages: &mut Messages) {
        let Some(r) = self.recorder.take() else { return };
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

    /// Adds a frame shown at `at` (`width`×`height` RGBA8) to the recording, if one runs; an error stops it.
    pub(super) fn record(
        &mut self,
        pixels: Result<Vec<u8>, String>,
        (width, height): (u32, u32),
        at: Instant,
        messages: &mut Messages,
    ) {
        let Some(recorder) = self.recorder.as_mut() else { return };
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

/// Writes the session file, saying in `messages` where or why not.
pub(super) fn save_session(path: &Path, state: &ViewState, messages: &mut Messages) {
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
    crate::render::png::save(&img, path).map_err(ViewerError::Other)?;
    // The view state: the settings (still readable as plain `RenderSettings`), the volume's origin and the
    // viewer's own state, so that `volcast render --state` renders this view again and `view --state` restores it.
    write_session(&path.with_extension("json"), state).map_err(ViewerError::Other)?;
    match step {
        Some(t) => eprintln!("saved screenshot {} (time step {t})", path.display()),
        None => eprintln!("saved screenshot {}", path.display()),
    }
    Ok(())
}

/// Seconds since 1970, for the names of screenshots and recordings.
pub(super) fn time_stamp() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0)
}
