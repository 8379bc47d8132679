//! The transfer-function editor: the opacity curve over a log-scale histogram of the volume's values with a
//! data-unit axis ([`axis`]), and a colour strip under it holding the colour points ([`strip`]); points are added
//! by clicking, moved by dragging and deleted by right-clicking. The point edits are the model's
//! (`model::tf`); this draws and takes the input. [`presets`] adds the preset menu (with "auto (by modality)")
//! and JSON save/load.

pub mod axis;
pub mod presets;
pub mod strip;

use crate::transfer::function::TransferFunction;
use crate::viewer::model::tf::{delete_point, insert_point, move_point, to_normalized};
use crate::viewer::widgets::rects;
use egui::{Color32, Pos2, Rect, Sense, Stroke};
use strip::StripState;

/// The most histogram bars the editor draws (about one per pixel and a half of its plot).
const BARS: usize = 256;

/// Height of the opacity plot, the data-unit axis under it and the colour strip under that (points).
const PLOT_HEIGHT: f32 = 110.0;
const AXIS_HEIGHT: f32 = 14.0;
const STRIP_HEIGHT: f32 = 18.0;
/// How near (points) a click must be to a point to pick it.
const PICK_RADIUS: f32 = 10.0;

/// `histogram` with runs of neighbouring bins summed, so that it has at most `bars` bins (the same counts when it
/// already has): 1024 bins fold into exactly the 256-bin histogram of the same values.
pub fn fold(histogram: &[u64], bars: usize) -> Vec<u64> {
    let run = histogram.len().div_ceil(bars.max(1)).max(1);
    histogram.chunks(run).map(|c| c.iter().sum()).collect()
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

/// Draws the editor; returns true when the transfer function changed. `dragging` keeps the opacity point being
/// dragged between frames. The axis is in data units without a unit name: [`editor_with_unit`] names it.
pub fn editor(
    ui: &mut egui::Ui,
    tf: &mut TransferFunction,
    window: [f32; 2],
    range: [f64; 2],
    histogram: &[u64],
    dragging: &mut Option<usize>,
) -> bool {
    editor_with_unit(ui, tf, window, range, histogram, dragging, None)
}

/// The editor: the opacity curve over the log-scale histogram (click: add, drag: move, right-click: delete), a
/// data-unit axis (`unit`, e.g. "HU", after the last label), and the colour strip with the colour points as
/// markers (click on the strip: add a point with the colour already there; drag a marker: move it; right-click:
/// delete; click a marker: its colour picker opens under the strip). Returns true when `tf` changed.
pub fn editor_with_unit(
    ui: &mut egui::Ui,
    tf: &mut TransferFunction,
    window: [f32; 2],
    range: [f64; 2],
    histogram: &[u64],
    dragging: &mut Option<usize>,
    unit: Option<&str>,
) -> bool {
    let width = ui.available_width();
    let (rect, _) = ui.allocate_exact_size(
        egui::vec2(width, PLOT_HEIGHT + AXIS_HEIGHT + STRIP_HEIGHT),
        Sense::hover(),
    );
    let plot = Plot(Rect::from_min_size(rect.min, egui::vec2(width, PLOT_HEIGHT)));
    let axis = Rect::from_min_size(Pos2::new(rect.left(), plot.0.bottom()), egui::vec2(width, AXIS_HEIGHT));
    let strip = Rect::from_min_max(Pos2::new(rect.left(), axis.bottom()), rect.max);
    let id = ui.id().with("tf_editor");
    let response = ui.interact(plot.0, id.with("plot"), Sense::click_and_drag());
    let strip_response = ui.interact(strip, id.with("strip"), Sense::click_and_drag());
    rects::log("tf-plot", plot.0);
    rects::log("tf-strip", strip);
    let painter = ui.painter_at(rect);
    painter.rect_filled(plot.0, 2.0, Color32::from_gray(20));
    paint_histogram(&painter, plot.0, histogram);
    axis::paint_axis(&painter, axis, range, unit);

    let mut changed = false;
    let mut strip_state: StripState = ui.data(|d| d.get_temp(id)).unwrap_or_default();
    changed |= strip::colour_strip_input(tf, window, range, strip, &strip_response, &mut strip_state);
    strip::paint_strip(&painter, tf, window, range, strip, strip_state.selected);
    changed |= opacity_input(ui.ctx(), tf, range, plot, &response, dragging);
    paint_curve(&painter, &plot.screen_points(tf, range), plot.0);
    changed |= strip::colour_picker(ui, tf, range, &mut strip_state);
    ui.data_mut(|d| d.insert_temp(id, strip_state));
    if changed {
        tf.name = "custom".into();
    }
    changed
}

/// The opacity plot's rect: normalised value across, opacity up.
#[derive(Clone, Copy)]
struct Plot(Rect);

impl Plot {
    fn to_screen(self, u: f32, a: f32) -> Pos2 {
        Pos2::new(
            egui::lerp(self.0.left()..=self.0.right(), u),
            egui::lerp(self.0.bottom()..=self.0.top(), a),
        )
    }

    /// The (normalised value, opacity) under screen point `p`, clamped to the plot.
    fn value_at(self, p: Pos2) -> (f32, f32) {
        (
            ((p.x - self.0.left()) / self.0.width()).clamp(0.0, 1.0),
            ((self.0.bottom() - p.y) / self.0.height()).clamp(0.0, 1.0),
        )
    }

    fn screen_points(self, tf: &TransferFunction, range: [f64; 2]) -> Vec<Pos2> {
        tf.opacity
            .iter()
            .map(|p| self.to_screen(to_normalized(tf, p[0], range), p[1]))
            .collect()
    }
}

/// Log-scale histogram: bar height ∝ ln(1 + count), at most [`BARS`] bars.
fn paint_histogram(painter: &egui::Painter, plot: Rect, histogram: &[u64]) {
    let histogram = &fold(histogram, BARS);
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
}

/// The opacity plot's clicks and drags; true when `tf` changed.
fn opacity_input(
    ctx: &egui::Context,
    tf: &mut TransferFunction,
    range: [f64; 2],
    plot: Plot,
    response: &egui::Response,
    dragging: &mut Option<usize>,
) -> bool {
    let mut changed = false;
    if let Some(pos) = response.interact_pointer_pos() {
        let (u, a) = plot.value_at(pos);
        if response.drag_started_by(egui::PointerButton::Primary) {
            // The point under the press, not under the pointer now: egui starts a drag only once the pointer has
            // moved, and in a slow frame it may have moved past PICK_RADIUS (a fast drag then added a point
            // instead of moving one; CI's viewer::tf failure).
            let origin = press_origin(ctx, pos);
            *dragging = nearest(&plot.screen_points(tf, range), origin, PICK_RADIUS).or_else(|| {
                changed = true;
                let (u0, a0) = plot.value_at(origin);
                Some(insert_point(tf, u0, a0, range))
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
        let hit = |tf: &TransferFunction| nearest(&plot.screen_points(tf, range), pos, PICK_RADIUS);
        if response.clicked_by(egui::PointerButton::Primary) && hit(tf).is_none() {
            insert_point(tf, u, a, range);
            changed = true;
        }
        if response.clicked_by(egui::PointerButton::Secondary) {
            if let Some(i) = hit(tf) {
                changed |= delete_point(tf, i);
            }
        }
    }
    if response.drag_stopped() {
        *dragging = None;
    }
    changed
}

/// The opacity curve (held flat beyond its first and last points) and its points.
fn paint_curve(painter: &egui::Painter, points: &[Pos2], plot: Rect) {
    if let (Some(first), Some(last)) = (points.first(), points.last()) {
        let mut line = vec![Pos2::new(plot.left(), first.y)];
        line.extend(points.iter().copied());
        line.push(Pos2::new(plot.right(), last.y));
        painter.add(egui::Shape::line(
            line,
            Stroke::new(1.5, Color32::from_rgb(240, 240, 240)),
        ));
    }
    for p in points {
        painter.circle_filled(*p, 4.0, Color32::from_rgb(255, 200, 60));
    }
}

/// Where the pointer was pressed (`fallback` when egui no longer knows).
fn press_origin(ctx: &egui::Context, fallback: Pos2) -> Pos2 {
    ctx.input(|i| i.pointer.press_origin()).unwrap_or(fallback)
}

fn to_u8(c: f32) -> u8 {
    (c.clamp(0.0, 1.0) * 255.0).round() as u8
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transfer::function::TfUnits;

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
    fn folding_1024_bins_gives_the_256_bin_histogram() {
        let values: Vec<f64> = (0..5000)
            .map(|i| ((i * 7919) % 5000) as f64 / 4999.0)
            .chain([f64::NAN])
            .collect();
        let fine = crate::transfer::auto::histogram(values.iter().copied(), 1024);
        assert_eq!(
            fold(&fine, 256),
            crate::transfer::auto::histogram(values.iter().copied(), 256)
        );
        assert_eq!(fold(&[1, 2, 3], 256), vec![1, 2, 3]);
        assert_eq!(fold(&[1, 2, 3, 4, 5], 2), vec![6, 9]);
    }

    /// Runs the editor in a bare egui context, one frame per entry of `frames` (the input events of that frame);
    /// returns the plot's rect.
    fn run_editor(tf: &mut TransferFunction, frames: &[Vec<egui::Event>]) -> Rect {
        let ctx = egui::Context::default();
        let mut plot = Rect::NOTHING;
        let mut dragging = None;
        for (i, events) in [vec![]].iter().chain(frames).enumerate() {
            let input = egui::RawInput {
                screen_rect: Some(Rect::from_min_size(Pos2::ZERO, egui::vec2(400.0, 400.0))),
                time: Some(i as f64 * 0.1),
                events: events.clone(),
                ..Default::default()
            };
            let _ = ctx.run_ui(input, |ui| {
                plot = Rect::from_min_size(ui.cursor().min, egui::vec2(ui.available_width(), PLOT_HEIGHT));
                editor(ui, tf, [0.0, 1.0], [0.0, 1.0], &[1; 16], &mut dragging);
            });
        }
        plot
    }

    fn button(pos: Pos2, button: egui::PointerButton, pressed: bool) -> egui::Event {
        egui::Event::PointerButton {
            pos,
            button,
            pressed,
            modifiers: Default::default(),
        }
    }

    #[test]
    fn a_drag_whose_motion_arrives_at_once_moves_the_point_pressed() {
        // CI's viewer::tf: the press, then the whole 24-point motion in the next frame. egui starts the drag only
        // there, with the pointer 24 points from the point, beyond PICK_RADIUS: the drag must still take the point
        // under the press (it added a new point at the pointer instead).
        let mut t = tf(TfUnits::Normalized);
        let plot = run_editor(&mut t.clone(), &[]);
        let at = |p: [f32; 2]| Pos2::new(plot.left() + p[0] * plot.width(), plot.bottom() - p[1] * plot.height());
        let (start, end) = (at(t.opacity[1]), at(t.opacity[1]) - egui::vec2(0.0, 24.0));
        let primary = egui::PointerButton::Primary;
        run_editor(
            &mut t,
            &[
                vec![egui::Event::PointerMoved(start), button(start, primary, true)],
                vec![egui::Event::PointerMoved(end)],
                vec![button(end, primary, false)],
            ],
        );
        assert_eq!(t.opacity.len(), 2, "no point added: {:?}", t.opacity);
        assert_eq!(t.opacity[1][0], 0.8);
        assert!(
            (t.opacity[1][1] - (0.5 + 24.0 / plot.height())).abs() < 1e-4,
            "{:?}",
            t.opacity
        );
    }

    #[test]
    fn picking_finds_the_nearest_point_within_reach() {
        let pts = [Pos2::new(0.0, 0.0), Pos2::new(10.0, 0.0)];
        assert_eq!(nearest(&pts, Pos2::new(8.0, 1.0), 5.0), Some(1));
        assert_eq!(nearest(&pts, Pos2::new(50.0, 1.0), 5.0), None);
    }
}
