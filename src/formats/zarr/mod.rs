//! OME-Zarr images (0.4 on Zarr v2, 0.5 on Zarr v3, sharded or not): zarrs reads the store (metadata, chunks,
//! shards, blosc/zstd/gzip, missing chunks as the fill value), ome_zarr_metadata parses the OME attributes, and this
//! module turns them into a [`Volume`]: one level (the finest that fits), one channel, every time step.

pub(crate) mod boxes;
mod guard;
pub(crate) mod levels;
pub(crate) mod metadata;
mod place;
mod read;

use super::decode::Progress;
use super::format;
use crate::pyramid::budget::{self, Budgets, Shape};
use crate::volume::{Scaling, Volume, VolumeError, VoxelType, MAX_DIM};
use levels::LevelSize;
use metadata::{AxisRole, Multiscale};
use std::path::Path;
use std::sync::Arc;
use zarrs::array::Array;
use zarrs::group::Group;
use zarrs::storage::{ReadableStorage, ReadableStorageTraits};

/// What to load from a store.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ZarrOptions {
    /// The channel along a `c` axis (default 0).
    pub channel: Option<u32>,
    /// Largest dimension a level may have to be chosen.
    pub max_dim: Option<u32>,
    /// The memory budgets a level must fit to be chosen (`pyramid::budget`); `None`: no budget.
    pub budgets: Option<Budgets>,
}

/// Whether a folder is a Zarr node (v3 `zarr.json`, v2 `.zgroup`/`.zattrs`/`.zarray`).
pub(crate) fn is_zarr_folder(path: &Path) -> bool {
    [".zarray", ".zgroup", ".zattrs", "zarr.json"]
        .iter()
        .any(|m| path.join(m).is_file())
}

/// Loads the OME-Zarr image in the folder `path`.
pub(crate) fn load(path: &Path, opts: ZarrOptions, progress: &mut Progress) -> Result<Volume, VolumeError> {
    let file = format::file_label(path);
    let store = zarrs::filesystem::FilesystemStore::new(path)
        .map_err(|e| format::header_error(&file, format!("cannot open the Zarr store: {e}")))?;
    let store: ReadableStorage = Arc::new(store);
    load_store(&file, &format::volume_name(path), store, opts, progress)
}

/// Loads the OME-Zarr image at the root of `store`; `file` names it in messages.
pub(crate) fn load_store(
    file: &str,
    name: &str,
    store: ReadableStorage,
    opts: ZarrOptions,
    progress: &mut Progress,
) -> Result<Volume, VolumeError> {
    let bad = |problem: String| format::header_error(file, problem);
    let attrs = group_attributes(&store).map_err(bad)?;
    let ms = metadata::parse(&attrs).map_err(bad)?;
    let Chosen {
        index: k,
        array,
        size,
        note: level_note,
    } = open_level(&store, &ms, opts.max_dim, opts.budgets).map_err(bad)?;
    let voxel_type = read::voxel_type(&array).map_err(|given| VolumeError::UnsupportedType {
        file: file.to_string(),
        format: "OME-Zarr",
        given,
    })?;
    let channel = pick_channel(&ms, &size, opts.channel).map_err(bad)?;
    crate::volume::time::check_series_memory(
        file,
        size.timesteps.min(u64::from(u32::MAX)) as u32,
        size.voxels() * voxel_type.size() as u64,
    )?;
    let array = Array::open(
        guard::guarded(store.clone(), &array),
        &format!("/{}", ms.levels[k].path),
    )
    .map_err(|e| bad(format!("level {k} ('{}'): {e}", ms.levels[k].path)))?;
    let mut steps = Vec::with_capacity(size.timesteps as usize);
    for t in 0..size.timesteps {
        let mut fixed = Vec::new();
        if let Some(i) = ms.axis_index(AxisRole::Time) {
            fixed.push((i, t));
        }
        if let Some(i) = ms.axis_index(AxisRole::Channel) {
            fixed.push((i, u64::from(channel)));
        }
        let data = read::read_step(&array, voxel_type, &fixed)
            .map_err(|e| bad(format!("level {k} ('{}'): {e}", ms.levels[k].path)))?;
        steps.push(data);
        progress.report((t + 1) as f64 / size.timesteps as f64);
    }
    let mut notes = ms.notes.clone();
    notes.push(format!("OME-Zarr {}", ms.version));
    notes.extend(level_note);
    assemble(name, &ms, k, size, voxel_type, steps, notes, channel)
}

/// The attributes of the store's root group.
fn group_attributes(store: &ReadableStorage) -> Result<serde_json::Value, String> {
    match Group::open(store.clone(), "/") {
        Ok(g) => Ok(serde_json::Value::Object(g.attributes().clone())),
        Err(e) => match Array::open(store.clone(), "/") {
            Ok(_) => Err(
                "a Zarr array, not an OME-Zarr image: open the group (the folder above the level) that holds \
                          its OME multiscales metadata"
                    .into(),
            ),
            Err(_) => Err(format!("its Zarr group metadata cannot be read: {e}")),
        },
    }
}

