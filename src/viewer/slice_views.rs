//! The three linked slice views beside the 3D view, laid out as 3D Slicer's "four-up": axial (red) top left, the
//! 3D view top right, sagittal (yellow) bottom left, coronal (green) bottom right. One crosshair is shared by all
//! three (and marked in the 3D view): a left click or drag in a slice moves it there, the wheel steps the slice
//! along its normal, a right drag changes window (horizontal) and level (vertical), and the value under the
//! cursor is shown in data units. The slab box and the clipping plane are drawn where they cut each slice.
//!
//! The images are resampled on the CPU from the volume the viewer keeps (`slice::render`), only when the plane,
//! the window/level, the volume or the view's size changed.

use super::ui::ViewerState;
use crate::scene::slice::{self, SliceFrame, SliceView, WindowLevel};
use crate::volume::Volume;
use egui::{Color32, Pos2, Stroke};
use glam::{DMat4, DVec2, DVec3};

/// The views' colours, as in 3D Slicer: axial red, coronal green, sagittal yellow.
pub fn view_color(view: SliceView) -> Color32 {
    match view {
        SliceView::Axial => Color32::from_rgb(240, 80, 80),
        SliceView::Coronal => Color32::from_rgb(90, 200, 90),
        SliceView::Sagittal => Color32::from_rgb(240, 210, 70),
    }
}

/// The value under the cursor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    pub view: SliceView,
    /// World millimetres (RAS for an anatomical volume).
    pub world: DVec3,
    /// The nearest voxel and its value in data units.
    pub voxel: [u32; 3],
    pub value: f64,
}

#[derive(Clone, Debug, PartialEq)]
struct Cached {
    generation: u64,
    frame: SliceFrame,
    wl: WindowLevel,
    voxel_axes: bool,
}

/// The slice views' state.
#[derive(Clone, Debug, Default)]
pub struct SliceViews {
    /// Four-up (three slices and the 3D view) instead of the 3D view alone (L, or the panel).
    pub shown: bool,
    /// The crosshair in continuous voxel index coordinates (so it stays on the same anatomy when the view
    /// switches between patient space and voxel axes).
    pub crosshair: DVec3,
    /// Window and level of the slices, in data units (apart from the 3D view's transfer function, as in Slicer).
    pub wl: Option<WindowLevel>,
    pub probe: Option<Probe>,
    /// Changes whenever the volume or its shown time step does: the images are made again.
    pub generation: u64,
    cache: Textures,
}

/// Each view's image on the GPU and what it shows.
#[derive(Clone, Default)]
struct Textures([Option<(Cached, egui::TextureHandle)>; 3]);

impl std::fmt::Debug for Textures {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Textures")
    }
}

impl SliceViews {
    /// A new volume (or time step): the crosshair at its centre, window/level from its histogram (the 0.5th to
    /// 99.5th percentile: an outlier voxel does not wash out the image).
    pub fn reset(&mut self, dims: [u32; 3], histogram: &[u64], range: [f64; 2]) {
        self.crosshair = DVec3::new(
            f64::from(dims[0]) - 1.0,
            f64::from(dims[1]) - 1.0,
            f64::from(dims[2]) - 1.0,
        ) * 0.5;
        self.wl = Some(percentile_window(histogram, range));
        self.probe = None;
        self.generation += 1;
    }
}

/// Window/level spanning the 0.5th to 99.5th percentile of a histogram over `range` (the whole range when empty).
pub fn percentile_window(histogram: &[u64], range: [f64; 2]) -> WindowLevel {
    let total: u64 = histogram.iter().sum();
    let at = |q: f64| {
        let mut seen = 0u64;
        for (i, &c) in histogram.iter().enumerate() {
            seen += c;
            if seen as f64 >= q * total as f64 {
                return (i as f64 + 0.5) / histogram.len() as f64;
            }
        }
        1.0
    };
    let (lo, hi) = if total == 0 { (0.0, 1.0) } else { (at(0.005), at(0.995)) };
    let (lo, hi) = if hi > lo { (lo, hi) } else { (0.0, 1.0) };
    let data = |u: f64| range[0] + u * (range[1] - range[0]);
    let (a, b) = (data(lo), data(hi));
    WindowLevel {
        window: (b - a).abs().max(1e-9),
        level: (a + b) / 2.0,
    }
}

