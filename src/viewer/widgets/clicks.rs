//! Double clicks as a user makes them, where egui's counting of clicks differs.

use egui::{Id, Response};

/// Where egui's memory keeps whether the last click that [`double_clicked`] saw was a double click.
fn last_was_double_id() -> Id {
    Id::new("volcast-last-click-was-double")
}

/// Whether `response` was double-clicked: a second click at the same place within egui's delay. egui counts a
/// click as the third of a triple click, and not as a double click, when the click two before it came within twice
/// that delay, wherever that one was: a button clicked and a row then double-clicked quickly is a "triple click" on
/// the row, and so is a row double-clicked soon after another double click there (a folder entered, then a file in
/// it). So a triple click counts too, unless it is the third click of a real triple click, which follows a double
/// click at once (a row double-clicked open would otherwise open the row that the third click lands on).
pub fn double_clicked(response: &Response) -> bool {
    if !response.clicked() {
        return false;
    }
    let ctx = &response.ctx;
    let after_double = ctx.data(|d| d.get_temp::<bool>(last_was_double_id())).unwrap_or(false);
    let double = response.double_clicked() || (response.triple_clicked() && !after_double);
    ctx.data_mut(|d| d.insert_temp(last_was_double_id(), double));
    double
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui::{Event, Pos2, Rect, Sense};

    /// Two targets side by side, 100 points apart.
    const A: Pos2 = Pos2::new(50.0, 50.0);
    const B: Pos2 = Pos2::new(150.0, 50.0);

    fn click_at(pos: Pos2) -> Vec<Event> {
        let button = |pressed| Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Default::default(),
        };
        vec![Event::PointerMoved(pos), button(true), button(false)]
    }

    /// Clicks each at its time, a frame each, and what egui and [`double_clicked`] made of each on its target:
    /// (egui's double click, egui's triple click, ours).
    fn clicks(at: &[(Pos2, f64)]) -> Vec<(bool, bool, bool)> {
        let ctx = egui::Context::default();
        let mut seen = Vec::new();
        // A first frame without input lays the targets out: egui hit-tests against the last frame's widgets.
        let first = std::iter::once((None, -1.0));
        for (pos, time) in first.chain(at.iter().map(|&(pos, time)| (Some(pos), time))) {
            let input = egui::RawInput {
                screen_rect: Some(Rect::from_min_size(Pos2::ZERO, egui::vec2(200.0, 100.0))),
                time: Some(time),
                events: pos.map_or_else(Vec::new, click_at),
                ..Default::default()
            };
            let _ = ctx.run_ui(input, |ui| {
                for (name, centre) in [("a", A), ("b", B)] {
                    let r = ui.interact(
                        Rect::from_center_size(centre, egui::vec2(80.0, 80.0)),
                        Id::new(name),
                        Sense::click(),
                    );
                    if r.clicked() {
                        seen.push((r.double_clicked(), r.triple_clicked(), double_clicked(&r)));
                    }
                }
            });
        }
        seen
    }

    #[test]
    fn a_double_click_soon_after_a_click_elsewhere_is_a_double_click() {
        let seen = clicks(&[(A, 0.0), (B, 0.2), (B, 0.3)]);
        // egui: no double click on B, a triple.
        assert_eq!(seen[2], (false, true, true), "{seen:?}");
        assert!(!seen[0].2 && !seen[1].2, "{seen:?}");
    }

    /// A folder entered by a double click, and a file in it double-clicked soon after, at the same place: egui
    /// counts the file's second click as a triple click (the folder's second click came within 0.6 s). On a slow
    /// machine, whose frames egui's clock follows, "soon" took 1.3 s.
    #[test]
    fn a_double_click_soon_after_a_double_click_there_is_a_double_click() {
        let seen = clicks(&[(B, 0.0), (B, 0.1), (B, 0.62), (B, 0.68)]);
        assert_eq!(seen[3], (false, true, true), "{seen:?}");
        assert_eq!(
            seen.iter().map(|s| s.2).collect::<Vec<_>>(),
            [false, true, false, true],
            "{seen:?}"
        );
    }

    #[test]
    fn a_triple_click_is_one_double_click() {
        let seen = clicks(&[(B, 0.0), (B, 0.1), (B, 0.2)]);
        assert_eq!(
            seen.iter().map(|s| s.2).collect::<Vec<_>>(),
            [false, true, false],
            "{seen:?}"
        );
    }

    #[test]
    fn slow_clicks_and_clicks_in_two_places_are_no_double_click() {
        let slow = clicks(&[(B, 0.0), (B, 0.5), (B, 1.0)]);
        let apart = clicks(&[(A, 0.0), (B, 0.1), (A, 0.2)]);
        assert!(slow.iter().chain(&apart).all(|s| !s.2), "{slow:?} {apart:?}");
    }

    #[test]
    fn a_second_double_click_after_a_pause_counts() {
        let seen = clicks(&[(B, 0.0), (B, 0.1), (B, 1.0), (B, 1.1)]);
        assert_eq!(
            seen.iter().map(|s| s.2).collect::<Vec<_>>(),
            [false, true, false, true],
            "{seen:?}"
        );
    }
}
