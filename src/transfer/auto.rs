//! The transfer function a volume gets when it opens ("auto (by modality)"): CT in Hounsfield units gets the
//! `ct-bone` preset; anything else (MR, microscopy, simulation output) a grey opacity ramp placed by percentiles
//! of its non-background histogram. Pure code.
//!
//! Which volumes are CT:
//! - a modality tag says so (DICOM's Modality (0008,0060) "CT"); any other tag ("MR", "PT", ...) means not CT;
//! - without a tag, the values must look like Hounsfield units: integer data (after the file's rescale) whose
//!   minimum lies in [−3072, −900] (air is −1000; scanners pad outside the field of view with −1024, −2048 or
//!   −3024) and whose maximum is at least 1000 (bone reaches 1000–3000 HU; an MR or a float map that happens to
//!   dip to −1000 rarely also spans 2000+ units).
//!
//! Everything else: a histogram of the values (any bin count) without its background, the voxels at or below
//! FSL BET's threshold `p2 + 0.1·(p98 − p2)` (the percentiles over all voxels; MR background is noise near the
//! minimum), or up to the most common value where a quarter of the voxels hold it above that threshold (a
//! statistical map's zeros). Over the span from that threshold to the 99th percentile of the rest, opacity and grey follow
//! [`MR_SHAPE`], the shape of 3D Slicer's MR-Default preset (its points 20, 40, 120 and 220 at 0, 10, 50 and 100%
//! of the span; opacity 0, 0.15, 0.3, 0.375), rising to [`MR_TOP`] at the range's top. Slicer's points are fixed
//! values for one scanner's range; placed by percentiles they fit any MR, microscopy or simulation range. The
//! head's surface shows as Slicer shows it, where the translucent ramp this replaced (0.08 at the 99th
//! percentile) showed a grey fog. Grey because MR intensities carry no physical scale a colormap would suggest
//! (napari and Slicer's slice views open MR in grey too).

use crate::transfer::function::{TfUnits, TransferFunction};
use crate::transfer::Colormap;
use crate::volume::{Volume, VoxelType};

/// Opacity per voxel-length step of an OME-Zarr channel's ramp at the top of its window (many channels add up).
pub const RAMP_ALPHA: f32 = 0.08;
/// The MR look, as [fraction of the span from the background's end to the 99th percentile, opacity per
/// voxel-length step, grey]: Slicer's MR-Default opacities in grey.
pub const MR_SHAPE: [[f32; 3]; 4] = [[0.0, 0.0, 0.2], [0.1, 0.15, 0.4], [0.5, 0.3, 0.7], [1.0, 0.375, 0.9]];
/// Opacity and grey at the top of the range, above the span (Slicer's 0.5 at 1024).
pub const MR_TOP: [f32; 2] = [0.5, 1.0];
/// Percentile of the non-background values where the span ends.
pub const SPAN_PERCENTILE: f64 = 0.99;
/// The preset CT volumes get.
pub const CT_PRESET: &str = "ct-bone";

/// What kind of data a volume holds, as far as choosing its transfer function goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataKind {
    /// Computed tomography: values in Hounsfield units.
    Ct,
    /// Anything else (MR, PET, microscopy, simulations): values in arbitrary units.
    Other,
}

impl DataKind {
    /// The presets that suit data of this kind, as the viewer offers them: the CT presets (in Hounsfield units,
    /// which nothing else has) for CT only, the MR one for the rest, and the generic ones always.
    pub fn presets(self) -> Vec<&'static str> {
        let other = match self {
            DataKind::Ct => "mr-",
            DataKind::Other => "ct-",
        };
        crate::transfer::function::PRESET_NAMES
            .iter()
            .copied()
            .filter(|name| !name.starts_with(other))
            .collect()
    }

    /// The unit of the values, for axis and colour-bar labels.
    pub fn unit(self) -> Option<&'static str> {
        match self {
            DataKind::Ct => Some("HU"),
            DataKind::Other => None,
        }
    }
}

