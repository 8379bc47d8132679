//! `--overlay`, `--labels` and their looks: the layers a render shows with its volume (rule 13,
//! `scene::layers`), read from their files, their label tables found, and handed to the renderer.

use crate::formats::{label_table, open, OpenOptions};
use crate::render::headless::Headless;
use crate::render::layers::LayerInput;
use crate::scene::layers::{Blend, LayerStyle};
use crate::scene::settings::RenderSettings;
use crate::scene::view_state::LayerFiles;
use crate::transfer::colormap::Colormap;
use crate::volume::labels::{LabelMap, LabelTable};
use crate::volume::Volume;
use anyhow::{bail, Context, Result};
use glam::DVec3;
use std::path::{Path, PathBuf};

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
    /// Each channel of an OME-Zarr image with a `c` axis is read as the volume is (the same level) and shown in its
    /// omero colour, a ramp from black over its window, blended by maximum (--overlay-blend) at full opacity
    /// (--overlay-opacity); `volcast info STORE` lists them. The volume itself shows --channel (default 0).
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

/// The layers read from their files, in order: the overlays, then the label maps.
pub struct Layers {
    pub volumes: Vec<Volume>,
    /// Per layer: a label map's dense ids and the sRGB colour of each.
    pub labels: Vec<Option<(LabelMap, Vec<[u8; 4]>)>>,
    pub styles: Vec<LayerStyle>,
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
        let mut layers = Layers {
            volumes: Vec::new(),
            labels: Vec::new(),
            styles: Vec::new(),
        };
        let (held_labels, held_overlays): (Vec<_>, Vec<_>) = held.into_iter().partition(|(_, labels)| *labels);
        for path in &self.overlay {
            let v = open(path, &OpenOptions::default())?;
            self.add_overlay(&mut layers, v, &path.display().to_string())?;
        }
        for v in channels {
            self.add_channel(&mut layers, v)?;
        }
        for (v, _) in held_overlays {
            let name = v.name.clone();
            self.add_overlay(&mut layers, v, &name)?;
        }
        for path in &self.labels {
            for (v, map, table) in read_labels(path, self.label_table.as_deref())? {
                self.add_labels(&mut layers, v, map, &table, &path.display().to_string())?;
            }
        }
        // The arrays' table: --label-table, read once for all of them.
        let held_table = match (&self.label_table, held_labels.is_empty()) {
            (Some(file), false) => label_table::read(file)?.0,
            _ => LabelTable::default(),
        };
        for (v, _) in held_labels {
            let map = LabelMap::of(&v).with_context(|| format!("{} is not a label map", v.name))?;
            let name = v.name.clone();
            self.add_labels(&mut layers, v, map, &held_table, &name)?;
        }
        Ok(layers)
    }

    fn add_overlay(&self, layers: &mut Layers, v: Volume, name: &str) -> Result<()> {
        let mut style = LayerStyle::overlay(v.range, self.threshold);
        style.opacity = self.overlay_opacity.unwrap_or(style.opacity);
        style.colormap = self.overlay_colormap.unwrap_or(style.colormap);
        style.blend = self.overlay_blend.unwrap_or(style.blend);
        style.check().map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        layers.volumes.push(v);
        layers.labels.push(None);
        layers.styles.push(style);
        Ok(())
    }

    /// A channel: its omero colour as a ramp over its window (shown from the window's start), by maximum at full
    /// opacity unless told otherwise.
    fn add_channel(&self, layers: &mut Layers, v: Volume) -> Result<()> {
        let display = v.channels.iter().find(|c| c.loaded).map(|c| (c.window, c.color));
        let (window, tint) = match display {
            Some((w, c)) if w[0] < w[1] => (w, c),
            Some((_, c)) => (v.range, c),
            None => (v.range, [255, 255, 255]),
        };
        let style = LayerStyle {
            window,
            threshold: Some(self.threshold.unwrap_or(window[0])),
            tint: self.overlay_colormap.is_none().then_some(tint),
            colormap: self.overlay_colormap.unwrap_or(Colormap::Grayscale),
            blend: self.overlay_blend.unwrap_or(Blend::Max),
            opacity: self.overlay_opacity.unwrap_or(1.0),
            ..LayerStyle::default()
        };
        let name = v.name.clone();
        style.check().map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        layers.volumes.push(v);
        layers.labels.push(None);
        layers.styles.push(style);
        Ok(())
    }

    fn add_labels(&self, layers: &mut Layers, v: Volume, map: LabelMap, table: &LabelTable, name: &str) -> Result<()> {
        let rgba = map.ids.iter().map(|&id| self.colour(table, id)).collect();
        let mut style = LayerStyle::labels();
        style.opacity = self.label_opacity.unwrap_or(style.opacity);
        style.check().map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        layers.volumes.push(v);
        layers.labels.push(Some((map, rgba)));
        layers.styles.push(style);
        Ok(())
    }

    /// An id's colour: the table's, hidden where --label-ids leaves it out.
    fn colour(&self, table: &LabelTable, id: u32) -> [u8; 4] {
        let mut c = table.rgba(id);
        if !self.label_ids.is_empty() && !self.label_ids.contains(&id) {
            c[3] = 0;
        }
        c
    }
}

impl Layers {
    /// Hands the layers to the renderer and styles `s` with them; says where a layer lies outside `base`'s box.
    pub fn show(
        &self,
        gpu: &crate::gpu::Gpu,
        headless: &mut Headless,
        base: &Volume,
        s: &mut RenderSettings,
    ) -> Result<()> {
        self.upload(gpu, headless, base)?;
        s.layers = self.looks(&s.layers);
        Ok(())
    }

