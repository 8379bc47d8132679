//! The gradient texture's texels (`RenderSettings::gradient_texture`, rule 5 of `RenderSettings`): per voxel the
//! derivative of the normalised values along each axis, smoothed across the other two, by the volume's
//! [`GradientFilter`]; neighbours clamped to the edge, NaN read as 0, stored as 2g in RGBA16 SNORM.

use crate::volume::{Volume, VoxelData, VoxelType};
use rayon::prelude::*;

/// The separable filter of rule 5's gradient texture, chosen by the data: a derivative along one axis and a
/// smoothing along the other two (1-D kernels over the neighbours −R..=R).
///
/// Integer data are quantised: a smooth field stored in few levels per voxel of change (an 8-bit MRI, a narrow
/// value range) has terraces a voxel or less apart, and a 3-tap gradient shades every terrace. Measured on a
/// three-Gaussian field stored as float32 and as 100-level uint8 (normals at its iso-surface, docs/rendering.md, Gradients):
/// central differences err 3.2° on the uint8 copy, Sobel 1.7°, Gaussian σ = 1 0.9°, σ = 1.5 0.6°; on float32 all
/// err 0.5° against the field. Rendered, σ = 1.5 brings the uint8 copy's iso-surface from 4.4/255 (p99 19) to
/// 1.3/255 (p99 4) of the float32 one, σ = 1 to 1.7 (p99 6). A wide kernel also rounds off real detail
/// (Marschner–Lobb's ridges), so float data keep the mildest smoothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GradientFilter {
    /// 3×3×3 Sobel: central differences `[−1, 0, 1]/2`, smoothed by `[1, 2, 1]/4`. Float data.
    Sobel,
    /// Derivative of a Gaussian of σ = 1.5 voxels over k = −5..=5 (3σ rounded up): smoothing `w_k ∝ e^(−k²/2σ²)`
    /// (sum 1), derivative `d_k = k·w_k / Σ j²·w_j` (exact on a linear ramp). Integer data.
    Gaussian,
}

impl GradientFilter {
    /// The filter for `volume`'s data: [`GradientFilter::Gaussian`] for integer source types, else Sobel.
    pub fn for_volume(volume: &Volume) -> GradientFilter {
        match volume.source_type {
            VoxelType::F32 | VoxelType::F64 => GradientFilter::Sobel,
            _ => GradientFilter::Gaussian,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            GradientFilter::Sobel => "Sobel 3x3x3",
            GradientFilter::Gaussian => "Gaussian derivative, sigma 1.5 voxels",
        }
    }

    /// The (smoothing, derivative) kernels, each over the neighbours −R..=R.
    pub fn kernels(self) -> (Vec<f64>, Vec<f64>) {
        match self {
            GradientFilter::Sobel => (vec![0.25, 0.5, 0.25], vec![-0.5, 0.0, 0.5]),
            GradientFilter::Gaussian => {
                const SIGMA: f64 = 1.5;
                let k: Vec<f64> = (-5..=5).map(f64::from).collect();
                let w: Vec<f64> = k.iter().map(|k| (-0.5 * k * k / (SIGMA * SIGMA)).exp()).collect();
                let sum: f64 = w.iter().sum();
                let w: Vec<f64> = w.iter().map(|w| w / sum).collect();
                let moment: f64 = k.iter().zip(&w).map(|(k, w)| k * k * w).sum();
                let d = k.iter().zip(&w).map(|(k, w)| k * w / moment).collect();
                (w, d)
            }
        }
    }
}

/// Fills `dst` with the texels of consecutive slices from `first` on (slice numbers past the last wrap to the
/// first: a depth-1 volume's texture holds its slice twice): per voxel (x fastest) the gradient (x, y, z) of
/// [`Volume::normalized`] by `filter`, as RGBA16 SNORM texels of 2g (the range of g, [−0.5, 0.5], fills SNORM's
/// [−1, 1]); alpha 0. Slice by slice on every core, each from the normalised planes within the kernel's reach,
/// filtered along z, then along x and y. Written straight into the upload's destination, so no copy of the
/// texture is held on the heap.
pub fn fill_gradient_slices(volume: &Volume, filter: GradientFilter, first: usize, dst: &mut [[i16; 4]]) {
    let [w, h, d] = volume.dims.map(|v| v as usize);
    let plane = w * h;
    let (smooth, deriv) = filter.kernels();
    let reach = (smooth.len() / 2) as i64;
    let clamp_z = |z: i64| z.clamp(0, d as i64 - 1) as usize;
    // The normalised planes every slice here reaches, made once (each slice reads 2R + 1 of them).
    let slices = dst.len() / plane;
    let zs: Vec<usize> = (0..slices).map(|k| (first + k) % d).collect();
    let lo = clamp_z(zs.iter().copied().min().unwrap_or(0) as i64 - reach);
    let hi = clamp_z(zs.iter().copied().max().unwrap_or(0) as i64 + reach);
    let planes: Vec<Vec<f64>> = (lo..=hi).into_par_iter().map(|z| normalized_plane(volume, z)).collect();
    dst.par_chunks_mut(plane).zip(zs).for_each(|(slice, z)| {
        let mut along_z_smooth = vec![0.0; plane];
        let mut along_z_deriv = vec![0.0; plane];
        for (j, (ws, wd)) in smooth.iter().zip(&deriv).enumerate() {
            let p = &planes[clamp_z(z as i64 + j as i64 - reach) - lo];
            for ((s, dz), v) in along_z_smooth.iter_mut().zip(along_z_deriv.iter_mut()).zip(p) {
                *s += ws * v;
                *dz += wd * v;
            }
        }
        let gx = filter_y(&filter_x(&along_z_smooth, w, h, &deriv), w, h, &smooth);
        let gy = filter_y(&filter_x(&along_z_smooth, w, h, &smooth), w, h, &deriv);
        let gz = filter_y(&filter_x(&along_z_deriv, w, h, &smooth), w, h, &smooth);
        let snorm = |g: f64| ((2.0 * g).clamp(-1.0, 1.0) * 32767.0).round() as i16;
        for (i, texel) in slice.iter_mut().enumerate() {
            *texel = [snorm(gx[i]), snorm(gy[i]), snorm(gz[i]), 0];
        }
    });
}