/// The facts about a volume the choice depends on (taken from a [`Volume`] by [`VolumeFacts::of`], or made up
/// in tests).
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeFacts {
    /// Data range after the file's rescale.
    pub range: [f64; 2],
    /// Whether the values are integers (integer voxels under an integer rescale).
    pub integer: bool,
    /// The modality the file names, upper case ("CT", "MR"), if any.
    pub modality: Option<String>,
    /// The display window (data units) and colour of the loaded channel (OME-Zarr omero; a TIFF's by ImageJ's
    /// order over the data's range), if it is one of several.
    pub display: Option<([f64; 2], [u8; 3])>,
}

impl VolumeFacts {
    pub fn of(volume: &Volume) -> VolumeFacts {
        let integer_type = !matches!(volume.source_type, VoxelType::F32 | VoxelType::F64);
        let s = volume.scaling;
        let integer_scale = s.slope.fract() == 0.0 && s.intercept.fract() == 0.0;
        VolumeFacts {
            range: volume.range,
            integer: integer_type && integer_scale,
            modality: volume.modality.as_ref().map(|m| m.trim().to_ascii_uppercase()),
            // A channel without a window of its own (a TIFF's) spans the data's range.
            display: volume.channels.iter().find(|c| c.loaded).map(|c| {
                let own = c.window[0] < c.window[1];
                (if own { c.window } else { volume.range }, c.color)
            }),
        }
    }

    /// CT or not, by the rule in the module's docs.
    pub fn kind(&self) -> DataKind {
        match self.modality.as_deref() {
            Some("CT") => DataKind::Ct,
            Some(_) => DataKind::Other,
            None => {
                let [min, max] = self.range;
                if self.integer && (-3072.0..=-900.0).contains(&min) && max >= 1000.0 {
                    DataKind::Ct
                } else {
                    DataKind::Other
                }
            }
        }
    }
}

/// Counts of normalised values in `bins` equal bins over [0, 1], every voxel of every time step (NaN skipped):
/// a series gets one transfer function that suits all its steps, as it has one range.
pub fn value_histogram(volume: &Volume, bins: usize) -> Vec<u64> {
    use crate::volume::VoxelData;
    use rayon::prelude::*;
    let bins = bins.max(1);
    let bin_of = |v: f64| ((v.clamp(0.0, 1.0) * bins as f64) as usize).min(bins - 1);
    let add = |a: Vec<u64>, b: Vec<u64>| a.into_iter().zip(b).map(|(x, y)| x + y).collect::<Vec<u64>>();
    // 8- and 16-bit elements are counted by element on every core, then each element value is normalised once:
    // the same counts as normalising every voxel, at memory speed.
    // `chunk` counts one chunk's elements into a table of `size`.
    fn counts<T: Copy + Into<usize> + Sync>(data: &[T], size: usize, chunk: fn(&[T], usize) -> Vec<u64>) -> Vec<u64> {
        data.par_chunks(1 << 20).map(|c| chunk(c, size)).reduce(
            || vec![0u64; size],
            |a, b| a.into_iter().zip(b).map(|(x, y)| x + y).collect(),
        )
    }
    // Four tables taking every fourth element: a run of one value (a background) does not wait on its own last
    // increment. Twice as fast for 8-bit data (1 GiB: 0.15 s against 0.30 s on 2 cores); no faster for 16-bit
    // data, whose four tables of 65536 leave the L1 cache.
    fn counts_plain<T: Copy + Into<usize>>(c: &[T], size: usize) -> Vec<u64> {
        let mut n = vec![0u64; size];
        c.iter().for_each(|&e| n[e.into()] += 1);
        n
    }
    fn counts_interleaved<T: Copy + Into<usize>>(c: &[T], size: usize) -> Vec<u64> {
        let mut n = vec![0u32; 4 * size];
        let (a, rest) = n.split_at_mut(size);
        let (b, rest) = rest.split_at_mut(size);
        let (d, e) = rest.split_at_mut(size);
        let mut quads = c.chunks_exact(4);
        for q in &mut quads {
            a[q[0].into()] += 1;
            b[q[1].into()] += 1;
            d[q[2].into()] += 1;
            e[q[3].into()] += 1;
        }
        for &v in quads.remainder() {
            a[v.into()] += 1;
        }
        (0..size)
            .map(|i| u64::from(a[i]) + u64::from(b[i]) + u64::from(d[i]) + u64::from(e[i]))
            .collect()
    }
    let mut h = vec![0u64; bins];
    for t in 0..volume.timesteps() {
        let Some(data) = volume.step_data(t) else { continue };
        let by_element = match data {
            VoxelData::U8(d) => counts(d, 256, counts_interleaved),
            VoxelData::U16(d) => counts(d, 65536, counts_plain),
            VoxelData::F32(d) => {
                let part = d
                    .par_chunks(1 << 16)
                    .map(|c| {
                        let mut n = vec![0u64; bins];
                        for &e in c {
                            let v = volume.normalize_element(f64::from(e));
                            if v.is_finite() {
                                n[bin_of(v)] += 1;
                            }
                        }
                        n
                    })
                    .reduce(|| vec![0u64; bins], add);
                h = add(h, part);
                continue;
            }
        };
        for (e, &n) in by_element.iter().enumerate().filter(|(_, &n)| n > 0) {
            let v = volume.normalize_element(e as f64);
            if v.is_finite() {
                h[bin_of(v)] += n;
            }
        }
    }
    h
}

