//! Sessions: the viewer's whole state as one JSON file (a [`ViewState`] with its `viewer` part, see
//! `model::session`), written by F12 beside the screenshot, by Ctrl+S or the panel's "Save session", and restored
//! by `volcast view --state FILE`, the panel's "Open session" or by dropping the file on the window. `volcast render
//! --state` renders the same file.

use super::{Running, VolumeSource};
use crate::scene::view_state::{ViewState, VolumeRef};
use crate::volume::{RawOptions, VoxelType};
use std::path::Path;

/// Reads a session (or any view state) file; the error names it.
pub fn read(path: &Path) -> Result<ViewState, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    ViewState::from_json(&text, &path.display().to_string())
}

/// Where a session's volume comes from; None when it names none.
pub fn source_of(r: &VolumeRef) -> Option<VolumeSource> {
    if let Some(name) = &r.builtin {
        return Some(VolumeSource::Builtin(name.clone(), r.builtin_size));
    }
    let path = r.path.clone()?;
    let raw = RawOptions {
        dims: r.raw_dims,
        voxel_type: r.raw_type.as_deref().and_then(VoxelType::parse),
        spacing: r.raw_spacing,
    };
    Some(VolumeSource::File(path, raw))
}

impl Running {
    /// Opens a session: loads its volume unless it is the one shown, then restores the view once it is there.
    pub(super) fn open_session(&mut self, path: &Path) {
        let state = match read(path) {
            Ok(s) => s,
            Err(e) => {
                self.state.messages.error = Some(format!("session {e}"));
                return;
            }
        };
        let Some(source) = source_of(&state.volume) else {
            self.state.messages.error = Some(format!("session {}: it names no volume", path.display()));
            return;
        };
        let shown = self
            .shown_source
            .as_ref()
            .map(|s| super::screenshot::volume_ref(Some(s), self.state.files.raw_spacing, 0));
        let same = shown.is_some_and(|r| {
            (r.path.as_ref(), r.builtin.as_ref(), r.builtin_size)
                == (
                    state.volume.path.as_ref(),
                    state.volume.builtin.as_ref(),
                    state.volume.builtin_size,
                )
        });
        self.state.messages.status = Some(format!("session {}", path.display()));
        if same && self.loading.is_none() {
            self.state.restore(&state);
        } else {
            self.pending_restore = Some(state);
            self.start_load(source);
        }
    }

    /// The whole state as a view state with the given render settings (those of the frame drawn).
    pub(super) fn session_state(&self, settings: &crate::scene::settings::RenderSettings) -> ViewState {
        let step = self.series.as_ref().map(crate::volume::Volume::shown_step);
        ViewState {
            volume: super::screenshot::volume_ref(
                self.shown_source.as_ref(),
                self.state.files.raw_spacing,
                step.unwrap_or(0),
            ),
            settings: settings.clone(),
            viewer: Some(self.state.session()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sources_come_back_from_the_reference() {
        let r = VolumeRef {
            path: Some("/d/x_8x8x8_uint8.raw".into()),
            raw_dims: Some([8, 8, 8]),
            raw_type: Some("uint8".into()),
            ..VolumeRef::default()
        };
        match source_of(&r) {
            Some(VolumeSource::File(p, raw)) => {
                assert_eq!(p, Path::new("/d/x_8x8x8_uint8.raw"));
                assert_eq!(raw.voxel_type, Some(VoxelType::U8));
            }
            other => panic!("{other:?}"),
        }
        assert!(source_of(&VolumeRef::default()).is_none());
    }
}
