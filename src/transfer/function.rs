//! Transfer functions: what colour and opacity a normalised value gets. Either the Qt example's simple model (a
//! colormap stretched over the value window with a constant or value-proportional step alpha) or a 1D transfer
//! function — a piecewise-linear opacity curve plus colours (control points, or a colormap) — with presets and a
//! JSON file format. Both are baked into the same 4096-entry lookup table of linear-light RGB and opacity, which
//! the GPU and the CPU reference interpolate identically. Pure code.

use crate::transfer::Colormap;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Entries in the baked table: 4096 resolves 1 HU of a typical CT range (−1024..3071).
pub const LUT_SIZE: usize = 4096;

/// Units of the control points' x.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TfUnits {
    /// Fractions of the data's value range, [0, 1].
    #[default]
    Normalized,
    /// The data's own values (Hounsfield units for CT), mapped through the volume's min/max when baked.
    Data,
}

/// A 1D transfer function.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransferFunction {
    #[serde(default)]
    pub name: String,
    #[serde(default)]
    pub units: TfUnits,
    /// Colour control points `[x, r, g, b]` (sRGB, 0–1), piecewise linear. Empty: the colormap spans the window.
    #[serde(default)]
    pub colors: Vec<[f32; 4]>,
    /// Used when `colors` is empty.
    #[serde(default)]
    pub colormap: Colormap,
    /// Opacity control points `[x, alpha]`: alpha is the opacity of one voxel-length step. Piecewise linear,
    /// constant beyond the end points.
    pub opacity: Vec<[f32; 2]>,
}

#[derive(Debug, thiserror::Error)]
pub enum TfError {
    #[error("cannot read transfer function {path}: {source}")]
    Io { path: String, source: std::io::Error },
    #[error("transfer function {path} is not valid JSON for a transfer function: {message}")]
    Json { path: String, message: String },
    #[error("transfer function {name}: {problem}")]
    Invalid { name: String, problem: String },
    #[error("unknown preset '{0}'; presets: {presets}", presets = PRESET_NAMES.join(", "))]
    UnknownPreset(String),
}

pub const PRESET_NAMES: &[&str] = &["ct-bone", "ct-soft-tissue", "ct-lung", "mr-default", "qt-example"];

impl TransferFunction {
    /// A named preset. CT presets are in Hounsfield units (data units); the others in fractions of the range.
    pub fn preset(name: &str) -> Result<TransferFunction, TfError> {
        let tf = |units, colors: &[[f32; 4]], colormap, opacity: &[[f32; 2]]| TransferFunction {
            name: name.to_string(),
            units,
            colors: colors.to_vec(),
            colormap,
            opacity: opacity.to_vec(),
        };
        Ok(match name {
            // Bone from ~200 HU, ivory to white; soft tissue invisible.
            "ct-bone" => tf(
                TfUnits::Data,
                &[
                    [150.0, 0.55, 0.25, 0.15],
                    [300.0, 0.9, 0.82, 0.68],
                    [1200.0, 1.0, 1.0, 0.95],
                ],
                Colormap::Grayscale,
                &[[150.0, 0.0], [300.0, 0.25], [700.0, 0.6], [1500.0, 0.9]],
            ),
            // Skin and muscle translucent, fat hidden, bone faint.
            "ct-soft-tissue" => tf(
                TfUnits::Data,
                &[
                    [-150.0, 0.75, 0.45, 0.35],
                    [40.0, 0.85, 0.35, 0.3],
                    [300.0, 1.0, 0.9, 0.8],
                ],
                Colormap::Grayscale,
                &[
                    [-150.0, 0.0],
                    [-60.0, 0.0],
                    [20.0, 0.04],
                    [80.0, 0.08],
                    [250.0, 0.02],
                    [600.0, 0.08],
                ],
            ),
            // Air-filled lung parenchyma and airways; everything denser than ~-300 HU hidden.
            "ct-lung" => tf(
                TfUnits::Data,
                &[
                    [-1000.0, 0.2, 0.45, 0.9],
                    [-700.0, 0.55, 0.8, 1.0],
                    [-400.0, 0.95, 0.95, 1.0],
                ],
                Colormap::Grayscale,
                &[
                    [-990.0, 0.0],
                    [-900.0, 0.03],
                    [-650.0, 0.06],
                    [-400.0, 0.02],
                    [-300.0, 0.0],
                ],
            ),
            "mr-default" => tf(
                TfUnits::Normalized,
                &[],
                Colormap::Grayscale,
                &[[0.12, 0.0], [0.3, 0.03], [0.6, 0.12], [1.0, 0.3]],
            ),
            // The Qt example's look: cool-warm over the range, a constant step alpha of 0.1 above 10%.
            "qt-example" => tf(
                TfUnits::Normalized,
                &[],
                Colormap::CoolWarm,
                &[[0.0, 0.0], [0.0999, 0.0], [0.1, 0.1], [1.0, 0.1]],
            ),
            _ => return Err(TfError::UnknownPreset(name.to_string())),
        })
    }

