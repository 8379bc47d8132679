//! Colormaps: each a continuous function from [0, 1] to sRGB, defined by its published control points (tabulated
//! maps, interpolated linearly in sRGB between them) or by its closed form. Pure code. `function::bake` evaluates them
//! in f32 for the renderer; the tests' CPU reference evaluates the same definitions in f64, from the constants in
//! [`tables`], and checks those constants against their sources.

pub mod tables;

use std::fmt;
use std::str::FromStr;
use tables::{COOL_WARM, PLASMA, VIRIDIS};

/// The colormaps the renderer offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Colormap {
    /// Kenneth Moreland's diverging blue–grey–red map: the default because it keeps both ends of a range
    /// distinguishable without the false edges of a rainbow.
    #[default]
    CoolWarm,
    Plasma,
    Viridis,
    Rainbow,
    Gnuplot,
    Grayscale,
}

/// A colormap name that [`Colormap::parse`] does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown colormap '{0}': choose one of cool-warm, plasma, viridis, rainbow, gnuplot, grayscale")]
pub struct UnknownColormap(pub String);

impl Colormap {
    pub const ALL: [Colormap; 6] = [
        Colormap::CoolWarm,
        Colormap::Plasma,
        Colormap::Viridis,
        Colormap::Rainbow,
        Colormap::Gnuplot,
        Colormap::Grayscale,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Colormap::CoolWarm => "cool-warm",
            Colormap::Plasma => "plasma",
            Colormap::Viridis => "viridis",
            Colormap::Rainbow => "rainbow",
            Colormap::Gnuplot => "gnuplot",
            Colormap::Grayscale => "grayscale",
        }
    }

    /// Case-insensitive; `-`, `_` and spaces are interchangeable (and optional), so "CoolWarm", "cool_warm" and
    /// "cool-warm" all name the same map. "greyscale"/"gray"/"grey" are accepted for the grey ramp.
    pub fn parse(s: &str) -> Option<Colormap> {
        let key: String = s
            .trim()
            .chars()
            .filter(|c| !matches!(c, '-' | '_' | ' '))
            .map(|c| c.to_ascii_lowercase())
            .collect();
        match key.as_str() {
            "coolwarm" => Some(Colormap::CoolWarm),
            "plasma" => Some(Colormap::Plasma),
            "viridis" => Some(Colormap::Viridis),
            "rainbow" => Some(Colormap::Rainbow),
            "gnuplot" => Some(Colormap::Gnuplot),
            "grayscale" | "greyscale" | "gray" | "grey" => Some(Colormap::Grayscale),
            _ => None,
        }
    }

    /// The map's sRGB colour at `x`, clamped to [0, 1]. Tabulated maps interpolate linearly between their
    /// control points: Moreland's 33 anchors at k/32 (cool-warm), matplotlib's 256 entries at k/255 (viridis,
    /// plasma); the others are their closed forms.
    pub fn srgb(self, x: f64) -> [f64; 3] {
        let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
        match self {
            Colormap::CoolWarm => interpolate(COOL_WARM.len(), |k| COOL_WARM[k].map(|b| f64::from(b) / 255.0), x),
            Colormap::Plasma => interpolate(PLASMA.len(), |k| PLASMA[k].map(f64::from), x),
            Colormap::Viridis => interpolate(VIRIDIS.len(), |k| VIRIDIS[k].map(f64::from), x),
            Colormap::Rainbow => rainbow(x),
            Colormap::Gnuplot => gnuplot(x),
            Colormap::Grayscale => [x, x, x],
        }
    }

    /// The map at `i / 255` as RGBA8, alpha 255 (for previews in the viewer; the renderer uses [`Colormap::srgb`]).
    pub fn lut(self) -> [[u8; 4]; 256] {
        std::array::from_fn(|i| {
            let [r, g, b] = self.srgb(i as f64 / 255.0).map(to_u8);
            [r, g, b, 255]
        })
    }
}

impl fmt::Display for Colormap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Colormap {
    type Err = UnknownColormap;

    fn from_str(s: &str) -> Result<Colormap, UnknownColormap> {
        Colormap::parse(s).ok_or_else(|| UnknownColormap(s.to_string()))
    }
}

