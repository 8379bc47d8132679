//! What the widgets ask of the app ([`UiAction`]), carried out: loads, captures, sessions, the file dialog.

use super::running::Running;
use crate::viewer::model::actions::UiAction;
use crate::viewer::VolumeSource;
use std::path::PathBuf;

impl Running {
    pub(super) fn apply(&mut self, actions: Vec<UiAction>) {
        for action in actions {
            let messages = &mut self.model.messages;
            messages.about = action.topic().unwrap_or(messages.about);
            match action {
                UiAction::LoadFile(path, opts) => self.loader.start(VolumeSource::File(path, opts), messages),
                UiAction::LoadBuiltin(name) => self.loader.start(VolumeSource::Builtin(name, None), messages),
                UiAction::LoadSeries(series) => self.load_series(series),
                UiAction::Screenshot => self.capture.screenshot_now(false),
                UiAction::ScreenshotAsShown => self.capture.screenshot_now(true),
                UiAction::ToggleRecording => self.capture.toggle_recording(false, messages),
                UiAction::ToggleRecordingAsShown => self.capture.toggle_recording(true, messages),
                UiAction::ExportFigure => self.export_figure(),
                UiAction::VsyncChanged => self.presenter.invalidate_swapchain(),
                UiAction::SaveSession => {
                    let path = PathBuf::from(self.model.files.session_path.trim());
                    self.capture.request_session(path);
                }
                UiAction::OpenSession(path) => self.open_session(&path),
                UiAction::OpenDialog => self.loader.open_dialog(),
                UiAction::SaveMeasurements(format) => super::capture::save_measurements(&mut self.model, format),
                UiAction::AddLayer(path, kind) => self.layers_or_report(|r| r.add_layer(&path, kind)),
                UiAction::RemoveLayer(i) => self.layers_or_report(|r| r.remove_layer(i)),
            }
        }
    }

    /// A change to the layers; where the device fails, its error goes under the Layers section.
    fn layers_or_report(&mut self, change: impl FnOnce(&mut Running) -> Result<(), crate::viewer::ViewerError>) {
        if let Err(e) = change(self) {
            self.model.messages.error = Some(e.to_string());
        }
    }

    /// Another series of the DICOM folder shown.
    fn load_series(&mut self, series: String) {
        if let Some(source @ VolumeSource::File(..)) = self.shown.source.clone() {
            (self.loader).start_series(source, Some(series), &mut self.model.messages);
        }
    }

    /// A file dropped on the window: loaded as a volume, or opened as a session.
    pub(super) fn drop_file(&mut self, path: PathBuf) {
        let action = self.model.files.load_action(path);
        self.apply(vec![action]);
    }
}
