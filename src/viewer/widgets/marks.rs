//! Marks shared by the 3D and slice views: each slice view's colour (3D Slicer's: axial red, coronal green,
//! sagittal yellow), and the patient's sides written at a view's edges.

use crate::scene::slice::SliceView;
use egui::{Color32, Pos2};

/// The views' colours, as in 3D Slicer: axial red, coronal green, sagittal yellow.
pub fn view_color(view: SliceView) -> Color32 {
    match view {
        SliceView::Axial => Color32::from_rgb(240, 80, 80),
        SliceView::Coronal => Color32::from_rgb(90, 200, 90),
        SliceView::Sagittal => Color32::from_rgb(240, 210, 70),
    }
}

/// The patient's sides at a view's left, right, top and bottom edges, `inset` in from them.
pub fn side_labels(
    painter: &egui::Painter,
    rect: egui::Rect,
    labels: [impl ToString; 4],
    size: f32,
    inset: egui::Vec2,
) {
    let [left, right, top, bottom] = labels;
    let font = egui::FontId::proportional(size);
    let color = Color32::from_rgb(255, 220, 120);
    let mid = rect.center();
    for (text, pos, align) in [
        (
            left.to_string(),
            Pos2::new(rect.left() + inset.x, mid.y),
            egui::Align2::LEFT_CENTER,
        ),
        (
            right.to_string(),
            Pos2::new(rect.right() - inset.x, mid.y),
            egui::Align2::RIGHT_CENTER,
        ),
        (
            top.to_string(),
            Pos2::new(mid.x, rect.top() + inset.y),
            egui::Align2::CENTER_TOP,
        ),
        (
            bottom.to_string(),
            Pos2::new(mid.x, rect.bottom() - inset.y),
            egui::Align2::CENTER_BOTTOM,
        ),
    ] {
        painter.text(pos, align, text, font.clone(), color);
    }
}
