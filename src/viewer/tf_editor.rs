//! The transfer-function editor: the opacity curve over a log-scale histogram of the volume's values, with
//! control points added by clicking, moved by dragging and deleted by right-clicking. The point maths is plain
//! functions (unit-tested); `editor` draws and handles input with egui.

use crate::tf::{bake, linear_to_srgb, lookup, Classification, TfUnits, TransferFunction};
use egui::{Color32, Pos2, Rect, Sense, Stroke};

/// Counts of normalised values in `bins` equal bins over [0, 1] (NaN skipped).
pub fn histogram(values: impl Iterator<Item = f64>, bins: usize) -> Vec<u64> {
    let mut h = vec![0u64; bins.max(1)];
    for v in values {
        if v.is_finite() {
            let i = ((v.clamp(0.0, 1.0) * bins as f64) as usize).min(bins - 1);
            h[i] += 1;
        }
    }
    h
}

/// A control point's x in normalised units for display, and back.
pub fn to_normalized(tf: &TransferFunction, x: f32, range: [f64; 2]) -> f32 {
    match tf.units {
        TfUnits::Normalized => x,
        TfUnits::Data => ((x as f64 - range[0]) / (range[1] - range[0]).max(f64::MIN_POSITIVE)) as f32,
    }
}

pub fn from_normalized(tf: &TransferFunction, u: f32, range: [f64; 2]) -> f32 {
    match tf.units {
        TfUnits::Normalized => u.clamp(0.0, 1.0),
        TfUnits::Data => (range[0] + u.clamp(0.0, 1.0) as f64 * (range[1] - range[0])) as f32,
    }
}

/// Inserts a point at normalised `u` with opacity `a`, keeping the points sorted; returns its index.
pub fn insert_point(tf: &mut TransferFunction, u: f32, a: f32, range: [f64; 2]) -> usize {
    let x = from_normalized(tf, u, range);
    let i = tf.opacity.partition_point(|p| p[0] < x);
    tf.opacity.insert(i, [x, a.clamp(0.0, 1.0)]);
    i
}

/// Moves point `i` to normalised `u`, opacity `a`, between its neighbours (points never cross).
pub fn move_point(tf: &mut TransferFunction, i: usize, u: f32, a: f32, range: [f64; 2]) {
    let mut x = from_normalized(tf, u, range);
    if i > 0 {
        x = x.max(tf.opacity[i - 1][0]);
    }
    if i + 1 < tf.opacity.len() {
        x = x.min(tf.opacity[i + 1][0]);
    }
    tf.opacity[i] = [x, a.clamp(0.0, 1.0)];
}

/// Removes point `i` unless it is the last one.
pub fn delete_point(tf: &mut TransferFunction, i: usize) -> bool {
    if tf.opacity.len() > 1 && i < tf.opacity.len() {
        tf.opacity.remove(i);
        true
    } else {
        false
    }
}