/// `plane` (w × h, x fastest) filtered along x by `kernel` (centred), neighbours clamped to the edge: each row is
/// padded with its edge values once, so the taps need no clamping.
fn filter_x(plane: &[f64], w: usize, h: usize, kernel: &[f64]) -> Vec<f64> {
    let reach = kernel.len() / 2;
    let mut out = vec![0.0; w * h];
    let mut padded = vec![0.0; w + 2 * reach];
    for y in 0..h {
        let row = &plane[y * w..(y + 1) * w];
        padded[..reach].fill(row[0]);
        padded[reach..reach + w].copy_from_slice(row);
        padded[reach + w..].fill(row[w - 1]);
        for (o, window) in out[y * w..(y + 1) * w].iter_mut().zip(padded.windows(kernel.len())) {
            *o = kernel.iter().zip(window).map(|(k, v)| k * v).sum();
        }
    }
    out
}

/// `plane` (w × h, x fastest) filtered along y by `kernel` (centred), neighbours clamped to the edge.
fn filter_y(plane: &[f64], w: usize, h: usize, kernel: &[f64]) -> Vec<f64> {
    let reach = (kernel.len() / 2) as i64;
    let mut out = vec![0.0; w * h];
    for (j, k) in kernel.iter().enumerate() {
        for y in 0..h {
            let src = (y as i64 + j as i64 - reach).clamp(0, h as i64 - 1) as usize;
            for (o, v) in out[y * w..(y + 1) * w].iter_mut().zip(&plane[src * w..(src + 1) * w]) {
                *o += k * v;
            }
        }
    }
    out
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
        for (v, filter) in [(i16v, GradientFilter::Gaussian), (f32v, GradientFilter::Sobel)] {
            assert_eq!(GradientFilter::for_volume(&v), filter);
            let mut texels = vec![[0i16; 4]; v.voxel_count()];
            // In two calls, as an upload's slabs come.
            let (head, tail) = texels.split_at_mut(2 * 7 * 5);
            fill_gradient_slices(&v, filter, 0, head);
            fill_gradient_slices(&v, filter, 2, tail);
            let at = |x: i64, y: i64, z: i64| {
                let c = |a: i64, n: u32| a.clamp(0, i64::from(n) - 1) as u32;
                let n = v.normalized(c(x, dims[0]), c(y, dims[1]), c(z, dims[2]));
                if n.is_nan() {
                    0.0
                } else {
                    n
                }
            };
            // The definition: a 3-D sum over the kernel's cube, derivative along one axis, smoothing along the others.
            let (smooth, deriv) = filter.kernels();
            let r = (smooth.len() / 2) as i64;
            for z in 0..i64::from(dims[2]) {
                for y in 0..i64::from(dims[1]) {
                    for x in 0..i64::from(dims[0]) {
                        let mut g = [0.0f64; 3];
                        for (k, (sk, dk)) in smooth.iter().zip(&deriv).enumerate() {
                            for (j, (sj, dj)) in smooth.iter().zip(&deriv).enumerate() {
                                for (i, (si, di)) in smooth.iter().zip(&deriv).enumerate() {
                                    let value = at(x + i as i64 - r, y + j as i64 - r, z + k as i64 - r);
                                    g[0] += di * sj * sk * value;
                                    g[1] += si * dj * sk * value;
                                    g[2] += si * sj * dk * value;
                                }
                            }
                        }
                        let expect = g.map(|g| ((2.0 * g).clamp(-1.0, 1.0) * 32767.0).round() as i16);
                        let got = texels[(x + 7 * (y + 5 * z)) as usize];
                        for a in 0..3 {
                            assert!(
                                (got[a] - expect[a]).abs() <= 1,
                                "{} ({x}, {y}, {z}): {got:?} {expect:?}",
                                v.name
                            );
                        }
                        assert_eq!(got[3], 0);
                    }
                }
            }
        }
    }

    #[test]
    fn kernels_smooth_to_one_and_differentiate_a_ramp_exactly() {
        for filter in [GradientFilter::Sobel, GradientFilter::Gaussian] {
            let (smooth, deriv) = filter.kernels();
            assert_eq!(smooth.len(), deriv.len());
            assert!((smooth.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{}", filter.name());
            let r = (smooth.len() / 2) as f64;
            let slope: f64 = deriv.iter().enumerate().map(|(k, d)| d * (k as f64 - r)).sum();
            assert!((slope - 1.0).abs() < 1e-12, "{}", filter.name());
            assert!(deriv.iter().sum::<f64>().abs() < 1e-12);
        }
    }
}