/// Counts of normalised values in `bins` equal bins over [0, 1] (NaN skipped).
pub fn histogram(values: impl Iterator<Item = f64>, bins: usize) -> Vec<u64> {
    let bins = bins.max(1);
    let mut h = vec![0u64; bins];
    for v in values.filter(|v| v.is_finite()) {
        h[((v.clamp(0.0, 1.0) * bins as f64) as usize).min(bins - 1)] += 1;
    }
    h
}

/// The normalised value below which fraction `p` of the counts in `histogram[from..]` lie, interpolated
/// linearly inside the bin that holds it (bins spread evenly over [0, 1]). 0 for an empty histogram.
pub fn percentile(histogram: &[u64], from: usize, p: f64) -> f64 {
    let n = histogram.len().max(1) as f64;
    let total: u64 = histogram.iter().skip(from).sum();
    if total == 0 {
        return from as f64 / n;
    }
    let target = p.clamp(0.0, 1.0) * total as f64;
    let mut below = 0.0;
    for (i, &c) in histogram.iter().enumerate().skip(from) {
        let c = c as f64;
        if c > 0.0 && below + c >= target {
            return (i as f64 + (target - below) / c) / n;
        }
        below += c;
    }
    1.0
}

/// The first bin above the background: FSL BET's threshold `p2 + 0.1·(p98 − p2)` over all voxels, or past the
/// most common bin where that holds a quarter of the voxels above the threshold (a statistical map's 0 outside
/// the brain, in the middle of its range: the map then shows its positive values, as FSLeyes and MRIcroGL show
/// an overlay).
pub fn background_end(histogram: &[u64]) -> usize {
    let p2 = percentile(histogram, 0, 0.02);
    let p98 = percentile(histogram, 0, 0.98);
    let t = p2 + 0.1 * (p98 - p2);
    let last = histogram.len().saturating_sub(1);
    let bin = ((t * histogram.len() as f64).ceil() as usize).min(last);
    let total: u64 = histogram.iter().sum();
    match histogram
        .iter()
        .enumerate()
        .max_by_key(|&(i, &n)| (n, std::cmp::Reverse(i)))
    {
        Some((mode, &n)) if mode >= bin && n.saturating_mul(4) >= total && total > 0 => (mode + 1).min(last),
        _ => bin,
    }
}

