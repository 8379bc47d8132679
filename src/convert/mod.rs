//! `volcast convert`: any volume volcast reads to an OME-Zarr store (0.5 on Zarr v3 by default, 0.4 on Zarr v2)
//! with a multiscale pyramid, written with the zarrs crate. Pure code, no Vulkan.
//!
//! The voxels stream through in z-slabs of one chunk (or shard) depth: level 0's chunks are encoded on every core
//! and each slab feeds the next level's, so a file read in place ([`crate::formats::in_place`]) is never held whole,
//! and a loaded volume is held once. docs/cli.md (convert) states the rules: levels, data type, placement.

pub mod layout;
pub mod sample;
pub mod source;
mod store;
mod write;

use crate::pyramid::geometry::store_levels;
use crate::pyramid::reduce::Reduce;
use crate::pyramid::sample::Sample;
use crate::volume::{Scaling, VolumeError, VoxelType};
use layout::{OmeVersion, Placement};
use source::Source;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use store::ChunkStore;
use write::{ArrayLayout, Cascade};

/// The chunks' compressor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    Zstd,
    /// Blosc with lz4 inside, byte-shuffled for multi-byte types.
    Blosc,
    None,
}

#[derive(Clone, Debug)]
pub struct ConvertOptions {
    pub version: OmeVersion,
    pub chunk: u64,
    pub shard: Option<u64>,
    pub compression: Compression,
    pub reduce: Reduce,
    /// Write only this time step (as a 3-D store); `None`: every step, with a t axis for a series.
    pub step: Option<u32>,
    /// Write the values as the file stores them, in the type volcast holds them, with the file's rescale under
    /// volcast's metadata (which volcast's reader applies) instead of the rescaled values: the pyramid cache's
    /// stores, whose levels must be the values a file's finer bricks are read in. `false` for `volcast convert`.
    pub stored: bool,
}

