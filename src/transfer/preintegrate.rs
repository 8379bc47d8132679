//! Pre-integrated classification (Engel, Kraus and Ertl 2001): the emission–absorption and density marches
//! composite each *segment* between two consecutive samples, assuming the value varies linearly along it, instead
//! of each sample alone. Sharp transfer functions (a window's edge, a thin opaque peak) then stay accurate at
//! large steps: a segment crossing the edge gets the opacity of the part of it inside the window, where point
//! sampling takes all or nothing.
//!
//! The segment integral is evaluated from *integral functions*, the paper's fast construction (§4): with the
//! extinction σ(v) per voxel length and its colour-weighted σ(v)·c(v) integrated over the value,
//! `T(v) = ∫₀ᵛ σ`, `K(v) = ∫₀ᵛ σ·c`, a segment from value v_a to v_b has the mean extinction
//! `σ̄ = (T(v_b) − T(v_a)) / (v_b − v_a)` and the extinction-weighted mean colour `c̄ = (K(v_b) − K(v_a)) /
//! (T(v_b) − T(v_a))`. The march then treats the segment as one sample of extinction σ̄ and colour c̄ (rule 6 of
//! `RenderSettings`). Unlike a 2-D table per step length, one 1-D table serves every step length, so adaptive
//! steps need no extra tables, and a transfer-function edit rebuilds 4096 entries, not 4096².
//!
//! The GPU reads [`integral_table`] from a uniform buffer (4096 × 16 bytes, the 64 KiB every desktop device
//! offers): on lavapipe a uniform load with per-lane indices is 8 branch-free loads where a storage load is a loop.

use crate::transfer::function::LUT_SIZE;

/// Extinction that stands for opacity 1 (per voxel length): `−ln(1 − a)` is infinite there. At a 1-voxel step
/// it is opacity 1 − e⁻³², at the finest step allowed (0.05 voxel) 0.80.
pub const SIGMA_MAX: f64 = 32.0;

/// Below this value difference (one table entry) the march uses the table's slope at the segment's end instead
/// of the quotient of differences, which f32 cancellation would spoil.
pub const SLOPE_BELOW: f32 = 1.0 / (LUT_SIZE - 1) as f32;

/// Extinction per voxel length of a sample of opacity `alpha` per voxel-length step: `−ln(1 − alpha)` for
/// emission–absorption (so that `1 − e^(−σ·s)` is rule 6's `1 − (1 − alpha)^s`), `alpha · density` for the
/// density model (whose opacity is linear, `min(1, σ·s)`); both at most [`SIGMA_MAX`].
pub fn extinction(alpha: f64, density: Option<f64>) -> f64 {
    let sigma = match density {
        Some(d) => alpha * d,
        None => -(1.0 - alpha.clamp(0.0, 1.0)).ln(),
    };
    if sigma.is_nan() {
        0.0
    } else {
        sigma.clamp(0.0, SIGMA_MAX)
    }
}

/// The integral functions of the baked table `lut` (`function::bake`, [`LUT_SIZE`] entries at v = i/(N − 1)), as the
/// march reads them: entry i holds `(K_r, K_g, K_b, T)` at v = i/(N − 1), where σ and σ·c are the linear
/// interpolation of their entry values (as the point table is read). Integrated in f64, stored as f32.
///
/// The table integrates the classification over the whole value range, outside the window too (where `bake` holds
/// the window edge's classification). The march applies the window by clamping: `∫ σ·[v ∈ window]` from v_a to v_b
/// is `T(clamp(v_b)) − T(clamp(v_a))`, exact at the window's edges wherever they fall between entries.
pub fn integral_table(lut: &[[f32; 4]], density: Option<f32>) -> Vec<[f32; 4]> {
    let width = 1.0 / (lut.len() - 1) as f64;
    let density = density.map(f64::from);
    let point = |e: &[f32; 4]| {
        let sigma = extinction(f64::from(e[3]), density);
        [
            sigma * f64::from(e[0]),
            sigma * f64::from(e[1]),
            sigma * f64::from(e[2]),
            sigma,
        ]
    };
    let mut sum = [0.0f64; 4];
    let mut out = Vec::with_capacity(lut.len());
    out.push([0.0; 4]);
    for pair in lut.windows(2) {
        let (p0, p1) = (point(&pair[0]), point(&pair[1]));
        for k in 0..4 {
            sum[k] += 0.5 * width * (p0[k] + p1[k]);
        }
        out.push(sum.map(|s| s as f32));
    }
    out
}

