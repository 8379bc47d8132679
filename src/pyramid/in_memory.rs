//! The levels of a volume held in memory, each made from the one before it by the mean: what a pool of bricks shows
//! above level 0 when the whole volume is held.

use super::geometry::{factors, next_level};
use super::reduce::{downsample, Reduce};
use crate::volume::{Volume, VolumeError, VoxelData};

/// Grows `pyramid`, levels 1.. of `volume` (level 0 is the volume), up to level `top`, each level made from the one
/// before it: a [`Volume`] with level 0's value range, so that its elements normalise the same way.
pub fn extend_pyramid(volume: &Volume, pyramid: &mut Vec<Volume>, top: u32) -> Result<(), VolumeError> {
    while pyramid.len() < top as usize {
        let from = pyramid.last().unwrap_or(volume);
        let dims = from.dims.map(|d| d as usize);
        let f = factors(from.dims.map(u64::from));
        let data = match &from.data {
            VoxelData::U8(v) => VoxelData::U8(downsample(v, dims, f, Reduce::Mean)),
            VoxelData::U16(v) => VoxelData::U16(downsample(v, dims, f, Reduce::Mean)),
            VoxelData::F32(v) => VoxelData::F32(downsample(v, dims, f, Reduce::Mean)),
        };
        let mut level = Volume::new(
            volume.name.clone(),
            next_level(from.dims),
            [1.0; 3],
            volume.source_type,
            data,
        )?
        .with_scaling(volume.scaling)?;
        (level.range, level.stored_range) = (volume.range, volume.stored_range);
        pyramid.push(level);
    }
    Ok(())
}
