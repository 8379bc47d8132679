//! Where the panel's widgets are, for tests that drive the viewer through real X input: with `VOLCAST_UI_RECTS`
//! set, each named widget's rectangle goes to stderr as `ui rect NAME LEFT TOP RIGHT BOTTOM` (points) whenever it
//! changes. The input itself still comes through the window system; this only says where to point.

use std::sync::{Mutex, OnceLock};

/// Logs `rect` under `name` if logging is on and it moved since the last time.
pub fn log(name: &'static str, rect: egui::Rect) {
    static ON: OnceLock<bool> = OnceLock::new();
    static LAST: Mutex<Vec<(&'static str, egui::Rect)>> = Mutex::new(Vec::new());
    if !*ON.get_or_init(|| std::env::var_os("VOLCAST_UI_RECTS").is_some_and(|v| !v.is_empty())) {
        return;
    }
    let Ok(mut last) = LAST.lock() else { return };
    match last.iter_mut().find(|(n, _)| *n == name) {
        Some((_, r)) if *r == rect => return,
        Some((_, r)) => *r = rect,
        None => last.push((name, rect)),
    }
    eprintln!(
        "ui rect {name} {} {} {} {}",
        rect.left(),
        rect.top(),
        rect.right(),
        rect.bottom()
    );
}
