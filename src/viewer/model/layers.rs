//! The layer list (rule 13's layers, `scene::layers`) as the panel edits it: each layer's name and look, the path
//! to add one from, and a count that changes with every edit (the slice views' images are made again). The layers'
//! voxels are the app's (`app::volumes::Shown`); frames take their looks from here.

use crate::scene::layers::{LayerKind, LayerStyle};
use crate::scene::settings::{CompositeMode, RenderSettings};

/// One layer as the panel shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerEntry {
    /// Its file, as the user named it.
    pub name: String,
    pub style: LayerStyle,
    /// An overlay's values (data units): the threshold's slider spans them.
    pub range: [f64; 2],
}

/// The layers shown with the volume, in the order frames mix them (overlays, then label maps).
#[derive(Clone, Debug, Default)]
pub struct LayerList {
    pub entries: Vec<LayerEntry>,
    /// The panel's field: the file to add as a layer.
    pub path: String,
    /// Changes whenever a layer is added, removed or restyled.
    pub generation: u64,
}

impl LayerList {
    /// Replaces the entries by the app's layers (after one was added or removed), keeping nothing of the old.
    pub fn set(&mut self, entries: Vec<LayerEntry>) {
        self.entries = entries;
        self.generation += 1;
    }

    /// Each layer's look, in order.
    pub fn styles(&self) -> Vec<LayerStyle> {
        self.entries.iter().map(|e| e.style.clone()).collect()
    }

    /// Why frames of `look` show no layers (layers mix in depth only in the emission and density modes, and not
    /// with shadows or ambient occlusion), or `None` where they show them.
    pub fn hidden_by(&self, look: &RenderSettings) -> Option<&'static str> {
        if self.entries.is_empty() {
            None
        } else if !matches!(look.compositing.mode, CompositeMode::Emission | CompositeMode::Density) {
            Some("layers show in the emission and density modes; this mode shows the volume alone")
        } else if look.uses_light_volume() {
            Some("layers do not show with shadows or ambient occlusion yet; turn them off to see them")
        } else {
            None
        }
    }

    /// The looks a frame of `look` mixes: every layer's, or none where the frame cannot mix them (`hidden_by`).
    pub fn frame_styles(&self, look: &RenderSettings) -> Vec<LayerStyle> {
        match self.hidden_by(look) {
            None => self.styles(),
            Some(_) => Vec::new(),
        }
    }

    /// How many overlays come before the label maps.
    pub fn overlays(&self) -> usize {
        self.entries
            .iter()
            .filter(|e| e.style.kind == LayerKind::Overlay)
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn list() -> LayerList {
        let entry = |kind| LayerEntry {
            name: "a".into(),
            style: LayerStyle {
                kind,
                ..LayerStyle::default()
            },
            range: [0.0, 1.0],
        };
        let mut l = LayerList::default();
        l.set(vec![entry(LayerKind::Overlay), entry(LayerKind::Labels)]);
        l
    }

    #[test]
    fn frames_mix_the_layers_only_where_they_can() {
        let l = list();
        let mut look = RenderSettings::default();
        look.compositing.mode = CompositeMode::Emission;
        assert_eq!(l.frame_styles(&look).len(), 2);
        assert!(l.hidden_by(&look).is_none());
        look.compositing.mode = CompositeMode::Mip;
        assert!(l.frame_styles(&look).is_empty());
        assert!(l.hidden_by(&look).is_some_and(|w| w.contains("emission")));
        assert_eq!(l.overlays(), 1);
    }
}
