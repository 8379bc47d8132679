//! The layers a frame shows with its volume (rule 13, [`super::layers`]), read from their files: their voxels, a
//! label map's dense ids, colours and table, and each one's look. `render --overlay/--labels`, the viewer's layer
//! list and the Python module build them here; the renderer takes them (`Renderer::show_layers`).

use super::layers::{Blend, LayerKind, LayerStyle};
use crate::formats::{label_table, open, OpenOptions};
use crate::transfer::colormap::Colormap;
use crate::volume::labels::{LabelMap, LabelTable};
use crate::volume::Volume;
use anyhow::{Context, Result};
use glam::DVec3;
use std::path::Path;

/// How new layers look unless a user says otherwise (the command line's look options).
#[derive(Clone, Debug, Default)]
pub struct Looks {
    /// Overlays show where value ≥ T (|value| ≥ T for a signed one), in their own units.
    pub threshold: Option<f64>,
    pub overlay_opacity: Option<f32>,
    pub overlay_colormap: Option<Colormap>,
    pub overlay_blend: Option<Blend>,
    pub label_opacity: Option<f32>,
    /// The label ids shown (empty: every id).
    pub label_ids: Vec<u32>,
}

impl Looks {
    /// An id's colour: `table`'s, hidden where `label_ids` leaves it out.
    fn colour(&self, table: &LabelTable, id: u32) -> [u8; 4] {
        let mut c = table.rgba(id);
        if !self.label_ids.is_empty() && !self.label_ids.contains(&id) {
            c[3] = 0;
        }
        c
    }
}

/// The layers, in the order frames mix them: the overlays, then the label maps (`shaders/layers.glsl` loops over
/// each kind). The vectors run in step.
#[derive(Default)]
pub struct Layers {
    pub volumes: Vec<Volume>,
    /// Per layer: a label map's dense ids and the sRGB colour and opacity (0–255) of each.
    pub labels: Vec<Option<(LabelMap, Vec<[u8; 4]>)>>,
    /// Per layer: a label map's table (names for the values under the cursor); empty for an overlay.
    pub tables: Vec<LabelTable>,
    /// Per layer: what the user called it (its file).
    pub names: Vec<String>,
    pub styles: Vec<LayerStyle>,
}

impl Layers {
    pub fn len(&self) -> usize {
        self.volumes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.volumes.is_empty()
    }

    /// Adds the layer, overlays before label maps.
    fn insert(
        &mut self,
        v: Volume,
        labels: Option<(LabelMap, Vec<[u8; 4]>)>,
        table: LabelTable,
        name: &str,
        style: LayerStyle,
    ) {
        let at = match style.kind {
            LayerKind::Overlay => self.styles.iter().take_while(|s| s.kind == LayerKind::Overlay).count(),
            LayerKind::Labels => self.len(),
        };
        self.volumes.insert(at, v);
        self.labels.insert(at, labels);
        self.tables.insert(at, table);
        self.names.insert(at, name.to_string());
        self.styles.insert(at, style);
    }

    /// Adds `other`'s layers, overlays before label maps.
    pub fn append(&mut self, other: Layers) {
        let Layers {
            volumes,
            labels,
            tables,
            names,
            styles,
        } = other;
        let all = volumes.into_iter().zip(labels).zip(tables).zip(names).zip(styles);
        for ((((v, l), t), n), s) in all {
            self.insert(v, l, t, &n, s);
        }
    }

    /// Removes layer `i` (nothing where there is none).
    pub fn remove(&mut self, i: usize) {
        if i < self.len() {
            self.volumes.remove(i);
            self.labels.remove(i);
            self.tables.remove(i);
            self.names.remove(i);
            self.styles.remove(i);
        }
    }

    /// An overlay of `v`'s values, named `name`.
    pub fn add_overlay(&mut self, v: Volume, name: &str, looks: &Looks) -> Result<()> {
        let mut style = LayerStyle::overlay(v.range, looks.threshold);
        style.opacity = looks.overlay_opacity.unwrap_or(style.opacity);
        style.colormap = looks.overlay_colormap.unwrap_or(style.colormap);
        style.blend = looks.overlay_blend.unwrap_or(style.blend);
        style.check().map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        self.insert(v, None, LabelTable::default(), name, style);
        Ok(())
    }

    /// A channel: its omero colour as a ramp over its window (shown from the window's start), by maximum at full
    /// opacity unless told otherwise.
    pub fn add_channel(&mut self, v: Volume, looks: &Looks) -> Result<()> {
        let display = v.channels.iter().find(|c| c.loaded).map(|c| (c.window, c.color));
        let (window, tint) = match display {
            Some((w, c)) if w[0] < w[1] => (w, c),
            Some((_, c)) => (v.range, c),
            None => (v.range, [255, 255, 255]),
        };
        let mut style = LayerStyle::channel(window, tint, looks.threshold.unwrap_or(window[0]));
        if let Some(colormap) = looks.overlay_colormap {
            (style.tint, style.colormap) = (None, colormap);
        }
        style.blend = looks.overlay_blend.unwrap_or(style.blend);
        style.opacity = looks.overlay_opacity.unwrap_or(style.opacity);
        let name = v.name.clone();
        style.check().map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        self.insert(v, None, LabelTable::default(), &name, style);
        Ok(())
    }

    /// A label map of `v` (its ids made dense, `map`), coloured by `table`.
    pub fn add_labels(&mut self, v: Volume, map: LabelMap, table: LabelTable, name: &str, looks: &Looks) -> Result<()> {
        let rgba = map.ids.iter().map(|&id| looks.colour(&table, id)).collect();
        let mut style = LayerStyle::labels();
        style.opacity = looks.label_opacity.unwrap_or(style.opacity);
        style.check().map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        self.insert(v, Some((map, rgba)), table, name, style);
        Ok(())
    }

    /// Reads `path` as an overlay, or as label maps (with `table`, else the table beside it).
    pub fn add_file(&mut self, path: &Path, kind: LayerKind, table: Option<&Path>, looks: &Looks) -> Result<()> {
        let name = path.display().to_string();
        match kind {
            LayerKind::Overlay => self.add_overlay(open(path, &OpenOptions::default())?, &name, looks),
            LayerKind::Labels => {
                for (v, map, table) in read_labels(path, table)? {
                    self.add_labels(v, map, table, &name, looks)?;
                }
                Ok(())
            }
        }
    }

    /// The files of these layers, absolute, as a saved view records them: each file once (a Slicer segmentation
    /// gives several layers), in order. A layer not read from a file (a channel, an array) has none.
    pub fn files(&self) -> super::view_state::LayerFiles {
        let mut files = super::view_state::LayerFiles::default();
        for (name, style) in self.names.iter().zip(&self.styles) {
            let Ok(path) = std::fs::canonicalize(name) else {
                continue;
            };
            let list = match style.kind {
                LayerKind::Overlay => &mut files.overlays,
                LayerKind::Labels => &mut files.labels,
            };
            if list.last() != Some(&path) {
                list.push(path);
            }
        }
        files
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

/// How a layer is named where space is short (the panel, the cursor's probe): the last part of its path.
pub fn short_name(name: &str) -> String {
    Path::new(name)
        .file_name()
        .map_or_else(|| name.to_string(), |n| n.to_string_lossy().into_owned())
}

/// A note where `layer` does not lie wholly inside `base`'s box in world space: the march runs through the base's
/// box, so only the part inside it is drawn.
pub fn overlap_note(base: &Volume, layer: &Volume) -> Option<String> {
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
