//! Time series: a 4-D NIfTI (`dim[4]`), NRRD or MetaImage (the fourth, slowest axis) loads every step; the
//! volume shows one at a time. [`Volume::data`](super::Volume::data) always holds the step shown, so every
//! consumer (upload, reference, stats) sees an ordinary 3-D volume; the other steps wait in [`TimeSteps`].
//!
//! The value range (and so the transfer function's window) is the union over all steps, as in ParaView's
//! "over all timesteps" range and napari's contrast limits of a 4-D layer: a step does not brighten or darken as
//! the series plays.

use super::{compute_range_of, Volume, VolumeError, VoxelData};

/// The steps of a time series not in [`Volume::data`].
#[derive(Clone, Default)]
pub struct TimeSteps {
    /// One entry per step, `None` at the step shown (its voxels are in `Volume::data`). Empty: not a series.
    steps: Vec<Option<VoxelData>>,
    shown: usize,
}

impl std::fmt::Debug for TimeSteps {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "TimeSteps({} steps, showing {})",
            self.steps.len().max(1),
            self.shown
        )
    }
}

/// Bytes a series may take: at most half of the memory the system says is available (`MemAvailable`), so the
/// upload and the renderer's own buffers still fit. `None` where the system does not say (not Linux).
pub(crate) fn memory_budget() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024) / 2)
}

/// Refuses, before anything is read, a series whose steps together need more than [`memory_budget`].
pub(crate) fn check_series_memory(file: &str, steps: u32, step_bytes: u64) -> Result<(), VolumeError> {
    let total = step_bytes.saturating_mul(u64::from(steps));
    match memory_budget() {
        Some(budget) if steps > 1 && total > budget => Err(VolumeError::Header {
            file: file.to_string(),
            problem: format!(
                "{steps} time steps of {step_bytes} bytes need {} MiB, more than half of the {} MiB this machine \
                 has available; free memory or cut the series into smaller files",
                total >> 20,
                (budget * 2) >> 20
            ),
        }),
        _ => Ok(()),
    }
}

impl VoxelData {
    /// Cuts `steps` consecutive equal parts (the slowest axis of a 4-D file) into one `VoxelData` each.
    /// The data of `steps` components stored interleaved (component fastest, as a NRRD whose first axis is a
    /// list: a Slicer segmentation's layers), one `VoxelData` per component.
    pub(crate) fn deinterleave(self, steps: usize) -> Vec<VoxelData> {
        fn part<T: Copy>(v: &[T], steps: usize, wrap: fn(Vec<T>) -> VoxelData) -> Vec<VoxelData> {
            (0..steps)
                .map(|c| wrap(v.iter().skip(c).step_by(steps).copied().collect()))
                .collect()
        }
        match self {
            VoxelData::U8(v) => part(&v, steps.max(1), VoxelData::U8),
            VoxelData::U16(v) => part(&v, steps.max(1), VoxelData::U16),
            VoxelData::F32(v) => part(&v, steps.max(1), VoxelData::F32),
        }
    }

    pub(crate) fn split_steps(self, steps: usize) -> Vec<VoxelData> {
        fn cut<T: Clone>(mut v: Vec<T>, steps: usize, wrap: fn(Vec<T>) -> VoxelData) -> Vec<VoxelData> {
            let each = v.len() / steps.max(1);
            // Back to front, so each part is split off the end without copying the rest.
            let mut parts: Vec<VoxelData> = (1..steps).rev().map(|k| wrap(v.split_off(k * each))).collect();
            v.truncate(each);
            parts.push(wrap(v));
            parts.reverse();
            parts
        }
        match self {
            VoxelData::U8(v) => cut(v, steps, VoxelData::U8),
            VoxelData::U16(v) => cut(v, steps, VoxelData::U16),
            VoxelData::F32(v) => cut(v, steps, VoxelData::F32),
        }
    }
}

impl Volume {
    /// How many time steps the volume has (1 unless it is a series).
    pub fn timesteps(&self) -> u32 {
        self.time.steps.len().max(1) as u32
    }

