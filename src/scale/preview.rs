//! The first image of a large file before the file has been read: a strided preview, every k-th voxel along each
//! axis (k a power of two), on every core. A file read in place takes one positioned read per kept row, so 1/k² of
//! the file (1/16 for k = 4); a DICOM series or multi-frame file decodes every k-th slice from its own file or frame,
//! so 1/k of it. The viewer shows the volume in a fraction of the time the full read takes, and refines when that
//! read ends. Values are samples, not means: the preview aliases, the level read after it does not.

use crate::convert::source::decode;
use crate::formats::dicom::slices::SeriesReader;
use crate::formats::in_place::InPlace;
use crate::volume::{Geometry, Volume, VolumeError, VoxelData, VoxelType};
use glam::{DMat4, DVec4};
use rayon::prelude::*;
use std::fs::File;
use std::os::unix::fs::FileExt;

/// A volume of at least this many voxels at the level it is shown gets a preview first.
pub const PREVIEW_FROM: u64 = 1 << 26;

/// The preview has at most this many voxels along each axis: 128² rows read (16384 positioned reads), which a cold
/// disk serves in about a second where 256² took 3 s (2048³, `bench --scale`).
pub const PREVIEW_SIDE: u32 = 128;

/// The stride for a `dims` volume: the smallest power of two (at least 2) leaving at most [`PREVIEW_SIDE`]
/// voxels along every axis.
pub fn stride(dims: [u32; 3]) -> u32 {
    let mut k = 2;
    while dims.iter().any(|&d| d.div_ceil(k) > PREVIEW_SIDE) {
        k *= 2;
    }
    k
}

/// Whether a `dims` volume shown at level `level` is large enough for a preview: at least [`PREVIEW_FROM`] voxels
/// there (a smaller one opens fast enough without one).
pub fn large_at(dims: [u32; 3], level: u32) -> bool {
    let shown = crate::pyramid::geometry::level_dims(dims, level);
    shown.iter().map(|&d| u64::from(d)).product::<u64>() >= PREVIEW_FROM
}

/// A preview of `place` if it is a single volume [`large_at`] the level `level` it will be shown; `None` otherwise.
pub fn preview(place: &InPlace, level: u32) -> Result<Option<Volume>, VolumeError> {
    if place.timesteps > 1 || !large_at(place.dims, level) {
        return Ok(None);
    }
    strided(place, stride(place.dims)).map(Some)
}

/// Every `k`-th voxel of `place` along each axis, from voxel 0: voxel j of the preview is voxel k·j of the file,
/// placed there (the box stays the file's, give or take k − 1 voxels at the far ends).
pub fn strided(place: &InPlace, k: u32) -> Result<Volume, VolumeError> {
    let out = place.dims.map(|n| n.div_ceil(k));
    let runs = match &place.slices {
        Some(series) => slice_samples(place, series, k, out)?,
        None => row_samples(place, k, out)?,
    };
    let values = runs.into_iter().flatten();
    let data = match place.voxel_type {
        VoxelType::U8 => VoxelData::U8(values.map(|v| v as u8).collect()),
        VoxelType::I8 => VoxelData::U8(values.map(|v| (v + 128.0) as u8).collect()),
        VoxelType::U16 => VoxelData::U16(values.map(|v| v as u16).collect()),
        VoxelType::I16 => VoxelData::U16(values.map(|v| (v + 32768.0) as u16).collect()),
        _ => VoxelData::F32(values.map(|v| v as f32).collect()),
    };
    let kf = f64::from(k);
    let geometry = Geometry {
        affine: place.geometry.affine * DMat4::from_diagonal(DVec4::new(kf, kf, kf, 1.0)),
        ..place.geometry
    };
    let mut v = Volume::new(&place.name, out, [1.0; 3], place.voxel_type, data)?.with_geometry(geometry)?;
    if !place.scaling.is_identity() {
        v = v.with_scaling(place.scaling)?;
    }
    let mut v = super::described(v, place).stand_in_for(&place.geometry, 1.0);
    let ([x, y, z], [w, h, d]) = (out, place.dims);
    v.notes.push(format!(
        "a preview of 1 voxel in {k} per axis ({x}x{y}x{z} of {w}x{h}x{d}) while the file is read"
    ));
    Ok(v)
}

