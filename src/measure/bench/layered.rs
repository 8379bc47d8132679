//! The bench's layered scenes (rule 13): the colin27 T1 alone and with the motor z-map, the AAL atlas or both, as
//! `volcast render T1 --overlay zmap --threshold 3 --labels aal` shows them; and a 256³ channel alone and with three
//! more, as `--channels all` shows them. Each layer's cost is a ratio of two rows of one run ([`PAIRS`]).

use super::BenchError;
use crate::gpu::Gpu;
use crate::render::layers::LayerInput;
use crate::render::Renderer;
use crate::scene::layers::LayerStyle;
use crate::volume::labels::{LabelMap, LabelTable};
use crate::volume::CHANNEL_COLOURS;
use crate::volume::{Volume, VoxelData, VoxelType};
use std::path::{Path, PathBuf};

/// A layer of a scene: a file in the `native/` folder beside the bench's data folder (`../shared/data/native`), or
/// a generated channel.
#[derive(Clone, Copy, Debug)]
pub struct BenchLayer {
    pub from: LayerFrom,
    /// A label map (else an overlay).
    pub labels: bool,
    /// An overlay's threshold (`render --threshold`).
    pub threshold: Option<f64>,
}

/// Where a layer's voxels come from.
#[derive(Clone, Copy, Debug)]
pub enum LayerFrom {
    Native(&'static str),
    /// Fluorescence channel k: [`channel_volume`], shown as `--channels` shows a channel.
    Channel(u32),
}

/// The scene of the T1 alone, and those with layers over it (scenes.rs).
pub const ALONE: &str = "mri-t1";
pub const OVER_T1: [&str; 3] = ["mri-zmap", "mri-aal", "mri-zmap-aal"];
/// One 256³ channel alone, and with three more (scenes.rs).
pub const ONE_CHANNEL: &str = "channels-1";
pub const FOUR_CHANNELS: &str = "channels-4";

/// Each layered scene and the scene without its layers that its frame time is compared with.
pub const PAIRS: [(&str, &str); 4] = [
    (OVER_T1[0], ALONE),
    (OVER_T1[1], ALONE),
    (OVER_T1[2], ALONE),
    (FOUR_CHANNELS, ONE_CHANNEL),
];

/// The T1 every layered scene shows, alone in [`ALONE`].
pub const T1: &str = "colin27_t1/ch2.nii.gz";
pub const ZMAP: BenchLayer = BenchLayer {
    from: LayerFrom::Native("motor_zmap/image_10426.nii.gz"),
    labels: false,
    threshold: Some(3.0),
};
pub const AAL: BenchLayer = BenchLayer {
    from: LayerFrom::Native("aal_labels/aal.nii.gz"),
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
        let file = match layer.from {
            LayerFrom::Native(file) => file,
            LayerFrom::Channel(k) => {
                let volume = channel_volume(k);
                loaded.styles.push(channel_style(k, volume.range));
                loaded.volumes.push((volume, None));
                continue;
            }
        };
        let path = native_path(data_dir, file);
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

/// The side of a generated channel.
pub const CHANNEL_SIDE: u32 = 256;

/// Channel k: 256³ uint8, 48 soft balls of radius 6–14 voxels at places of its own (a seeded generator), as a
/// fluorescence channel's scattered cells: its balls spread over the whole box, so every sample of the march
/// runs the layers' code (their worst case).
pub fn channel_volume(k: u32) -> Volume {
    let n = CHANNEL_SIDE as usize;
    let mut data = vec![0u8; n * n * n];
    let mut seed = 0x9E37_79B9_7F4A_7C15u64 ^ u64::from(k + 1).wrapping_mul(0xD1B5_4A32_D192_ED03);
    let mut next = move |range: usize| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % range as u64) as usize
    };
    for _ in 0..48 {
        let r = 6 + next(9);
        let c = [0, 1, 2].map(|_| r + next(n - 2 * r));
        for z in c[2] - r..=c[2] + r {
            for y in c[1] - r..=c[1] + r {
                for x in c[0] - r..=c[0] + r {
                    let d2 = [x, y, z]
                        .iter()
                        .zip(c)
                        .map(|(&p, q)| (p as f64 - q as f64).powi(2))
                        .sum::<f64>();
                    let v = (255.0 * (1.0 - d2.sqrt() / r as f64)).max(0.0) as u8;
                    let i = x + n * (y + n * z);
                    data[i] = data[i].max(v);
                }
            }
        }
    }
    let dims = [CHANNEL_SIDE; 3];
    Volume::new(
        format!("channel {k}"),
        dims,
        [1.0; 3],
        VoxelType::U8,
        VoxelData::U8(data),
    )
    .expect("a 256³ volume")
}

/// Channel k's look as `--channels` gives it (`LayerStyle::channel`): a ramp to ImageJ's colour k over its range,
/// shown from a tenth of it.
fn channel_style(k: u32, range: [f64; 2]) -> LayerStyle {
    let tint = CHANNEL_COLOURS[(k as usize + 1) % CHANNEL_COLOURS.len()];
    LayerStyle::channel(range, tint, range[1] * 0.1)
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