#[derive(Debug, thiserror::Error)]
pub enum ConvertError {
    #[error(transparent)]
    Volume(#[from] VolumeError),
    #[error("{0}")]
    Usage(String),
    #[error("writing the Zarr store: {0}")]
    Zarr(String),
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
}

/// What was written.
#[derive(Clone, Debug)]
pub struct Report {
    /// (x, y, z) of every level, finest first.
    pub levels: Vec<[u64; 3]>,
    pub data_type: VoxelType,
    /// Why that type, in words.
    pub type_reason: String,
    pub steps: u32,
    pub notes: Vec<String>,
}

/// The stored type: the values as the user sees them. Without a rescale, the type the voxels are held in; with one
/// of integer slope and intercept over integers, the narrowest of int16 and int32 that holds every scaled value;
/// otherwise float32.
pub fn output_type(source: &Source) -> Result<(VoxelType, String), VolumeError> {
    let (held, file_type, s) = (source.held_type(), source.source_type(), source.scaling());
    if s.is_identity() {
        let reason = if held == file_type {
            format!("{held}, the file's type")
        } else {
            format!("{held}: volcast holds {file_type} voxels as {held}")
        };
        return Ok((held, reason));
    }
    let integers = !matches!(held, VoxelType::F32 | VoxelType::F64);
    if integers && s.slope.fract() == 0.0 && s.intercept.fract() == 0.0 {
        let [lo, hi] = source.stored_range()?.unwrap_or([0.0, 0.0]);
        let (a, b) = (lo * s.slope + s.intercept, hi * s.slope + s.intercept);
        let (lo, hi) = (a.min(b), a.max(b));
        for (t, min, max) in [
            (VoxelType::I16, f64::from(i16::MIN), f64::from(i16::MAX)),
            (VoxelType::I32, f64::from(i32::MIN), f64::from(i32::MAX)),
        ] {
            if lo >= min && hi <= max {
                return Ok((
                    t,
                    format!(
                        "{t}: the narrowest integer type holding the rescaled values {lo}..{hi} (slope {}, intercept {})",
                        s.slope, s.intercept
                    ),
                ));
            }
        }
    }
    Ok((
        VoxelType::F32,
        format!(
            "float32: the values rescaled by slope {}, intercept {}",
            s.slope, s.intercept
        ),
    ))
}

/// Makes `out` an empty folder for the store. An existing path is refused unless `overwrite`; then only a Zarr
/// store (a folder with zarr.json, .zgroup or .zattrs) is removed, never anything else.
pub fn prepare_output(out: &Path, overwrite: bool) -> Result<(), ConvertError> {
    if out.symlink_metadata().is_ok() {
        if !overwrite {
            return Err(ConvertError::Usage(format!(
                "{} exists; pass --overwrite to replace it",
                out.display()
            )));
        }
        let is_store = out.is_dir()
            && [".zgroup", ".zattrs", "zarr.json"]
                .iter()
                .any(|f| out.join(f).is_file());
        if !is_store {
            return Err(ConvertError::Usage(format!(
                "{} exists and is not a Zarr store; volcast replaces only a store",
                out.display()
            )));
        }
        std::fs::remove_dir_all(out).map_err(|source| ConvertError::Io {
            path: out.to_path_buf(),
            source,
        })?;
    }
    std::fs::create_dir(out).map_err(|source| ConvertError::Io {
        path: out.to_path_buf(),
        source,
    })
}

/// Writes `source` as an OME-Zarr store into the empty folder `out` ([`prepare_output`]), reporting the fraction
/// done (0 to 1) as it goes.
pub fn convert(
    source: &Source,
    out: &Path,
    opts: &ConvertOptions,
    progress: &mut dyn FnMut(f32),
) -> Result<Report, ConvertError> {
    if opts.chunk == 0 || opts.shard.is_some_and(|s| s == 0 || s % opts.chunk != 0) {
        return Err(ConvertError::Usage(
            "the shard edge must be a positive multiple of the chunk edge".into(),
        ));
    }
    if opts.shard.is_some() && opts.version == OmeVersion::V04 {
        return Err(ConvertError::Usage(
            "sharding needs Zarr v3 (OME-Zarr 0.5); OME-Zarr 0.4 is Zarr v2".into(),
        ));
    }
    if let Some(t) = opts.step.filter(|&t| t >= source.timesteps()) {
        return Err(ConvertError::Usage(format!(
            "time step {t} is past the series' last, {}",
            source.timesteps() - 1
        )));
    }
    let (data_type, type_reason) = if opts.stored {
        let held = source.held_type();
        (
            held,
            format!("{held}, the values as stored (the rescale is in volcast's metadata)"),
        )
    } else {
        output_type(source)?
    };
    macro_rules! run {
        ($t:ty) => {
            write_store::<$t>(source, out, opts, progress)?
        };
    }
    let (levels, steps) = match data_type {
        VoxelType::U8 => run!(u8),
        VoxelType::I8 => run!(i8),
        VoxelType::U16 => run!(u16),
        VoxelType::I16 => run!(i16),
        VoxelType::U32 => run!(u32),
        VoxelType::I32 => run!(i32),
        VoxelType::F32 => run!(f32),
        VoxelType::F64 => run!(f64),
    };
    let mut notes = Vec::new();
    let placement = Placement::of(&source.geometry());
    if !placement.axis_aligned {
        notes.push(
            "the volume's affine is not a positive axis-aligned scale (a flipped, permuted, oblique or sheared \
             axis): the scale and translation written are the nearest axis-aligned placement; the full affine is \
             in the multiscale's metadata, under \"volcast\""
                .to_string(),
        );
    }
    Ok(Report {
        levels,
        data_type,
        type_reason,
        steps,
        notes,
    })
}

/// The store's metadata, then every step's slabs through the cascade. Returns the levels and steps written.
fn write_store<T: Sample>(
    source: &Source,
    out: &Path,
    opts: &ConvertOptions,
    progress: &mut dyn FnMut(f32),
) -> Result<(Vec<[u64; 3]>, u32), ConvertError> {
    let store = Arc::new(ChunkStore::new(out.to_path_buf()).map_err(ConvertError::Zarr)?);
    let dims = source.dims().map(u64::from);
    let levels = store_levels(dims);
    let steps: Vec<u32> = match opts.step {
        Some(t) => vec![t],
        None => (0..source.timesteps()).collect(),
    };
    let series = steps.len() > 1;
    let layout = ArrayLayout {
        version: opts.version,
        chunk: opts.chunk,
        shard: opts.shard,
        compression: opts.compression,
        steps: series.then_some(steps.len() as u64),
    };
    let placement = Placement::of(&source.geometry());
    // The values written: rescaled, or as stored with the rescale beside them for volcast's reader.
    let (scaling, hint) = match source.scaling() {
        s if opts.stored => (Scaling::IDENTITY, Some(s).filter(|s| !s.is_identity())),
        s => (s, None),
    };
    let mut multiscale = layout::multiscale(source.name(), opts.version, series, &placement, &levels);
    if let Some(s) = hint {
        multiscale["metadata"]["volcast"]["scaling"] = serde_json::json!({"slope": s.slope, "intercept": s.intercept});
    }
    let attributes = layout::root_attributes(opts.version, multiscale);
    write_group(&store, opts.version, attributes)?;
    let mut arrays = Vec::new();
    for (k, &d) in levels.iter().enumerate() {
        arrays.push((write::create_array::<T>(&store, &format!("/{k}"), d, &layout)?, d));
    }
    let depth = layout.depth();
    let total = steps.len() as f64 * dims[2] as f64;
    for (i, &t) in steps.iter().enumerate() {
        let mut cascade = Cascade::<T>::new(arrays, depth, opts.reduce, series.then_some(i as u64));
        for z0 in (0..dims[2]).step_by(depth as usize) {
            let n = depth.min(dims[2] - z0);
            let slab = source.read_slab::<T>(t, z0 as u32, n as u32, scaling)?;
            cascade.push(0, slab)?;
            progress(((i as f64 * dims[2] as f64 + (z0 + n) as f64) / total) as f32);
        }
        cascade.finish()?;
        arrays = cascade.into_arrays();
    }
    Ok((levels, steps.len() as u32))
}

fn write_group(
    store: &Arc<ChunkStore>,
    version: OmeVersion,
    attributes: serde_json::Map<String, serde_json::Value>,
) -> Result<(), ConvertError> {
    let zarr = |e: &dyn std::fmt::Display| ConvertError::Zarr(e.to_string());
    let group = match version {
        OmeVersion::V05 => zarrs::group::GroupBuilder::new()
            .attributes(attributes)
            .build(store.clone(), "/")
            .map_err(|e| zarr(&e))?,
        OmeVersion::V04 => {
            let metadata = zarrs::metadata::v2::GroupMetadataV2::new().with_attributes(attributes);
            zarrs::group::Group::new_with_metadata(store.clone(), "/", metadata.into()).map_err(|e| zarr(&e))?
        }
    };
    group.store_metadata().map_err(|e| zarr(&e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{Scaling, Volume, VoxelData};

    fn scaled(slope: f64, intercept: f64) -> VoxelType {
        // int16 -1000 and 3000, held biased by +32768.
        let data = VoxelData::U16(vec![31768, 35768]);
        let v = Volume::new("v", [2, 1, 1], [1.0; 3], VoxelType::I16, data).unwrap();
        let v = v.with_scaling(Scaling { slope, intercept }).unwrap();
        output_type(&Source::Loaded(Box::new(v))).unwrap().0
    }

    #[test]
    fn the_type_holds_the_rescaled_values() {
        assert_eq!(scaled(1.0, 0.0), VoxelType::I16, "no rescale: the file's type");
        assert_eq!(scaled(1.0, -1024.0), VoxelType::I16, "-2024..1976");
        assert_eq!(scaled(20.0, 0.0), VoxelType::I32, "-20000..60000");
        assert_eq!(scaled(-20.0, 5.0), VoxelType::I32);
        assert_eq!(scaled(0.5, 0.0), VoxelType::F32, "a fractional slope");
        assert_eq!(scaled(1.0, 0.25), VoxelType::F32, "a fractional intercept");
        let f = Volume::new("f", [1, 1, 1], [1.0; 3], VoxelType::F64, VoxelData::F32(vec![1.5])).unwrap();
        let (t, why) = output_type(&Source::Loaded(Box::new(f))).unwrap();
        assert_eq!(t, VoxelType::F32, "{why}");
    }
}