    /// Reads a transfer function from JSON (the format [`TransferFunction::to_json`] writes).
    pub fn load(path: &Path) -> Result<TransferFunction, TfError> {
        let p = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| TfError::Io {
            path: p.clone(),
            source,
        })?;
        let mut tf: TransferFunction = serde_json::from_str(&text).map_err(|e| TfError::Json {
            path: p.clone(),
            message: e.to_string(),
        })?;
        if tf.name.is_empty() {
            tf.name = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
        }
        tf.validate()?;
        Ok(tf)
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Control points must be finite, sorted by x, colours and opacities within [0, 1]; at least one opacity
    /// point; normalised x within [0, 1].
    pub fn validate(&self) -> Result<(), TfError> {
        let bad = |problem: String| TfError::Invalid {
            name: self.name.clone(),
            problem,
        };
        if self.opacity.is_empty() {
            return Err(bad("needs at least one opacity point".into()));
        }
        let check_x = |xs: &mut dyn Iterator<Item = f32>, what: &str| -> Result<(), TfError> {
            let mut last = f32::NEG_INFINITY;
            for x in xs {
                if !x.is_finite() {
                    return Err(bad(format!("{what} point x {x} is not a finite number")));
                }
                if x < last {
                    return Err(bad(format!("{what} points must be sorted by x ({x} after {last})")));
                }
                if self.units == TfUnits::Normalized && !(0.0..=1.0).contains(&x) {
                    return Err(bad(format!("{what} point x {x} is outside [0, 1] (units: normalized)")));
                }
                last = x;
            }
            Ok(())
        };
        check_x(&mut self.opacity.iter().map(|p| p[0]), "opacity")?;
        check_x(&mut self.colors.iter().map(|p| p[0]), "colour")?;
        for p in &self.opacity {
            if !(0.0..=1.0).contains(&p[1]) {
                return Err(bad(format!("opacity {} at x {} is outside [0, 1]", p[1], p[0])));
            }
        }
        for p in &self.colors {
            if p[1..].iter().any(|c| !(0.0..=1.0).contains(c)) {
                return Err(bad(format!(
                    "colour {:?} at x {} has a channel outside [0, 1]",
                    &p[1..],
                    p[0]
                )));
            }
        }
        Ok(())
    }
}

/// Piecewise-linear interpolation through sorted points `(x, y)`, constant beyond the ends.
pub fn piecewise<const N: usize>(points: &[(f32, [f32; N])], x: f32) -> [f32; N] {
    let Some(first) = points.first() else { return [0.0; N] };
    if x <= first.0 {
        return first.1;
    }
    for w in points.windows(2) {
        let (a, b) = (w[0], w[1]);
        if x <= b.0 {
            let t = if b.0 > a.0 { (x - a.0) / (b.0 - a.0) } else { 1.0 };
            return std::array::from_fn(|i| a.1[i] + (b.1[i] - a.1[i]) * t);
        }
    }
    points[points.len() - 1].1
}