/// The transfer function a volume with `facts` and value `histogram` (normalised values, any bin count) opens
/// with; see the module's docs. Always valid.
pub fn auto_transfer_function(facts: &VolumeFacts, histogram: &[u64]) -> TransferFunction {
    if facts.kind() == DataKind::Ct {
        let mut tf = TransferFunction::preset(CT_PRESET).unwrap_or_else(|_| ramp(facts, [0.5, 1.0]));
        tf.name = format!("auto: {CT_PRESET}");
        return tf;
    }
    if let Some((window, color)) = facts
        .display
        .filter(|(w, _)| w[0].is_finite() && w[1].is_finite() && w[1] > w[0])
    {
        return channel_ramp(window, color);
    }
    let from = background_end(histogram);
    let lo = from as f64 / histogram.len().max(1) as f64;
    let hi = percentile(histogram, from, SPAN_PERCENTILE);
    ramp(facts, [lo, hi])
}

/// [`MR_SHAPE`] over the span from normalised `lo` to `hi`, then [`MR_TOP`] at the range's top, in data units.
fn ramp(facts: &VolumeFacts, [lo, hi]: [f64; 2]) -> TransferFunction {
    let [min, max] = facts.range;
    let to_data = |u: f64| (min + u.clamp(0.0, 1.0) * (max - min)) as f32;
    let (mut a, mut b) = (to_data(lo), to_data(hi));
    if b <= a {
        // A volume of (nearly) one value: the shape over its whole range still shows it.
        (a, b) = (min as f32, max as f32);
    }
    let mut colors: Vec<[f32; 4]> = Vec::with_capacity(MR_SHAPE.len() + 1);
    let mut opacity: Vec<[f32; 2]> = Vec::with_capacity(MR_SHAPE.len() + 1);
    for [f, alpha, grey] in MR_SHAPE {
        let x = a + f * (b - a);
        colors.push([x, grey, grey, grey]);
        opacity.push([x, alpha]);
    }
    if (max as f32) > b {
        let [alpha, grey] = MR_TOP;
        colors.push([max as f32, grey, grey, grey]);
        opacity.push([max as f32, alpha]);
    }
    TransferFunction {
        name: "auto: percentile ramp".into(),
        units: TfUnits::Data,
        colors,
        colormap: Colormap::Grayscale,
        opacity,
    }
}

/// A channel's own display (OME-Zarr omero): opacity rising over its window, from black to its colour, as
/// napari and OMERO show a channel (its window is its contrast limits).
fn channel_ramp([a, b]: [f64; 2], [r, g, bl]: [u8; 3]) -> TransferFunction {
    let (a, b) = (a as f32, b as f32);
    let c = |v: u8| f32::from(v) / 255.0;
    TransferFunction {
        name: "auto: channel window".into(),
        units: TfUnits::Data,
        colors: vec![[a, 0.0, 0.0, 0.0], [b, c(r), c(g), c(bl)]],
        colormap: Colormap::Grayscale,
        opacity: vec![[a, 0.0], [b, RAMP_ALPHA]],
    }
}

/// The bins of the histogram the automatic transfer function reads (its percentiles' resolution).
pub const AUTO_BINS: usize = 1024;

/// [`auto_transfer_function`] for a loaded volume (its histogram computed here, [`AUTO_BINS`] bins).
pub fn auto_for_volume(volume: &Volume) -> TransferFunction {
    auto_transfer_function(&VolumeFacts::of(volume), &value_histogram(volume, AUTO_BINS))
}

#[cfg(test)]
mod tests {
    #[test]
    fn presets_follow_the_kind_of_data() {
        assert_eq!(
            DataKind::Ct.presets(),
            ["ct-bone", "ct-soft-tissue", "ct-lung", "qt-example"]
        );
        assert_eq!(DataKind::Other.presets(), ["mr-default", "qt-example"]);
    }

    use super::*;
    use crate::volume::VoxelData;

    fn facts(range: [f64; 2], integer: bool, modality: Option<&str>) -> VolumeFacts {
        VolumeFacts {
            range,
            integer,
            modality: modality.map(str::to_string),
            display: None,
        }
    }

