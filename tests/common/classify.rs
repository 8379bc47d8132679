//! The reference's own classification (rule 4), written from the definitions in f64: no code shared with
//! `function::bake` or `Colormap::srgb`, only the documented control points in `volcast::transfer::colormap::tables` (checked
//! against their published values in tests/reference/classify.rs) and the user's settings.
//!
//! A sample of normalised value v inside the window [lo, hi] has window position c = (v − lo)/(hi − lo).
//! - The simple (Qt) model: colour = colormap(c), opacity = step_alpha, or c·step_alpha when multiplied.
//! - A transfer function: its abscissa is x = v (normalised units) or x = min + v·(max − min) (data units, the
//!   volume's value range); colour = its colour points interpolated linearly at x, or its colormap at c when it
//!   has none; opacity = its opacity points interpolated linearly at x, clamped to [0, 1]. Points are constant
//!   beyond the first and last.
//! - Outside the window: no colour, no opacity.
//! - Colours are sRGB; the renderer composites their linear-light values (IEC 61966-2-1 decoding).

use glam::DVec3;
use volcast::scene::settings::RenderSettings;
use volcast::transfer::colormap::tables::{COOL_WARM, PLASMA, VIRIDIS};
use volcast::transfer::function::{Classification, TfUnits};
use volcast::transfer::Colormap;

/// The sRGB decoding (IEC 61966-2-1).
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB encoding.
pub fn linear_to_srgb(c: f64) -> f64 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// `c` decoded channel by channel.
pub fn linear(c: DVec3) -> DVec3 {
    DVec3::new(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z))
}

/// Rule 8's encoding of a linear-light colour: clamped to [0,1], then sRGB-encoded (not yet rounded).
pub fn encode(c: DVec3) -> DVec3 {
    let c = c.clamp(DVec3::ZERO, DVec3::ONE);
    DVec3::new(linear_to_srgb(c.x), linear_to_srgb(c.y), linear_to_srgb(c.z))
}

/// Evenly spaced control points over [0, 1], interpolated linearly.
fn through(points: &[DVec3], x: f64) -> DVec3 {
    let segments = (points.len() - 1) as f64;
    let u = x * segments;
    let k = (u.floor() as usize).min(points.len() - 2);
    points[k].lerp(points[k + 1], u - k as f64)
}

/// HSV (hue in degrees, full saturation and value) to RGB, the textbook sextant construction.
fn hue(degrees: f64) -> DVec3 {
    let h = degrees.rem_euclid(360.0) / 60.0;
    let x = 1.0 - (h % 2.0 - 1.0).abs();
    match h as u32 {
        0 => DVec3::new(1.0, x, 0.0),
        1 => DVec3::new(x, 1.0, 0.0),
        2 => DVec3::new(0.0, 1.0, x),
        3 => DVec3::new(0.0, x, 1.0),
        4 => DVec3::new(x, 0.0, 1.0),
        _ => DVec3::new(1.0, 0.0, x),
    }
}

/// A colormap's sRGB colour at `x` ∈ [0, 1] (clamped):
/// - cool-warm: Moreland (2009), his 33-point table of sRGB bytes at k/32;
/// - viridis, plasma: matplotlib's 256 listed colours at k/255;
/// - rainbow: hue from 240° (blue) at 0 down to 0° (red) at 1, full saturation and value;
/// - gnuplot: `rgbformulae 7,5,15`, i.e. (√x, x³, sin 2πx), each clipped to [0, 1];
/// - grayscale: (x, x, x).
pub fn colormap_srgb(map: Colormap, x: f64) -> DVec3 {
    let x = x.clamp(0.0, 1.0);
    match map {
        Colormap::CoolWarm => {
            let points: Vec<DVec3> = COOL_WARM
                .iter()
                .map(|c| DVec3::new(c[0].into(), c[1].into(), c[2].into()) / 255.0)
                .collect();
            through(&points, x)
        }
        Colormap::Viridis | Colormap::Plasma => {
            let table = if map == Colormap::Viridis { &VIRIDIS } else { &PLASMA };
            let points: Vec<DVec3> = table
                .iter()
                .map(|c| DVec3::new(c[0].into(), c[1].into(), c[2].into()))
                .collect();
            through(&points, x)
        }
        Colormap::Rainbow => hue(240.0 * (1.0 - x)),
        Colormap::Gnuplot => DVec3::new(x.sqrt(), x.powi(3), (2.0 * std::f64::consts::PI * x).sin().max(0.0)),
        Colormap::Grayscale => DVec3::splat(x),
    }
}

