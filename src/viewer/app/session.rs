//! Sessions from the running viewer: the whole state as a view state (saved with a frame's settings), and opening
//! a session file — its layers read again, its volume loaded unless it is the one shown, then the view restored.

use super::running::Running;
use crate::scene::settings::RenderSettings;
use crate::scene::view_state::ViewState;
use crate::viewer::session::{read, source_of, volume_ref};
use std::path::Path;

impl Running {
    /// The whole state as a view state with the given render settings (those of the frame drawn).
    pub(super) fn view_state(&self, settings: &RenderSettings) -> ViewState {
        let mut volume = volume_ref(
            self.shown.source.as_ref(),
            self.model.files.raw_spacing,
            self.shown.series_step().unwrap_or(0),
        );
        volume.channel = self.loader.channel;
        ViewState {
            volume,
            settings: settings.clone(),
            viewer: Some(self.model.session()),
            layer_files: self.shown.layers.files(),
        }
    }

    /// Opens a session: loads its volume unless it is the one shown, then restores the view once it is there.
    pub(super) fn open_session(&mut self, path: &Path) {
        let messages = &mut self.model.messages;
        let state = match read(path) {
            Ok(s) => s,
            Err(e) => {
                messages.error = Some(format!("session {e}"));
                return;
            }
        };
        let Some(source) = source_of(&state.volume) else {
            messages.error = Some(format!("session {}: it names no volume", path.display()));
            return;
        };
        if state.volume.channel.is_some() {
            self.loader.channel = state.volume.channel;
        }
        let shown = (self.shown.source.as_ref()).map(|s| volume_ref(Some(s), self.model.files.raw_spacing, 0));
        let same = shown.is_some_and(|r| {
            (r.path.as_ref(), r.builtin.as_ref(), r.builtin_size)
                == (
                    state.volume.path.as_ref(),
                    state.volume.builtin.as_ref(),
                    state.volume.builtin_size,
                )
        });
        messages.status = Some(format!("session {}", path.display()));
        if let Err(e) = self.restore_layers(&state) {
            self.model.messages.error = Some(format!("session {}: {e}", path.display()));
        }
        if same && !self.loader.busy() {
            self.model.restore(&state);
        } else {
            self.loader.pending_restore = Some(state);
            self.loader.start(source, &mut self.model.messages);
        }
    }
}
