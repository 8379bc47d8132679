//! The bench's layered scenes (rule 13): the colin27 T1 alone and with the motor z-map, the AAL atlas or both, as
//! `volcast render T1 --overlay zmap --threshold 3 --labels aal` shows them, so each layer's cost is a ratio of two
//! rows of one run.

use super::BenchError;
use crate::gpu::Gpu;
use crate::render::layers::LayerInput;
use crate::render::Renderer;
use crate::scene::layers::LayerStyle;
use crate::volume::labels::{LabelMap, LabelTable};
use crate::volume::Volume;
use std::path::{Path, PathBuf};

/// A layer of a scene: a file in the `native/` folder beside the bench's data folder (`../shared/data/native`).
#[derive(Clone, Copy, Debug)]
pub struct BenchLayer {
    pub file: &'static str,
    /// A label map (else an overlay).
    pub labels: bool,
    /// An overlay's threshold (`render --threshold`).
    pub threshold: Option<f64>,
}

/// The scene of the T1 alone, and those with layers over it (scenes.rs).
pub const ALONE: &str = "mri-t1";
pub const OVER_T1: [&str; 3] = ["mri-zmap", "mri-aal", "mri-zmap-aal"];

/// The T1 every layered scene shows, alone in [`ALONE`].
pub const T1: &str = "colin27_t1/ch2.nii.gz";
pub const ZMAP: BenchLayer = BenchLayer {
    file: "motor_zmap/image_10426.nii.gz",
    labels: false,
    threshold: Some(3.0),
};
pub const AAL: BenchLayer = BenchLayer {
    file: "aal_labels/aal.nii.gz",
    labels: true,
    threshold: None,
};

/// Where a native file lies: `native/` beside the raw data folder.
pub fn native_path(data_dir: &Path, file: &str) -> PathBuf {
    data_dir.join("..").join("native").join(file)
}

/// The layers loaded: each volume, a label map's dense ids, and the style each frame gives it.
pub struct Loaded {
    volumes: Vec<(Volume, Option<LabelMap>)>,
    pub styles: Vec<LayerStyle>,
}

/// Loads `layers`; `Ok(Err(reason))` when a file is missing.
pub fn load(layers: &[BenchLayer], data_dir: &Path) -> Result<Result<Loaded, String>, BenchError> {
    let mut loaded = Loaded {
        volumes: Vec::new(),
        styles: Vec::new(),
    };
    for layer in layers {
        let path = native_path(data_dir, layer.file);
        if !path.is_file() {
            return Ok(Err(format!("{} not found", path.display())));
        }
        let volume = Volume::open(&path)?;
        if layer.labels {
            let map = LabelMap::of(&volume).map_err(|e| BenchError::Usage(format!("{}: {e}", path.display())))?;
            loaded.volumes.push((volume, Some(map)));
            loaded.styles.push(LayerStyle::labels());
        } else {
            loaded.styles.push(LayerStyle::overlay(volume.range, layer.threshold));
            loaded.volumes.push((volume, None));
        }
    }
    Ok(Ok(loaded))
}

impl Loaded {
    /// Gives the renderer these layers (default label colours).
    pub fn upload(&self, gpu: &Gpu, renderer: &mut Renderer) -> Result<(), BenchError> {
        let table = LabelTable::default();
        let inputs: Vec<LayerInput> = self
            .volumes
            .iter()
            .map(|(volume, map)| LayerInput {
                volume,
                labels: map
                    .as_ref()
                    .map(|m| (m, m.ids.iter().map(|&id| table.rgba(id)).collect())),
            })
            .collect();
        renderer.set_layers(gpu, &inputs)?;
        Ok(())
    }
}
