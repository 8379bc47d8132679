//! Keyboard shortcuts over the whole window, from one table ([`KEYS`]) that both dispatches them and lists them in
//! the shortcut overlay (F1), so the list cannot go stale; the mouse's gestures are listed beside it ([`MOUSE`]).

use crate::scene::settings::Shading;
use crate::viewer::model::actions::UiAction;
use crate::viewer::model::settings::next_lower;
use crate::viewer::model::Model;
use crate::viewer::widgets::clip_plane;

/// What a shortcut does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shortcut {
    ResetView,
    AutoRotate,
    Panel,
    Screenshot,
    ScreenshotAsShown,
    SliceViews,
    Play,
    ClipPlane,
    FlipClipPlane,
    Record,
    RecordAsShown,
    Quality,
    Shading,
    SaveSession,
    Undo,
    Redo,
    ShortcutOverlay,
    Ruler,
    Dismiss,
}

/// Which modifiers a key needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mods {
    /// Whatever is held (the single-letter shortcuts always were).
    Any,
    /// No Ctrl (⌘): S shades, Ctrl+S saves.
    Plain,
    /// Ctrl (⌘), no Shift.
    Command,
    /// Ctrl (⌘) and Shift.
    CommandShift,
    /// No Shift (F12: the clean render).
    NoShift,
    /// Shift (Shift+F12: the view as shown).
    Shift,
}

/// One key binding: the key, its modifiers, what it does, and how the overlay names it.
#[derive(Clone, Copy, Debug)]
pub struct Binding {
    pub key: egui::Key,
    pub mods: Mods,
    pub shortcut: Shortcut,
    /// As written in the overlay ("Ctrl+Z").
    pub label: &'static str,
    pub does: &'static str,
}

const fn bind(key: egui::Key, mods: Mods, shortcut: Shortcut, label: &'static str, does: &'static str) -> Binding {
    Binding {
        key,
        mods,
        shortcut,
        label,
        does,
    }
}

/// Every keyboard shortcut. Tab is the app's (taken from egui's input so that egui's focus does not move); the
/// entry here serves scripted keys and the overlay.
pub const KEYS: &[Binding] = {
    use egui::Key::*;
    use Mods::*;
    use Shortcut::*;
    &[
        bind(F1, Any, ShortcutOverlay, "F1 or ?", "show or hide this list"),
        bind(Questionmark, Any, ShortcutOverlay, "?", "show or hide this list"),
        bind(Tab, Any, Panel, "Tab", "hide or show the panel"),
        bind(R, Any, ResetView, "R", "reset the view"),
        bind(Space, Any, AutoRotate, "Space", "turn the view by itself"),
        bind(L, Any, SliceViews, "L", "slice views (four-up) on or off"),
        bind(M, Any, Ruler, "M", "ruler tool in the slice views"),
        bind(C, Any, ClipPlane, "C", "clipping plane on or off"),
        bind(F, Any, FlipClipPlane, "F", "flip the clipping plane"),
        bind(S, Plain, Shading, "S", "shading on or off"),
        bind(Q, Any, Quality, "Q", "lower the sampling quality"),
        bind(P, Any, Play, "P", "play or pause a series"),
        bind(
            Z,
            Command,
            Undo,
            "Ctrl+Z",
            "undo (transfer function, clip plane, camera)",
        ),
        bind(Z, CommandShift, Redo, "Ctrl+Shift+Z or Ctrl+Y", "redo"),
        bind(Y, Command, Redo, "Ctrl+Y", "redo"),
        bind(S, Command, SaveSession, "Ctrl+S", "save the session"),
        bind(
            F12,
            NoShift,
            Screenshot,
            "F12",
            "screenshot: the clean render of the 3D view",
        ),
        bind(
            F12,
            Shift,
            ScreenshotAsShown,
            "Shift+F12",
            "screenshot of the view as shown (box, outlines, labels)",
        ),
        bind(
            F9,
            NoShift,
            Record,
            "F9",
            "start or stop recording a GIF (clean render)",
        ),
        bind(F9, Shift, RecordAsShown, "Shift+F9", "record the view as shown"),
        bind(Escape, Any, Dismiss, "Esc", "close this list; clear the ruler"),
    ]
};

