//! One frame's whole UI: the keyboard shortcuts, the settings panel on the left (Tab hides it), and the view area —
//! the 3D view alone, or the four-up layout with the three slice views.

use crate::scene::slice::SliceView;
use crate::viewer::model::actions::UiAction;
use crate::viewer::model::slices::SliceData;
use crate::viewer::model::Model;
use crate::viewer::widgets::slice_view::{self, SliceImages};
use crate::viewer::widgets::{keys, overlay, panel};

/// The settings panel's width (points). Fixed: a panel that grew with a long status line moved the views under
/// the cursor.
pub const PANEL_WIDTH: f32 = 270.0;

/// The width of the grey bars between the four-up views (points): each view's edge labels then read as its own, not
/// as a pair with the next view's ("L | R", not "L R").
pub const SEPARATOR: f32 = 4.0;
/// The bars' colour.
pub const SEPARATOR_COLOR: egui::Color32 = egui::Color32::from_gray(72);

/// The quadrants of the central area: (axial, 3D, sagittal, coronal), a [`SEPARATOR`] between.
pub fn four_up(rect: egui::Rect) -> [egui::Rect; 4] {
    let gap = SEPARATOR;
    let mid = rect.center();
    let (l, r) = (rect.left()..=mid.x - gap / 2.0, mid.x + gap / 2.0..=rect.right());
    let (t, b) = (rect.top()..=mid.y - gap / 2.0, mid.y + gap / 2.0..=rect.bottom());
    let q = |x: &std::ops::RangeInclusive<f32>, y: &std::ops::RangeInclusive<f32>| {
        egui::Rect::from_x_y_ranges(x.clone(), y.clone())
    };
    [q(&l, &t), q(&r, &t), q(&l, &b), q(&r, &b)]
}

/// The UI of one frame over `ui` (the whole window). `tab_presses`: how many times Tab was pressed (the app takes
/// Tab from egui); `data`: what the slice views show, `images` their textures. Returns what the app must do
/// beyond editing `model`.
pub fn frame_ui(
    ui: &mut egui::Ui,
    model: &mut Model,
    tab_presses: usize,
    data: SliceData,
    images: &mut SliceImages<'_>,
) -> Vec<UiAction> {
    if tab_presses % 2 == 1 {
        model.display.panel_visible = !model.display.panel_visible;
    }
    if !model.display.panel_visible {
        // Nothing hidden may keep the keyboard.
        ui.ctx().memory_mut(|m| m.stop_text_input());
    }
    let mut actions = keys::shortcuts(ui.ctx(), model);
    if model.display.panel_visible {
        egui::Panel::left("settings")
            .resizable(false)
            .exact_size(PANEL_WIDTH)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| actions.extend(panel::settings_panel(ui, model)));
            });
    }
    egui::CentralPanel::no_frame().show(ui, |ui| view_area(ui, model, data, images));
    overlay::shortcut_overlay(ui.ctx(), model);
    model.observe_history(keys::gesture_under_way(ui.ctx(), model));
    actions
}

/// The 3D view, or four-up: axial top left, 3D top right, sagittal bottom left, coronal bottom right.
fn view_area(ui: &mut egui::Ui, model: &mut Model, data: SliceData, images: &mut SliceImages<'_>) {
    if !model.slices.shown {
        overlay::view_overlay(ui, model);
        return;
    }
    let area = ui.max_rect();
    let [axial, three_d, sagittal, coronal] = four_up(area);
    let bars = [
        egui::Rect::from_x_y_ranges(axial.right()..=three_d.left(), area.y_range()),
        egui::Rect::from_x_y_ranges(area.x_range(), axial.bottom()..=sagittal.top()),
    ];
    for bar in bars {
        ui.painter().rect_filled(bar, 0.0, SEPARATOR_COLOR);
    }
    for (view, rect) in [
        (SliceView::Axial, axial),
        (SliceView::Sagittal, sagittal),
        (SliceView::Coronal, coronal),
    ] {
        slice_view::slice_view(ui, rect, model, view, data, images);
    }
    let mut view_ui = ui.new_child(egui::UiBuilder::new().max_rect(three_d));
    overlay::view_overlay(&mut view_ui, model);
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui::Pos2;

    #[test]
    fn the_four_quadrants_tile_the_area() {
        let r = egui::Rect::from_min_size(Pos2::new(10.0, 20.0), egui::vec2(400.0, 300.0));
        let [axial, three_d, sagittal, coronal] = four_up(r);
        assert_eq!(axial.left_top(), r.left_top());
        assert_eq!(coronal.right_bottom(), r.right_bottom());
        assert_eq!(three_d.left() - axial.right(), SEPARATOR);
        assert_eq!(sagittal.top() - axial.bottom(), SEPARATOR);
        assert!((axial.width() - three_d.width()).abs() < 1e-3);
    }
}