/// sRGB transfer function, decoding (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// sRGB transfer function, encoding.
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The colormap's sRGB colour at `c` ∈ [0, 1]: its definition ([`Colormap::srgb`]) in f32.
pub fn colormap_at(colormap: Colormap, c: f32) -> [f32; 3] {
    colormap.srgb(f64::from(c)).map(|x| x as f32)
}

/// How opacity is assigned.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Classification {
    /// Qt's model: the colormap stretched over the value window, opacity `step_alpha` (or `c × step_alpha`
    /// with `multiplied`, c the position in the window).
    Simple {
        colormap: Colormap,
        step_alpha: f32,
        multiplied: bool,
    },
    /// A transfer function (its colours, or its colormap stretched over the window).
    Function(TransferFunction),
}

/// Bakes `classification` for data with value range `range` and the value window `window` (normalised) into
/// [`LUT_SIZE`] entries of `[r, g, b, alpha]`, colours in linear light. Entry i is the value v = i / (N − 1).
/// Entries outside the window hold the classification at the window's nearer edge: the march never classifies
/// a value outside the window, but interpolates between the two entries around a value just inside it, and a
/// zero entry there would fade the edge's colour and opacity out over one entry's width.
pub fn bake(classification: &Classification, window: [f32; 2], range: [f64; 2]) -> Vec<[f32; 4]> {
    let [lo, hi] = window;
    let span = (hi - lo).max(f32::MIN_POSITIVE);
    (0..LUT_SIZE)
        .map(|i| {
            let v = (i as f32 / (LUT_SIZE - 1) as f32).clamp(lo, hi);
            let c = (v - lo) / span;
            let (srgb, alpha) = match classification {
                Classification::Simple {
                    colormap,
                    step_alpha,
                    multiplied,
                } => (
                    colormap_at(*colormap, c),
                    if *multiplied { c * step_alpha } else { *step_alpha },
                ),
                Classification::Function(tf) => {
                    let x = match tf.units {
                        TfUnits::Normalized => v,
                        TfUnits::Data => (range[0] + v as f64 * (range[1] - range[0])) as f32,
                    };
                    let opacity: Vec<(f32, [f32; 1])> = tf.opacity.iter().map(|p| (p[0], [p[1]])).collect();
                    let colors: Vec<(f32, [f32; 3])> = tf.colors.iter().map(|p| (p[0], [p[1], p[2], p[3]])).collect();
                    let srgb = if colors.is_empty() {
                        colormap_at(tf.colormap, c)
                    } else {
                        piecewise(&colors, x)
                    };
                    (srgb, piecewise(&opacity, x)[0].clamp(0.0, 1.0))
                }
            };
            [
                srgb_to_linear(srgb[0]),
                srgb_to_linear(srgb[1]),
                srgb_to_linear(srgb[2]),
                alpha.clamp(0.0, 1.0),
            ]
        })
        .collect()
}

