//! Keyboard shortcuts over the whole window.

use crate::scene::settings::Shading;
use crate::viewer::model::actions::UiAction;
use crate::viewer::model::settings::next_lower;
use crate::viewer::model::Model;
use crate::viewer::widgets::clip_plane;

/// Keyboard shortcuts: R reset, Space auto-rotate, L slice views, Tab panel (scripted keys; the app takes a
/// real Tab from egui's input), F12 screenshot and F9 record (Shift: as shown), C clipping plane, F flip it, P play, Q quality, S shading,
/// Ctrl+S session.
pub fn shortcuts(ctx: &egui::Context, model: &mut Model) -> Vec<UiAction> {
    let mut actions = Vec::new();
    if ctx.egui_wants_keyboard_input() {
        return actions;
    }
    ctx.input(|i| {
        if i.key_pressed(egui::Key::R) {
            model.reset_view();
        }
        if i.key_pressed(egui::Key::Space) {
            model.camera.auto_rotate = !model.camera.auto_rotate;
        }
        if i.key_pressed(egui::Key::Tab) {
            model.display.panel_visible = !model.display.panel_visible;
        }
        // Each press its own capture, Shift for the view as shown: two quick presses may arrive in one frame.
        for (key, shift) in presses(i, &[egui::Key::F12, egui::Key::F9]) {
            actions.push(match (key, shift) {
                (egui::Key::F12, false) => UiAction::Screenshot,
                (egui::Key::F12, true) => UiAction::ScreenshotAsShown,
                (_, false) => UiAction::ToggleRecording,
                (_, true) => UiAction::ToggleRecordingAsShown,
            });
        }
        if i.key_pressed(egui::Key::L) {
            model.slices.shown = !model.slices.shown;
        }
        if i.key_pressed(egui::Key::P) {
            model.time.toggle_play();
        }
        if i.key_pressed(egui::Key::C) {
            model.look.clip_plane = match model.look.clip_plane {
                Some(_) => None,
                None => Some(clip_plane::facing_away(model)),
            };
        }
        if i.key_pressed(egui::Key::F) {
            model.look.clip_plane = model.look.clip_plane.map(|p| p.flipped());
        }
        if i.key_pressed(egui::Key::Q) {
            model.sampling.quality = Some(next_lower(model.sampling.quality));
        }
        // Each press's own modifiers: a quick Ctrl+S arrives whole within one frame, so the frame's modifier
        // state (read after it) no longer has Ctrl down.
        let s_presses = |command: bool| {
            i.events.iter().any(|e| {
                matches!(e, egui::Event::Key { key: egui::Key::S, pressed: true, repeat: false, modifiers, .. }
                    if modifiers.command == command)
            })
        };
        if s_presses(true) {
            actions.push(UiAction::SaveSession);
        }
        if s_presses(false) {
            model.look.shading = match model.look.shading {
                Some(_) => None,
                None => Some(Shading::default()),
            };
        }
    });
    actions
}

/// Each press (not repeat) of one of `keys` this frame, in order, with whether Shift was held.
fn presses(i: &egui::InputState, keys: &[egui::Key]) -> Vec<(egui::Key, bool)> {
    i.events
        .iter()
        .filter_map(|e| match e {
            egui::Event::Key {
                key,
                pressed: true,
                repeat: false,
                modifiers,
                ..
            } if keys.contains(key) => Some((*key, modifiers.shift)),
            _ => None,
        })
        .collect()
}