/// The mouse's gestures, by where they are made: (where, gesture, what it does).
pub const MOUSE: &[(&str, &str, &str)] = &[
    ("3D view", "left drag", "turn the camera (arcball)"),
    ("3D view", "right or middle drag", "pan"),
    ("3D view", "wheel", "zoom"),
    ("3D view", "click a gizmo axis", "look along it"),
    (
        "3D view",
        "drag the plane's handle / ring",
        "slide / turn the clipping plane",
    ),
    ("3D view", "drag the light gizmo", "move the light"),
    ("slice view", "left click or drag", "move the crosshair"),
    ("slice view", "wheel", "step the slice"),
    ("slice view", "right drag", "window (across) and level (up and down)"),
    (
        "slice view",
        "ruler tool (M): click, click",
        "measure in mm; right click or Esc clears",
    ),
    (
        "transfer function",
        "click / drag / right click",
        "add / move / delete a point",
    ),
];

/// The entries of the overlay's key list: one per shortcut label (the aliases that repeat one are left out).
pub fn listed_keys() -> impl Iterator<Item = &'static Binding> {
    KEYS.iter()
        .enumerate()
        .filter(|(i, b)| KEYS[..*i].iter().all(|a| a.shortcut != b.shortcut))
        .map(|(_, b)| b)
}

/// How often the window's `input` pressed `binding` in this frame. Each press's own modifiers: a quick Ctrl+S
/// arrives whole within one frame, so the frame's modifier state (read after it) no longer has Ctrl down.
fn presses(input: &egui::InputState, binding: &Binding) -> usize {
    input
        .events
        .iter()
        .filter(|e| match e {
            egui::Event::Key {
                key,
                pressed: true,
                repeat: false,
                modifiers,
                ..
            } if *key == binding.key => match binding.mods {
                Mods::Any => true,
                Mods::Plain => !modifiers.command,
                Mods::Command => modifiers.command && !modifiers.shift,
                Mods::CommandShift => modifiers.command && modifiers.shift,
                Mods::NoShift => !modifiers.shift,
                Mods::Shift => modifiers.shift,
            },
            _ => false,
        })
        .count()
}

/// The shortcuts pressed in this frame, in the table's order, each as many times as it was pressed: a slow frame
/// may hold two quick presses (Q twice lowers the quality twice, Space twice leaves auto-rotation as it was). A
/// shortcut with two bindings counts the one that saw more presses, so a press both see ("?" and F1, or Ctrl+Shift+Z
/// and Ctrl+Y) counts once.
fn fired_in(input: &egui::InputState) -> Vec<Shortcut> {
    let mut counted: Vec<(Shortcut, usize)> = Vec::new();
    for binding in KEYS {
        let n = presses(input, binding);
        match counted.iter_mut().find(|(s, _)| *s == binding.shortcut) {
            Some((_, most)) => *most = (*most).max(n),
            None => counted.push((binding.shortcut, n)),
        }
    }
    counted
        .into_iter()
        .flat_map(|(s, n)| std::iter::repeat_n(s, n))
        .collect()
}

/// The keyboard shortcuts of [`KEYS`] pressed in this frame, unless a text field has the keyboard.
pub fn shortcuts(ctx: &egui::Context, model: &mut Model) -> Vec<UiAction> {
    let mut actions = Vec::new();
    if ctx.egui_wants_keyboard_input() {
        return actions;
    }
    for shortcut in ctx.input(fired_in) {
        act(shortcut, model, &mut actions);
    }
    actions
}

fn act(shortcut: Shortcut, model: &mut Model, actions: &mut Vec<UiAction>) {
    match shortcut {
        Shortcut::ResetView => model.reset_view(),
        Shortcut::AutoRotate => model.camera.auto_rotate = !model.camera.auto_rotate,
        Shortcut::Panel => model.display.panel_visible = !model.display.panel_visible,
        Shortcut::Screenshot => actions.push(UiAction::Screenshot),
        Shortcut::ScreenshotAsShown => actions.push(UiAction::ScreenshotAsShown),
        Shortcut::SliceViews => model.slices.shown = !model.slices.shown,
        Shortcut::Play => model.time.toggle_play(),
        Shortcut::ClipPlane => {
            model.look.cut.clip_plane = match model.look.cut.clip_plane {
                Some(_) => None,
                None => Some(clip_plane::facing_away(model)),
            }
        }
        Shortcut::FlipClipPlane => model.look.cut.clip_plane = model.look.cut.clip_plane.map(|p| p.flipped()),
        Shortcut::Record => actions.push(UiAction::ToggleRecording),
        Shortcut::RecordAsShown => actions.push(UiAction::ToggleRecordingAsShown),
        Shortcut::Quality => model.sampling.quality = Some(next_lower(model.sampling.quality)),
        Shortcut::SaveSession => actions.push(UiAction::SaveSession),
        Shortcut::Shading => {
            model.look.lighting.shading = match model.look.lighting.shading {
                Some(_) => None,
                None => Some(Shading::default()),
            }
        }
        Shortcut::Undo => {
            model.undo();
        }
        Shortcut::Redo => {
            model.redo();
        }
        Shortcut::ShortcutOverlay => model.display.show_shortcuts = !model.display.show_shortcuts,
        Shortcut::Ruler => model.slices.ruler.toggle_tool(),
        Shortcut::Dismiss => {
            model.display.show_shortcuts = false;
            model.slices.ruler.clear();
        }
    }
}