/// The table interpolated at `v` ∈ [0, 1] (index v·(N − 1)): the lookup both renderers perform.
pub fn lookup(lut: &[[f32; 4]], v: f32) -> [f32; 4] {
    let u = v.clamp(0.0, 1.0) * (lut.len() - 1) as f32;
    let i0 = (u as usize).min(lut.len() - 2);
    let f = u - i0 as f32;
    std::array::from_fn(|k| lut[i0][k] + (lut[i0 + 1][k] - lut[i0][k]) * f)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trip_and_known_values() {
        for i in 0..=255 {
            let c = i as f32 / 255.0;
            assert!((linear_to_srgb(srgb_to_linear(c)) - c).abs() < 1e-5);
        }
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn simple_model_bakes_the_window_and_alpha_modes() {
        let simple = Classification::Simple {
            colormap: Colormap::Grayscale,
            step_alpha: 0.4,
            multiplied: false,
        };
        let lut = bake(&simple, [0.25, 0.75], [0.0, 1.0]);
        assert_eq!(lut.len(), LUT_SIZE);
        // Entries up to 1023 (v = 0.2498) and from 3072 (v = 0.7502) are outside; they hold the window's edges.
        assert_eq!(lut[0], lut[1023], "below the window: its lower edge");
        assert_eq!(lut[LUT_SIZE - 1], lut[3072], "above the window: its upper edge");
        assert_eq!(lut[0][0], 0.0, "grey at the window's lower edge is black");
        let mid = lookup(&lut, 0.5);
        assert!((mid[3] - 0.4).abs() < 1e-6);
        assert!((mid[0] - srgb_to_linear(colormap_at(Colormap::Grayscale, 0.5)[0])).abs() < 1e-3);
        let multiplied = Classification::Simple {
            colormap: Colormap::Grayscale,
            step_alpha: 0.4,
            multiplied: true,
        };
        let lut = bake(&multiplied, [0.0, 1.0], [0.0, 1.0]);
        assert!((lookup(&lut, 0.5)[3] - 0.2).abs() < 1e-4);
    }

    #[test]
    fn data_unit_presets_follow_the_volume_range() {
        let bone = TransferFunction::preset("ct-bone").unwrap();
        let lut = bake(&Classification::Function(bone), [0.0, 1.0], [-1024.0, 2986.0]);
        let at_hu = |hu: f64| lookup(&lut, ((hu + 1024.0) / 4010.0) as f32);
        assert!(at_hu(0.0)[3] < 1e-6, "soft tissue is transparent");
        assert!((at_hu(300.0)[3] - 0.25).abs() < 0.01);
        assert!((at_hu(3000.0)[3] - 0.9).abs() < 1e-3, "constant beyond the last point");
        for name in PRESET_NAMES {
            let tf = TransferFunction::preset(name).unwrap();
            tf.validate().unwrap();
            let lut = bake(&Classification::Function(tf), [0.0, 1.0], [-1024.0, 3071.0]);
            assert!(lut.iter().any(|e| e[3] > 0.0), "{name} shows something");
        }
        assert!(matches!(
            TransferFunction::preset("jet"),
            Err(TfError::UnknownPreset(_))
        ));
    }

    #[test]
    fn json_round_trip_and_malformed_files() {
        let dir = std::env::temp_dir().join(format!("volcast-tf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let tf = TransferFunction::preset("ct-soft-tissue").unwrap();
        let path = dir.join("soft.json");
        std::fs::write(&path, tf.to_json()).unwrap();
        assert_eq!(TransferFunction::load(&path).unwrap(), tf);

        let cases = [
            ("{\"opacity\": [[0.5, 0.1], [0.2, 0.3]]}", "sorted"),
            ("{\"opacity\": []}", "at least one opacity point"),
            ("{\"opacity\": [[0.5, 1.5]]}", "outside [0, 1]"),
            ("{\"opacity\": [[2.0, 0.5]]}", "units: normalized"),
            ("{\"opacity\": [[0.5, 0.5]], \"colour\": 3}", "not valid JSON"),
            ("{\"opacity\": [[0.5, 0.5]], \"colormap\": \"jet\"}", "not valid JSON"),
            ("not json", "not valid JSON"),
        ];
        for (i, (text, needle)) in cases.iter().enumerate() {
            let p = dir.join(format!("bad{i}.json"));
            std::fs::write(&p, text).unwrap();
            let err = TransferFunction::load(&p).unwrap_err().to_string();
            assert!(err.contains(needle), "{text}: {err}");
        }
        let err = TransferFunction::load(&dir.join("missing.json"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("missing.json"), "{err}");
    }

    #[test]
    fn piecewise_is_constant_beyond_the_ends() {
        let pts = [(0.2f32, [1.0f32]), (0.6, [3.0])];
        assert_eq!(piecewise(&pts, 0.0), [1.0]);
        assert_eq!(piecewise(&pts, 0.4), [2.0]);
        assert_eq!(piecewise(&pts, 0.9), [3.0]);
    }
}
