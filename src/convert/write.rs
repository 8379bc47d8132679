//! Writing the levels: one zarrs array per level ("0", "1", ...) in the chosen Zarr version, compression and chunk
//! (or shard) shape, and the cascade that writes level 0 slab by slab while building every coarser level from the
//! slabs of the one above, so memory stays a few slabs whatever the volume's size.

use super::layout::OmeVersion;
use super::sample::{numpy_dtype, zarr_data_type};
use super::store::ChunkStore;
use super::{Compression, ConvertError};
use crate::pyramid::geometry::factors;
use crate::pyramid::reduce::{downsample, Reduce};
use crate::pyramid::sample::Sample;
use std::num::NonZeroU64;
use std::sync::Arc;
use zarrs::array::codec::{BloscCodec, BloscCompressionLevel, BloscCompressor, BloscShuffleMode, ZstdCodec};
use zarrs::array::{Array, ArrayBuilder, ArrayMetadataV2, ArraySubset, ChunkKeySeparator, FillValueMetadata};

/// zstd's level in both Zarr versions: its fastest strategy. Level 3 (zstd's default) took twice the CPU time on
/// a 1 GiB CT-like volume for a few percent smaller chunks, and compression is most of a conversion's time.
const ZSTD_LEVEL: i32 = 1;
const BLOSC_LEVEL: u8 = 5;

/// How every level's arrays are laid out.
#[derive(Clone, Copy, Debug)]
pub struct ArrayLayout {
    pub version: OmeVersion,
    pub chunk: u64,
    /// Shard edge in voxels (Zarr v3 only), a multiple of `chunk`.
    pub shard: Option<u64>,
    pub compression: Compression,
    /// A leading time axis of this many steps.
    pub steps: Option<u64>,
}

impl ArrayLayout {
    /// Slices written at once: whole chunks (or shards) along z, so no chunk is ever read back and rewritten.
    pub fn depth(&self) -> u64 {
        self.shard.unwrap_or(self.chunk)
    }

    fn shape(&self, dims: [u64; 3]) -> Vec<u64> {
        let mut s: Vec<u64> = self.steps.into_iter().collect();
        s.extend([dims[2], dims[1], dims[0]]);
        s
    }

    fn block(&self, edge: u64) -> Vec<u64> {
        let mut s: Vec<u64> = self.steps.map(|_| 1).into_iter().collect();
        s.extend([edge; 3]);
        s
    }
}

fn zarr_error(e: impl std::fmt::Display) -> ConvertError {
    ConvertError::Zarr(e.to_string())
}

fn fill<T: Sample>() -> FillValueMetadata {
    if matches!(T::TYPE, crate::volume::VoxelType::F32 | crate::volume::VoxelType::F64) {
        FillValueMetadata::from(0.0f64)
    } else {
        FillValueMetadata::from(0u8)
    }
}

/// Creates level `path`'s array of `dims` (x, y, z) and stores its metadata.
pub fn create_array<T: Sample>(
    store: &Arc<ChunkStore>,
    path: &str,
    dims: [u64; 3],
    layout: &ArrayLayout,
) -> Result<Array<ChunkStore>, ConvertError> {
    let array = match layout.version {
        OmeVersion::V05 => {
            let mut b = ArrayBuilder::new(
                layout.shape(dims),
                layout.block(layout.depth()),
                zarr_data_type(T::TYPE),
                fill::<T>(),
            );
            let mut names: Vec<&str> = layout.steps.map(|_| "t").into_iter().collect();
            names.extend(["z", "y", "x"]);
            b.dimension_names(Some(names));
            if layout.shard.is_some() {
                b.subchunk_shape(Some(layout.block(layout.chunk)));
            }
            let size = T::TYPE.size();
            let codec: Option<Arc<dyn zarrs::array::codec::api::BytesToBytesCodecTraits>> = match layout.compression {
                Compression::None => None,
                Compression::Zstd => Some(Arc::new(ZstdCodec::new(ZSTD_LEVEL, false))),
                Compression::Blosc => Some(Arc::new(
                    BloscCodec::new(
                        BloscCompressor::LZ4,
                        BloscCompressionLevel::try_from(BLOSC_LEVEL).map_err(zarr_error)?,
                        None,
                        if size > 1 {
                            BloscShuffleMode::Shuffle
                        } else {
                            BloscShuffleMode::NoShuffle
                        },
                        Some(size),
                    )
                    .map_err(zarr_error)?,
                )),
            };
            b.bytes_to_bytes_codecs(codec.into_iter().collect());
            b.build(store.clone(), path).map_err(zarr_error)?
        }
        OmeVersion::V04 => {
            let compressor = match layout.compression {
                Compression::None => None,
                Compression::Zstd => Some(serde_json::json!({"id": "zstd", "level": ZSTD_LEVEL})),
                Compression::Blosc => Some(serde_json::json!({
                    "id": "blosc", "cname": "lz4", "clevel": BLOSC_LEVEL,
                    "shuffle": if T::TYPE.size() > 1 { 1 } else { 0 }, "blocksize": 0,
                })),
            };
            let compressor = compressor.map(serde_json::from_value).transpose().map_err(zarr_error)?;
            let chunks = layout
                .block(layout.chunk)
                .into_iter()
                .map(|n| NonZeroU64::new(n).expect("chunk edges are positive"))
                .collect();
            let metadata = ArrayMetadataV2::new(
                layout.shape(dims),
                chunks,
                numpy_dtype(T::TYPE).into(),
                fill::<T>(),
                compressor,
                None,
            )
            .with_dimension_separator(ChunkKeySeparator::Slash);
            Array::new_with_metadata(store.clone(), path, metadata.into()).map_err(zarr_error)?
        }
    };
    array.store_metadata().map_err(zarr_error)?;
    Ok(array)
}