    /// The looks frames give these layers: `saved` (a saved view's, for its own layers) where it styles layers of the
    /// same kinds, else their own.
    pub fn looks(&self, saved: &[LayerStyle]) -> Vec<LayerStyle> {
        let fits = saved.len() == self.styles.len() && saved.iter().zip(&self.styles).all(|(a, b)| a.kind == b.kind);
        if fits {
            saved.to_vec()
        } else {
            self.styles.clone()
        }
    }

    /// Gives the renderer these layers over `base` (a note where one reaches beyond its box); frames style them
    /// with `styles`.
    pub fn upload(&self, gpu: &crate::gpu::Gpu, headless: &mut Headless, base: &Volume) -> Result<()> {
        for v in &self.volumes {
            if let Some(note) = overlap_note(base, v) {
                eprintln!("note: {note}");
            }
        }
        let inputs: Vec<LayerInput> = self
            .volumes
            .iter()
            .zip(&self.labels)
            .map(|(volume, labels)| LayerInput {
                volume,
                labels: labels.as_ref().map(|(m, c)| (m, c.clone())),
            })
            .collect();
        headless.renderer.set_layers(gpu, &inputs)?;
        Ok(())
    }
}

/// A label map's layer: its volume, its ids made dense, and its table.
pub type LabelLayer = (Volume, LabelMap, LabelTable);

/// The label map at `path`, its ids made dense, and its table: `table` if given, else the one beside it, else
/// none. A 3D Slicer segmentation (`.seg.nrrd`) gives one label map per layer (overlapping segments lie in
/// separate layers), named and coloured by its segments. Warnings (a table naming ids the map lacks, duplicate
/// ids) go to stderr.
pub fn read_labels(path: &Path, table: Option<&Path>) -> Result<Vec<LabelLayer>> {
    let mut v = open(path, &OpenOptions::default())?;
    if table.is_none() {
        if let Some(segments) = label_table::seg_nrrd(path)? {
            let mut layers = Vec::new();
            for t in 0..v.timesteps() {
                v.show_step(t)?;
                let mut step = v.clone();
                step.time = Default::default();
                let map = label_map(&step, path)?;
                let table = label_table::layer_table(&segments, t);
                eprintln!(
                    "labels: layer {t} of {}: {} segment(s)",
                    path.display(),
                    table.entries.len()
                );
                layers.push((step, map, table));
            }
            return Ok(layers);
        }
    }
    let map = label_map(&v, path)?;
    let Some(file) = table.map(Path::to_path_buf).or_else(|| label_table::beside(path)) else {
        return Ok(vec![(v, map, LabelTable::default())]);
    };
    let (table, warnings) = label_table::read(&file)?;
    for w in warnings {
        eprintln!("warning: {w}");
    }
    warn_missing(&table, &map, &file, path);
    eprintln!(
        "labels: {} ids in {}, named by {}",
        map.ids.len() - 1,
        path.display(),
        file.display()
    );
    Ok(vec![(v, map, table)])
}

fn label_map(v: &Volume, path: &Path) -> Result<LabelMap> {
    LabelMap::of(v).with_context(|| format!("{} is not a label map", path.display()))
}

/// Warns where `table` (read from `file`) names ids the map at `path` lacks.
fn warn_missing(table: &LabelTable, map: &LabelMap, file: &Path, path: &Path) {
    let missing: Vec<u32> = table
        .entries
        .iter()
        .map(|e| e.id)
        .filter(|&id| id != 0 && map.dense(id).is_none())
        .collect();
    if !missing.is_empty() {
        let shown: Vec<String> = missing.iter().take(5).map(u32::to_string).collect();
        eprintln!(
            "warning: {} names {} id(s) that {} does not hold ({}{})",
            file.display(),
            missing.len(),
            path.display(),
            shown.join(", "),
            if missing.len() > 5 { ", …" } else { "" }
        );
    }
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

/// A note where `layer` does not lie wholly inside `base`'s box in world space: the march runs through the base's
/// box, so only the part inside it is drawn.
fn overlap_note(base: &Volume, layer: &Volume) -> Option<String> {
    let to_base = base.geometry.affine.inverse() * layer.geometry.affine;
    let [w, h, d] = layer.dims.map(|n| f64::from(n) - 0.5);
    let corners = [-0.5, w].into_iter().flat_map(|x| {
        [-0.5, h]
            .into_iter()
            .flat_map(move |y| [-0.5, d].into_iter().map(move |z| DVec3::new(x, y, z)))
    });
    let idx: Vec<DVec3> = corners.map(|c| to_base.transform_point3(c)).collect();
    let hi = DVec3::from_array(base.dims.map(|n| f64::from(n) - 0.5));
    let lo = DVec3::splat(-0.5);
    let (min, max) = idx.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), p| {
        (a.min(*p), b.max(*p))
    });
    let tol = 0.51;
    if min.cmpgt(hi).any() || max.cmplt(lo).any() {
        Some(format!(
            "{} does not overlap {} in world space (millimetres by their affines): nothing of it is drawn",
            layer.name, base.name
        ))
    } else if min.cmplt(lo - tol).any() || max.cmpgt(hi + tol).any() {
        Some(format!(
            "{} reaches beyond {}'s box: the march runs through that box, so only the part inside it is drawn",
            layer.name, base.name
        ))
    } else {
        None
    }
}
