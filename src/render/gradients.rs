//! The gradient texture's texels (`RenderSettings::gradient_texture`): central differences of the normalised
//! values on the voxel grid, neighbours clamped to the edge, NaN read as 0, stored as 2g in RGBA16 SNORM.

use crate::volume::{Volume, VoxelData};
use rayon::prelude::*;

/// Fills `dst` with the texels of consecutive slices from `first` on (slice numbers past the last wrap to the
/// first: a depth-1 volume's texture holds its slice twice): per voxel (x fastest) the central differences
/// (x, y, z) of [`Volume::normalized`] one voxel apart, as RGBA16 SNORM texels of 2g (the range of g, [−0.5, 0.5],
/// fills SNORM's [−1, 1]); alpha 0. Slice by slice on every core, each from the normalised planes before, at and
/// after it (a per-voxel `normalized` call for each of six neighbours took 0.6 s for a 256³ volume). Written
/// straight into the upload's destination, so no copy of the texture is held on the heap.
pub(super) fn fill_gradient_slices(volume: &Volume, first: usize, dst: &mut [[i16; 4]]) {
    let [w, h, d] = volume.dims.map(|v| v as usize);
    let plane = w * h;
    dst.par_chunks_mut(plane).enumerate().for_each(|(k, slice)| {
        let z = (first + k) % d;
        let (below, here, above) = (
            normalized_plane(volume, z.saturating_sub(1)),
            normalized_plane(volume, z),
            normalized_plane(volume, (z + 1).min(d - 1)),
        );
        let snorm = |g: f64| (g.clamp(-1.0, 1.0) * 32767.0).round() as i16;
        for y in 0..h {
            let (y0, y1) = (y.saturating_sub(1), (y + 1).min(h - 1));
            for x in 0..w {
                let (x0, x1) = (x.saturating_sub(1), (x + 1).min(w - 1));
                let i = x + w * y;
                slice[i] = [
                    snorm(here[x1 + w * y] - here[x0 + w * y]),
                    snorm(here[x + w * y1] - here[x + w * y0]),
                    snorm(above[i] - below[i]),
                    0,
                ];
            }
        }
    });
}

/// Slice `z` of the volume, each voxel's [`Volume::normalized`] value (NaN as 0), from its stored elements
/// (`Volume::normalize_element` is the same arithmetic).
fn normalized_plane(volume: &Volume, z: usize) -> Vec<f64> {
    let plane = volume.dims[0] as usize * volume.dims[1] as usize;
    let range = z * plane..(z + 1) * plane;
    let norm = |e: f64| {
        let v = volume.normalize_element(e);
        if v.is_nan() {
            0.0
        } else {
            v
        }
    };
    match &volume.data {
        VoxelData::U8(v) => v[range].iter().map(|&e| norm(f64::from(e))).collect(),
        VoxelData::U16(v) => v[range].iter().map(|&e| norm(f64::from(e))).collect(),
        VoxelData::F32(v) => v[range].iter().map(|&e| norm(f64::from(e))).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{Scaling, VoxelType};

    #[test]
    fn texels_equal_the_per_voxel_definition() {
        // Odd sizes, a scaled signed type with a negative slope, and NaN in a float volume.
        let dims = [7u32, 5, 4];
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let words: Vec<u16> = (0..n).map(|i| ((i * 7919) % 65536) as u16).collect();
        let i16v = Volume::new("i16", dims, [1.0; 3], VoxelType::I16, VoxelData::U16(words))
            .unwrap()
            .with_scaling(Scaling {
                slope: -2.5,
                intercept: 7.0,
            })
            .unwrap();
        let floats: Vec<f32> = (0..n)
            .map(|i| if i % 5 == 0 { f32::NAN } else { (i % 11) as f32 })
            .collect();
        let f32v = Volume::new("f32", dims, [1.0; 3], VoxelType::F32, VoxelData::F32(floats)).unwrap();
        for v in [i16v, f32v] {
            let mut texels = vec![[0i16; 4]; v.voxel_count()];
            // In two calls, as an upload's slabs come.
            let (head, tail) = texels.split_at_mut(2 * 7 * 5);
            fill_gradient_slices(&v, 0, head);
            fill_gradient_slices(&v, 2, tail);
            let at = |x: i64, y: i64, z: i64| {
                let c = |a: i64, n: u32| a.clamp(0, i64::from(n) - 1) as u32;
                let n = v.normalized(c(x, dims[0]), c(y, dims[1]), c(z, dims[2]));
                if n.is_nan() {
                    0.0
                } else {
                    n
                }
            };
            for z in 0..i64::from(dims[2]) {
                for y in 0..i64::from(dims[1]) {
                    for x in 0..i64::from(dims[0]) {
                        let g = [
                            at(x + 1, y, z) - at(x - 1, y, z),
                            at(x, y + 1, z) - at(x, y - 1, z),
                            at(x, y, z + 1) - at(x, y, z - 1),
                        ];
                        let [gx, gy, gz] = g.map(|g| (g.clamp(-1.0, 1.0) * 32767.0).round() as i16);
                        let i = (x + 7 * (y + 5 * z)) as usize;
                        assert_eq!(texels[i], [gx, gy, gz, 0], "{} ({x}, {y}, {z})", v.name);
                    }
                }
            }
        }
    }
}
