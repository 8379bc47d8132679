//! The layers the app holds (their voxels, `scene::layer_set`): those the command line named and those the panel
//! adds or removes. Each change goes to the renderer (which then holds exactly these) and to the model's layer
//! list, whose looks the user edits; a layer that fails to read leaves the others as they were.

use super::running::Running;
use crate::scene::layer_set::{overlap_note, Layers, Looks};
use crate::scene::layers::LayerKind;
use crate::scene::view_state::ViewState;
use crate::viewer::model::layers::LayerEntry;
use crate::viewer::model::Topic;
use crate::viewer::ViewerError;
use std::path::Path;

impl Running {
    /// Shows `layers` in place of those shown. Where the device cannot hold them, the error goes under the Layers
    /// section and no layer is shown.
    pub(super) fn set_layers(&mut self, layers: Layers) -> Result<(), ViewerError> {
        if let Err(e) = self.presenter.set_layers(&layers) {
            self.model.messages.about = Topic::Layers;
            self.model.messages.error = Some(format!("the layers could not be shown: {e}"));
            self.model.messages.status = None;
            self.presenter.set_layers(&Layers::default())?;
            return self.set_layers_shown(Layers::default());
        }
        self.set_layers_shown(layers)
    }

    /// The model's list and what the app holds, after the renderer took `layers`.
    fn set_layers_shown(&mut self, layers: Layers) -> Result<(), ViewerError> {
        let entries = (0..layers.len())
            .map(|i| LayerEntry {
                name: layers.names[i].clone(),
                style: layers.styles[i].clone(),
                range: layers.volumes[i].range,
            })
            .collect();
        self.model.layers.set(entries);
        self.shown.layers = layers;
        Ok(())
    }

    /// The layers held, with the looks the user gave them since.
    fn current_layers(&mut self) -> Layers {
        let mut layers = std::mem::take(&mut self.shown.layers);
        for (style, entry) in layers.styles.iter_mut().zip(&self.model.layers.entries) {
            *style = entry.style.clone();
        }
        layers
    }

    /// Reads `path` as a layer of `kind` and shows it with the others; an error (nothing of the file is kept),
    /// or a note where it lies outside the volume's box, goes under the Layers section.
    pub(super) fn add_layer(&mut self, path: &Path, kind: LayerKind) -> Result<(), ViewerError> {
        let mut read = Layers::default();
        let result = read.add_file(path, kind, None, &self.layer_looks);
        let messages = &mut self.model.messages;
        messages.about = Topic::Layers;
        if let Err(e) = result {
            messages.error = Some(format!("{e:#}"));
            messages.status = None;
            return Ok(());
        }
        let base = self.shown.for_slices();
        let note = read.volumes.iter().find_map(|v| base.and_then(|b| overlap_note(b, v)));
        messages.error = None;
        messages.status = Some(note.unwrap_or_else(|| format!("added {}", path.display())));
        eprintln!("layer added {}", path.display());
        let mut layers = self.current_layers();
        layers.append(read);
        self.set_layers(layers)
    }

    /// A session's layers in place of those shown: its overlays and label maps read again, with the looks it saved.
    /// A file that fails to read leaves the layers as they were (its error under the Layers section). Channels are
    /// the session volume's own: `view --state` reads them with it; here a note says so.
    pub(super) fn restore_layers(&mut self, state: &ViewState) -> Result<(), ViewerError> {
        let files = &state.layer_files;
        let looks = Looks {
            label_ids: files.label_ids.clone(),
            ..self.layer_looks.clone()
        };
        let mut read = Layers::default();
        let table = files.label_table.as_deref();
        let result = (files.overlays.iter().map(|p| (p, LayerKind::Overlay)))
            .chain(files.labels.iter().map(|p| (p, LayerKind::Labels)))
            .try_for_each(|(path, kind)| {
                read.add_file(path, kind, table.filter(|_| kind == LayerKind::Labels), &looks)
            });
        if let Err(e) = result {
            self.model.messages.about = Topic::Layers;
            self.model.messages.error = Some(format!("the session's layers: {e:#}"));
            return Ok(());
        }
        read.styles = read.looks(&state.settings.layers);
        if !files.channels.is_empty() {
            self.model.messages.about = Topic::Layers;
            self.model.messages.status = Some("the session's channels show with `volcast view --state FILE`".into());
        }
        eprintln!("layers restored {}", read.len());
        self.set_layers(read)
    }

    /// Removes layer `i`.
    pub(super) fn remove_layer(&mut self, i: usize) -> Result<(), ViewerError> {
        let mut layers = self.current_layers();
        layers.remove(i);
        self.set_layers(layers)
    }
}