/// The index of the point nearest `pos` within `radius` (screen units), given each point's screen position.
pub fn nearest(points: &[Pos2], pos: Pos2, radius: f32) -> Option<usize> {
    points
        .iter()
        .enumerate()
        .map(|(i, p)| (i, p.distance(pos)))
        .filter(|(_, d)| *d <= radius)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// Draws the editor; returns true when the transfer function changed. `dragging` keeps the point being dragged
/// between frames.
pub fn editor(
    ui: &mut egui::Ui,
    tf: &mut TransferFunction,
    window: [f32; 2],
    range: [f64; 2],
    histogram: &[u64],
    dragging: &mut Option<usize>,
) -> bool {
    let width = ui.available_width();
    let (rect, response) = ui.allocate_exact_size(egui::vec2(width, 130.0), Sense::click_and_drag());
    let plot = Rect::from_min_max(rect.min, Pos2::new(rect.max.x, rect.max.y - 14.0));
    let painter = ui.painter_at(rect);
    painter.rect_filled(plot, 2.0, Color32::from_gray(20));

    // Log-scale histogram: bar height ∝ ln(1 + count).
    let max = histogram.iter().copied().max().unwrap_or(0).max(1) as f32;
    let n = histogram.len().max(1) as f32;
    for (i, &count) in histogram.iter().enumerate() {
        let h = (1.0 + count as f32).ln() / (1.0 + max).ln() * plot.height();
        let x0 = egui::lerp(plot.left()..=plot.right(), i as f32 / n);
        let x1 = egui::lerp(plot.left()..=plot.right(), (i + 1) as f32 / n);
        painter.rect_filled(
            Rect::from_min_max(Pos2::new(x0, plot.bottom() - h), Pos2::new(x1, plot.bottom())),
            0.0,
            Color32::from_gray(60),
        );
    }

    // The colours of the baked table (at full opacity) as a strip under the plot.
    let lut = bake(&Classification::Function(tf.clone()), window, range);
    let strip = Rect::from_min_max(Pos2::new(rect.left(), plot.bottom() + 2.0), rect.max);
    let steps = 96;
    for i in 0..steps {
        let v = (i as f32 + 0.5) / steps as f32;
        // Outside the window nothing is shown (the table repeats the window's edges there for interpolation).
        let e = if (window[0]..=window[1]).contains(&v) {
            lookup(&lut, v)
        } else {
            [0.0; 4]
        };
        let c = |x: f32| (linear_to_srgb(x.clamp(0.0, 1.0)) * 255.0).round() as u8;
        let x0 = egui::lerp(strip.left()..=strip.right(), i as f32 / steps as f32);
        let x1 = egui::lerp(strip.left()..=strip.right(), (i + 1) as f32 / steps as f32);
        painter.rect_filled(
            Rect::from_min_max(Pos2::new(x0, strip.top()), Pos2::new(x1, strip.bottom())),
            0.0,
            Color32::from_rgb(c(e[0]), c(e[1]), c(e[2])),
        );
    }

    let to_screen = |u: f32, a: f32| {
        Pos2::new(
            egui::lerp(plot.left()..=plot.right(), u),
            egui::lerp(plot.bottom()..=plot.top(), a),
        )
    };
    let from_screen = |p: Pos2| {
        (
            ((p.x - plot.left()) / plot.width()).clamp(0.0, 1.0),
            ((plot.bottom() - p.y) / plot.height()).clamp(0.0, 1.0),
        )
    };
    let mut changed = false;
    let screen_points = |tf: &TransferFunction| -> Vec<Pos2> {
        tf.opacity
            .iter()
            .map(|p| to_screen(to_normalized(tf, p[0], range), p[1]))
            .collect()
    };

    if let Some(pos) = response.interact_pointer_pos() {
        let (u, a) = from_screen(pos);
        if response.drag_started_by(egui::PointerButton::Primary) {
            *dragging = nearest(&screen_points(tf), pos, 10.0).or_else(|| {
                changed = true;
                Some(insert_point(tf, u, a, range))
            });
        }
        if response.dragged_by(egui::PointerButton::Primary) {
            if let Some(i) = *dragging {
                if i < tf.opacity.len() {
                    move_point(tf, i, u, a, range);
                    changed = true;
                }
            }
        }
        if response.clicked_by(egui::PointerButton::Primary) && nearest(&screen_points(tf), pos, 10.0).is_none() {
            insert_point(tf, u, a, range);
            changed = true;
        }
        if response.clicked_by(egui::PointerButton::Secondary) {
            if let Some(i) = nearest(&screen_points(tf), pos, 10.0) {
                changed |= delete_point(tf, i);
            }
        }
    }
    if response.drag_stopped() {
        *dragging = None;
    }

    let points = screen_points(tf);
    let mut line = vec![Pos2::new(plot.left(), points[0].y)];
    line.extend(points.iter().copied());
    line.push(Pos2::new(plot.right(), points[points.len() - 1].y));
    painter.add(egui::Shape::line(
        line,
        Stroke::new(1.5, Color32::from_rgb(240, 240, 240)),
    ));
    for p in &points {
        painter.circle_filled(*p, 4.0, Color32::from_rgb(255, 200, 60));
    }
    if changed {
        tf.name = "custom".into();
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tf(units: TfUnits) -> TransferFunction {
        TransferFunction {
            name: "t".into(),
            units,
            colors: vec![],
            colormap: Default::default(),
            opacity: vec![[0.2, 0.0], [0.8, 0.5]],
        }
    }

    #[test]
    fn points_stay_sorted_and_between_neighbours() {
        let mut t = tf(TfUnits::Normalized);
        let i = insert_point(&mut t, 0.5, 0.3, [0.0, 1.0]);
        assert_eq!(i, 1);
        assert_eq!(t.opacity, vec![[0.2, 0.0], [0.5, 0.3], [0.8, 0.5]]);
        move_point(&mut t, 1, 0.95, 1.4, [0.0, 1.0]);
        assert_eq!(
            t.opacity[1],
            [0.8, 1.0],
            "clamped to the right neighbour and to opacity 1"
        );
        assert!(delete_point(&mut t, 0));
        assert!(delete_point(&mut t, 0));
        assert!(!delete_point(&mut t, 0), "the last point stays");
        t.validate().unwrap();
    }

    #[test]
    fn data_units_convert_through_the_range() {
        let mut t = tf(TfUnits::Data);
        t.opacity = vec![[-1024.0, 0.0], [2986.0, 1.0]];
        let range = [-1024.0, 2986.0];
        assert!((to_normalized(&t, 981.0, range) - 0.5).abs() < 1e-6);
        insert_point(&mut t, 0.5, 0.2, range);
        assert!((t.opacity[1][0] - 981.0).abs() < 1e-3);
    }

    #[test]
    fn histogram_and_picking() {
        let h = histogram([0.0, 0.1, 0.99, 1.0, f64::NAN].into_iter(), 4);
        assert_eq!(h, vec![2, 0, 0, 2]);
        let pts = [Pos2::new(0.0, 0.0), Pos2::new(10.0, 0.0)];
        assert_eq!(nearest(&pts, Pos2::new(8.0, 1.0), 5.0), Some(1));
        assert_eq!(nearest(&pts, Pos2::new(50.0, 1.0), 5.0), None);
    }
}