/// The quadrants of the central area: (axial, 3D, sagittal, coronal), a thin gap between.
pub fn four_up(rect: egui::Rect) -> [egui::Rect; 4] {
    let gap = 2.0;
    let mid = rect.center();
    let (l, r) = (rect.left()..=mid.x - gap / 2.0, mid.x + gap / 2.0..=rect.right());
    let (t, b) = (rect.top()..=mid.y - gap / 2.0, mid.y + gap / 2.0..=rect.bottom());
    let q = |x: &std::ops::RangeInclusive<f32>, y: &std::ops::RangeInclusive<f32>| {
        egui::Rect::from_x_y_ranges(x.clone(), y.clone())
    };
    [q(&l, &t), q(&r, &t), q(&l, &b), q(&r, &b)]
}

/// Where a slice image of `frame` is drawn in `rect`: as large as fits, centred, square pixels.
pub fn image_rect(frame: &SliceFrame, rect: egui::Rect) -> egui::Rect {
    let (w, h) = (frame.width as f32, frame.height as f32);
    let scale = (rect.width() / w).min(rect.height() / h);
    egui::Rect::from_center_size(rect.center(), egui::vec2(w * scale, h * scale))
}

/// The frame a view shows now: through the crosshair, at most as many pixels as the view has.
pub fn frame_of(state: &ViewerState, view: SliceView, rect: egui::Rect, pixels_per_point: f32) -> SliceFrame {
    let mm = slice::mm_from_index(&state.geometry, state.look.voxel_axes);
    let through = mm.transform_point3(state.slices.crosshair);
    let side = (rect.width().max(rect.height()) * pixels_per_point).clamp(16.0, 1024.0) as u32;
    SliceFrame::new(view, state.anatomical(), mm, state.dims, through, side)
}