    /// Every voxel's normalised value in every step (the shown step first, then the others in order): a series'
    /// histogram, like its range, covers the whole series, so an automatic transfer function suits every step.
    pub fn normalized_values(&self) -> impl Iterator<Item = f64> + '_ {
        std::iter::once(&self.data)
            .chain(self.time.steps.iter().flatten())
            .flat_map(move |data| {
                (0..data.len()).map(move |i| {
                    self.normalize_value(self.scaling.apply(super::stored_value(self.source_type, data, i)))
                })
            })
    }

    /// The step in [`Volume::data`].
    pub fn shown_step(&self) -> u32 {
        self.time.shown as u32
    }

    /// Adds `later` steps after the one in `data` (step 0). Each must match it in length and kind; the value
    /// ranges become the union over every step.
    pub fn with_time_steps(mut self, later: Vec<VoxelData>) -> Result<Volume, VolumeError> {
        if later.is_empty() {
            return Ok(self);
        }
        for step in &later {
            if step.len() != self.data.len() || step.kind() != self.data.kind() {
                return Err(VolumeError::DataLength {
                    dims: self.dims,
                    expected: self.data.len() as u64,
                    actual: step.len(),
                });
            }
        }
        let mut stored = compute_range_of(self.source_type, &self.data);
        for step in &later {
            if let Some([lo, hi]) = compute_range_of(self.source_type, step) {
                stored = Some(stored.map_or([lo, hi], |[a, b]| [a.min(lo), b.max(hi)]));
            }
        }
        self.stored_range = stored.unwrap_or([0.0, 0.0]);
        self.time = TimeSteps {
            steps: std::iter::once(None).chain(later.into_iter().map(Some)).collect(),
            shown: 0,
        };
        let scaling = self.scaling;
        self.with_scaling(scaling)
    }

    /// Puts step `t` into [`Volume::data`]; the ranges stay those of the whole series.
    pub fn show_step(&mut self, t: u32) -> Result<(), VolumeError> {
        let count = self.timesteps();
        if t >= count {
            return Err(VolumeError::Header {
                file: self.name.clone(),
                problem: format!(
                    "time step {t} does not exist: the volume has {count} (0 to {})",
                    count - 1
                ),
            });
        }
        let t = t as usize;
        if t == self.time.shown {
            return Ok(());
        }
        let next = self.time.steps[t]
            .take()
            .expect("only the shown step is out of the list");
        let previous = std::mem::replace(&mut self.data, next);
        self.time.steps[self.time.shown] = Some(previous);
        self.time.shown = t;
        Ok(())
    }

    /// The voxels of step `t` (the shown one included).
    pub fn step_data(&self, t: u32) -> Option<&VoxelData> {
        if t as usize == self.time.shown {
            return (t < self.timesteps()).then_some(&self.data);
        }
        self.time.steps.get(t as usize)?.as_ref()
    }

    /// Applies `f` (a resampling such as downsampling) to every step as a 3-D volume of its own and reassembles
    /// the series; the result keeps the shown step and the series' ranges.
    pub(crate) fn map_steps(mut self, f: impl Fn(Volume) -> Volume) -> Volume {
        if self.timesteps() == 1 {
            return f(self);
        }
        let shown = self.time.shown;
        let steps = std::mem::take(&mut self.time.steps);
        let (range, stored_range) = (self.range, self.stored_range);
        // The template carries everything but voxels, so cloning it per step copies no data.
        let mut shown_data = Some(std::mem::replace(&mut self.data, VoxelData::U8(Vec::new())));
        let template = self;
        let mut mapped: Vec<Volume> = Vec::with_capacity(steps.len());
        for step in steps {
            let data = step.or_else(|| shown_data.take()).expect("one shown step");
            mapped.push(f(Volume {
                data,
                ..template.clone()
            }));
        }
        let mut first = mapped.remove(shown);
        let mut all: Vec<Option<VoxelData>> = mapped.into_iter().map(|v| Some(v.data)).collect();
        all.insert(shown, None);
        first.time = TimeSteps { steps: all, shown };
        first.range = range;
        first.stored_range = stored_range;
        first
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{Scaling, VoxelType};

    fn series() -> Volume {
        let v = Volume::new("s", [2, 1, 1], [1.0; 3], VoxelType::U8, VoxelData::U8(vec![10, 20])).unwrap();
        v.with_time_steps(vec![VoxelData::U8(vec![5, 6]), VoxelData::U8(vec![30, 40])])
            .unwrap()
            .with_scaling(Scaling {
                slope: 2.0,
                intercept: 1.0,
            })
            .unwrap()
    }

    #[test]
    fn steps_are_shown_in_turn_with_the_series_range() {
        let mut v = series();
        assert_eq!(v.timesteps(), 3);
        assert_eq!((v.stored_range, v.range), ([5.0, 40.0], [11.0, 81.0]));
        v.show_step(2).unwrap();
        assert_eq!((v.shown_step(), v.value(1, 0, 0)), (2, 81.0));
        v.show_step(1).unwrap();
        assert_eq!(v.value(0, 0, 0), 11.0);
        assert_eq!(v.step_data(2), Some(&VoxelData::U8(vec![30, 40])));
        assert_eq!(v.step_data(1), Some(&VoxelData::U8(vec![5, 6])));
        v.show_step(0).unwrap();
        assert_eq!(v.value(1, 0, 0), 41.0);
        assert_eq!(v.range, [11.0, 81.0]);
        let e = v.show_step(3).unwrap_err().to_string();
        assert!(
            e.contains("time step 3 does not exist: the volume has 3 (0 to 2)"),
            "{e}"
        );
    }

    #[test]
    fn split_and_map_keep_every_step() {
        let parts = VoxelData::U16(vec![1, 2, 3, 4, 5, 6]).split_steps(3);
        assert_eq!(
            parts,
            vec![
                VoxelData::U16(vec![1, 2]),
                VoxelData::U16(vec![3, 4]),
                VoxelData::U16(vec![5, 6])
            ]
        );
        let mut v = series();
        v.show_step(1).unwrap();
        let v = v.map_steps(|mut s| {
            if let VoxelData::U8(d) = &mut s.data {
                d.reverse();
            }
            s
        });
        assert_eq!((v.timesteps(), v.shown_step()), (3, 1));
        assert_eq!(v.data, VoxelData::U8(vec![6, 5]));
        assert_eq!(v.step_data(0), Some(&VoxelData::U8(vec![20, 10])));
        assert_eq!(v.step_data(2), Some(&VoxelData::U8(vec![40, 30])));
        assert_eq!(v.stored_range, [5.0, 40.0]);
    }

    #[test]
    fn a_step_of_another_size_is_refused() {
        let v = Volume::new("s", [2, 1, 1], [1.0; 3], VoxelType::U8, VoxelData::U8(vec![1, 2])).unwrap();
        assert!(v.with_time_steps(vec![VoxelData::U8(vec![1])]).is_err());
    }
}
