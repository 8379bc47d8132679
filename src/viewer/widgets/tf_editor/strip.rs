//! The colour strip under the opacity plot: the baked colours at full opacity, the colour points as markers
//! (click: add a point with the colour already there; drag: move; right-click: delete; click a marker: its colour
//! picker opens under the strip).

use super::{press_origin, to_u8, PICK_RADIUS};
use crate::transfer::function::{bake, linear_to_srgb, lookup, Classification, TransferFunction};
use crate::viewer::model::tf::colors::{
    color_positions, delete_color_point, insert_color_point, move_color_point, set_color,
};
use egui::{Color32, Pos2, Rect, Stroke};

/// What the strip keeps between frames: the colour point being dragged and the one whose picker is open. Kept in
/// egui's memory under the editor's id, so the editor's signature stays that of the opacity plot alone.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct StripState {
    pub(super) dragging: Option<usize>,
    pub(super) selected: Option<usize>,
}

/// The index of the marker nearest `x` within `radius` along the strip (screen units).
pub fn nearest_on_strip(xs: &[f32], x: f32, radius: f32) -> Option<usize> {
    xs.iter()
        .enumerate()
        .map(|(i, p)| (i, (p - x).abs()))
        .filter(|(_, d)| *d <= radius)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// The colour strip's clicks and drags; true when `tf` changed.
pub(super) fn colour_strip_input(
    tf: &mut TransferFunction,
    window: [f32; 2],
    range: [f64; 2],
    strip: Rect,
    response: &egui::Response,
    state: &mut StripState,
) -> bool {
    let Some(pos) = response.interact_pointer_pos() else {
        if response.drag_stopped() {
            state.dragging = None;
        }
        return false;
    };
    let u = ((pos.x - strip.left()) / strip.width()).clamp(0.0, 1.0);
    let markers: Vec<f32> = color_positions(tf, range)
        .iter()
        .map(|&p| egui::lerp(strip.left()..=strip.right(), p))
        .collect();
    let hit = nearest_on_strip(&markers, pos.x, PICK_RADIUS);
    let mut changed = false;
    if response.drag_started_by(egui::PointerButton::Primary) {
        // The marker under the press (see the opacity plot's drag).
        state.dragging = nearest_on_strip(&markers, press_origin(&response.ctx, pos).x, PICK_RADIUS);
    }
    if response.dragged_by(egui::PointerButton::Primary) {
        if let Some(i) = state.dragging {
            move_color_point(tf, i, u, range);
            changed = true;
        }
    }
    if response.drag_stopped() {
        state.dragging = None;
    }
    if response.clicked_by(egui::PointerButton::Primary) {
        state.selected = Some(match hit {
            Some(i) => i,
            None => {
                changed = true;
                insert_color_point(tf, u, window, range)
            }
        });
    }
    if response.clicked_by(egui::PointerButton::Secondary) {
        if let Some(i) = hit {
            changed |= delete_color_point(tf, i);
            state.selected = None;
        }
    }
    changed
}

/// The baked table's colours (at full opacity) along the strip, and the colour points as markers.
pub(super) fn paint_strip(
    painter: &egui::Painter,
    tf: &TransferFunction,
    window: [f32; 2],
    range: [f64; 2],
    strip: Rect,
    selected: Option<usize>,
) {
    let lut = bake(&Classification::Function(tf.clone()), window, range);
    let steps = 96;
    for i in 0..steps {
        let v = (i as f32 + 0.5) / steps as f32;
        // Outside the window nothing is shown (the table repeats the window's edges there for interpolation).
        let e = if (window[0]..=window[1]).contains(&v) {
            lookup(&lut, v)
        } else {
            [0.0; 4]
        };
        let c = |x: f32| to_u8(linear_to_srgb(x));
        let x0 = egui::lerp(strip.left()..=strip.right(), i as f32 / steps as f32);
        let x1 = egui::lerp(strip.left()..=strip.right(), (i + 1) as f32 / steps as f32);
        painter.rect_filled(
            Rect::from_min_max(Pos2::new(x0, strip.top()), Pos2::new(x1, strip.bottom())),
            0.0,
            Color32::from_rgb(c(e[0]), c(e[1]), c(e[2])),
        );
    }
    for (i, p) in color_positions(tf, range).iter().enumerate() {
        let x = egui::lerp(strip.left()..=strip.right(), *p);
        let fill = Color32::from_rgb(to_u8(tf.colors[i][1]), to_u8(tf.colors[i][2]), to_u8(tf.colors[i][3]));
        let outline = if selected == Some(i) {
            Color32::YELLOW
        } else {
            Color32::WHITE
        };
        let tri = vec![
            Pos2::new(x, strip.top() + 2.0),
            Pos2::new(x - 5.0, strip.bottom() - 1.0),
            Pos2::new(x + 5.0, strip.bottom() - 1.0),
        ];
        painter.add(egui::Shape::convex_polygon(tri, fill, Stroke::new(1.5, outline)));
    }
}

/// The selected colour point's picker (and a button to close it), under the strip; true when `tf` changed.
pub(super) fn colour_picker(
    ui: &mut egui::Ui,
    tf: &mut TransferFunction,
    range: [f64; 2],
    state: &mut StripState,
) -> bool {
    let Some(i) = state.selected.filter(|&i| i < tf.colors.len()) else {
        return false;
    };
    let mut changed = false;
    ui.horizontal(|ui| {
        let p = tf.colors[i];
        ui.label(format!(
            "colour at {}",
            super::axis::value_text(p[0] as f64, tf.units, range)
        ));
        let mut c = Color32::from_rgb(to_u8(p[1]), to_u8(p[2]), to_u8(p[3]));
        if egui::color_picker::color_edit_button_srgba(ui, &mut c, egui::color_picker::Alpha::Opaque).changed() {
            set_color(tf, i, [c.r(), c.g(), c.b()].map(|v| f32::from(v) / 255.0));
            changed = true;
        }
        if ui.small_button("close").clicked() {
            state.selected = None;
        }
    });
    changed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strip_hit_testing() {
        let xs = [10.0, 30.0, 34.0];
        assert_eq!(nearest_on_strip(&xs, 33.0, 6.0), Some(2));
        assert_eq!(nearest_on_strip(&xs, 20.0, 6.0), None);
        assert_eq!(nearest_on_strip(&[], 20.0, 6.0), None);
    }
}
