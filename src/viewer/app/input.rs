//! The window's input before egui sees it: Tab taken for the panel, and a frame's events cut so that drags and
//! typing survive slow frames.
//!
//! Why a frame is cut: egui decides "dragged" from one frame to the next: a press and the motion after
//! it in one frame is not yet a drag, and the frame with the release ends it without a drag delta. When frames are
//! slower than the hand (lavapipe at full size: a few frames a second), a whole quick drag (press, moves,
//! release) arrives in one frame's input and egui sees no drag at all: the camera, the clipping plane and the
//! light stayed put. So a frame's events are cut where a drag needs a new frame: after a press that the pointer
//! then leaves by more than a click's distance, and before the release that ends such a motion. The rest waits
//! for the next frame. Clicks (a press and a release without such motion) stay in one frame, as before.
//!
//! Typing after a click is cut from it too: egui gives a text field the focus at the end of the frame that
//! clicked it, so keys typed in that same frame went nowhere (a path typed quickly into the editor's file field
//! lost its first letters, or all of them: CI's viewer::tf, under load).

use egui::{Event, Pos2};

/// Removes the presses of Tab (without modifiers) from `input` and returns how many there were: the viewer handles
/// Tab itself (panel on/off) and egui must not move its focus with it.
pub fn take_tab_presses(input: &mut egui::RawInput) -> usize {
    let is_tab =
        |e: &Event| matches!(e, egui::Event::Key { key: egui::Key::Tab, modifiers, .. } if modifiers.is_none());
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

/// Where to cut a frame's `events` (deliver `events[..cut]`, keep the rest for the next frame), or None to deliver
/// them all: before a drag's motion, before its release, between a click and keys typed after it, and between a
/// click and the pointer leaving it (egui hit-tests a frame's clicks where the pointer ends up, so a second click
/// elsewhere in one slow frame took the first one with it). `held` is where the press began if a button is still
/// down from an earlier frame; `click_dist` is how far the pointer may move and still click (egui's
/// `max_click_dist`). The cut is never 0, so every frame makes progress.
pub fn drag_cut(events: &[Event], held: Option<Pos2>, click_dist: f32) -> Option<usize> {
    // The press the pointer is measured from, whether it happened in this frame, and whether the pointer has left
    // it by more than a click's distance in this frame.
    let mut origin = held;
    let mut pressed_here = false;
    let mut moved_far = false;
    // Just after the last click's release in this frame: where typing that follows it is cut off.
    let mut after_click = None;
    // Where the last click in this frame was released: the pointer leaving it cuts.
    let mut released: Option<Pos2> = None;
    let left = |released: Option<Pos2>, pos: Pos2| released.is_some_and(|r| r.distance(pos) > click_dist);
    for (i, event) in events.iter().enumerate() {
        match *event {
            Event::PointerMoved(pos) | Event::PointerButton { pos, .. } if left(released, pos) => {
                return Some(i);
            }
            Event::PointerButton { pos, pressed: true, .. } => {
                if moved_far {
                    return Some(i);
                }
                if origin.is_none() {
                    (origin, pressed_here) = (Some(pos), true);
                }
            }
            Event::PointerMoved(pos) if origin.is_some_and(|o| o.distance(pos) > click_dist) => {
                if pressed_here {
                    return Some(i);
                }
                moved_far = true;
            }
            Event::PointerButton {
                pos, pressed: false, ..
            } => {
                if moved_far {
                    return Some(i);
                }
                after_click = Some(i + 1);
                released = Some(pos);
                (origin, pressed_here) = (None, false);
            }
            Event::Text(_) | Event::Paste(_) | Event::Key { pressed: true, .. } if after_click.is_some() => {
                return after_click;
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui::{Modifiers, PointerButton};

    fn button(x: f32, pressed: bool) -> Event {
        Event::PointerButton {
            pos: Pos2::new(x, 0.0),
            button: PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        }
    }

    fn moved(x: f32) -> Event {
        Event::PointerMoved(Pos2::new(x, 0.0))
    }

    /// Feeds `events` frame by frame as the viewer does, returning each frame's events.
    fn frames(mut events: Vec<Event>) -> Vec<Vec<Event>> {
        let mut out = Vec::new();
        let mut held = None;
        while !events.is_empty() {
            let rest = match drag_cut(&events, held, 6.0) {
                Some(cut) => events.split_off(cut),
                None => Vec::new(),
            };
            for e in &events {
                if let Event::PointerButton { pos, pressed, .. } = *e {
                    held = if pressed { held.or(Some(pos)) } else { None };
                }
            }
            out.push(std::mem::replace(&mut events, rest));
        }
        out
    }

    #[test]
    fn a_quick_drag_in_one_frame_becomes_press_motion_release() {
        let events = vec![
            moved(10.0),
            button(10.0, true),
            moved(20.0),
            moved(40.0),
            button(40.0, false),
        ];
        assert_eq!(
            frames(events),
            vec![
                vec![moved(10.0), button(10.0, true)],
                vec![moved(20.0), moved(40.0)],
                vec![button(40.0, false)],
            ]
        );
    }

    #[test]
    fn clicks_and_hovering_stay_in_one_frame() {
        // A click with a little jitter, a double click, and plain motion.
        let click = vec![moved(10.0), button(10.0, true), moved(13.0), button(13.0, false)];
        assert_eq!(frames(click.clone()), vec![click]);
        let double = vec![
            button(5.0, true),
            button(5.0, false),
            button(5.0, true),
            button(5.0, false),
        ];
        assert_eq!(frames(double.clone()), vec![double]);
        let hover = vec![moved(1.0), moved(50.0), moved(90.0)];
        assert_eq!(drag_cut(&hover, None, 6.0), None);
    }

    #[test]
    fn a_click_then_a_click_elsewhere_take_a_frame_each() {
        // Under a slow frame both clicks arrived together, and egui gave both to the widget under the second.
        let events = vec![
            moved(10.0),
            button(10.0, true),
            button(10.0, false),
            moved(80.0),
            button(80.0, true),
            button(80.0, false),
            moved(200.0),
        ];
        assert_eq!(
            frames(events),
            vec![
                vec![moved(10.0), button(10.0, true), button(10.0, false)],
                vec![moved(80.0), button(80.0, true), button(80.0, false)],
                vec![moved(200.0)],
            ]
        );
        // A press far from the release without a motion event between them cuts too.
        let jump = vec![button(10.0, true), button(10.0, false), button(90.0, true)];
        assert_eq!(drag_cut(&jump, None, 6.0), Some(2));
    }

    #[test]
    fn a_drag_already_under_way_moves_then_releases() {
        // The press was in an earlier frame: motion stays together, the release gets a frame of its own.
        let events = vec![moved(30.0), moved(60.0), button(60.0, false), moved(61.0)];
        assert_eq!(drag_cut(&events, Some(Pos2::new(10.0, 0.0)), 6.0), Some(2));
        assert_eq!(drag_cut(&events[2..], None, 6.0), None);
        // Motion within a click's distance of the press does not cut.
        assert_eq!(drag_cut(&events[..2], Some(Pos2::new(10.0, 0.0)), 6.0), None);
    }

    #[test]
    fn typing_after_a_click_waits_for_the_next_frame() {
        let text = |t: &str| Event::Text(t.into());
        let events = vec![
            moved(10.0),
            button(10.0, true),
            button(10.0, false),
            text("a"),
            text("b"),
        ];
        assert_eq!(
            frames(events),
            vec![
                vec![moved(10.0), button(10.0, true), button(10.0, false)],
                vec![text("a"), text("b")],
            ]
        );
        // Typing before a click, and a double click, stay in one frame.
        let before = vec![text("x"), button(5.0, true), button(5.0, false)];
        assert_eq!(frames(before.clone()), vec![before]);
        let double = vec![
            button(5.0, true),
            button(5.0, false),
            button(5.0, true),
            button(5.0, false),
            text("y"),
        ];
        assert_eq!(frames(double.clone()), vec![double[..4].to_vec(), vec![text("y")]]);
    }

    #[test]
    fn a_field_clicked_and_typed_into_within_one_slow_frame_gets_the_text() {
        // egui focuses a text field at the end of the frame that clicked it: fed whole, the text is lost; cut as
        // the viewer cuts it, the field gets every letter.
        let typed = |cut: bool| {
            let ctx = egui::Context::default();
            let mut text = String::new();
            // Runs one frame; returns where the field is.
            let run = |events: Vec<Event>, text: &mut String| {
                let input = egui::RawInput {
                    screen_rect: Some(egui::Rect::from_min_size(Pos2::ZERO, egui::vec2(400.0, 300.0))),
                    events,
                    ..Default::default()
                };
                let mut field = egui::Rect::NOTHING;
                let _ = ctx.run_ui(input, |ui| field = ui.text_edit_singleline(text).rect);
                field
            };
            let at = run(vec![], &mut text).center();
            let press = |pressed| Event::PointerButton {
                pos: at,
                button: PointerButton::Primary,
                pressed,
                modifiers: Modifiers::NONE,
            };
            let events = vec![
                Event::PointerMoved(at),
                press(true),
                press(false),
                Event::Text("edited.json".into()),
            ];
            let batches = if cut { frames(events) } else { vec![events] };
            for events in batches.into_iter().chain([vec![]]) {
                run(events, &mut text);
            }
            text
        };
        assert_eq!(
            typed(false),
            "",
            "egui itself drops keys typed in the frame of the focusing click"
        );
        assert_eq!(typed(true), "edited.json");
    }

    #[test]
    fn tab_presses_are_taken_from_egui() {
        let key = |key, pressed| Event::Key {
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