/// The level to load, its array opened, and the note naming it.
struct Chosen {
    index: usize,
    array: Array<dyn ReadableStorageTraits>,
    size: LevelSize,
    note: Option<String>,
}

/// Opens the level to load: each level's array metadata is read finest first until one fits.
fn open_level(
    store: &ReadableStorage,
    ms: &Multiscale,
    max_dim: Option<u32>,
    budgets: Option<Budgets>,
) -> Result<Chosen, String> {
    let max_dim = max_dim.unwrap_or(MAX_DIM);
    let mut sizes = Vec::with_capacity(ms.levels.len());
    let mut misfits = Vec::with_capacity(ms.levels.len());
    let mut arrays = Vec::with_capacity(ms.levels.len());
    for (k, level) in ms.levels.iter().enumerate() {
        let array = Array::open(store.clone(), &format!("/{}", level.path)).map_err(|e| {
            let text = e.to_string();
            if text.contains("metadata is missing") {
                format!(
                    "level {k} ('{}') is missing from the store (a half-written store?): {text}",
                    level.path
                )
            } else {
                format!("level {k} ('{}') cannot be read: {text}", level.path)
            }
        })?;
        let size = LevelSize::of(ms, array.shape()).ok_or_else(|| {
            format!(
                "level {k} ('{}') has {} dimensions but the multiscale names {} axes",
                level.path,
                array.shape().len(),
                ms.axes.len()
            )
        })?;
        if array.shape().contains(&0) {
            return Err(format!(
                "level {k} ('{}') has a zero dimension: {:?}",
                level.path,
                array.shape()
            ));
        }
        let misfit = budgets.and_then(|b| over_budget(&size, &array, &b));
        let fits = size.too_large(max_dim).is_none() && misfit.is_none();
        sizes.push(size);
        misfits.push(misfit);
        arrays.push(array);
        if fits {
            break;
        }
    }
    let (k, note) = levels::choose(&sizes, &misfits, ms.levels.len(), max_dim)?;
    let array = arrays.swap_remove(k);
    Ok(Chosen {
        index: k,
        array,
        size: sizes[k],
        note,
    })
}

/// Why a level of `size` does not fit `budgets` (one channel, every time step held), or `None` if it does or its
/// type is one volcast does not read (refused later, by name).
fn over_budget(size: &LevelSize, array: &Array<dyn ReadableStorageTraits>, budgets: &Budgets) -> Option<String> {
    let voxel_type = read::voxel_type(array).ok()?;
    let dims = size.dims.map(|d| u32::try_from(d).unwrap_or(u32::MAX));
    let shape = Shape {
        dims,
        voxel_type,
        steps: u32::try_from(size.timesteps).unwrap_or(u32::MAX),
    };
    budget::misfit(&shape, 0, budgets)
}

/// The channel to load, checked against the `c` axis; the message lists the channels.
fn pick_channel(ms: &Multiscale, size: &LevelSize, asked: Option<u32>) -> Result<u32, String> {
    let c = asked.unwrap_or(0);
    if u64::from(c) < size.channels {
        return Ok(c);
    }
    let list: Vec<String> = (0..size.channels.min(64))
        .map(|i| match ms.channels.get(i as usize) {
            Some(ch) => format!("{i} ({})", ch.name),
            None => i.to_string(),
        })
        .collect();
    Err(format!(
        "channel {c} does not exist: the image has {} channel(s): {}",
        size.channels,
        list.join(", ")
    ))
}

#[allow(clippy::too_many_arguments)]
fn assemble(
    name: &str,
    ms: &Multiscale,
    k: usize,
    size: LevelSize,
    voxel_type: VoxelType,
    steps: Vec<crate::volume::VoxelData>,
    mut notes: Vec<String>,
    channel: u32,
) -> Result<Volume, VolumeError> {
    let dims = size.dims.map(|d| d as u32);
    let (affine, ras) = place::affine(ms, k, &mut notes);
    let spacing = place::xyz(ms, &ms.levels[k]).0.map(|s| s.abs() as f32);
    let mut steps = steps.into_iter();
    let first = steps.next().expect("at least one step");
    let mut v = Volume::new(name, dims, spacing, voxel_type, first)?.with_time_steps(steps.collect())?;
    if let Some((slope, intercept)) = ms.hint.as_ref().and_then(|h| h.scaling) {
        v = v.with_scaling(Scaling { slope, intercept })?;
    }
    let mut v = v.with_geometry(crate::volume::Geometry {
        affine,
        anatomical: ras,
    })?;
    if !ras {
        notes.push(frame_note(ms));
    }
    if size.channels > 1 {
        let named = ms
            .channels
            .get(channel as usize)
            .map_or(String::new(), |c| format!(" ({})", c.name));
        notes.push(format!(
            "channel {channel}{named} of {}; choose another with --channel",
            size.channels
        ));
    }
    v.channels = ms.channels.clone();
    if let Some(c) = v.channels.get_mut(channel as usize) {
        c.loaded = true;
    }
    v.format = "OME-Zarr".into();
    v.notes = notes;
    // A coarser level stands in for level 0, the store's own voxels (rule 6).
    v.source_voxels = min_side(place::xyz(ms, &ms.levels[k]).0) / min_side(place::xyz(ms, &ms.levels[0]).0);
    Ok(v)
}

