//! The editor's data-unit axis under the histogram: nice round ticks over the volume's value range (the same
//! tick rule as the colour bar, `colorbar::nice_ticks`), labelled in the data's units.

use crate::transfer::colorbar::{nice_ticks, tick_label};
use crate::transfer::function::TfUnits;
use egui::{Align2, Color32, FontId, Pos2, Rect, Stroke};

/// Least room (points) a tick label gets along the axis.
const LABEL_SPACING: f32 = 56.0;

/// The ticks of an axis `width` points wide over the data range: each tick's position as a fraction of the
/// width and its label.
pub fn axis_ticks(range: [f64; 2], width: f32) -> Vec<(f32, String)> {
    let max_count = (width / LABEL_SPACING).floor().max(1.0) as usize;
    let (ticks, step) = nice_ticks(range[0], range[1], max_count);
    let span = range[1] - range[0];
    ticks
        .into_iter()
        .map(|t| {
            let u = if span > 0.0 {
                ((t - range[0]) / span) as f32
            } else {
                0.5
            };
            (u, tick_label(t, step))
        })
        .collect()
}

/// A control point's x as text in data units (a normalised x is converted through the range).
pub fn value_text(x: f64, units: TfUnits, range: [f64; 2]) -> String {
    let v = match units {
        TfUnits::Data => x,
        TfUnits::Normalized => range[0] + x * (range[1] - range[0]),
    };
    let step = ((range[1] - range[0]).abs() / 1000.0).max(f64::MIN_POSITIVE);
    tick_label(v, 10f64.powf(step.log10().floor()))
}

/// Ticks and labels in `rect`; `unit` ("HU") after the last label.
pub fn paint_axis(painter: &egui::Painter, rect: Rect, range: [f64; 2], unit: Option<&str>) {
    let ticks = axis_ticks(range, rect.width());
    let font = FontId::proportional(10.0);
    let colour = Color32::from_gray(180);
    let count = ticks.len();
    for (k, (u, label)) in ticks.into_iter().enumerate() {
        let x = egui::lerp(rect.left()..=rect.right(), u);
        painter.line_segment(
            [Pos2::new(x, rect.top()), Pos2::new(x, rect.top() + 3.0)],
            Stroke::new(1.0, colour),
        );
        let text = match unit {
            Some(unit) if k + 1 == count => format!("{label} {unit}"),
            _ => label,
        };
        // Labels near the ends are anchored inside the rect so they are not cut off.
        let anchor = if x - rect.left() < 20.0 {
            Align2::LEFT_TOP
        } else if rect.right() - x < 40.0 {
            Align2::RIGHT_TOP
        } else {
            Align2::CENTER_TOP
        };
        painter.text(Pos2::new(x, rect.top() + 2.0), anchor, text, font.clone(), colour);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_in_data_units_over_the_range() {
        let t = axis_ticks([-1024.0, 2986.0], 300.0);
        let labels: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["-1000", "0", "1000", "2000"]);
        assert!((t[1].0 - 1024.0 / 4010.0).abs() < 1e-6);
        let narrow = axis_ticks([0.0, 254.0], 200.0);
        assert_eq!(
            narrow.iter().map(|(_, l)| l.as_str()).collect::<Vec<_>>(),
            ["0", "100", "200"]
        );
        assert_eq!(
            axis_ticks([3.0, 3.0], 100.0).len(),
            1,
            "a flat volume: one tick, no panic"
        );
        assert_eq!(value_text(0.5, TfUnits::Normalized, [-1000.0, 1000.0]), "0");
        assert_eq!(value_text(300.0, TfUnits::Data, [-1024.0, 2986.0]), "300");
    }
}
