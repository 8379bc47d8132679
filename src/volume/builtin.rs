//! Deterministic generated volumes, so the renderer can be shown and tested without data files. The first three
//! follow Qt Quick 3D's volumetric rendering example; Marschner–Lobb is the classic reconstruction-filter test.

use super::{Volume, VolumeError, VoxelData, VoxelType};
use std::f64::consts::PI;

pub const BUILTIN_NAMES: &[&str] = &["helix", "box", "colormap", "marschner-lobb"];

const DEFAULT_SIZE: u32 = 256;
/// Marschner & Lobb's paper samples their function on a 41³ grid; artefacts of a reconstruction filter show there.
const DEFAULT_MARSCHNER_LOBB_SIZE: u32 = 41;
const MIN_SIZE: u32 = 2;
const MAX_SIZE: u32 = 1024;

/// Deterministic built-in volumes. `size` = edge length (default 256 for helix/box/colormap, 41 for
/// marschner-lobb), 2..=1024. Spacing is 1, so every built-in is a cube.
pub fn builtin(name: &str, size: Option<u32>) -> Result<Volume, VolumeError> {
    let key = name.trim().to_ascii_lowercase();
    let default_size = match key.as_str() {
        "helix" | "box" | "colormap" => DEFAULT_SIZE,
        "marschner-lobb" => DEFAULT_MARSCHNER_LOBB_SIZE,
        _ => {
            return Err(VolumeError::UnknownBuiltin {
                given: name.to_string(),
            })
        }
    };
    let size = size.unwrap_or(default_size);
    if !(MIN_SIZE..=MAX_SIZE).contains(&size) {
        return Err(VolumeError::BuiltinSize { size });
    }
    let dims = [size; 3];
    let (source_type, data) = match key.as_str() {
        "helix" => (VoxelType::U8, VoxelData::U8(helix(size)?)),
        "box" => (VoxelType::U8, VoxelData::U8(box_shell(size)?)),
        "colormap" => (VoxelType::U8, VoxelData::U8(colormap_ramp(size)?)),
        _ => (VoxelType::F32, VoxelData::F32(marschner_lobb(size)?)),
    };
    Volume::new(key, dims, [1.0; 3], source_type, data)
}

/// size³ zeroes, or an error rather than an abort if a large size doesn't fit in memory.
fn zeroed<T: Clone + Default>(size: u32, bytes_per_voxel: u64) -> Result<Vec<T>, VolumeError> {
    let count = (size as usize).pow(3);
    let mut v = Vec::new();
    v.try_reserve_exact(count).map_err(|_| VolumeError::OutOfMemory {
        dims: [size; 3],
        bytes: count as u64 * bytes_per_voxel,
    })?;
    v.resize(count, T::default());
    Ok(v)
}

/// Voxel centre in [0, 1].
fn centre(i: u32, size: u32) -> f64 {
    (f64::from(i) + 0.5) / f64::from(size)
}

/// A tube wound three times around the z axis. Values are highest on the tube's centre line, fall smoothly to 0
/// at its surface, and rise along the helix from bottom to top so a colormap shows along its length.
fn helix(size: u32) -> Result<Vec<u8>, VolumeError> {
    const RADIUS: f64 = 0.3;
    const TUBE_RADIUS: f64 = 0.07;
    const TURNS: u32 = 3;
    const Z_START: f64 = 0.1;
    const Z_END: f64 = 0.9;
    let pitch = (Z_END - Z_START) / f64::from(TURNS);
    // A vertical offset dz from the helix is, to first order, dz·cos(climb angle) away from its centre line.
    let circumference = 2.0 * PI * RADIUS;
    let vertical_scale = circumference / circumference.hypot(pitch);

    let n = size as usize;
    let mut data = zeroed::<u8>(size, 1)?;
    // Per (x, y) column: squared radial distance from the helix cylinder and the angle as a fraction of a turn.
    // Columns farther than a tube radius from the cylinder stay empty.
    let columns: Vec<Option<(f64, f64)>> = (0..size)
        .flat_map(|y| (0..size).map(move |x| (x, y)))
        .map(|(x, y)| {
            let (dx, dy) = (centre(x, size) - 0.5, centre(y, size) - 0.5);
            let radial = dx.hypot(dy) - RADIUS;
            (radial.abs() < TUBE_RADIUS).then(|| (radial * radial, (dy.atan2(dx) / (2.0 * PI)).rem_euclid(1.0)))
        })
        .collect();

    for z in 0..size {
        let zc = centre(z, size);
        let slice = &mut data[z as usize * n * n..][..n * n];
        for (voxel, column) in slice.iter_mut().zip(&columns) {
            let Some((radial_sq, turn_fraction)) = *column else {
                continue;
            };
            // The helix passes this column once per turn; the nearest pass decides.
            let (mut dist_sq, mut s) = (f64::INFINITY, 0.0);
            for k in 0..TURNS {
                let s_k = (turn_fraction + f64::from(k)) / f64::from(TURNS);
                let dz = (zc - (Z_START + s_k * (Z_END - Z_START))) * vertical_scale;
                if radial_sq + dz * dz < dist_sq {
                    (dist_sq, s) = (radial_sq + dz * dz, s_k);
                }
            }
            let r = dist_sq.sqrt() / TUBE_RADIUS;
            if r < 1.0 {
                let profile = (0.5 * PI * r).cos().powi(2);
                *voxel = (255.0 * profile * (0.3 + 0.7 * s)).round() as u8;
            }
        }
    }
    Ok(data)
}

