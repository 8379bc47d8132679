//! The slice views' state (3D Slicer's "four-up": axial, sagittal and coronal beside the 3D view): the shared
//! crosshair, the slices' own window/level, the value under the cursor, and what each view's image shows.

use crate::scene::slice::{SliceFrame, SliceView, WindowLevel};
use glam::{DMat4, DVec3};

/// The value under the cursor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    pub view: SliceView,
    /// World millimetres (RAS for an anatomical volume).
    pub world: DVec3,
    /// The nearest voxel and its value in data units.
    pub voxel: [u32; 3],
    pub value: f64,
}

/// The slice views' state.
#[derive(Clone, Debug, Default)]
pub struct SliceViews {
    /// Four-up (three slices and the 3D view) instead of the 3D view alone (L, or the panel).
    pub shown: bool,
    /// The crosshair in continuous voxel index coordinates (so it stays on the same anatomy when the view
    /// switches between patient space and voxel axes).
    pub crosshair: DVec3,
    /// Window and level of the slices, in data units (apart from the 3D view's transfer function, as in Slicer).
    pub wl: Option<WindowLevel>,
    pub probe: Option<Probe>,
    /// Changes whenever the volume or its shown time step does: the images are made again.
    pub generation: u64,
}

/// What one slice view's image shows: it is resampled (`slice::render`) only when this changes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceImage {
    /// [`SliceViews::generation`] when it was made.
    pub generation: u64,
    pub frame: SliceFrame,
    /// Voxel index to the slices' millimetres.
    pub mm_from_index: DMat4,
    pub wl: WindowLevel,
    pub voxel_axes: bool,
}

impl SliceImage {
    /// Which of the three views (and so which cached image) this is: its normal's axis.
    pub fn slot(&self) -> usize {
        self.frame.view.normal_axis()
    }
}

impl SliceViews {
    /// A new volume (or time step): the crosshair at its centre, window/level from its histogram (the 0.5th to
    /// 99.5th percentile: an outlier voxel does not wash out the image).
    pub fn reset(&mut self, dims: [u32; 3], histogram: &[u64], range: [f64; 2]) {
        self.crosshair = DVec3::new(
            f64::from(dims[0]) - 1.0,
            f64::from(dims[1]) - 1.0,
            f64::from(dims[2]) - 1.0,
        ) * 0.5;
        self.wl = Some(percentile_window(histogram, range));
        self.probe = None;
        self.generation += 1;
    }

    /// The slices' window/level: their own, or the whole value range before they have one.
    pub fn window_level(&self, range: [f64; 2]) -> WindowLevel {
        self.wl.unwrap_or(WindowLevel {
            window: range[1] - range[0],
            level: (range[0] + range[1]) / 2.0,
        })
    }
}

/// Window/level spanning the 0.5th to 99.5th percentile of a histogram over `range` (the whole range when empty).
pub fn percentile_window(histogram: &[u64], range: [f64; 2]) -> WindowLevel {
    let total: u64 = histogram.iter().sum();
    let at = |q: f64| {
        let mut seen = 0u64;
        for (i, &c) in histogram.iter().enumerate() {
            seen += c;
            if seen as f64 >= q * total as f64 {
                return (i as f64 + 0.5) / histogram.len() as f64;
            }
        }
        1.0
    };
    let (lo, hi) = if total == 0 { (0.0, 1.0) } else { (at(0.005), at(0.995)) };
    let (lo, hi) = if hi > lo { (lo, hi) } else { (0.0, 1.0) };
    let data = |u: f64| range[0] + u * (range[1] - range[0]);
    let (a, b) = (data(lo), data(hi));
    WindowLevel {
        window: (b - a).abs().max(1e-9),
        level: (a + b) / 2.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_ignore_outliers_and_map_to_data_units() {
        // 1000 voxels in bins 10..20, one outlier in bin 255.
        let mut h = vec![0u64; 256];
        h[10..20].fill(100);
        h[255] = 1;
        let wl = percentile_window(&h, [-1000.0, 1560.0]);
        let (lo, hi) = (wl.level - wl.window / 2.0, wl.level + wl.window / 2.0);
        // Bin b spans −1000 + 10·b .. +10: the window is inside bins 10..20, far below the outlier.
        assert!(
            (-900.0..=-880.0).contains(&lo) && (-810.0..=-790.0).contains(&hi),
            "{lo} {hi}"
        );
        assert_eq!(
            percentile_window(&[], [0.0, 2.0]),
            WindowLevel {
                window: 2.0,
                level: 1.0
            }
        );
    }
}
