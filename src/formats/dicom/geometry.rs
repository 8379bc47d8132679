//! A DICOM series' place in patient space (PS3.3 C.7.6.2): slices sorted along their normal, the voxel-to-RAS
//! affine from Image Orientation and Image Position (Patient), a gantry tilt kept as the shear it is, and uneven
//! slice spacing resampled onto a regular grid. Pure maths over what the headers say.

use crate::volume::geometry::{self, Geometry};
use crate::volume::VoxelData;
use glam::DVec3;

/// What one slice's header says about where it is.
#[derive(Clone, Copy, Debug)]
pub(super) struct Placed {
    pub position: Option<[f64; 3]>,
    pub orientation: Option<[f64; 6]>,
    pub instance: i64,
}

/// How the slices make a volume.
#[derive(Debug)]
pub(super) struct Arrangement {
    /// The slices' indices in volume order (k = 0 first).
    pub order: Vec<usize>,
    pub geometry: Geometry,
    /// For uneven spacing: per output slice, its position as a fractional index into the sorted input slices.
    pub resample: Option<Vec<f64>>,
    pub notes: Vec<String>,
}

/// Largest deviation of a slice from the regular grid, as a share of the step, before the series is resampled.
/// Scanners write positions rounded (brain_pd_mr in ../shared: to 0.1 mm, so its 7 mm steps read 6.96 to 7.07
/// and a slice sits 0.07 mm off the grid); 5% of a step is beyond rounding and still under what shows.
const UNEVEN_TOLERANCE: f64 = 0.05;

/// Arranges `slices` (one file each, or one multi-frame file of `frames` frames) of in-plane `pixel_spacing`
/// (DICOM's order: between rows, between columns) and nominal slice step `slice_step` (SpacingBetweenSlices or
/// SliceThickness). `Err` says why they cannot make one volume.
pub(super) fn arrange(
    slices: &[Placed],
    pixel_spacing: [f64; 2],
    slice_step: Option<f64>,
) -> Result<Arrangement, String> {
    let [row_spacing, column_spacing] = pixel_spacing;
    let step = slice_step.unwrap_or(1.0);
    let Some(o) = slices[0].orientation else {
        return Ok(unoriented(slices, pixel_spacing, step));
    };
    let mut notes = Vec::new();
    let mut order: Vec<usize> = (0..slices.len()).collect();
    // Column index i runs along the row direction (the first triple), row index j along the column direction.
    let row_dir = DVec3::new(o[0], o[1], o[2]);
    let column_dir = DVec3::new(o[3], o[4], o[5]);
    let normal = row_dir.cross(column_dir);
    if normal.length() < 1e-3 || (row_dir.length() - 1.0).abs() > 0.01 || (column_dir.length() - 1.0).abs() > 0.01 {
        return Err(format!(
            "ImageOrientationPatient {o:?} is not two perpendicular unit vectors"
        ));
    }
    let normal = normal.normalize();
    let positions: Option<Vec<DVec3>> = slices.iter().map(|s| s.position.map(DVec3::from_array)).collect();
    let (origin, k_step, resample) = match positions {
        Some(p) if slices.len() > 1 => {
            if slices.iter().any(|s| s.orientation.is_some_and(|so| differs(so, o))) {
                return Err("the slices have different ImageOrientationPatient: not one stack".into());
            }
            stack(&p, normal, pixel_spacing, &mut order, &mut notes)?
        }
        Some(p) => (p[0], normal * step, None),
        None => {
            if slices.len() > 1 {
                order.sort_by_key(|&i| slices[i].instance);
                notes.push(format!(
                    "no ImagePositionPatient: slices ordered by InstanceNumber, {step} mm apart along the normal"
                ));
            }
            (DVec3::ZERO, normal * step, None)
        }
    };
    let tilt = k_step.angle_between(normal * k_step.dot(normal).signum()).to_degrees();
    if tilt > 0.01 {
        notes.push(format!(
            "slices offset {tilt:.2}° from their normal (gantry tilt): drawn sheared, as they were scanned"
        ));
    }
    let columns = [row_dir * column_spacing, column_dir * row_spacing, k_step];
    let geometry = Geometry::anatomical(geometry::LPS_TO_RAS * geometry::from_columns(columns, origin));
    Ok(Arrangement {
        order,
        geometry,
        resample,
        notes,
    })
}