/// One slice view in `rect`: its image, the crosshair, slab and clip plane over it, the probe, and its input.
pub fn slice_view(
    ui: &mut egui::Ui,
    rect: egui::Rect,
    state: &mut ViewerState,
    view: SliceView,
    volume: Option<&Volume>,
) {
    let ppp = ui.ctx().pixels_per_point();
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, Color32::BLACK);
    let mm = slice::mm_from_index(&state.geometry, state.look.voxel_axes);
    let frame = frame_of(state, view, rect, ppp);
    let wl = state.slices.wl.unwrap_or(WindowLevel {
        window: state.range[1] - state.range[0],
        level: (state.range[0] + state.range[1]) / 2.0,
    });
    let slot = view.normal_axis();
    let wanted = Cached {
        generation: state.slices.generation,
        frame,
        wl,
        voxel_axes: state.look.voxel_axes,
    };
    if let Some(volume) = volume.filter(|v| v.dims == state.dims) {
        let fresh = state.slices.cache.0[slot].as_ref().is_some_and(|(c, _)| *c == wanted);
        if !fresh {
            let rgba = slice::render(volume, mm, &frame, wl);
            let image = egui::ColorImage::from_rgba_unmultiplied([frame.width as usize, frame.height as usize], &rgba);
            match &mut state.slices.cache.0[slot] {
                Some((c, texture)) => {
                    texture.set(image, egui::TextureOptions::LINEAR);
                    *c = wanted;
                }
                None => {
                    let texture = ui
                        .ctx()
                        .load_texture(format!("slice {slot}"), image, egui::TextureOptions::LINEAR);
                    state.slices.cache.0[slot] = Some((wanted, texture));
                }
            }
        }
    }
    let shown = image_rect(&frame, rect);
    if let Some((_, texture)) = &state.slices.cache.0[slot] {
        let uv = egui::Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        painter.image(texture.id(), shown, uv, Color32::WHITE);
    }
    let scale = shown.width() / frame.width as f32;
    let to_screen = |p: DVec2| Pos2::new(shown.left() + p.x as f32 * scale, shown.top() + p.y as f32 * scale);
    let to_image = |p: Pos2| {
        DVec2::new(
            f64::from((p.x - shown.left()) / scale),
            f64::from((p.y - shown.top()) / scale),
        )
    };

    // The other two views' planes through the crosshair, in their colours.
    let through = mm.transform_point3(state.slices.crosshair);
    for other in SliceView::ALL.into_iter().filter(|&o| o != view) {
        let (r, d) = other.screen_axes(state.anatomical());
        if let Some((a, b)) = frame.line_of_plane(through, r.cross(d)) {
            painter.line_segment([to_screen(a), to_screen(b)], Stroke::new(1.0, view_color(other)));
        }
    }
    // The slab box where it cuts this slice.
    let s = state.render_settings(1, 1);
    if s.slab_lo != glam::Vec3::ZERO || s.slab_hi != glam::Vec3::ONE {
        let outline = frame.section(&slab_corners_mm(mm, state.dims, s.slab_lo, s.slab_hi));
        if outline.len() >= 3 {
            let points: Vec<Pos2> = outline.iter().map(|&p| to_screen(p)).collect();
            painter.add(egui::Shape::closed_line(
                points,
                Stroke::new(1.5, Color32::from_rgb(255, 200, 60)),
            ));
        }
    }
    // The clipping plane where it cuts this slice.
    if let Some(plane) = state.look.clip_plane {
        let (point, normal) = super::clip_widget::plane_in_slices(state, &plane, mm);
        if let Some((a, b)) = frame.line_of_plane(point, normal) {
            painter.line_segment(
                [to_screen(a), to_screen(b)],
                Stroke::new(1.5, super::clip_widget::COLOR),
            );
        }
    }
    draw_labels(&painter, rect, state, view, through);

    let response = ui.interact(rect, ui.id().with(("slice view", slot)), egui::Sense::click_and_drag());
    let index_from_mm = mm.inverse();
    if let Some(pos) = response.interact_pointer_pos() {
        if response.dragged_by(egui::PointerButton::Primary) || response.clicked() {
            let w = frame.world(to_image(pos));
            state.slices.crosshair = index_from_mm.transform_point3(w);
        }
        if response.dragged_by(egui::PointerButton::Secondary) {
            let d = response.drag_delta();
            state.slices.wl = Some(wl.dragged(f64::from(d.x), f64::from(d.y), state.range));
        }
    }
    if response.hovered() {
        // Wheel events (not egui's smoothed scroll), one voxel's depth along the normal per frame that has any: X11
        // delivers each notch twice (measured under Xvfb: two MouseWheel events of one line for one `click 4`).
        let notches: f32 = ui.input(|i| {
            i.events
                .iter()
                .filter_map(|e| match e {
                    egui::Event::MouseWheel { delta, .. } if delta.y != 0.0 => Some(delta.y.signum()),
                    _ => None,
                })
                .sum::<f32>()
        });
        let notches = if notches == 0.0 { 0.0 } else { notches.signum() };
        if notches != 0.0 {
            let step = frame.normal() * frame.pixel.min(smallest_spacing(mm)) * f64::from(notches);
            let moved = mm.transform_point3(state.slices.crosshair) + step;
            state.slices.crosshair = index_from_mm.transform_point3(moved);
        }
    }
    if let (Some(pos), Some(volume)) = (response.hover_pos(), volume.filter(|v| v.dims == state.dims)) {
        let w = frame.world(to_image(pos));
        state.slices.probe = slice::voxel_at(state.dims, index_from_mm, w).map(|voxel| Probe {
            view,
            world: w,
            voxel,
            value: volume.value(voxel[0], voxel[1], voxel[2]),
        });
    } else if state.slices.probe.is_some_and(|p| p.view == view) {
        state.slices.probe = None;
    }
    if let Some(p) = state.slices.probe.filter(|p| p.view == view) {
        let text = probe_text(&p, state.anatomical(), &state.value_unit);
        let at = Pos2::new(rect.left() + 6.0, rect.bottom() - 6.0);
        painter.text(
            at,
            egui::Align2::LEFT_BOTTOM,
            text,
            egui::FontId::monospace(11.0),
            Color32::WHITE,
        );
    }
}

fn smallest_spacing(mm: DMat4) -> f64 {
    (0..3).map(|a| mm.col(a).truncate().length()).fold(f64::MAX, f64::min)
}

/// The texture-space box [lo, hi] as world millimetres (texture coordinate t is voxel index t·dims − ½).
pub fn slab_corners_mm(mm: DMat4, dims: [u32; 3], lo: glam::Vec3, hi: glam::Vec3) -> [DVec3; 8] {
    let d = DVec3::new(f64::from(dims[0]), f64::from(dims[1]), f64::from(dims[2]));
    std::array::from_fn(|c| {
        let pick = |bit: usize, a: usize| f64::from(if c >> bit & 1 == 1 { hi[a] } else { lo[a] });
        let t = DVec3::new(pick(0, 0), pick(1, 1), pick(2, 2));
        mm.transform_point3(t * d - 0.5)
    })
}