fn to_u8(value: f64) -> u8 {
    (value.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// Linear interpolation at `x` ∈ [0, 1] through `n` points spaced evenly over [0, 1] (point k at k / (n − 1)).
fn interpolate(n: usize, point: impl Fn(usize) -> [f64; 3], x: f64) -> [f64; 3] {
    let last = n - 1;
    let position = x * last as f64;
    let lo = (position.floor() as usize).min(last - 1);
    let t = position - lo as f64;
    let (a, b) = (point(lo), point(lo + 1));
    [0, 1, 2].map(|c| a[c] + (b[c] - a[c]) * t)
}

/// HSV hue sweep at full saturation and value, from blue (240°) at 0 through cyan, green and yellow to red (0°)
/// at 1: the "rainbow" of most scientific viewers (not matplotlib's `rainbow`, which starts at purple).
fn rainbow(x: f64) -> [f64; 3] {
    // Hue in sixths of the circle: 4 = blue, 3 = cyan, 2 = green, 1 = yellow, 0 = red.
    let h = 4.0 * (1.0 - x.clamp(0.0, 1.0));
    let f = h - h.floor();
    match h.floor() as u32 {
        0 => [1.0, f, 0.0],
        1 => [1.0 - f, 1.0, 0.0],
        2 => [0.0, 1.0, f],
        3 => [0.0, 1.0 - f, 1.0],
        _ => [0.0, 0.0, 1.0],
    }
}

/// gnuplot's default palette, `set palette rgbformulae 7,5,15`: formula 7 = sqrt(x), 5 = x³, 15 = sin(360°·x),
/// each clipped to [0, 1] (gnuplot clips, so blue rises then falls to 0 over the second half).
fn gnuplot(x: f64) -> [f64; 3] {
    let x = x.clamp(0.0, 1.0);
    [
        x.sqrt(),
        x * x * x,
        (2.0 * std::f64::consts::PI * x).sin().clamp(0.0, 1.0),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn srgb_to_linear(c: u8) -> f64 {
        let c = f64::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    }

    /// CIE L* of an sRGB colour (D65).
    fn lightness(rgba: [u8; 4]) -> f64 {
        let y = 0.2126 * srgb_to_linear(rgba[0]) + 0.7152 * srgb_to_linear(rgba[1]) + 0.0722 * srgb_to_linear(rgba[2]);
        if y > 216.0 / 24389.0 {
            116.0 * y.cbrt() - 16.0
        } else {
            24389.0 / 27.0 * y
        }
    }

    fn close(actual: [u8; 4], expected: [u8; 3], tolerance: u8) -> bool {
        (0..3).all(|c| actual[c].abs_diff(expected[c]) <= tolerance) && actual[3] == 255
    }

    #[test]
    fn name_parse_round_trip() {
        for map in Colormap::ALL {
            assert_eq!(Colormap::parse(map.name()), Some(map));
            assert_eq!(Colormap::parse(&map.name().to_uppercase()), Some(map));
            assert_eq!(map.name().parse::<Colormap>(), Ok(map));
        }
        assert_eq!(Colormap::parse("coolwarm"), Some(Colormap::CoolWarm));
        assert_eq!(Colormap::parse("cool_warm"), Some(Colormap::CoolWarm));
        assert_eq!(Colormap::parse("CoolWarm"), Some(Colormap::CoolWarm));
        assert_eq!(Colormap::parse("greyscale"), Some(Colormap::Grayscale));
        assert_eq!(Colormap::parse("jet"), None);
        assert_eq!(Colormap::parse(""), None);
        let err = "jet".parse::<Colormap>().unwrap_err();
        assert_eq!(
            err.to_string(),
            "unknown colormap 'jet': choose one of cool-warm, plasma, viridis, rainbow, gnuplot, grayscale"
        );
        assert_eq!(Colormap::default(), Colormap::CoolWarm);
    }

    #[test]
    fn all_alpha_opaque() {
        for map in Colormap::ALL {
            assert!(map.lut().iter().all(|e| e[3] == 255), "{map}");
        }
    }

    #[test]
    fn endpoints() {
        // Expected values: matplotlib's viridis/plasma at 0 and 1 (x255, rounded), Moreland's table ends,
        // and the defining formulas for the rest.
        let cases: [(Colormap, [u8; 3], [u8; 3]); 6] = [
            (Colormap::CoolWarm, [59, 76, 192], [180, 4, 38]),
            (Colormap::Plasma, [13, 8, 135], [240, 249, 33]),
            (Colormap::Viridis, [68, 1, 84], [253, 231, 37]),
            (Colormap::Rainbow, [0, 0, 255], [255, 0, 0]),
            (Colormap::Gnuplot, [0, 0, 0], [255, 255, 0]),
            (Colormap::Grayscale, [0, 0, 0], [255, 255, 255]),
        ];
        for (map, first, last) in cases {
            let lut = map.lut();
            assert!(close(lut[0], first, 0), "{map} at 0: {:?}", lut[0]);
            assert!(close(lut[255], last, 0), "{map} at 1: {:?}", lut[255]);
        }
    }

    #[test]
    fn midpoints_match_references() {
        // matplotlib viridis(128/255) = (0.127568, 0.566949, 0.550556), plasma(128/255) = (0.798216, 0.280197,
        // 0.469538); Moreland's table at 0.5 is (221, 221, 221).
        assert!(close(Colormap::Viridis.lut()[128], [33, 145, 140], 0));
        assert!(close(Colormap::Plasma.lut()[128], [204, 71, 120], 0));
        // 0.5 lies between entries 127 and 128; both are within a step of the table's grey.
        assert!(close(Colormap::CoolWarm.lut()[127], [221, 221, 221], 2));
        assert!(close(Colormap::CoolWarm.lut()[128], [221, 221, 221], 2));
        // Rainbow passes through cyan, green and yellow at 1/4, 1/2 and 3/4.
        let rainbow = Colormap::Rainbow.lut();
        assert!(close(rainbow[64], [0, 255, 255], 2), "{:?}", rainbow[64]);
        assert!(close(rainbow[128], [0, 255, 0], 2), "{:?}", rainbow[128]);
        assert!(close(rainbow[191], [255, 255, 0], 2), "{:?}", rainbow[191]);
        // gnuplot 7,5,15 at x = 0.25: sqrt = 0.5, cube = 1/64, sin(90°) = 1.
        assert!(
            close(Colormap::Gnuplot.lut()[64], [128, 4, 255], 1),
            "{:?}",
            Colormap::Gnuplot.lut()[64]
        );
        // Past x = 0.5 the blue formula is negative and clipped.
        assert_eq!(Colormap::Gnuplot.lut()[200][2], 0);
    }

    #[test]
    fn grayscale_is_identity() {
        for (i, e) in Colormap::Grayscale.lut().iter().enumerate() {
            assert_eq!(*e, [i as u8, i as u8, i as u8, 255]);
        }
    }

    #[test]
    fn lightness_is_monotonic_for_sequential_maps() {
        // Rounding to 8 bits makes adjacent viridis entries dip by up to ~0.03 L*; anything bigger is a table error.
        for map in [Colormap::Viridis, Colormap::Plasma, Colormap::Grayscale] {
            let l: Vec<f64> = map.lut().iter().map(|&e| lightness(e)).collect();
            for i in 1..256 {
                assert!(
                    l[i] >= l[i - 1] - 0.1,
                    "{map}: L* drops from {} to {} at {i}",
                    l[i - 1],
                    l[i]
                );
            }
            for i in 8..256 {
                assert!(l[i] > l[i - 8], "{map}: L* not rising over 8 entries at {i}");
            }
        }
    }

    #[test]
    fn tables_are_smooth() {
        // A mistyped digit in a data table shows up as a jump between neighbours. (The formula maps are left
        // out: gnuplot's sqrt rises steeply at 0 by design.)
        for map in [Colormap::CoolWarm, Colormap::Plasma, Colormap::Viridis] {
            let lut = map.lut();
            for i in 1..256 {
                for (c, (now, before)) in lut[i].iter().zip(lut[i - 1]).take(3).enumerate() {
                    let step = now.abs_diff(before);
                    assert!(step <= 8, "{map}: channel {c} jumps by {step} at {i}");
                }
            }
        }
    }

    #[test]
    fn cool_warm_hits_every_anchor() {
        // Anchor k sits at k/32 = i/255 only for k = 0, 32 exactly; elsewhere the nearest entry is within
        // half an entry, so within a couple of 8-bit steps of the anchor.
        let lut = Colormap::CoolWarm.lut();
        for (k, anchor) in COOL_WARM.iter().enumerate() {
            let i = ((k as f64 / 32.0) * 255.0).round() as usize;
            assert!(close(lut[i], *anchor, 3), "anchor {k}: {:?} vs {:?}", lut[i], anchor);
        }
    }
}
