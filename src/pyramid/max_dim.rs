//! Halving a volume along the axes that exceed a limit (2× box filter), for volumes larger than `--max-dim` allows.
//! A halved axis follows the pyramid's rule ([`halve`]); unlike the pyramid's levels, only the axes over the limit
//! are halved, and NaN voxels are left out of a mean.

use super::geometry::halve;
use crate::volume::{Volume, VoxelData};

/// Halves every axis longer than `max_dim` (repeatedly) with a 2-voxel box filter. An odd axis keeps its last
/// voxel on its own. Voxels grow to twice their size along a halved
/// axis, each centred between the two it replaces (`Geometry::downsampled`). NaN voxels are left out of an average (all NaN
/// stays NaN). Adds a note saying what happened. `max_dim` of 0 is treated as 1.
pub fn downsample_to(mut volume: Volume, max_dim: u32) -> Volume {
    let max_dim = max_dim.max(1);
    let (original, source, source_voxels) = (volume.dims, volume.geometry, volume.source_voxels);
    let ranges = (volume.range, volume.stored_range);
    while volume.dims.iter().any(|&d| d > max_dim) {
        let over = volume.dims.map(|d| d > max_dim);
        volume = halve_axes(volume, over);
    }
    if volume.dims != original {
        let [a, b, c] = original;
        let [x, y, z] = volume.dims;
        volume.notes.push(format!(
            "downsampled from {a}x{b}x{c} to {x}x{y}x{z} (2x box filter) to fit the maximum dimension {max_dim}"
        ));
        // A stand-in shows its source's look: the same optical depth, and values normalised by the source's range
        // (as a level read under a budget is), so the window does not move as the means narrow it.
        volume = volume.stand_in_for(&source, source_voxels);
        (volume.range, volume.stored_range) = ranges;
    }
    volume
}

fn halve_axes(volume: Volume, halved: [bool; 3]) -> Volume {
    let src = volume.dims.map(|d| d as usize);
    let dst: Vec<usize> = (0..3)
        .map(|i| {
            if halved[i] {
                halve(src[i] as u64) as usize
            } else {
                src[i]
            }
        })
        .collect();
    let factor = halved.map(|h| if h { 2 } else { 1 });
    // Averages the (up to 8) source voxels of output voxel (x, y, z) through `get`.
    let average = |x: usize, y: usize, z: usize, get: &dyn Fn(usize) -> f64| -> f64 {
        let (mut sum, mut n) = (0.0, 0u32);
        for dz in 0..factor[2] {
            for dy in 0..factor[1] {
                for dx in 0..factor[0] {
                    let (sx, sy, sz) = (x * factor[0] + dx, y * factor[1] + dy, z * factor[2] + dz);
                    if sx < src[0] && sy < src[1] && sz < src[2] {
                        let v = get(sx + src[0] * (sy + src[1] * sz));
                        if !v.is_nan() {
                            sum += v;
                            n += 1;
                        }
                    }
                }
            }
        }
        if n == 0 {
            f64::NAN
        } else {
            sum / f64::from(n)
        }
    };
    let count = dst[0] * dst[1] * dst[2];
    let cells = || (0..count).map(|i| (i % dst[0], (i / dst[0]) % dst[1], i / (dst[0] * dst[1])));
    let data = match &volume.data {
        VoxelData::U8(v) => VoxelData::U8(
            cells()
                .map(|(x, y, z)| average(x, y, z, &|i| f64::from(v[i])).round() as u8)
                .collect(),
        ),
        VoxelData::U16(v) => VoxelData::U16(
            cells()
                .map(|(x, y, z)| average(x, y, z, &|i| f64::from(v[i])).round() as u16)
                .collect(),
        ),
        VoxelData::F32(v) => VoxelData::F32(
            cells()
                .map(|(x, y, z)| average(x, y, z, &|i| f64::from(v[i])) as f32)
                .collect(),
        ),
    };
    let dims = [dst[0] as u32, dst[1] as u32, dst[2] as u32];
    // New voxel j averages old voxels 2j and 2j + 1: twice the size, centred between them.
    let geometry = volume.geometry.downsampled(factor.map(|f| f as u32));
    // Same type, smaller dims: `new` cannot fail on a volume that was valid before.
    let spacing = geometry.spacing().map(|s| s as f32);
    let out = Volume::new(volume.name.clone(), dims, spacing, volume.source_type, data)
        .and_then(|v| v.with_scaling(volume.scaling))
        .and_then(|v| v.with_geometry(geometry));
    let mut out = match out {
        Ok(v) => v,
        Err(_) => return volume,
    };
    out.format = volume.format;
    out.notes = volume.notes;
    out.arrays = volume.arrays;
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelType;

    #[test]
    fn halves_long_axes_only() {
        let data: Vec<u8> = (0..5 * 2).map(|i| i * 10).collect();
        let v = Volume::new("t", [5, 2, 1], [1.0, 2.0, 3.0], VoxelType::U8, VoxelData::U8(data)).unwrap();
        let d = downsample_to(v, 3);
        assert_eq!(d.dims, [3, 2, 1]);
        // Row 0: (0+10)/2, (20+30)/2, 40 alone.
        assert_eq!(
            [d.value(0, 0, 0), d.value(1, 0, 0), d.value(2, 0, 0)],
            [5.0, 25.0, 40.0]
        );
        assert_eq!(d.value(2, 1, 0), 90.0);
        // Each new voxel is two old ones wide, centred between them (the odd last one too: its value is its own).
        assert_eq!(d.spacing(), [2.0, 2.0, 3.0]);
        assert_eq!(d.geometry.origin().to_array(), [0.5, 0.0, 0.0]);
        assert!(d.notes[0].contains("downsampled from 5x2x1 to 3x2x1"), "{:?}", d.notes);
    }

    #[test]
    fn repeats_until_it_fits_and_ignores_nan() {
        let mut data = vec![1.0f32; 8 * 8 * 8];
        data[0] = f32::NAN;
        let v = Volume::new("t", [8, 8, 8], [1.0; 3], VoxelType::F32, VoxelData::F32(data)).unwrap();
        let d = downsample_to(v, 2);
        assert_eq!(d.dims, [2, 2, 2]);
        assert_eq!(d.value(0, 0, 0), 1.0);
        assert_eq!(d.spacing(), [4.0; 3]);
        let small = Volume::new("t", [2, 2, 2], [1.0; 3], VoxelType::U8, VoxelData::U8(vec![3; 8])).unwrap();
        assert!(downsample_to(small, 2).notes.is_empty());
    }
}
