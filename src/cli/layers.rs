//! `--overlay`, `--labels` and their looks: the layers a render shows with its volume (rule 13,
//! `scene::layers`), read from their files (`scene::layer_set`) and handed to the renderer.

use crate::formats::label_table;
use crate::render::headless::Headless;
use crate::scene::layer_set::{overlap_note, Looks};
use crate::scene::layers::{Blend, LayerKind};
use crate::scene::settings::RenderSettings;
use crate::scene::view_state::LayerFiles;
use crate::transfer::colormap::Colormap;
use crate::volume::labels::{LabelMap, LabelTable};
use crate::volume::Volume;
use anyhow::{bail, Context, Result};
use std::path::PathBuf;

pub use crate::scene::layer_set::{read_labels, Layers};

/// Further volumes shown in depth with the first, each on its own grid.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct LayerArgs {
    /// A further volume composited in depth with the first (repeatable): an fMRI map, a second modality
    ///
    /// Placed by its own affine in the first volume's world (no resampling); a signed map (values both sides of
    /// 0) gets the diverging cool-warm colormap centred on 0.
    #[arg(long, value_name = "FILE", help_heading = "Layers")]
    pub overlay: Vec<PathBuf>,
    /// Show the overlays where value ≥ T, or |value| ≥ T for a signed one, in the overlay's own units
    #[arg(long, value_name = "T", help_heading = "Layers")]
    pub threshold: Option<f64>,
    /// The overlays' opacity per voxel of their own grid (default 0.6)
    #[arg(long, value_name = "A", help_heading = "Layers", hide_short_help = true)]
    pub overlay_opacity: Option<f32>,
    /// The overlays' colormap (default: cool-warm for signed maps, plasma for others)
    #[arg(long, value_name = "NAME", value_parser = super::parse::parse_colormap, help_heading = "Layers", hide_short_help = true)]
    pub overlay_colormap: Option<Colormap>,
    /// How the overlays meet the rest: composite (in depth, default), max (each one's brightest along the ray) or
    /// add (light without absorption, as fluorescence); max and add are dimmed by what lies in front
    #[arg(long, value_name = "BLEND", value_parser = super::parse::parse_blend, help_heading = "Layers", hide_short_help = true)]
    pub overlay_blend: Option<Blend>,
    /// Further channels of the volume's file as overlays: `all`, or their numbers (e.g. 1,2)
    ///
    /// Each channel of an OME-Zarr image with a `c` axis, an ImageJ or OME-TIFF hyperstack, or a 5-D NIfTI is read
    /// as the volume is (the same level) and shown in its colour (omero's, else ImageJ's), a ramp from black over
    /// its window (else its range), blended by maximum (--overlay-blend) at full opacity (--overlay-opacity);
    /// `volcast info FILE` lists them. The volume itself shows --channel (default 0).
    #[arg(
        long,
        value_name = "all|N,..",
        value_delimiter = ',',
        help_heading = "Layers",
        hide_short_help = true
    )]
    pub channels: Vec<String>,
    /// A label map (an atlas, a segmentation) composited in depth with the volume (repeatable)
    ///
    /// Integer ids, sampled at the nearest voxel and coloured per id: by the label table beside it (NAME.txt with
    /// mricron's NAME.lut, NAME.ctbl, NAME.label) or --label-table, else a distinct default colour per id.
    #[arg(long, value_name = "FILE", help_heading = "Layers")]
    pub labels: Vec<PathBuf>,
    /// The label maps' table: FreeSurfer/Slicer colour table, ITK-SNAP label description or mricron .txt (+ .lut)
    #[arg(long, value_name = "FILE", help_heading = "Layers", hide_short_help = true)]
    pub label_table: Option<PathBuf>,
    /// Show only these label ids, comma-separated (default: every id)
    #[arg(
        long,
        value_name = "IDS",
        value_delimiter = ',',
        help_heading = "Layers",
        hide_short_help = true
    )]
    pub label_ids: Vec<u32>,
    /// The label maps' opacity per voxel of their own grid (default 0.5)
    #[arg(long, value_name = "A", help_heading = "Layers", hide_short_help = true)]
    pub label_opacity: Option<f32>,
}

impl LayerArgs {
    pub fn any(&self) -> bool {
        !self.overlay.is_empty() || !self.labels.is_empty() || !self.channels.is_empty()
    }

    /// These arguments with a saved view's layer files where none are given here; true where they are the view's.
    pub fn or_from(&self, files: &LayerFiles) -> (LayerArgs, bool) {
        if self.any() || files.is_empty() {
            return (self.clone(), false);
        }
        let mut a = self.clone();
        a.overlay = files.overlays.clone();
        a.labels = files.labels.clone();
        a.label_table = a.label_table.or(files.label_table.clone());
        a.label_ids = files.label_ids.clone();
        a.channels = files.channels.clone();
        (a, true)
    }

    /// The files these arguments name, absolute: what a saved view records.
    pub fn files(&self) -> LayerFiles {
        let absolute = |p: &PathBuf| std::fs::canonicalize(p).unwrap_or_else(|_| p.clone());
        LayerFiles {
            overlays: self.overlay.iter().map(absolute).collect(),
            labels: self.labels.iter().map(absolute).collect(),
            label_table: self.label_table.as_ref().map(absolute),
            label_ids: self.label_ids.clone(),
            channels: self.channels.clone(),
        }
    }