/// The table at `v` and its slope over the entry holding v: what the march's `integral_at` computes.
pub fn integral_at(table: &[[f32; 4]], v: f32) -> ([f32; 4], [f32; 4]) {
    let last = (table.len() - 1) as f32;
    let u = v.clamp(0.0, 1.0) * last;
    let i0 = (u as usize).min(table.len() - 2);
    let f = u - i0 as f32;
    let (a, b) = (table[i0], table[i0 + 1]);
    (
        std::array::from_fn(|k| a[k] + (b[k] - a[k]) * f),
        std::array::from_fn(|k| (b[k] - a[k]) * last),
    )
}

/// The segment from value `va` to `vb` with the classification zero outside `window`: its mean `(σ̄·c̄, σ̄)`, as
/// the march computes it. The integrals are read at the values clamped into the window; below [`SLOPE_BELOW`]
/// the slope at `vb` (clamped) is used, or zero when the segment's midpoint is outside the window.
pub fn segment_mean(table: &[[f32; 4]], window: [f32; 2], va: f32, vb: f32) -> [f32; 4] {
    let clamp = |v: f32| v.clamp(window[0], window[1]);
    let (ia, _) = integral_at(table, clamp(va));
    let (ib, slope) = integral_at(table, clamp(vb));
    let dv = vb - va;
    let mid = 0.5 * (va + vb);
    if dv.abs() >= SLOPE_BELOW {
        std::array::from_fn(|k| (ib[k] - ia[k]) / dv)
    } else if mid >= window[0] && mid <= window[1] {
        slope
    } else {
        [0.0; 4]
    }
}

