//! Keyboard shortcuts, and Tab taken from egui's input before egui sees it.

use super::state::{UiAction, ViewerState};
use crate::scene::quality::Quality;
use crate::scene::settings::Shading;

/// Removes the presses of Tab (without modifiers) from `input` and returns how many there were: the viewer handles
/// Tab itself (panel on/off) and egui must not move its focus with it.
pub fn take_tab_presses(input: &mut egui::RawInput) -> usize {
    let is_tab =
        |e: &egui::Event| matches!(e, egui::Event::Key { key: egui::Key::Tab, modifiers, .. } if modifiers.is_none());
    let presses = input
        .events
        .iter()
        .filter(|e| {
            is_tab(e)
                && matches!(
                    e,
                    egui::Event::Key {
                        pressed: true,
                        repeat: false,
                        ..
                    }
                )
        })
        .count();
    input.events.retain(|e| !is_tab(e));
    presses
}

/// Keyboard shortcuts: R reset, Space auto-rotate, L slice views, Tab panel (scripted keys; a real Tab is taken before egui,
/// `take_tab_presses`), F12 screenshot, F9 record, C clipping plane, F flip it, P play, Q quality, S shading,
/// Ctrl+S session.
pub fn shortcuts(ctx: &egui::Context, state: &mut ViewerState) -> Vec<UiAction> {
    let mut actions = Vec::new();
    if ctx.egui_wants_keyboard_input() {
        return actions;
    }
    ctx.input(|i| {
        if i.key_pressed(egui::Key::R) {
            state.reset_view();
        }
        if i.key_pressed(egui::Key::Space) {
            state.auto_rotate = !state.auto_rotate;
        }
        if i.key_pressed(egui::Key::Tab) {
            state.panel_visible = !state.panel_visible;
        }
        if i.key_pressed(egui::Key::F12) {
            actions.push(UiAction::Screenshot);
        }
        if i.key_pressed(egui::Key::L) {
            state.slices.shown = !state.slices.shown;
        }
        if i.key_pressed(egui::Key::P) {
            state.time.toggle_play();
        }
        if i.key_pressed(egui::Key::C) {
            state.look.clip_plane = match state.look.clip_plane {
                Some(_) => None,
                None => Some(crate::viewer::clip_widget::facing_away(state)),
            };
        }
        if i.key_pressed(egui::Key::F) {
            state.look.clip_plane = state.look.clip_plane.map(|p| p.flipped());
        }
        if i.key_pressed(egui::Key::F9) {
            actions.push(UiAction::ToggleRecording);
        }
        if i.key_pressed(egui::Key::Q) {
            state.quality = Some(next_lower(state.quality));
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
            state.look.shading = match state.look.shading {
                Some(_) => None,
                None => Some(Shading::default()),
            };
        }
    });
    actions
}

/// The Q key's cycle: one level lower, from draft to converged (a custom step goes to normal).
pub fn next_lower(q: Option<Quality>) -> Quality {
    match q {
        Some(Quality::Converged) | None => Quality::Normal,
        Some(Quality::Normal) => Quality::Fast,
        Some(Quality::Fast) => Quality::Draft,
        Some(Quality::Draft) => Quality::Converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tab_presses_are_taken_from_egui() {
        let key = |key, pressed| egui::Event::Key {
            key,
            physical_key: None,
            pressed,
            repeat: false,
            modifiers: Default::default(),
        };
        let mut input = egui::RawInput {
            events: vec![
                key(egui::Key::Tab, true),
                key(egui::Key::Tab, false),
                key(egui::Key::R, true),
            ],
            ..Default::default()
        };
        assert_eq!(take_tab_presses(&mut input), 1);
        assert_eq!(input.events.len(), 1, "R stays for the shortcuts");
    }
}
