//! What the widgets ask of the app beyond editing the model: loading, files, captures — work that needs the GPU,
//! a thread or the file system.

use crate::formats::RawOptions;
use std::path::PathBuf;

/// What the panel (or a shortcut) asks the viewer to do.
#[derive(Clone, Debug)]
pub enum UiAction {
    LoadFile(PathBuf, RawOptions),
    LoadBuiltin(String),
    /// Load another series (its number or UID) from the DICOM folder shown.
    LoadSeries(String),
    /// Write the session to `FileFields::session_path`.
    SaveSession,
    /// Restore a session file (loading its volume if another is shown).
    OpenSession(PathBuf),
    /// F12: the clean render of the 3D view (what `render --state` renders again).
    Screenshot,
    /// Shift+F12: the 3D view as shown, with its outlines, labels and gizmos.
    ScreenshotAsShown,
    /// Start recording the 3D view into a GIF, or stop and write it.
    ToggleRecording,
    /// Shift+F9: the same, recording the view as shown.
    ToggleRecordingAsShown,
    VsyncChanged,
    /// Render the 3D view offscreen at the export fields' size (the colour bar included when asked) into a PNG.
    ExportFigure,
    /// Show the platform's file dialog (off the render thread).
    OpenDialog,
    /// Write the ruler's measurements into the working folder.
    SaveMeasurements(super::measurements::Format),
    /// Read a file as a layer of this kind and show it with the volume.
    AddLayer(PathBuf, crate::scene::layers::LayerKind),
    /// Stop showing layer `i`.
    RemoveLayer(usize),
}

impl UiAction {
    /// Which controls the messages this action causes show beside (`None`: it leaves them where they are).
    pub fn topic(&self) -> Option<super::Topic> {
        use super::Topic;
        match self {
            UiAction::LoadFile(..) | UiAction::LoadBuiltin(_) | UiAction::OpenDialog => Some(Topic::Volume),
            UiAction::SaveSession | UiAction::OpenSession(_) => Some(Topic::Session),
            UiAction::Screenshot | UiAction::ToggleRecording => Some(Topic::Capture),
            UiAction::SaveMeasurements(_) => Some(Topic::Measurements),
            UiAction::AddLayer(..) | UiAction::RemoveLayer(_) => Some(Topic::Layers),
            _ => None,
        }
    }
}