/// A hollow box with walls a tenth of the volume thick; values ramp along the box's diagonal (1 at one corner,
/// 255 at the opposite one) so the shell is never confused with the empty space (0) around and inside it.
fn box_shell(size: u32) -> Result<Vec<u8>, VolumeError> {
    const OUTER: [f64; 2] = [0.15, 0.85];
    const INNER: [f64; 2] = [0.25, 0.75];
    let within = |u: f64, [lo, hi]: [f64; 2]| (lo..=hi).contains(&u);
    let n = size as usize;
    let mut data = zeroed::<u8>(size, 1)?;
    for (i, voxel) in data.iter_mut().enumerate() {
        let u = [i % n, (i / n) % n, i / (n * n)].map(|c| centre(c as u32, size));
        let in_outer = u.iter().all(|&c| within(c, OUTER));
        let in_inner = u.iter().all(|&c| within(c, INNER));
        if in_outer && !in_inner {
            let t = (u.iter().sum::<f64>() - 3.0 * OUTER[0]) / (3.0 * (OUTER[1] - OUTER[0]));
            *voxel = (1.0 + 254.0 * t).round().clamp(1.0, 255.0) as u8;
        }
    }
    Ok(data)
}

/// Values ramp 0..=255 along x and fill the volume, so a render shows the colormap itself.
fn colormap_ramp(size: u32) -> Result<Vec<u8>, VolumeError> {
    let row: Vec<u8> = (0..size)
        .map(|x| (255.0 * f64::from(x) / f64::from(size - 1)).round() as u8)
        .collect();
    let mut data = zeroed::<u8>(size, 1)?;
    for chunk in data.chunks_exact_mut(size as usize) {
        chunk.copy_from_slice(&row);
    }
    Ok(data)
}

