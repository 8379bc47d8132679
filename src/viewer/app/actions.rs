//! What the widgets ask of the app ([`UiAction`]), carried out: loads, captures, sessions, the file dialog.

use super::capture::time_stamp;
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
                UiAction::Screenshot => {
                    let path = PathBuf::from(format!("volcast-{}.png", time_stamp()));
                    self.capture.request_screenshot(path);
                }
                UiAction::ToggleRecording => self.capture.toggle_recording(messages),
                UiAction::VsyncChanged => self.presenter.invalidate_swapchain(),
                UiAction::SaveSession => {
                    let path = PathBuf::from(self.model.files.session_path.trim());
                    self.capture.request_session(path);
                }
                UiAction::OpenSession(path) => self.open_session(&path),
                UiAction::OpenDialog => self.loader.open_dialog(),
            }
        }
    }

    /// A file dropped on the window: loaded as a volume, or opened as a session.
    pub(super) fn drop_file(&mut self, path: PathBuf) {
        let action = self.model.files.load_action(path);
        self.apply(vec![action]);
    }
}
