//! A colour bar painted into a rect of the 3D view with egui: the same colours, opacity plot and ticks as the
//! PNG's colour bar (`crate::transfer::colorbar`), labels in egui's font.

use crate::transfer::colorbar::{colour_at, nice_ticks, tick_label};
use crate::transfer::function::{bake, Classification};
use egui::{Align2, Color32, FontId, Pos2, Rect, Stroke};

/// Paints the colour bar of `classification` over `window` (normalised) of data `range` into `rect`: the bar
/// at the left (top = the window's upper value), the opacity (relative to its largest) as a thin plot left of
/// it, ticks and labels at nice data values to its right, `unit` above.
pub fn paint_colorbar(
    painter: &egui::Painter,
    rect: Rect,
    classification: &Classification,
    window: [f32; 2],
    range: [f64; 2],
    unit: Option<&str>,
) {
    let text = Color32::from_gray(230);
    let font = FontId::proportional(11.0);
    painter.rect_filled(rect, 3.0, Color32::from_black_alpha(140));
    let inner = rect.shrink(4.0);
    let top = inner.top() + 14.0;
    let bottom = inner.bottom() - 6.0;
    if bottom <= top + 4.0 {
        return;
    }
    let plot = [inner.left(), inner.left() + 6.0];
    let bar = [plot[1] + 1.0, plot[1] + 15.0];
    let lut = bake(classification, window, range);
    let rows = 128;
    let values: Vec<([u8; 3], f32)> = (0..rows)
        .map(|k| {
            let t = (k as f32 + 0.5) / rows as f32;
            colour_at(&lut, window[1] - t * (window[1] - window[0]))
        })
        .collect();
    let max_alpha = values.iter().map(|v| v.1).fold(0.0f32, f32::max);
    for (k, (rgb, alpha)) in values.iter().enumerate() {
        let y0 = egui::lerp(top..=bottom, k as f32 / rows as f32);
        let y1 = egui::lerp(top..=bottom, (k + 1) as f32 / rows as f32);
        painter.rect_filled(
            Rect::from_x_y_ranges(bar[0]..=bar[1], y0..=y1),
            0.0,
            Color32::from_rgb(rgb[0], rgb[1], rgb[2]),
        );
        if max_alpha > 0.0 {
            let w = alpha / max_alpha * (plot[1] - plot[0]);
            painter.rect_filled(
                Rect::from_x_y_ranges(plot[1] - w..=plot[1], y0..=y1),
                0.0,
                Color32::from_gray(200),
            );
        }
    }
    let [min, max] = range;
    let data = window.map(|w| min + f64::from(w) * (max - min));
    let max_count = ((bottom - top) / 28.0).max(1.0) as usize;
    let (ticks, step) = nice_ticks(data[0], data[1], max_count);
    for t in ticks {
        let f = if data[1] > data[0] {
            ((data[1] - t) / (data[1] - data[0])) as f32
        } else {
            0.5
        };
        let y = egui::lerp(top..=bottom, f);
        painter.line_segment(
            [Pos2::new(bar[1], y), Pos2::new(bar[1] + 4.0, y)],
            Stroke::new(1.0, text),
        );
        painter.text(
            Pos2::new(bar[1] + 6.0, y),
            Align2::LEFT_CENTER,
            tick_label(t, step),
            font.clone(),
            text,
        );
    }
    if let Some(unit) = unit {
        painter.text(Pos2::new(bar[0], inner.top()), Align2::LEFT_TOP, unit, font, text);
    }
}
