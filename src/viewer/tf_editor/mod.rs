//! The transfer-function editor: the opacity curve over a log-scale histogram of the volume's values with a
//! data-unit axis, and a colour strip under it holding the colour points; points are added by clicking, moved by
//! dragging and deleted by right-clicking. The point maths is plain functions (unit-tested, here and in
//! [`colors`]); `editor` draws and handles input with egui. [`panel`] adds the preset menu (with "auto (by
//! modality)") and JSON save/load; [`overlay`] paints a colour bar into a rect of the 3D view.

pub mod axis;
pub mod colors;
pub mod overlay;
pub mod panel;

pub use colors::{
    color_positions, delete_color_point, insert_color_point, move_color_point, nearest_on_strip, set_color,
};
pub use overlay::paint_colorbar;
pub use panel::{panel, TfEditorState};

use crate::transfer::function::{bake, linear_to_srgb, lookup, Classification, TfUnits, TransferFunction};
use egui::{Color32, Pos2, Rect, Sense, Stroke};

/// The most histogram bars the editor draws (about one per pixel and a half of its plot).
const BARS: usize = 256;

/// `histogram` with runs of neighbouring bins summed, so that it has at most `bars` bins (the same counts when it
/// already has): 1024 bins fold into exactly the 256-bin histogram of the same values.
pub fn fold(histogram: &[u64], bars: usize) -> Vec<u64> {
    let run = histogram.len().div_ceil(bars.max(1)).max(1);
    histogram.chunks(run).map(|c| c.iter().sum()).collect()
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

/// What the editor keeps between frames besides the opacity point being dragged: the colour point being dragged
/// and the one whose picker is open. Kept in egui's memory under the editor's id, so [`editor`] keeps its
/// original signature.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct StripState {
    dragging: Option<usize>,
    selected: Option<usize>,
}

/// Height of the opacity plot, the data-unit axis under it and the colour strip under that (points).
const PLOT_HEIGHT: f32 = 110.0;
const AXIS_HEIGHT: f32 = 14.0;
const STRIP_HEIGHT: f32 = 18.0;
/// How near (points) a click must be to a point to pick it.
const PICK_RADIUS: f32 = 10.0;

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
    let plot = Rect::from_min_size(rect.min, egui::vec2(width, PLOT_HEIGHT));
    let axis = Rect::from_min_size(Pos2::new(rect.left(), plot.bottom()), egui::vec2(width, AXIS_HEIGHT));
    let strip = Rect::from_min_max(Pos2::new(rect.left(), axis.bottom()), rect.max);
    let id = ui.id().with("tf_editor");
    let response = ui.interact(plot, id.with("plot"), Sense::click_and_drag());
    let strip_response = ui.interact(strip, id.with("strip"), Sense::click_and_drag());
    crate::viewer::ui::rects::log("tf-plot", plot);
    crate::viewer::ui::rects::log("tf-strip", strip);
    let painter = ui.painter_at(rect);
    painter.rect_filled(plot, 2.0, Color32::from_gray(20));

    // Log-scale histogram: bar height ∝ ln(1 + count), at most BARS bars.
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
    axis::paint_axis(&painter, axis, range, unit);

    let mut changed = false;
    let mut strip_state: StripState = ui.data(|d| d.get_temp(id)).unwrap_or_default();
    changed |= colour_strip_input(tf, window, range, strip, &strip_response, &mut strip_state);
    paint_strip(&painter, tf, window, range, strip, strip_state.selected);

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
    let screen_points = |tf: &TransferFunction| -> Vec<Pos2> {
        tf.opacity
            .iter()
            .map(|p| to_screen(to_normalized(tf, p[0], range), p[1]))
            .collect()
    };

    if let Some(pos) = response.interact_pointer_pos() {
        let (u, a) = from_screen(pos);
        if response.drag_started_by(egui::PointerButton::Primary) {
            // The point under the press, not under the pointer now: egui starts a drag only once the pointer has
            // moved, and in a slow frame it may have moved past PICK_RADIUS (a fast drag then added a point
            // instead of moving one; CI's viewer_tf failure).
            let origin = press_origin(ui.ctx(), pos);
            *dragging = nearest(&screen_points(tf), origin, PICK_RADIUS).or_else(|| {
                changed = true;
                let (u0, a0) = from_screen(origin);
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
        if response.clicked_by(egui::PointerButton::Primary) && nearest(&screen_points(tf), pos, PICK_RADIUS).is_none()
        {
            insert_point(tf, u, a, range);
            changed = true;
        }
        if response.clicked_by(egui::PointerButton::Secondary) {
            if let Some(i) = nearest(&screen_points(tf), pos, PICK_RADIUS) {
                changed |= delete_point(tf, i);
            }
        }
    }
    if response.drag_stopped() {
        *dragging = None;
    }

    let points = screen_points(tf);
    if let (Some(first), Some(last)) = (points.first(), points.last()) {
        let mut line = vec![Pos2::new(plot.left(), first.y)];
        line.extend(points.iter().copied());
        line.push(Pos2::new(plot.right(), last.y));
        painter.add(egui::Shape::line(
            line,
            Stroke::new(1.5, Color32::from_rgb(240, 240, 240)),
        ));
    }
    for p in &points {
        painter.circle_filled(*p, 4.0, Color32::from_rgb(255, 200, 60));
    }

    if let Some(i) = strip_state.selected.filter(|&i| i < tf.colors.len()) {
        ui.horizontal(|ui| {
            let p = tf.colors[i];
            ui.label(format!("colour at {}", axis::value_text(p[0] as f64, tf.units, range)));
            let mut c = Color32::from_rgb(to_u8(p[1]), to_u8(p[2]), to_u8(p[3]));
            if egui::color_picker::color_edit_button_srgba(ui, &mut c, egui::color_picker::Alpha::Opaque).changed() {
                set_color(tf, i, [c.r(), c.g(), c.b()].map(|v| f32::from(v) / 255.0));
                changed = true;
            }
            if ui.small_button("close").clicked() {
                strip_state.selected = None;
            }
        });
    }
    ui.data_mut(|d| d.insert_temp(id, strip_state));
    if changed {
        tf.name = "custom".into();
    }
    changed
}

/// Where the pointer was pressed (`fallback` when egui no longer knows).
fn press_origin(ctx: &egui::Context, fallback: Pos2) -> Pos2 {
    ctx.input(|i| i.pointer.press_origin()).unwrap_or(fallback)
}

fn to_u8(c: f32) -> u8 {
    (c.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The colour strip's clicks and drags; true when `tf` changed.
fn colour_strip_input(
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
fn paint_strip(
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
        // CI's viewer_tf: the press, then the whole 24-point motion in the next frame. egui starts the drag only
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