/// Whether a gesture that the undo history must see whole is under way at the end of this frame: a button held,
/// the wheel's smoothed scroll still turning, or the camera moving by itself.
pub fn gesture_under_way(ctx: &egui::Context, model: &Model) -> bool {
    model.camera_moving() || ctx.input(|i| i.pointer.any_down() || i.smooth_scroll_delta != egui::Vec2::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shortcut_is_listed_once_and_no_key_is_bound_twice() {
        let listed: Vec<Shortcut> = listed_keys().map(|b| b.shortcut).collect();
        for b in KEYS {
            assert_eq!(listed.iter().filter(|&&s| s == b.shortcut).count(), 1, "{b:?}");
        }
        for (i, a) in KEYS.iter().enumerate() {
            for b in &KEYS[..i] {
                let overlap = a.key == b.key && (a.mods == b.mods || a.mods == Mods::Any || b.mods == Mods::Any);
                assert!(!overlap, "{a:?} and {b:?}");
            }
        }
    }

    fn key_event(key: egui::Key, command: bool, shift: bool) -> egui::Event {
        egui::Event::Key {
            key,
            physical_key: None,
            pressed: true,
            repeat: false,
            modifiers: egui::Modifiers {
                ctrl: command,
                command,
                shift,
                ..Default::default()
            },
        }
    }

    /// The shortcuts `events` fire, through egui's input as a frame sees it.
    fn fired(events: Vec<egui::Event>) -> Vec<Shortcut> {
        let ctx = egui::Context::default();
        let input = egui::RawInput {
            events,
            ..Default::default()
        };
        let mut out = Vec::new();
        let _ = ctx.run_ui(input, |ui| {
            out = ui.input(fired_in);
        });
        out
    }

    #[test]
    fn ctrl_z_undoes_and_ctrl_shift_z_or_ctrl_y_redo() {
        use egui::Key;
        assert_eq!(fired(vec![key_event(Key::Z, true, false)]), [Shortcut::Undo]);
        assert_eq!(fired(vec![key_event(Key::Z, true, true)]), [Shortcut::Redo]);
        assert_eq!(fired(vec![key_event(Key::Y, true, false)]), [Shortcut::Redo]);
        assert_eq!(fired(vec![key_event(Key::Z, false, false)]), []);
        assert_eq!(fired(vec![key_event(Key::S, true, false)]), [Shortcut::SaveSession]);
        assert_eq!(fired(vec![key_event(Key::S, false, false)]), [Shortcut::Shading]);
    }

    #[test]
    fn each_press_counts_and_shift_captures_the_view_as_shown() {
        use egui::Key;
        let release = egui::Event::Key {
            key: Key::F12,
            physical_key: None,
            pressed: false,
            repeat: false,
            modifiers: Default::default(),
        };
        let twice = vec![
            key_event(Key::F12, false, false),
            release.clone(),
            key_event(Key::F12, false, false),
            release,
        ];
        assert_eq!(fired(twice), [Shortcut::Screenshot, Shortcut::Screenshot]);
        // Every shortcut counts its presses: Q twice in one slow frame lowers the quality twice.
        let q = key_event(Key::Q, false, false);
        let q_up = egui::Event::Key {
            key: Key::Q,
            physical_key: None,
            pressed: false,
            repeat: false,
            modifiers: Default::default(),
        };
        let q_twice = vec![q.clone(), q_up.clone(), q, q_up];
        assert_eq!(fired(q_twice), [Shortcut::Quality, Shortcut::Quality]);
        // One press seen by two bindings of a shortcut counts once.
        let help = vec![
            key_event(Key::F1, false, false),
            key_event(Key::Questionmark, false, false),
        ];
        assert_eq!(fired(help), [Shortcut::ShortcutOverlay]);
        assert_eq!(
            fired(vec![key_event(Key::F12, false, true)]),
            [Shortcut::ScreenshotAsShown]
        );
        assert_eq!(fired(vec![key_event(Key::F9, false, true)]), [Shortcut::RecordAsShown]);
        assert_eq!(fired(vec![key_event(Key::F9, false, false)]), [Shortcut::Record]);
    }
}