/// One level being written: its array and the slices received but not yet written.
struct Level<T> {
    array: Array<ChunkStore>,
    dims: [u64; 3],
    pending: Vec<T>,
    next_z: u64,
}

/// Writes one time step's levels as slabs arrive at level 0.
pub struct Cascade<T> {
    levels: Vec<Level<T>>,
    depth: usize,
    reduce: Reduce,
    step: Option<u64>,
}

impl<T: Sample> Cascade<T> {
    pub fn new(arrays: Vec<(Array<ChunkStore>, [u64; 3])>, depth: u64, reduce: Reduce, step: Option<u64>) -> Self {
        let levels = arrays
            .into_iter()
            .map(|(array, dims)| Level {
                array,
                dims,
                pending: Vec::new(),
                next_z: 0,
            })
            .collect();
        Cascade {
            levels,
            depth: depth as usize,
            reduce,
            step,
        }
    }

    /// Gives back the arrays, for the next time step.
    pub fn into_arrays(self) -> Vec<(Array<ChunkStore>, [u64; 3])> {
        self.levels.into_iter().map(|l| (l.array, l.dims)).collect()
    }

    /// Adds whole slices to level `k`; writes (and passes down) every full block of `depth` slices.
    pub fn push(&mut self, k: usize, slices: Vec<T>) -> Result<(), ConvertError> {
        let level = &mut self.levels[k];
        let slice = (level.dims[0] * level.dims[1]) as usize;
        if level.pending.is_empty() {
            level.pending = slices;
        } else {
            level.pending.extend_from_slice(&slices);
        }
        while self.levels[k].pending.len() >= self.depth * slice {
            let level = &mut self.levels[k];
            let rest = level.pending.split_off(self.depth * slice);
            let block = std::mem::replace(&mut level.pending, rest);
            self.write_and_pass(k, block)?;
        }
        Ok(())
    }

    /// Writes what level 0 and then each coarser level still holds: the last, partial block of each.
    pub fn finish(&mut self) -> Result<(), ConvertError> {
        for k in 0..self.levels.len() {
            let block = std::mem::take(&mut self.levels[k].pending);
            if !block.is_empty() {
                self.write_and_pass(k, block)?;
            }
        }
        Ok(())
    }

    fn write_and_pass(&mut self, k: usize, block: Vec<T>) -> Result<(), ConvertError> {
        let coarser = k + 1 < self.levels.len();
        let level = &mut self.levels[k];
        let [w, h, d] = level.dims;
        let n = block.len() as u64 / (w * h);
        let z = level.next_z;
        let mut ranges = Vec::new();
        if let Some(t) = self.step {
            ranges.push(t..t + 1);
        }
        ranges.extend([z..z + n, 0..h, 0..w]);
        let coarse = coarser.then(|| {
            downsample(
                &block,
                [w as usize, h as usize, n as usize],
                factors([w, h, d]),
                self.reduce,
            )
        });
        level
            .array
            .store_array_subset(&ArraySubset::new_with_ranges(&ranges), block)
            .map_err(zarr_error)?;
        level.next_z += n;
        if let Some(coarse) = coarse {
            self.push(k + 1, coarse)?;
        }
        Ok(())
    }
}
