//! The time controls of a series (hidden for a single volume): the step slider, play/pause and the speed.

use crate::viewer::model::time::{TimeControl, MAX_FPS};

/// The controls, for a series only.
pub fn time_controls(ui: &mut egui::Ui, time: &mut TimeControl) {
    if time.steps < 2 {
        return;
    }
    ui.separator();
    ui.label(format!("Time: step {} of {}", time.wanted, time.steps));
    ui.add(egui::Slider::new(&mut time.wanted, 0..=time.steps - 1).text("step"));
    ui.horizontal(|ui| {
        let label = if time.playing { "⏸ Pause" } else { "▶ Play" };
        if ui
            .button(label)
            .on_hover_text("play the series in a loop (P)")
            .clicked()
        {
            time.toggle_play();
        }
        ui.add(
            egui::DragValue::new(&mut time.fps)
                .range(0.5..=MAX_FPS)
                .speed(0.2)
                .suffix(" steps/s"),
        );
    });
    // Frames slower than the rate asked: say what is reached (every step is still shown).
    match time.falling_behind() {
        Some(r) => ui.weak(format!("reaching {r:.1} steps/s (frames are the limit)")),
        None => ui.weak(""),
    };
}