    #[test]
    fn a_channel_window_seeds_the_ramp() {
        let mut f = facts([0.0, 1000.0], true, None);
        f.display = Some(([50.0, 240.0], [0, 255, 0]));
        let tf = auto_transfer_function(&f, &[1; 16]);
        assert_eq!(tf.opacity, vec![[50.0, 0.0], [240.0, RAMP_ALPHA]]);
        assert_eq!(tf.colors[1], [240.0, 0.0, 1.0, 0.0]);
        // A window that is empty is no window.
        f.display = Some(([5.0, 5.0], [0, 255, 0]));
        assert_eq!(auto_transfer_function(&f, &[1; 16]).name, "auto: percentile ramp");
    }

    #[test]
    fn histogram_bins_values_and_skips_nan() {
        let h = histogram([0.0, 0.1, 0.99, 1.0, f64::NAN].into_iter(), 4);
        assert_eq!(h, vec![2, 0, 0, 2]);
    }

    #[test]
    fn ct_by_tag_or_by_hounsfield_range() {
        assert_eq!(facts([-1024.0, 2986.0], true, None).kind(), DataKind::Ct);
        assert_eq!(facts([-1000.0, 1500.0], true, None).kind(), DataKind::Ct);
        assert_eq!(facts([-3024.0, 3071.0], true, None).kind(), DataKind::Ct);
        assert_eq!(
            facts([-1024.0, 2986.0], true, Some("MR")).kind(),
            DataKind::Other,
            "the tag wins"
        );
        assert_eq!(
            facts([0.0, 4095.0], true, Some("CT")).kind(),
            DataKind::Ct,
            "the tag wins"
        );
        assert_eq!(
            facts([0.0, 4095.0], true, None).kind(),
            DataKind::Other,
            "unsigned: MR-like"
        );
        assert_eq!(facts([-1024.0, 400.0], true, None).kind(), DataKind::Other, "no bone");
        assert_eq!(facts([-117.8, 2121.1], false, None).kind(), DataKind::Other);
        assert_eq!(
            facts([-1024.0, 2986.0], false, None).kind(),
            DataKind::Other,
            "float maps are not HU"
        );
        assert_eq!(facts([-32768.0, 32767.0], true, None).kind(), DataKind::Other);
        assert_eq!(DataKind::Ct.unit(), Some("HU"));
    }

    #[test]
    fn percentiles_interpolate_inside_bins() {
        let h = [0, 10, 10, 0];
        assert!((percentile(&h, 0, 0.5) - 0.5).abs() < 1e-12);
        assert!((percentile(&h, 0, 0.25) - 0.375).abs() < 1e-12);
        assert!((percentile(&h, 2, 0.5) - 0.625).abs() < 1e-12, "from bin 2 on");
        assert_eq!(percentile(&[0, 0], 0, 0.5), 0.0);
    }

    #[test]
    fn synthetic_mr_gets_the_mr_shape_over_its_foreground() {
        // 60% background noise in the lowest 5% of the range, tissue spread evenly over 0.3..0.7, a few bright
        // voxels at 0.95.
        let mut h = vec![0u64; 100];
        for c in h.iter_mut().take(5) {
            *c = 1200;
        }
        for c in h.iter_mut().take(70).skip(30) {
            *c = 95;
        }
        h[95] = 200;
        let f = facts([0.0, 1000.0], true, None);
        let tf = auto_transfer_function(&f, &h);
        tf.validate().unwrap();
        assert_eq!(tf.units, TfUnits::Data);
        // Background: p2 = 200/1200 of bin 0, p98 = the end of bin 69; t = 0.00167 + 0.1 * (0.7 - 0.00167) lies in
        // bin 7, so the span starts at bin 8 (80). p99 = 3960 counts of the foreground's 4000: inside the bright
        // bin, 0.95 + 160/200/100 (958).
        let (a, b) = (80.0, 958.0);
        let want: Vec<[f32; 2]> = MR_SHAPE
            .iter()
            .map(|&[f, alpha, _]| [a + f * (b - a), alpha])
            .chain([[1000.0, MR_TOP[0]]])
            .collect();
        assert_eq!(tf.opacity.len(), want.len());
        for (got, want) in tf.opacity.iter().zip(&want) {
            assert!(
                (got[0] - want[0]).abs() < 1.0 && got[1] == want[1],
                "{got:?} against {want:?}"
            );
        }
        assert_eq!(tf.colors[0][1..], [0.2, 0.2, 0.2]);
        assert_eq!(tf.colors[4], [1000.0, 1.0, 1.0, 1.0]);
        // Slicer's look, not a fog: tissue at the span's middle takes 0.3 per voxel, so ten voxels of it hide what
        // lies behind (97%); the translucent ramp this replaced let 55% through.
        let mid = tf.opacity[2];
        let through = (1.0 - f64::from(mid[1])).powi(10);
        assert!(
            through < 0.05,
            "{:.0}% through ten voxels at {}",
            through * 100.0,
            mid[0]
        );
    }