/// Slices without ImageOrientationPatient: ordered by InstanceNumber, `step` apart, with no anatomical place.
fn unoriented(slices: &[Placed], [row_spacing, column_spacing]: [f64; 2], step: f64) -> Arrangement {
    let mut notes = Vec::new();
    let mut order: Vec<usize> = (0..slices.len()).collect();
    if slices.len() > 1 {
        order.sort_by_key(|&i| slices[i].instance);
        notes.push(format!(
            "no ImageOrientationPatient: slices ordered by InstanceNumber, {step} apart \
             (SpacingBetweenSlices/SliceThickness), and no anatomical orientation"
        ));
    }
    Arrangement {
        order,
        geometry: Geometry::from_spacing([column_spacing, row_spacing, step]),
        resample: None,
        notes,
    }
}

/// Two or more slices at positions `p`: sorts `order` along `normal` and returns the first slice's position, the
/// step from slice to slice as a vector, and (for uneven spacing) where to resample.
fn stack(
    p: &[DVec3],
    normal: DVec3,
    [row_spacing, column_spacing]: [f64; 2],
    order: &mut [usize],
    notes: &mut Vec<String>,
) -> Result<(DVec3, DVec3, Option<Vec<f64>>), String> {
    let along = |i: usize| p[i].dot(normal);
    order.sort_by(|&a, &b| along(a).total_cmp(&along(b)));
    let d: Vec<f64> = order.iter().map(|&i| along(i)).collect();
    let n = d.len();
    let mean = (d[n - 1] - d[0]) / (n - 1) as f64;
    if mean.is_nan() || mean <= 1e-6 {
        return Err("the slices all lie at the same position along the slice normal".into());
    }
    if d.windows(2).any(|w| w[1] - w[0] < 1e-6 * mean) {
        return Err("two slices share a position: the folder holds more than one acquisition".into());
    }
    let (first_p, last_p) = (p[order[0]], p[order[n - 1]]);
    // The mean step between slices, as a vector: along the normal, or tilted off it (gantry tilt). A sideways
    // drift over the whole stack under half a pixel is rounding in the positions, not a tilt: the step is then
    // taken along the normal (as ITK takes it).
    let span = last_p - first_p;
    let drift = (span - normal * span.dot(normal)).length();
    let k_step = if drift < 0.5 * column_spacing.min(row_spacing) {
        normal * mean
    } else {
        span / (n - 1) as f64
    };
    Ok((first_p, k_step, resample_if_uneven(&d, mean, notes)))
}

/// For slices at sorted distances `d` along the normal, `mean` apart on average: where to resample them if one lies
/// off the regular grid by more than [`UNEVEN_TOLERANCE`] of a step (None if not), with a note either way once
/// the spacing is not exactly even.
fn resample_if_uneven(d: &[f64], mean: f64, notes: &mut Vec<String>) -> Option<Vec<f64>> {
    let n = d.len();
    let off_grid = (0..n)
        .map(|k| (d[k] - (d[0] + k as f64 * mean)).abs())
        .fold(0.0, f64::max);
    let steps: Vec<f64> = d.windows(2).map(|w| w[1] - w[0]).collect();
    let lo = steps.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = steps.iter().copied().fold(0.0, f64::max);
    let uneven =
        format!("uneven slice spacing ({lo:.4} to {hi:.4} mm; a slice lies {off_grid:.3} mm off the regular grid)");
    if off_grid > UNEVEN_TOLERANCE * mean {
        notes.push(format!(
            "{uneven}: resampled linearly onto {n} slices {mean:.4} mm apart"
        ));
        Some((0..n).map(|k| fractional_index(d, d[0] + k as f64 * mean)).collect())
    } else {
        if off_grid > 1e-3 * mean {
            notes.push(format!("{uneven}: within rounding, the mean step {mean:.4} mm is used"));
        }
        None
    }
}

fn differs(a: [f64; 6], b: [f64; 6]) -> bool {
    a.iter().zip(&b).any(|(x, y)| (x - y).abs() > 1e-4)
}

/// Where `target` lies in the increasing sequence `d`, as a fractional index (clamped to its ends).
fn fractional_index(d: &[f64], target: f64) -> f64 {
    let j = d.partition_point(|&x| x <= target).clamp(1, d.len() - 1) - 1;
    let w = ((target - d[j]) / (d[j + 1] - d[j])).clamp(0.0, 1.0);
    j as f64 + w
}