/// Every `k`-th voxel of every `k`-th row and slice of a file read in place, a row at a time: one positioned read
/// per kept row, on every core.
fn row_samples(place: &InPlace, k: u32, out: [u32; 3]) -> Result<Vec<Vec<f64>>, VolumeError> {
    let file = File::open(&place.data_file).map_err(|source| VolumeError::Io {
        path: place.data_file.clone(),
        source,
    })?;
    let h = place.dims[1];
    let size = place.voxel_type.size();
    let big = place.endian == crate::formats::Endian::Big;
    let row_bytes = place.dims[0] as usize * size;
    (0..out[1] as usize * out[2] as usize)
        .into_par_iter()
        .map(|r| {
            let (y, z) = (
                (r % out[1] as usize) as u64 * u64::from(k),
                (r / out[1] as usize) as u64 * u64::from(k),
            );
            let at = place.offset + (z * u64::from(h) + y) * row_bytes as u64;
            let mut bytes = vec![0u8; row_bytes];
            file.read_exact_at(&mut bytes, at)?;
            Ok(bytes
                .chunks_exact(size)
                .step_by(k as usize)
                .map(|b| decode(place.voxel_type, big, b))
                .collect())
        })
        .collect::<Result<_, std::io::Error>>()
        .map_err(|source| VolumeError::Io {
            path: place.data_file.clone(),
            source,
        })
}

/// Every `k`-th voxel of every `k`-th row of every `k`-th slice of a DICOM series or multi-frame file, each kept
/// slice decoded from its own file or frame as the loader decodes it (uneven spacing resampled), on every core.
fn slice_samples(place: &InPlace, series: &SeriesReader, k: u32, out: [u32; 3]) -> Result<Vec<Vec<f64>>, VolumeError> {
    let size = place.voxel_type.size();
    let row_bytes = place.dims[0] as usize * size;
    let plane = row_bytes * place.dims[1] as usize;
    (0..out[2])
        .into_par_iter()
        .map(|z| {
            let mut bytes = vec![0u8; plane];
            series.read_at(u64::from(z) * u64::from(k) * plane as u64, &mut bytes)?;
            Ok(bytes
                .chunks_exact(row_bytes)
                .step_by(k as usize)
                .flat_map(|row| row.chunks_exact(size).step_by(k as usize))
                .map(|b| decode(place.voxel_type, false, b))
                .collect())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::in_place::in_place;

    #[test]
    fn strides_keep_every_kth_voxel_where_it_lies() {
        assert_eq!(stride([1024, 1024, 1024]), 8);
        assert_eq!(stride([2048, 300, 10]), 16);
        assert_eq!(stride([100, 100, 100]), 2);
        let dims = [9u32, 7, 5];
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let src: Vec<i16> = (0..n).map(|i| (i as i16) * 3 - 200).collect();
        let (path, opts) = crate::scale::test_file::int16_raw("preview", dims, &src, Some([0.5, 1.0, 2.0]));
        let place = in_place(&path, &opts).unwrap().unwrap();
        let v = strided(&place, 4).unwrap();
        assert_eq!(v.dims, [3, 2, 2]);
        let full = crate::formats::open(&path, &opts).unwrap();
        for (x, y, z) in [(0, 0, 0), (2, 1, 1), (1, 0, 1)] {
            assert_eq!(v.value(x, y, z), full.value(x * 4, y * 4, z * 4), "({x}, {y}, {z})");
            let p = v
                .geometry
                .affine
                .transform_point3(glam::DVec3::new(x as f64, y as f64, z as f64));
            let q =
                full.geometry
                    .affine
                    .transform_point3(glam::DVec3::new(x as f64 * 4.0, y as f64 * 4.0, z as f64 * 4.0));
            assert_eq!(p, q);
        }
        std::fs::remove_dir_all(path.parent().unwrap()).ok();
    }
}