/// A segment's opacity and colour (not premultiplied) from its mean `(σ̄·c̄, σ̄)` over `steps` voxel lengths:
/// emission `1 − e^(−σ̄·steps)`, density `min(1, σ̄·steps)`; colour `c̄` clamped to [0, 1] (an f32 quotient of
/// small differences may stray just outside what is a weighted mean of colours in [0, 1]).
pub fn segment(mean: [f32; 4], steps: f32, density_model: bool) -> ([f32; 3], f32) {
    let sigma = mean[3].max(0.0);
    let alpha = if density_model {
        (sigma * steps).min(1.0)
    } else {
        1.0 - (-sigma * steps).exp()
    };
    let rgb = if sigma > 0.0 {
        [0, 1, 2].map(|k| (mean[k] / sigma).clamp(0.0, 1.0))
    } else {
        [0.0; 3]
    };
    (rgb, alpha)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(alpha: f32, rgb: [f32; 3]) -> Vec<[f32; 4]> {
        vec![[rgb[0], rgb[1], rgb[2], alpha]; LUT_SIZE]
    }

    #[test]
    fn a_constant_classification_gives_the_point_rule_at_any_step() {
        let lut = flat(0.2, [0.5, 0.25, 1.0]);
        let table = integral_table(&lut, None);
        for (va, vb) in [(0.3, 0.7), (0.5, 0.5), (0.9, 0.1), (0.2, 0.2001)] {
            let mean = segment_mean(&table, [0.0, 1.0], va, vb);
            for steps in [0.125f32, 1.0, 4.0] {
                let (rgb, a) = segment(mean, steps, false);
                let expected = 1.0 - 0.8f32.powf(steps);
                assert!((a - expected).abs() < 1e-4, "{va}->{vb} at {steps}: {a} vs {expected}");
                for (c, e) in rgb.iter().zip([0.5, 0.25, 1.0]) {
                    assert!((c - e).abs() < 1e-4, "{rgb:?}");
                }
            }
        }
    }

    #[test]
    fn a_segment_across_the_window_edge_gets_the_part_inside() {
        // Opacity 0.5 per voxel inside [0.5, 1]: a segment from 0.25 to 0.75 spends half its length inside, so its
        // mean extinction is half the inside one: opacity 1 − 0.5^0.5 over one voxel, where point sampling would
        // give 0.5 or 0 depending on which end it looks at.
        let lut = flat(0.5, [1.0, 1.0, 1.0]);
        let table = integral_table(&lut, None);
        let (_, a) = segment(segment_mean(&table, [0.5, 1.0], 0.25, 0.75), 1.0, false);
        assert!((a - (1.0 - 0.5f32.sqrt())).abs() < 1e-4, "{a}");
        let (_, a) = segment(segment_mean(&table, [0.5, 1.0], 0.75, 0.25), 1.0, false);
        assert!((a - (1.0 - 0.5f32.sqrt())).abs() < 1e-4, "either direction: {a}");
        let (_, outside) = segment(segment_mean(&table, [0.5, 1.0], 0.1, 0.4), 1.0, false);
        assert_eq!(outside, 0.0);
        // An edge between two entries is exact too: a quarter of 0.3..0.34 lies above 0.33.
        let (_, a) = segment(segment_mean(&table, [0.33, 1.0], 0.3, 0.34), 4.0, false);
        assert!((a - (1.0 - 0.5f32.powf(1.0))).abs() < 2e-3, "{a}");
        // Within one entry of the edge: the midpoint decides.
        let e = 0.5 * SLOPE_BELOW;
        assert_eq!(
            segment(segment_mean(&table, [0.33, 1.0], 0.33 - e, 0.33 - 0.1 * e), 1.0, false).1,
            0.0
        );
        assert!(segment(segment_mean(&table, [0.33, 1.0], 0.33 + 0.1 * e, 0.33 + e), 1.0, false).1 > 0.49);
    }

    #[test]
    fn colour_is_weighted_by_extinction() {
        // Red and transparent below 0.5, blue and opaque-ish above: a segment across is blue, only less opaque.
        let mut lut = flat(0.0, [1.0, 0.0, 0.0]);
        for (i, e) in lut.iter_mut().enumerate() {
            if i >= LUT_SIZE / 2 {
                *e = [0.0, 0.0, 1.0, 0.6];
            }
        }
        let table = integral_table(&lut, None);
        let (rgb, a) = segment(segment_mean(&table, [0.0, 1.0], 0.0, 1.0), 1.0, false);
        assert!(rgb[0] < 1e-3 && (rgb[2] - 1.0).abs() < 1e-3, "{rgb:?}");
        let half = 1.0 - 0.4f32.sqrt();
        assert!((a - half).abs() < 2e-3, "{a} vs {half}");
    }

    #[test]
    fn density_model_is_linear_and_clamped() {
        let lut = flat(0.1, [1.0; 3]);
        let table = integral_table(&lut, Some(2.0));
        let mean = segment_mean(&table, [0.0, 1.0], 0.2, 0.8);
        assert!((segment(mean, 1.5, true).1 - 0.3).abs() < 1e-5);
        assert_eq!(segment(mean, 10.0, true).1, 1.0);
    }

    #[test]
    fn opacity_one_is_capped_not_infinite() {
        assert_eq!(extinction(1.0, None), SIGMA_MAX);
        assert_eq!(extinction(f64::NAN, None), 0.0);
        let table = integral_table(&flat(1.0, [1.0; 3]), None);
        assert!(table.iter().all(|e| e.iter().all(|x| x.is_finite())));
        let (_, a) = segment(segment_mean(&table, [0.0, 1.0], 0.4, 0.6), 1.0, false);
        assert!(a > 0.999_999, "{a}");
    }
}