/// The volume resampled along k: output slice k is the linear blend of the input slices around `at[k]`.
pub(super) fn resample_slices(data: &VoxelData, dims: [u32; 3], at: &[f64]) -> VoxelData {
    let plane = dims[0] as usize * dims[1] as usize;
    let depth = dims[2] as usize;
    fn blend<T: Copy>(src: &[T], plane: usize, depth: usize, at: &[f64], mix: impl Fn(T, T, f64) -> T) -> Vec<T> {
        let mut out = Vec::with_capacity(src.len());
        for &f in at {
            let j = (f.floor() as usize).min(depth - 1);
            let (j1, w) = if j + 1 < depth { (j + 1, f - j as f64) } else { (j, 0.0) };
            let (a, b) = (&src[j * plane..(j + 1) * plane], &src[j1 * plane..(j1 + 1) * plane]);
            out.extend(a.iter().zip(b).map(|(&x, &y)| mix(x, y, w)));
        }
        out
    }
    match data {
        VoxelData::U8(v) => VoxelData::U8(blend(v, plane, depth, at, |a, b, w| {
            (f64::from(a) + (f64::from(b) - f64::from(a)) * w).round() as u8
        })),
        VoxelData::U16(v) => VoxelData::U16(blend(v, plane, depth, at, |a, b, w| {
            (f64::from(a) + (f64::from(b) - f64::from(a)) * w).round() as u16
        })),
        VoxelData::F32(v) => VoxelData::F32(blend(v, plane, depth, at, |a, b, w| {
            (f64::from(a) + (f64::from(b) - f64::from(a)) * w) as f32
        })),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const AXIAL: [f64; 6] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

    fn at(z: f64, instance: i64) -> Placed {
        Placed {
            position: Some([-100.0, -120.0, z]),
            orientation: Some(AXIAL),
            instance,
        }
    }

    #[test]
    fn an_axial_series_is_lps_flipped_into_ras() {
        // Stored in reverse: sorted by position, not by file order.
        let slices = [at(20.0, 3), at(10.0, 2), at(0.0, 1)];
        let a = arrange(&slices, [0.5, 0.25], Some(9.0)).unwrap();
        assert_eq!(a.order, vec![2, 1, 0]);
        assert!(a.resample.is_none() && a.notes.is_empty(), "{:?}", a.notes);
        // LPS (−100, −120, 0) is RAS (100, 120, 0); column index i runs to the patient's left (−x in RAS).
        let rows = a.geometry.rows();
        assert_eq!(rows[0], [-0.25, 0.0, 0.0, 100.0]);
        assert_eq!(rows[1], [0.0, -0.5, 0.0, 120.0]);
        assert_eq!(rows[2], [0.0, 0.0, 10.0, 0.0]);
        assert_eq!(a.geometry.axcodes(), Some(['L', 'P', 'S']));
    }

    #[test]
    fn gantry_tilt_is_a_shear_and_uneven_spacing_is_resampled() {
        let tilted: Vec<Placed> = (0..4)
            .map(|k| Placed {
                position: Some([0.0, 2.0 * k as f64, 5.0 * k as f64]),
                ..at(0.0, k)
            })
            .collect();
        let a = arrange(&tilted, [1.0, 1.0], None).unwrap();
        assert!(a.notes.iter().any(|n| n.contains("gantry tilt")), "{:?}", a.notes);
        assert!((a.geometry.shear_deg() - (2.0f64 / 5.0).atan().to_degrees()).abs() < 1e-9);

        let uneven = [at(0.0, 1), at(2.0, 2), at(5.0, 3), at(6.0, 4)];
        let a = arrange(&uneven, [1.0, 1.0], None).unwrap();
        let r = a.resample.expect("resampled");
        assert_eq!(r.len(), 4);
        // Targets 0, 2, 4, 6 mm: slice 0, slice 1, two thirds from slice 1 to 2, slice 3.
        for (got, want) in r.iter().zip([0.0, 1.0, 1.0 + 2.0 / 3.0, 3.0]) {
            assert!((got - want).abs() < 1e-12, "{r:?}");
        }
        let data = VoxelData::U16(vec![0, 100, 400, 1000]);
        assert_eq!(
            resample_slices(&data, [1, 1, 4], &r),
            VoxelData::U16(vec![0, 100, 300, 1000])
        );
    }

    #[test]
    fn impossible_stacks_are_refused() {
        assert!(arrange(&[at(0.0, 1), at(0.0, 2)], [1.0, 1.0], None).is_err());
        let mut other = at(5.0, 2);
        other.orientation = Some([0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        assert!(arrange(&[at(0.0, 1), other], [1.0, 1.0], None).is_err());
        let mut bad = at(0.0, 1);
        bad.orientation = Some([1.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
        assert!(arrange(&[bad], [1.0, 1.0], None).is_err());
    }
}
