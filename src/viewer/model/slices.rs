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
    /// The ruler tool and the line it measures.
    pub ruler: Ruler,
}

/// The ruler (3D Slicer's line markup): with the tool on (M), a left click in a slice view places one end and the
/// next click the other; the length is in millimetres of the world (the volume's spacing and affine).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Ruler {
    /// Left clicks in the slice views place ruler ends instead of moving the crosshair.
    pub active: bool,
    pub line: Option<RulerLine>,
    /// Every line finished on this volume, to save as CSV or JSON (the panel's Measurements).
    pub measured: Vec<super::measurements::Measurement>,
}

/// A ruler line in one slice view, its ends in continuous voxel index coordinates (as the crosshair: it stays
/// on the same anatomy whether the view is in patient space or voxel axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RulerLine {
    pub view: SliceView,
    pub start: DVec3,
    /// `None` while only the first end is placed.
    pub end: Option<DVec3>,
}

impl Ruler {
    pub fn toggle_tool(&mut self) {
        self.active = !self.active;
    }

    pub fn clear(&mut self) {
        self.line = None;
    }

    /// A click at voxel index point `at` in `view`: the first end of a new line, or the second end of the line
    /// begun in this view. Returns the finished line.
    pub fn place(&mut self, view: SliceView, at: DVec3) -> Option<RulerLine> {
        match &mut self.line {
            Some(line) if line.view == view && line.end.is_none() => {
                line.end = Some(at);
                Some(*line)
            }
            _ => {
                self.line = Some(RulerLine {
                    view,
                    start: at,
                    end: None,
                });
                None
            }
        }
    }
}

impl RulerLine {
    /// The finished line's length in world millimetres, through `mm_from_index` (the volume's affine).
    pub fn length_mm(&self, mm_from_index: DMat4) -> Option<f64> {
        self.end.map(|end| distance_mm(mm_from_index, self.start, end))
    }
}

/// The distance in millimetres between two voxel index points, through `mm_from_index`: with anisotropic
/// spacing (or a sheared affine) a voxel step along each axis is a different length.
pub fn distance_mm(mm_from_index: DMat4, a: DVec3, b: DVec3) -> f64 {
    mm_from_index
        .transform_point3(a)
        .distance(mm_from_index.transform_point3(b))
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
    /// [`LayerList::generation`](super::layers::LayerList) when it was made: the layers drawn over it.
    pub layers: u64,
}

/// What the slice views show: the volume (none while loading) and the layers over it.
#[derive(Clone, Copy)]
pub struct SliceData<'a> {
    pub volume: Option<&'a crate::volume::Volume>,
    pub layers: &'a crate::scene::layer_set::Layers,
}

/// What one slice image is resampled from: the volume, and the layers with their looks.
#[derive(Clone, Copy)]
pub struct SliceSource<'a> {
    pub volume: &'a crate::volume::Volume,
    pub layers: &'a crate::scene::layer_set::Layers,
    pub styles: &'a [crate::scene::layers::LayerStyle],
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
        self.ruler.line = None;
        self.ruler.measured.clear();
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

/// A window/level preset of the slice views, in Hounsfield units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WlPreset {
    pub name: &'static str,
    /// Its name in the tests' widget log (`ui rect wl-…`).
    pub id: &'static str,
    pub wl: WindowLevel,
}

const fn preset(name: &'static str, id: &'static str, window: f64, level: f64) -> WlPreset {
    WlPreset {
        name,
        id,
        wl: WindowLevel { window, level },
    }
}

/// The CT presets, with 3D Slicer's values (its Volumes module's CT-Brain, CT-Bone, CT-Lung and CT-Abdomen), so
/// the same names show the same images here: the textbook values (brain W80/L40, bone W1800/L400, lung
/// W1500/L−600, abdomen W400/L40) differ a little.
pub const CT_PRESETS: [WlPreset; 4] = [
    preset("Brain", "wl-brain", 100.0, 50.0),
    preset("Bone", "wl-bone", 1000.0, 400.0),
    preset("Lung", "wl-lung", 1400.0, -500.0),
    preset("Abdomen", "wl-abdomen", 350.0, 40.0),
];

/// Whether the CT presets fit the shown volume's values.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PresetFit {
    /// A CT (by its modality, or by values that look like Hounsfield units): offered as they are.
    Hounsfield,
    /// Nothing says what the values are: offered, labelled as assuming HU.
    Unknown,
    /// Another modality: its values are not HU, so the presets are disabled with this note.
    NotHounsfield(String),
}

/// What the presets mean for a volume of `modality` (as its file says) whose values' unit is `unit` ("HU" when
/// its values look like CT's).
pub fn preset_fit(modality: Option<&str>, unit: &str) -> PresetFit {
    match modality {
        Some("CT") => PresetFit::Hounsfield,
        Some(other) => PresetFit::NotHounsfield(format!("{other} values are not Hounsfield units")),
        None if unit == "HU" => PresetFit::Hounsfield,
        None => PresetFit::Unknown,
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
    fn ct_presets_are_offered_by_modality() {
        assert_eq!(preset_fit(Some("CT"), ""), PresetFit::Hounsfield);
        assert_eq!(preset_fit(None, "HU"), PresetFit::Hounsfield);
        assert_eq!(preset_fit(None, ""), PresetFit::Unknown);
        assert!(matches!(preset_fit(Some("MR"), ""), PresetFit::NotHounsfield(n) if n.starts_with("MR")));
        let bone = CT_PRESETS.iter().find(|p| p.name == "Bone").unwrap();
        assert_eq!((bone.wl.window, bone.wl.level), (1000.0, 400.0), "3D Slicer's CT-Bone");
    }

    #[test]
    fn the_ruler_measures_world_millimetres_with_anisotropic_spacing() {
        // Spacing 0.5 × 2 × 3 mm: 4 voxels along i and 3 along j are 2 mm and 6 mm.
        let mm = DMat4::from_scale(DVec3::new(0.5, 2.0, 3.0)) * DMat4::from_translation(DVec3::splat(7.0));
        let d = distance_mm(mm, DVec3::new(1.0, 2.0, 5.0), DVec3::new(5.0, 5.0, 5.0));
        assert!((d - 40f64.sqrt()).abs() < 1e-12, "{d}");
        // Along k only: 2 slices are 6 mm.
        assert!((distance_mm(mm, DVec3::ZERO, DVec3::new(0.0, 0.0, 2.0)) - 6.0).abs() < 1e-12);
        let mut ruler = Ruler::default();
        assert_eq!(ruler.place(SliceView::Axial, DVec3::new(1.0, 2.0, 5.0)), None);
        let line = ruler
            .place(SliceView::Axial, DVec3::new(5.0, 5.0, 5.0))
            .expect("two ends");
        assert!((line.length_mm(mm).unwrap() - 40f64.sqrt()).abs() < 1e-12);
        // A third click starts a new line; one in another view does too.
        assert_eq!(ruler.place(SliceView::Axial, DVec3::ZERO), None);
        assert_eq!(ruler.place(SliceView::Coronal, DVec3::ONE), None);
        assert_eq!(ruler.line.unwrap().view, SliceView::Coronal);
        ruler.clear();
        assert_eq!(ruler.line, None);
    }

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