/// Piecewise-linear interpolation through points sorted by x, constant beyond the first and last.
pub fn piecewise(points: &[(f64, DVec3)], x: f64) -> DVec3 {
    let Some(&(x0, y0)) = points.first() else {
        return DVec3::ZERO;
    };
    if x <= x0 {
        return y0;
    }
    for pair in points.windows(2) {
        let ((xa, ya), (xb, yb)) = (pair[0], pair[1]);
        if x <= xb {
            return if xb > xa { ya.lerp(yb, (x - xa) / (xb - xa)) } else { yb };
        }
    }
    points[points.len() - 1].1
}

/// One frame's classification, prepared once.
pub struct Classifier {
    window: [f64; 2],
    range: [f64; 2],
    model: Model,
}

enum Model {
    Simple {
        colormap: Colormap,
        step_alpha: f64,
        multiplied: bool,
    },
    Function {
        data_units: bool,
        colormap: Colormap,
        colors: Vec<(f64, DVec3)>,
        opacity: Vec<(f64, DVec3)>,
    },
}

impl Classifier {
    /// The classification of `s` for data whose value range (the one normalisation used) is `range`.
    pub fn new(s: &RenderSettings, range: [f64; 2]) -> Classifier {
        let model = match s.classification() {
            Classification::Simple {
                colormap,
                step_alpha,
                multiplied,
            } => Model::Simple {
                colormap,
                step_alpha: step_alpha.into(),
                multiplied,
            },
            Classification::Function(tf) => Model::Function {
                data_units: tf.units == TfUnits::Data,
                colormap: tf.colormap,
                colors: tf
                    .colors
                    .iter()
                    .map(|p| (p[0].into(), DVec3::new(p[1].into(), p[2].into(), p[3].into())))
                    .collect(),
                opacity: tf
                    .opacity
                    .iter()
                    .map(|p| (p[0].into(), DVec3::splat(p[1].into())))
                    .collect(),
            },
        };
        Classifier {
            window: s.colour.window.map(f64::from),
            range,
            model,
        }
    }

    /// The isosurface's colour: the classification at `iso`, clamped into the window (rule 7; the isosurface
    /// ignores the window for its crossing test).
    pub fn iso_rgb(&self, iso: f64) -> DVec3 {
        self.at(iso.clamp(self.window[0], self.window[1])).0
    }

    /// Linear-light colour and opacity per voxel-length step of normalised value `v`; zero outside the window.
    pub fn at(&self, v: f64) -> (DVec3, f64) {
        let [lo, hi] = self.window;
        if v.is_nan() || v < lo || v > hi {
            return (DVec3::ZERO, 0.0);
        }
        let c = (v - lo) / (hi - lo);
        let (srgb, alpha) = match &self.model {
            Model::Simple {
                colormap,
                step_alpha,
                multiplied,
            } => (
                colormap_srgb(*colormap, c),
                if *multiplied { c * step_alpha } else { *step_alpha },
            ),
            Model::Function {
                data_units,
                colormap,
                colors,
                opacity,
            } => {
                let x = if *data_units {
                    self.range[0] + v * (self.range[1] - self.range[0])
                } else {
                    v
                };
                let srgb = if colors.is_empty() {
                    colormap_srgb(*colormap, c)
                } else {
                    piecewise(colors, x)
                };
                (srgb, piecewise(opacity, x).x.clamp(0.0, 1.0))
            }
        };
        (linear(srgb), alpha.clamp(0.0, 1.0))
    }

    /// The linear-light colour alone.
    pub fn rgb(&self, v: f64) -> DVec3 {
        self.at(v).0
    }
}

/// Rule 2's per-pixel start offset of jittered rays, in [0, 1): the PCG-style integer hash the rule documents
/// (O'Neill's RXS-M-XS output of one LCG step, of the pixel and seed mixed by three odd constants), top 24 bits.
pub fn jitter_offset(x: u32, y: u32, seed: u32) -> f64 {
    let mixed = x
        .wrapping_mul(1973)
        .wrapping_add(y.wrapping_mul(9277))
        .wrapping_add(seed.wrapping_mul(26699))
        | 1;
    let state = mixed.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let shift = (state >> 28) + 4;
    let word = ((state >> shift) ^ state).wrapping_mul(277_803_737);
    let hash = word ^ (word >> 22);
    f64::from(hash >> 8) / f64::from(1u32 << 24)
}
