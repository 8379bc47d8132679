//! Boxes of an OME-Zarr store's full-resolution level, read by zarrs (only the chunks under the box): what the
//! levels finer than the one a volume holds are made from when it came from a store (`scale::finer`), as a file's
//! are made from its voxels in place. Offered only where the held level is a halving of level 0 as the pyramid
//! rule makes it (its size and placement), so that the finer bricks sit where the held ones do.

use super::metadata::{AxisRole, Multiscale};
use super::{group_attributes, guard, metadata, place, read};
use crate::formats::format;
use crate::pyramid::geometry::{level_geometry, level_of};
use crate::pyramid::sample::Sample;
use crate::volume::{Geometry, Volume, VolumeError, VoxelType};
use std::path::Path;
use std::sync::Arc;
use zarrs::array::{Array, ArraySubset};
use zarrs::storage::{ReadableStorage, ReadableStorageTraits};

/// A store's level 0, one channel of its first time step.
pub struct ZarrBoxes {
    file: String,
    array: Array<dyn ReadableStorageTraits>,
    /// The array's axis of x, y and z, and positions on its other axes (time 0, the channel).
    space: [usize; 3],
    fixed: Vec<(usize, u64)>,
    pub voxel_type: VoxelType,
    /// Level 0's size and placement.
    pub dims: [u32; 3],
    pub geometry: Geometry,
}

impl std::fmt::Debug for ZarrBoxes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ZarrBoxes({}, {:?})", self.file, self.dims)
    }
}

/// Level 0 of the store at `path` and the pyramid level `v` (one level of it, channel `channel`) is of it; `None`
/// where `v` is level 0, a series, a 2-D image, or a level the pyramid rule does not make from level 0 (another
/// size, placement or type).
pub(crate) fn finer_of(path: &Path, v: &Volume, channel: Option<u32>) -> Result<Option<(ZarrBoxes, u32)>, VolumeError> {
    let file = format::file_label(path);
    let bad = |problem: String| format::header_error(&file, problem);
    let store =
        zarrs::filesystem::FilesystemStore::new(path).map_err(|e| bad(format!("cannot open the store: {e}")))?;
    let store: ReadableStorage = Arc::new(store);
    let ms = metadata::parse(&group_attributes(&store).map_err(bad)?).map_err(bad)?;
    let space = ms.space_axes();
    if v.timesteps() > 1 || space.len() != 3 {
        return Ok(None);
    }
    let level0 = &ms.levels[0];
    let opened = Array::open(store.clone(), &format!("/{}", level0.path)).map_err(|e| bad(e.to_string()))?;
    let array =
        Array::open(guard::guarded(store, &opened), &format!("/{}", level0.path)).map_err(|e| bad(e.to_string()))?;
    let shape = array.shape().to_vec();
    let Ok(dims) = [2, 1, 0]
        .map(|k| u32::try_from(shape[space[k]]))
        .into_iter()
        .collect::<Result<Vec<u32>, _>>()
    else {
        return Ok(None);
    };
    let dims = [dims[0], dims[1], dims[2]];
    let Some(held) = level_of(dims, v.dims) else {
        return Ok(None);
    };
    let (affine, anatomical) = place::affine(&ms, 0, &mut Vec::new());
    let geometry = Geometry { affine, anatomical };
    let placed = level_geometry(geometry, dims, held);
    let tolerance = 1e-6 * placed.affine.to_cols_array().iter().fold(1.0f64, |m, x| m.max(x.abs()));
    if !placed.affine.abs_diff_eq(v.geometry.affine, tolerance) {
        return Ok(None);
    }
    let voxel_type = read::voxel_type(&array).map_err(bad)?;
    // Level 0's bricks land in the held level's texture: a store whose levels differ in type keeps its level.
    if voxel_type != v.source_type {
        return Ok(None);
    }
    Ok(Some((
        ZarrBoxes {
            file,
            array,
            space: [space[2], space[1], space[0]],
            fixed: fixed_axes(&ms, channel),
            voxel_type,
            dims,
            geometry,
        },
        held,
    )))
}

/// Time step 0 and the channel, on the axes the store has.
fn fixed_axes(ms: &Multiscale, channel: Option<u32>) -> Vec<(usize, u64)> {
    let mut fixed = Vec::new();
    if let Some(i) = ms.axis_index(AxisRole::Time) {
        fixed.push((i, 0));
    }
    if let Some(i) = ms.axis_index(AxisRole::Channel) {
        fixed.push((i, u64::from(channel.unwrap_or(0))));
    }
    fixed
}

impl ZarrBoxes {
    pub fn name(&self) -> &str {
        &self.file
    }

    /// Level-0 voxels `lo..lo + size`, x fastest, as `T` (the store's values, as a file's box is read).
    pub fn read_box<T: Sample>(&self, lo: [u32; 3], size: [u32; 3]) -> Result<Vec<T>, VolumeError> {
        let ranges: Vec<std::ops::Range<u64>> = (0..self.array.dimensionality())
            .map(|i| {
                match (
                    self.space.iter().position(|&a| a == i),
                    self.fixed.iter().find(|f| f.0 == i),
                ) {
                    (Some(k), _) => u64::from(lo[k])..u64::from(lo[k] + size[k]),
                    (None, Some(&(_, at))) => at..at + 1,
                    (None, None) => 0..1,
                }
            })
            .collect();
        let subset = ArraySubset::new_with_ranges(&ranges);
        let bad = |e: zarrs::array::ArrayError| format::header_error(&self.file, format!("level 0: {e}"));
        macro_rules! get {
            ($t:ty) => {
                self.array
                    .retrieve_array_subset::<Vec<$t>>(&subset)
                    .map_err(bad)?
                    .into_iter()
                    .map(|v| T::from_f64(v as f64))
                    .collect()
            };
        }
        Ok(match self.voxel_type {
            VoxelType::U8 => get!(u8),
            VoxelType::I8 => get!(i8),
            VoxelType::U16 => get!(u16),
            VoxelType::I16 => get!(i16),
            VoxelType::U32 => get!(u32),
            VoxelType::I32 => get!(i32),
            VoxelType::F32 => get!(f32),
            VoxelType::F64 => get!(f64),
        })
    }
}
