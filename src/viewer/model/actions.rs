//! What the widgets ask of the app beyond editing the model: loading, files, captures — work that needs the GPU,
//! a thread or the file system.

use crate::volume::RawOptions;
use std::path::PathBuf;

/// What the panel (or a shortcut) asks the viewer to do.
#[derive(Clone, Debug)]
pub enum UiAction {
    LoadFile(PathBuf, RawOptions),
    LoadBuiltin(String),
    /// Write the session to `FileFields::session_path`.
    SaveSession,
    /// Restore a session file (loading its volume if another is shown).
    OpenSession(PathBuf),
    Screenshot,
    /// Start recording the 3D view into a GIF, or stop and write it.
    ToggleRecording,
    VsyncChanged,
    /// Show the platform's file dialog (off the render thread).
    OpenDialog,
}

impl UiAction {
    /// Which controls the messages this action causes show beside (`None`: it leaves them where they are).
    pub fn topic(&self) -> Option<super::Topic> {
        use super::Topic;
        match self {
            UiAction::LoadFile(..) | UiAction::LoadBuiltin(_) | UiAction::OpenDialog => Some(Topic::Volume),
            UiAction::SaveSession | UiAction::OpenSession(_) => Some(Topic::Session),
            UiAction::Screenshot | UiAction::ToggleRecording => Some(Topic::Capture),
            _ => None,
        }
    }
}