    #[test]
    fn a_statistical_map_shows_what_lies_above_its_background_of_zeros() {
        // 70% zeros in the middle of the range (bin 50 of 100), the rest spread over both signs.
        let mut h = vec![10u64; 100];
        h[50] = 2310;
        assert_eq!(background_end(&h), 51, "past the zeros");
        // An MR's background of noise near the minimum stays the threshold's.
        let mut mr = vec![0u64; 100];
        mr[0] = 6000;
        for c in mr.iter_mut().take(70).skip(30) {
            *c = 100;
        }
        assert_eq!(background_end(&mr), 7, "p2 + 0.1·(p98 − p2) = 0.0003 + 0.068: bin 7");
    }

    #[test]
    fn ct_volume_gets_the_ct_preset_and_a_flat_volume_a_valid_ramp() {
        let data: Vec<u16> = (0..64u32).map(|i| (32768 - 1024 + i * 60) as u16).collect();
        let v = Volume::new("ct", [4, 4, 4], [1.0; 3], VoxelType::I16, VoxelData::U16(data)).unwrap();
        let tf = auto_for_volume(&v);
        assert_eq!(tf.opacity, TransferFunction::preset(CT_PRESET).unwrap().opacity);
        assert!(tf.name.contains(CT_PRESET));
        let mut mr = v.clone();
        mr.modality = Some("mr".into());
        assert!(auto_for_volume(&mr).name.contains("ramp"), "a tag other than CT: ramp");

        let flat = Volume::new("flat", [2, 2, 2], [1.0; 3], VoxelType::U8, VoxelData::U8(vec![7; 8])).unwrap();
        let tf = auto_for_volume(&flat);
        tf.validate().unwrap();
    }

    /// The per-element counting gives exactly the histogram of every voxel's normalised value: 8-bit, signed
    /// 16-bit with a negative rescale, float with NaN, and a time series.
    #[test]
    fn value_histogram_counts_every_voxel_by_its_normalised_value() {
        use crate::volume::{Scaling, VoxelType};
        let u8v = Volume::new(
            "a",
            [4, 3, 2],
            [1.0; 3],
            VoxelType::U8,
            VoxelData::U8((0..24).map(|i| i * 9).collect()),
        )
        .unwrap();
        let i16v = Volume::new(
            "b",
            [5, 2, 1],
            [1.0; 3],
            VoxelType::I16,
            VoxelData::U16((0..10).map(|i| 30000 + i * 700).collect()),
        )
        .unwrap()
        .with_scaling(Scaling {
            slope: -0.5,
            intercept: 3.0,
        })
        .unwrap();
        let f = vec![0.5, f32::NAN, -2.0, 7.0, 1e-3, 3.0];
        let f32v = Volume::new("c", [3, 2, 1], [1.0; 3], VoxelType::F32, VoxelData::F32(f)).unwrap();
        let series = u8v
            .clone()
            .with_time_steps(vec![VoxelData::U8((0..24).map(|i| 255 - i).collect())])
            .unwrap();
        for v in [u8v, i16v, f32v, series] {
            for bins in [1, 7, 256] {
                assert_eq!(
                    value_histogram(&v, bins),
                    histogram(v.normalized_values(), bins),
                    "{} {bins}",
                    v.name
                );
            }
        }
    }
}