    /// Whether a layer's look is given here: then a saved view's looks give way to these.
    pub fn styled(&self) -> bool {
        self.threshold.is_some()
            || self.overlay_opacity.is_some()
            || self.overlay_colormap.is_some()
            || self.overlay_blend.is_some()
            || self.label_opacity.is_some()
    }

    /// The channels `--channels` names of `base`'s file (not the one `base` shows), each read by `open(channel)`.
    pub fn channels_of(&self, base: &Volume, open: impl Fn(u32) -> Result<Volume>) -> Result<Vec<Volume>> {
        if self.channels.is_empty() {
            return Ok(Vec::new());
        }
        let count = base.channels.len() as u32;
        if count == 0 {
            bail!(
                "{}: --channels needs a file with channels (an OME-Zarr image with a c axis); this one has one",
                base.name
            );
        }
        let shown = base.channels.iter().position(|c| c.loaded).unwrap_or(0) as u32;
        let wanted: Vec<u32> = if self.channels.iter().any(|c| c.trim() == "all") {
            (0..count).collect()
        } else {
            let number = |c: &String| {
                c.trim()
                    .parse::<u32>()
                    .ok()
                    .filter(|&k| k < count)
                    .with_context(|| format!("{}: --channels {c}: the channels are 0 to {}", base.name, count - 1))
            };
            self.channels.iter().map(number).collect::<Result<_>>()?
        };
        let mut volumes = Vec::new();
        for k in wanted.into_iter().filter(|&k| k != shown) {
            volumes.push(open(k)?);
        }
        Ok(volumes)
    }

    /// Reads every layer; warnings (a table naming ids the map lacks, duplicate ids) go to stderr.
    pub fn load(&self) -> Result<Layers> {
        self.load_with(Vec::new())
    }

    /// The layers of the files named, and `held` (volumes the caller holds, each an overlay or, with `true`, a
    /// label map), in order: the overlays' files, the overlays held, the label maps' files, the label maps held.
    pub fn load_with(&self, held: Vec<(Volume, bool)>) -> Result<Layers> {
        self.load_all(Vec::new(), held)
    }

    /// [`LayerArgs::load_with`] with `channels` (from [`LayerArgs::channels_of`]) after the overlays' files.
    pub fn load_all(&self, channels: Vec<Volume>, held: Vec<(Volume, bool)>) -> Result<Layers> {
        let looks = self.looks();
        let mut layers = Layers::default();
        let (held_labels, held_overlays): (Vec<_>, Vec<_>) = held.into_iter().partition(|(_, labels)| *labels);
        for path in &self.overlay {
            layers.add_file(path, LayerKind::Overlay, None, &looks)?;
        }
        for v in channels {
            layers.add_channel(v, &looks)?;
        }
        for (v, _) in held_overlays {
            let name = v.name.clone();
            layers.add_overlay(v, &name, &looks)?;
        }
        for path in &self.labels {
            layers.add_file(path, LayerKind::Labels, self.label_table.as_deref(), &looks)?;
        }
        // The arrays' table: --label-table, read once for all of them.
        let held_table = match (&self.label_table, held_labels.is_empty()) {
            (Some(file), false) => label_table::read(file)?.0,
            _ => LabelTable::default(),
        };
        for (v, _) in held_labels {
            let map = LabelMap::of(&v).with_context(|| format!("{} is not a label map", v.name))?;
            let name = v.name.clone();
            layers.add_labels(v, map, held_table.clone(), &name, &looks)?;
        }
        Ok(layers)
    }

    /// The looks new layers take from these arguments.
    pub fn looks(&self) -> Looks {
        Looks {
            threshold: self.threshold,
            overlay_opacity: self.overlay_opacity,
            overlay_colormap: self.overlay_colormap,
            overlay_blend: self.overlay_blend,
            label_opacity: self.label_opacity,
            label_ids: self.label_ids.clone(),
        }
    }
}

/// Hands `layers` to the renderer and styles `s` with them; says where a layer lies outside `base`'s box.
pub fn show(
    layers: &Layers,
    gpu: &crate::gpu::Gpu,
    headless: &mut Headless,
    base: &Volume,
    s: &mut RenderSettings,
) -> Result<()> {
    upload(layers, gpu, headless, base)?;
    s.layers = layers.looks(&s.layers);
    Ok(())
}

/// Gives the renderer `layers` over `base` (a note where one reaches beyond its box); frames style them with their
/// styles.
pub fn upload(layers: &Layers, gpu: &crate::gpu::Gpu, headless: &mut Headless, base: &Volume) -> Result<()> {
    for v in &layers.volumes {
        if let Some(note) = overlap_note(base, v) {
            eprintln!("note: {note}");
        }
    }
    headless.renderer.show_layers(gpu, layers)?;
    Ok(())
}

/// Refuses options that layers do not mix with, before anything is read: `any`, whether there are layers (files
/// named in `LayerArgs`, or volumes a caller holds).
pub fn check(any: bool, s: &RenderSettings) -> Result<()> {
    use crate::scene::settings::CompositeMode as M;
    if any && !matches!(s.compositing.mode, M::Emission | M::Density) {
        bail!(super::UsageError(format!(
            "--overlay and --labels are composited in depth in the emission and density modes; --mode {} shows one \
             volume",
            s.compositing.mode.name()
        )));
    }
    Ok(())
}
