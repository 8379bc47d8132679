//! The ruler in a slice view (3D Slicer's line markup): with the tool on (M, or the view's "ruler" button) a left
//! click places one end and the next the other; the line is drawn with its length in world millimetres. A right
//! click (or Esc) clears it. A finished ruler's length also goes to stderr (`ruler: 12.345 mm (Axial)`), where a
//! user can copy it and the tests read it, and the line joins the measurements the panel saves.

use crate::viewer::model::measurements::Measurement;
use crate::viewer::model::Model;
use crate::viewer::widgets::shown_slice::ShownSlice;
use egui::{Color32, Pos2, Stroke};

const COLOR: Color32 = Color32::from_rgb(255, 230, 0);

/// The ruler's clicks in one view. True when it took the left click (the crosshair then stays put).
pub fn take_input(model: &mut Model, slice: &ShownSlice, response: &egui::Response) -> bool {
    if response.clicked_by(egui::PointerButton::Secondary) && model.slices.ruler.line.is_some() {
        model.slices.ruler.clear();
        eprintln!("ruler: cleared");
    }
    if !model.slices.ruler.active {
        return false;
    }
    if response.clicked_by(egui::PointerButton::Primary) {
        if let Some(pos) = response.interact_pointer_pos() {
            let at = slice.mm.inverse().transform_point3(slice.world_at(pos));
            if let Some(line) = model.slices.ruler.place(slice.frame.view, at) {
                let mm = line.length_mm(slice.mm).unwrap_or_default();
                eprintln!("ruler: {mm:.3} mm ({})", slice.frame.view.name(model.anatomical()));
                let (anatomical, affine) = (model.anatomical(), model.geometry.affine);
                let measured = Measurement::new(line.view, anatomical, affine, line.start, at);
                model.slices.ruler.measured.push(measured);
            }
        }
    }
    true
}

/// The ruler drawn in the view it was made in: a line with its length, or while one end waits for the other, a
/// line to the pointer.
pub fn paint(painter: &egui::Painter, model: &Model, slice: &ShownSlice, hover: Option<Pos2>) {
    let Some(line) = model.slices.ruler.line.filter(|l| l.view == slice.frame.view) else {
        return;
    };
    let on_screen = |index: glam::DVec3| slice.to_screen(slice.frame.image(slice.mm.transform_point3(index)));
    let a = on_screen(line.start);
    let b = match line.end {
        Some(end) => on_screen(end),
        None => match hover.filter(|_| model.slices.ruler.active) {
            Some(p) => p,
            None => a,
        },
    };
    painter.line_segment([a, b], Stroke::new(1.5, COLOR));
    for p in [a, b] {
        painter.circle_stroke(p, 3.0, Stroke::new(1.5, COLOR));
    }
    if let Some(mm) = line.length_mm(slice.mm) {
        painter.text(
            a.lerp(b, 0.5) + egui::vec2(6.0, -6.0),
            egui::Align2::LEFT_BOTTOM,
            format!("{mm:.1} mm"),
            egui::FontId::proportional(13.0),
            COLOR,
        );
    }
}
