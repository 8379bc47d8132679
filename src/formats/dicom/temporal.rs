//! A DICOM series at several times (TemporalPositionIdentifier: cine MR, perfusion, 4-D CT): each temporal
//! position is placed like a series of its own, every position must share one grid, and the volumes become the
//! time steps of one volume.

use super::pixels::load_planned;
use super::{plan, Plan, Slice};
use crate::formats::decode::Progress;
use crate::formats::format::header_error;
use crate::volume::{check_dims, Volume, VolumeError, VoxelData};
use std::path::PathBuf;

/// Loads `slices` (one series) as one time step per entry of `times` (sorted, distinct).
pub(super) fn load_steps(
    slices: Vec<Slice>,
    times: &[i64],
    files: &[PathBuf],
    name: String,
    label: &str,
    mut notes: Vec<String>,
    progress: &mut Progress,
) -> Result<Volume, VolumeError> {
    let groups: Vec<Vec<Slice>> = times
        .iter()
        .map(|&t| slices.iter().filter(|s| s.temporal == Some(t)).cloned().collect())
        .collect();
    let plans = groups
        .into_iter()
        .map(|g| plan(g, label))
        .collect::<Result<Vec<Plan>, VolumeError>>()?;
    let first = &plans[0];
    let step_bytes = check_dims(first.dims)? * first.voxel_type.size() as u64;
    crate::volume::time::check_series_memory(label, plans.len() as u32, step_bytes)?;
    for (p, t) in plans.iter().zip(times) {
        let same_place = p
            .geometry
            .rows()
            .iter()
            .flatten()
            .zip(first.geometry.rows().iter().flatten())
            .all(|(a, b)| (a - b).abs() < 1e-3);
        if p.dims != first.dims || p.voxel_type != first.voxel_type || p.scaling != first.scaling || !same_place {
            return Err(header_error(
                label,
                format!(
                    "temporal position {t} has {}x{}x{} slices placed differently from position {}; the time steps \
                     of a series must share one grid",
                    p.dims[0], p.dims[1], p.dims[2], times[0]
                ),
            ));
        }
    }
    notes.extend(plans[0].notes.iter().cloned());
    notes.push(format!(
        "{} temporal positions (TemporalPositionIdentifier {} to {}) loaded as time steps",
        times.len(),
        times[0],
        times[times.len() - 1]
    ));
    let steps = plans.len();
    let mut volumes = Vec::with_capacity(steps);
    for (k, mut p) in plans.into_iter().enumerate() {
        p.notes = Vec::new();
        let mut part = |f: f32| progress.report((k as f64 + f64::from(f)) / steps as f64);
        let mut sub = Progress::new(Some(&mut part));
        volumes.push(load_planned(p, files, name.clone(), label, &mut sub)?);
    }
    let mut rest = volumes.split_off(1);
    let mut volume = volumes.pop().expect("two or more steps");
    volume.notes = notes;
    let later = rest
        .iter_mut()
        .map(|v| std::mem::replace(&mut v.data, VoxelData::U8(Vec::new())))
        .collect();
    volume.with_time_steps(later)
}