/// Marschner & Lobb, "An evaluation of reconstruction filters for volume rendering" (1994):
/// ρ(x,y,z) = (1 − sin(πz/2) + α(1 + ρr(√(x²+y²)))) / (2(1+α)), ρr(r) = cos(2π f_M cos(πr/2)),
/// f_M = 6, α = 0.25, on [−1, 1]³ with grid points at −1 + 2i/(size−1). Values lie in [0, 1].
fn marschner_lobb(size: u32) -> Result<Vec<f32>, VolumeError> {
    const F_M: f64 = 6.0;
    const ALPHA: f64 = 0.25;
    let coord = |i: u32| -1.0 + 2.0 * f64::from(i) / f64::from(size - 1);
    let n = size as usize;
    let mut data = zeroed::<f32>(size, 4)?;
    for (i, voxel) in data.iter_mut().enumerate() {
        let (x, y, z) = (
            coord((i % n) as u32),
            coord(((i / n) % n) as u32),
            coord((i / (n * n)) as u32),
        );
        let rho_r = (2.0 * PI * F_M * (0.5 * PI * x.hypot(y)).cos()).cos();
        let rho = (1.0 - (0.5 * PI * z).sin() + ALPHA * (1.0 + rho_r)) / (2.0 * (1.0 + ALPHA));
        *voxel = rho as f32;
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_have_expected_shape_and_range() {
        for name in ["helix", "box", "colormap"] {
            let v = builtin(name, None).unwrap();
            assert_eq!(v.name, name);
            assert_eq!(v.dims, [256; 3]);
            assert_eq!(v.spacing(), [1.0; 3]);
            assert_eq!(v.source_type, VoxelType::U8);
            assert!(matches!(v.data, VoxelData::U8(_)));
            assert_eq!(v.range[0], 0.0, "{name} must have empty space");
            assert!(v.range[1] >= 240.0, "{name}: max {}", v.range[1]);
        }
        let v = builtin("colormap", None).unwrap();
        assert_eq!(v.range, [0.0, 255.0]);
        assert_eq!(v.value(0, 17, 200), 0.0);
        assert_eq!(v.value(255, 3, 9), 255.0);
        assert_eq!(v.value(128, 100, 100), 128.0);

        let v = builtin("marschner-lobb", None).unwrap();
        assert_eq!(v.dims, [41; 3]);
        assert_eq!(v.source_type, VoxelType::F32);
        assert!(matches!(v.data, VoxelData::F32(_)));
        // The maximum 1 is attained at (0, 0, -1), a grid point when size is odd; the minimum 0 needs
        // ρr = -1 at z = 1, which the grid only approaches.
        assert!((v.range[1] - 1.0).abs() < 1e-6, "{:?}", v.range);
        assert!(v.range[0] >= 0.0 && v.range[0] < 0.05, "{:?}", v.range);
        // At the centre: (1 - 0 + 0.25·2) / 2.5 = 0.6.
        assert!((v.value(20, 20, 20) - 0.6).abs() < 1e-6);
        // At (1, 1, 1): r = √2, ρr = cos(12π·cos(π/√2)).
        let rho_r = (12.0 * PI * (PI / 2f64.sqrt()).cos()).cos();
        let expected = (0.25 * (1.0 + rho_r)) / 2.5;
        assert!((v.value(40, 40, 40) - expected).abs() < 1e-6);
    }

    #[test]
    fn builtins_are_deterministic() {
        for &name in BUILTIN_NAMES {
            let a = builtin(name, Some(24)).unwrap();
            let b = builtin(name, Some(24)).unwrap();
            assert_eq!(a.data, b.data, "{name}");
            assert_eq!(a.range, b.range, "{name}");
            assert_eq!(a.dims, [24; 3]);
        }
    }

    #[test]
    fn helix_shape() {
        let v = builtin("helix", Some(64)).unwrap();
        // The axis and the corners are outside the tube.
        assert_eq!(v.value(32, 32, 32), 0.0);
        assert_eq!(v.value(0, 0, 0), 0.0);
        assert_eq!(v.value(63, 63, 63), 0.0);
        // The tube starts at angle 0 (the +x side) at z = 0.1 and climbs; the centre line at the start of its
        // second turn is at x = 0.5 + 0.3, z = 0.1 + 0.8/3.
        let (x, z) = ((0.8 * 64.0) as u32, ((0.1 + 0.8 / 3.0) * 64.0) as u32);
        assert!(v.value(x, 32, z) > 50.0, "{}", v.value(x, 32, z));
        // Values rise along the helix: a later turn is brighter on its centre line than an earlier one.
        let z_late = ((0.1 + 2.0 * 0.8 / 3.0) * 64.0) as u32;
        assert!(v.value(x, 32, z_late) > v.value(x, 32, z));
        // Roughly a tube's worth of voxels is filled: length ≈ 3·2π·0.3 (plus the climb), cross-section π·0.07².
        let filled = match &v.data {
            VoxelData::U8(d) => d.iter().filter(|&&b| b > 0).count(),
            _ => unreachable!(),
        } as f64;
        let expected = 3.0 * (2.0 * PI * 0.3f64).hypot(0.8 / 3.0) * PI * 0.07 * 0.07 * 64f64.powi(3);
        assert!((filled / expected - 1.0).abs() < 0.2, "{filled} vs {expected}");
    }

    #[test]
    fn box_is_a_shell() {
        let v = builtin("box", Some(40)).unwrap();
        assert_eq!(v.value(20, 20, 20), 0.0, "inside must be empty");
        assert_eq!(v.value(1, 1, 1), 0.0, "outside must be empty");
        assert_eq!(v.value(39, 20, 20), 0.0);
        // In the -x wall (0.15..0.25) at mid height, and in the +x wall.
        let low = v.value(7, 20, 20);
        let high = v.value(32, 20, 20);
        assert!(low > 0.0 && high > low, "{low} {high}");
    }

    #[test]
    fn builtin_errors() {
        let err = builtin("torus", None).unwrap_err();
        assert_eq!(
            err.to_string(),
            "unknown built-in volume 'torus': choose one of helix, box, colormap, marschner-lobb"
        );
        for size in [0, 1, 1025] {
            let err = builtin("helix", Some(size)).unwrap_err();
            assert_eq!(
                err.to_string(),
                format!("built-in volume size {size} is out of range: use 2 to 1024")
            );
        }
        let v = builtin("colormap", Some(2)).unwrap();
        assert_eq!(v.range, [0.0, 255.0]);
        assert_eq!(builtin("Marschner-Lobb", Some(3)).unwrap().name, "marschner-lobb");
    }
}
