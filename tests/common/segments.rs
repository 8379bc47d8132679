//! The reference's pre-integration (rule 6), written from its definition in f64 and sharing no code with
//! `volcast::transfer::preintegrate`: the segment between two consecutive samples of values v_a and v_b is taken as a value
//! varying linearly from v_a to v_b, and composited as one sample of
//! - mean extinction σ̄ = (1/(v_b − v_a)) ∫ σ(v) dv over [v_a, v_b], with σ(v) = −ln(1 − a(v)) (emission) or
//!   a(v)·density (density model), at most 32 per voxel length, zero outside the window;
//! - colour c̄ = ∫ σ(v)·c(v) dv / ∫ σ(v) dv, the extinction-weighted mean of the classified colour.
//!
//! The integrals are the exact classification (classify.rs) integrated numerically: two-point Gauss–Legendre on
//! 65536 cells of the value range (cut at the window's edges, where the classification jumps), accumulated into
//! integral functions read by linear interpolation. Where v_a and v_b (nearly) coincide, the limit: the point
//! classification at their midpoint. The GPU instead integrates a 4096-entry table and uses the table's slope
//! within one entry; the two differ within one entry of a jump or kink of the transfer function.

use super::classify::Classifier;
use glam::DVec3;

/// Extinction per voxel length that stands for opacity 1 (rule 6).
pub const SIGMA_MAX: f64 = 32.0;

const CELLS: usize = 1 << 16;

/// Segments of one frame's classification, integrated once.
pub struct Segments {
    /// Integral functions at v = i / CELLS: (∫σ·c, ∫σ).
    cumulative: Vec<(DVec3, f64)>,
    classifier: Classifier,
    density: Option<f64>,
}

impl Segments {
    /// `density`: the density model's factor, or None for emission–absorption.
    pub fn new(classifier: Classifier, window: [f64; 2], density: Option<f64>) -> Segments {
        let mut s = Segments {
            cumulative: Vec::with_capacity(CELLS + 1),
            classifier,
            density,
        };
        let (node, weight) = (0.5 / 3f64.sqrt(), 0.5);
        let mut sum = (DVec3::ZERO, 0.0);
        s.cumulative.push(sum);
        for i in 0..CELLS {
            let (v0, v1) = (i as f64 / CELLS as f64, (i + 1) as f64 / CELLS as f64);
            let (a, b) = (v0.max(window[0]), v1.min(window[1]));
            if a < b {
                let (mid, half) = (0.5 * (a + b), b - a);
                for x in [mid - node * half, mid + node * half] {
                    let (sc, sigma) = s.point(x);
                    sum.0 += weight * half * sc;
                    sum.1 += weight * half * sigma;
                }
            }
            s.cumulative.push(sum);
        }
        s
    }

    /// (σ·c, σ) at value v.
    pub fn point(&self, v: f64) -> (DVec3, f64) {
        let (rgb, a) = self.classifier.at(v);
        let sigma = match self.density {
            Some(d) => a * d,
            None => -(1.0 - a).ln(),
        };
        let sigma = if sigma.is_nan() {
            0.0
        } else {
            sigma.clamp(0.0, SIGMA_MAX)
        };
        (rgb * sigma, sigma)
    }

    fn integral(&self, v: f64) -> (DVec3, f64) {
        let u = v.clamp(0.0, 1.0) * CELLS as f64;
        let i = (u as usize).min(CELLS - 1);
        let f = u - i as f64;
        let (lo, hi) = (self.cumulative[i], self.cumulative[i + 1]);
        (lo.0.lerp(hi.0, f), lo.1 + (hi.1 - lo.1) * f)
    }

    /// The segment from value `va` to `vb`: its mean extinction σ̄ and colour c̄ (zero when σ̄ is).
    pub fn mean(&self, va: f64, vb: f64) -> (f64, DVec3) {
        let (sc, sigma) = if (vb - va).abs() < 1e-7 {
            self.point(0.5 * (va + vb))
        } else {
            let ((ka, ta), (kb, tb)) = (self.integral(va), self.integral(vb));
            ((kb - ka) / (vb - va), (tb - ta) / (vb - va))
        };
        if sigma <= 0.0 {
            return (0.0, DVec3::ZERO);
        }
        (sigma, (sc / sigma).clamp(DVec3::ZERO, DVec3::ONE))
    }
}