/// "R 12.3 A −4.0 S 30.1 mm  [i j k]  value unit" (x, y, z for a volume without orientation).
pub fn probe_text(p: &Probe, anatomical: bool, unit: &str) -> String {
    let coords = if anatomical {
        let letter = |v: f64, pos: char, neg: char| format!("{}{:.1}", if v >= 0.0 { pos } else { neg }, v.abs());
        format!(
            "{} {} {} mm",
            letter(p.world.x, 'R', 'L'),
            letter(p.world.y, 'A', 'P'),
            letter(p.world.z, 'S', 'I')
        )
    } else {
        format!("x {:.1} y {:.1} z {:.1}", p.world.x, p.world.y, p.world.z)
    };
    let value = if p.value.fract() == 0.0 && p.value.abs() < 1e9 {
        format!("{}", p.value)
    } else {
        format!("{:.4}", p.value)
    };
    let [i, j, k] = p.voxel;
    format!("{coords}  [{i} {j} {k}]  {value} {unit}")
        .trim_end()
        .to_string()
}

/// The view's name and position (top left) and, in patient space, the sides at its edges.
fn draw_labels(painter: &egui::Painter, rect: egui::Rect, state: &ViewerState, view: SliceView, through: DVec3) {
    let anatomical = state.anatomical();
    let axis = view.normal_axis();
    let position = through[axis];
    let name = view.name(anatomical);
    let title = if anatomical {
        let (pos, neg) = [('R', 'L'), ('A', 'P'), ('S', 'I')][axis];
        format!(
            "{name}  {}{:.1} mm",
            if position >= 0.0 { pos } else { neg },
            position.abs()
        )
    } else {
        format!("{name}  {}{:.1}", ['x', 'y', 'z'][axis], position)
    };
    painter.text(
        rect.left_top() + egui::vec2(6.0, 4.0),
        egui::Align2::LEFT_TOP,
        title,
        egui::FontId::proportional(13.0),
        view_color(view),
    );
    if anatomical {
        super::ui::side_labels(painter, rect, view.edge_labels(), 14.0, egui::vec2(6.0, 22.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_ignore_outliers_and_map_to_data_units() {
        // 1000 voxels in bins 10..20, one outlier in bin 255.
        let mut h = vec![0u64; 256];
        h[10..20].fill(100);
        h[255] = 1;
        let wl = percentile_window(&h, [-1000.0, 1560.0]);
        let (lo, hi) = (wl.level - wl.window / 2.0, wl.level + wl.window / 2.0);
        // Bin b spans −1000 + 10·b .. +10: the window is inside bins 10..20, far below the outlier.
        assert!(
            (-900.0..=-880.0).contains(&lo) && (-810.0..=-790.0).contains(&hi),
            "{lo} {hi}"
        );
        assert_eq!(
            percentile_window(&[], [0.0, 2.0]),
            WindowLevel {
                window: 2.0,
                level: 1.0
            }
        );
    }

    #[test]
    fn the_four_quadrants_tile_the_area() {
        let r = egui::Rect::from_min_size(Pos2::new(10.0, 20.0), egui::vec2(400.0, 300.0));
        let [axial, three_d, sagittal, coronal] = four_up(r);
        assert_eq!(axial.left_top(), r.left_top());
        assert_eq!(coronal.right_bottom(), r.right_bottom());
        assert!(three_d.left() > axial.right() && sagittal.top() > axial.bottom());
        assert!((axial.width() - three_d.width()).abs() < 1e-3);
    }

    #[test]
    fn probe_text_names_sides_and_units() {
        let p = Probe {
            view: SliceView::Axial,
            world: DVec3::new(-12.34, 4.0, -30.0),
            voxel: [1, 2, 3],
            value: 53.0,
        };
        assert_eq!(probe_text(&p, true, "HU"), "L12.3 A4.0 I30.0 mm  [1 2 3]  53 HU");
        assert_eq!(probe_text(&p, false, ""), "x -12.3 y 4.0 z -30.0  [1 2 3]  53");
    }

    #[test]
    fn slab_corners_are_the_voxel_faces_of_the_texture_box() {
        let c = slab_corners_mm(DMat4::IDENTITY, [10, 10, 10], glam::Vec3::ZERO, glam::Vec3::ONE);
        assert_eq!(c[0], DVec3::splat(-0.5));
        assert_eq!(c[7], DVec3::splat(9.5));
    }
}
