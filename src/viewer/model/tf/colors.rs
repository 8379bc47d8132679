//! Colour control points of a transfer function, edited on the strip under the opacity curve: plain functions
//! (unit-tested) that keep the points sorted and valid. Positions come in normalised units `u` (fractions of the
//! data range, as the strip is laid out) and are stored in the transfer function's own units.

use super::{from_normalized, to_normalized};
use crate::transfer::function::{colormap_at, piecewise, TransferFunction};

/// Points a colormap is turned into when its transfer function gets its first colour point: 17 samples over the
/// window follow every listed colormap within a few 8-bit steps.
pub const COLORMAP_SAMPLES: usize = 17;

/// The sRGB colour the transfer function gives normalised value `u` (its colour points, or its colormap over
/// `window`), as `function::bake` defines it.
pub fn color_at(tf: &TransferFunction, u: f32, window: [f32; 2], range: [f64; 2]) -> [f32; 3] {
    if tf.colors.is_empty() {
        let [lo, hi] = window;
        let c = (u.clamp(lo, hi) - lo) / (hi - lo).max(f32::MIN_POSITIVE);
        colormap_at(tf.colormap, c)
    } else {
        let points: Vec<(f32, [f32; 3])> = tf.colors.iter().map(|p| (p[0], [p[1], p[2], p[3]])).collect();
        piecewise(&points, from_normalized(tf, u, range))
    }
}

/// Replaces a colormap by colour points sampling it over the window, so that adding a point keeps the look.
pub fn colormap_to_points(tf: &mut TransferFunction, window: [f32; 2], range: [f64; 2]) {
    if !tf.colors.is_empty() {
        return;
    }
    let [lo, hi] = window;
    tf.colors = (0..COLORMAP_SAMPLES)
        .map(|k| {
            let u = lo + (hi - lo) * k as f32 / (COLORMAP_SAMPLES - 1) as f32;
            let [r, g, b] = color_at(tf, u, window, range);
            [from_normalized(tf, u, range), r, g, b]
        })
        .collect();
    tf.colors.dedup_by(|a, b| a[0] <= b[0]);
}

/// Adds a colour point at normalised `u` with the colour the transfer function already has there (so the image
/// does not change until the point is moved or recoloured); returns its index.
pub fn insert_color_point(tf: &mut TransferFunction, u: f32, window: [f32; 2], range: [f64; 2]) -> usize {
    let rgb = color_at(tf, u, window, range);
    colormap_to_points(tf, window, range);
    let x = from_normalized(tf, u, range);
    let i = tf.colors.partition_point(|p| p[0] < x);
    tf.colors.insert(i, [x, rgb[0], rgb[1], rgb[2]]);
    i
}

/// Moves colour point `i` to normalised `u`, between its neighbours (points never cross).
pub fn move_color_point(tf: &mut TransferFunction, i: usize, u: f32, range: [f64; 2]) {
    if i >= tf.colors.len() {
        return;
    }
    let mut x = from_normalized(tf, u, range);
    if i > 0 {
        x = x.max(tf.colors[i - 1][0]);
    }
    if i + 1 < tf.colors.len() {
        x = x.min(tf.colors[i + 1][0]);
    }
    tf.colors[i][0] = x;
}

/// Removes colour point `i`. Removing the last one is allowed: the transfer function's colormap takes over.
pub fn delete_color_point(tf: &mut TransferFunction, i: usize) -> bool {
    if i < tf.colors.len() {
        tf.colors.remove(i);
        true
    } else {
        false
    }
}

/// Sets colour point `i`'s sRGB colour (clamped to [0, 1]).
pub fn set_color(tf: &mut TransferFunction, i: usize, rgb: [f32; 3]) {
    if let Some(p) = tf.colors.get_mut(i) {
        p[1..].copy_from_slice(&rgb.map(|c| c.clamp(0.0, 1.0)));
    }
}

/// The colour points' normalised positions (for drawing and hit-testing on the strip).
pub fn color_positions(tf: &TransferFunction, range: [f64; 2]) -> Vec<f32> {
    tf.colors.iter().map(|p| to_normalized(tf, p[0], range)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transfer::function::TfUnits;
    use crate::transfer::Colormap;

    fn tf(units: TfUnits, colors: Vec<[f32; 4]>) -> TransferFunction {
        TransferFunction {
            name: "t".into(),
            units,
            colors,
            colormap: Colormap::Grayscale,
            opacity: vec![[0.0, 0.1]],
        }
    }

    #[test]
    fn inserting_keeps_the_colour_and_the_order() {
        let range = [-1000.0, 3000.0];
        let mut t = tf(TfUnits::Data, vec![[0.0, 0.0, 0.0, 0.0], [2000.0, 1.0, 0.5, 0.0]]);
        // u = 0.375 is 500 data units: a quarter of the way between the points.
        let i = insert_color_point(&mut t, 0.375, [0.0, 1.0], range);
        assert_eq!(i, 1);
        assert_eq!(t.colors[1], [500.0, 0.25, 0.125, 0.0]);
        move_color_point(&mut t, 1, 0.99, range);
        assert_eq!(t.colors[1][0], 2000.0, "stopped at the right neighbour");
        move_color_point(&mut t, 1, 0.0, range);
        assert_eq!(t.colors[1][0], 0.0, "stopped at the left neighbour");
        set_color(&mut t, 1, [2.0, 0.2, -1.0]);
        assert_eq!(t.colors[1], [0.0, 1.0, 0.2, 0.0]);
        t.validate().unwrap();
        assert!(delete_color_point(&mut t, 0));
        assert!(!delete_color_point(&mut t, 5));
        assert!(delete_color_point(&mut t, 0) && delete_color_point(&mut t, 0));
        assert!(t.colors.is_empty(), "all may go: the colormap takes over");
        t.validate().unwrap();
    }

    #[test]
    fn the_first_point_turns_the_colormap_into_points() {
        let mut t = tf(TfUnits::Normalized, vec![]);
        t.colormap = Colormap::Viridis;
        let window = [0.2, 0.6];
        let before: Vec<[f32; 3]> = (0..=20)
            .map(|k| color_at(&t, k as f32 / 20.0, window, [0.0, 1.0]))
            .collect();
        insert_color_point(&mut t, 0.33, window, [0.0, 1.0]);
        assert_eq!(t.colors.len(), COLORMAP_SAMPLES + 1);
        t.validate().unwrap();
        for (k, want) in before.iter().enumerate() {
            let got = color_at(&t, k as f32 / 20.0, window, [0.0, 1.0]);
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() < 0.02,
                    "u {}: {got:?} vs {want:?}",
                    k as f32 / 20.0
                );
            }
        }
    }

    #[test]
    fn colour_positions_are_normalised() {
        let t = tf(TfUnits::Data, vec![[-1000.0, 0.0, 0.0, 0.0], [1000.0, 1.0, 1.0, 1.0]]);
        assert_eq!(color_positions(&t, [-1000.0, 3000.0]), vec![0.0, 0.5]);
    }
}