/// The shortest of three voxel sides (absolute).
fn min_side(spacing: [f64; 3]) -> f64 {
    spacing.iter().fold(f64::INFINITY, |m, s| m.min(s.abs()))
}

/// OME-Zarr names axes but no patient frame: say which stored axes x, y, z are.
fn frame_note(ms: &Multiscale) -> String {
    let space = ms.space_axes();
    let n = space.len();
    let name = |k: usize| ms.axes[space[n - 1 - k]].name.clone();
    let z = if n == 3 {
        format!("z = axis '{}'", name(2))
    } else {
        "z = a single slice".into()
    };
    format!(
        "OME-Zarr has no anatomical frame: x, y, z are shown as stored (x = axis '{}', y = axis '{}', {z})",
        name(0),
        name(1)
    )
}

/// In-memory entry points for the fuzz targets (`formats::from_bytes`).
pub mod from_bytes {
    use super::*;
    use zarrs::storage::store::MemoryStore;
    use zarrs::storage::{StoreKey, WritableStorageTraits};

    /// Interprets group attributes (JSON bytes) as OME multiscales metadata; the error says what is wrong.
    pub fn zarr_meta(data: &[u8]) -> Result<(), String> {
        let attrs: serde_json::Value = serde_json::from_slice(data).map_err(|e| e.to_string())?;
        metadata::parse(&attrs).map(|_| ())
    }

    /// Reads a one-level zyx image whose level array has the metadata `array_json` (Zarr v3 `zarr.json`) and whose
    /// first chunk is `chunk`, as a store on disk would be read. Levels over 2^22 voxels are refused first, so the
    /// fuzzer spends its time in decoding rather than in filling large arrays with the fill value.
    pub fn zarr_chunk(array_json: &[u8], chunk: &[u8]) -> Result<Volume, VolumeError> {
        let bad = |problem: String| format::header_error("fuzz.zarr", problem);
        let meta: serde_json::Value = serde_json::from_slice(array_json).map_err(|e| bad(e.to_string()))?;
        let voxels = meta
            .get("shape")
            .and_then(serde_json::Value::as_array)
            .map(|s| {
                s.iter()
                    .map(|d| d.as_u64().unwrap_or(u64::MAX))
                    .fold(1u64, u64::saturating_mul)
            })
            .unwrap_or(0);
        if voxels > 1 << 22 {
            return Err(bad(format!("{voxels} voxels: too many for a fuzz input")));
        }
        let group = serde_json::json!({"zarr_format": 3, "node_type": "group", "attributes": {"ome": {
            "version": "0.5", "multiscales": [{"axes": [
                {"name": "z", "type": "space"}, {"name": "y", "type": "space"}, {"name": "x", "type": "space"}],
                "datasets": [{"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1.0, 1.0, 1.0]}]}]}]}}});
        let store = MemoryStore::new();
        let files: [(&str, Vec<u8>); 4] = [
            ("zarr.json", group.to_string().into_bytes()),
            ("0/zarr.json", array_json.to_vec()),
            ("0/c/0/0/0", chunk.to_vec()),
            ("0/0.0.0", chunk.to_vec()),
        ];
        for (key, bytes) in files {
            let key = StoreKey::new(key).map_err(|e| bad(e.to_string()))?;
            store.set(&key, bytes.into()).map_err(|e| bad(e.to_string()))?;
        }
        let opts = ZarrOptions {
            channel: None,
            max_dim: Some(256),
            budgets: None,
        };
        load_store("fuzz.zarr", "fuzz", Arc::new(store), opts, &mut Progress::none())
    }

    #[cfg(test)]
    mod tests {
        #[test]
        fn the_fuzz_entry_reads_a_chunk_and_refuses_garbage() {
            let meta = std::fs::read("tests/data/zarr/dtype_uint16.zarr/s0/zarr.json").unwrap();
            let chunk = std::fs::read("tests/data/zarr/dtype_uint16.zarr/s0/c/0/0/0").unwrap();
            let v = super::zarr_chunk(&meta, &chunk).unwrap();
            assert_eq!(v.dims, [4, 3, 2]);
            assert!(super::zarr_chunk(&meta, &chunk[..5]).is_err());
            assert!(super::zarr_chunk(b"{", &chunk).is_err());
            let attrs = std::fs::read("tests/data/zarr/v04_blosc.zarr/.zattrs").unwrap();
            super::zarr_meta(&attrs).unwrap();
            assert!(super::zarr_meta(b"[]").is_err());
        }
    }
}
