//! Where the panel's widgets are, for tests that drive the viewer through real X input: with `VOLCAST_UI_RECTS`
//! set, each named widget's rectangle goes to stderr as `ui rect NAME LEFT TOP RIGHT BOTTOM` (points) when it is
//! first drawn and whenever it moves (and `ui label NAME TEXT` when a widget that says what it shows, a chooser's row,
//! shows something new), `ui gone NAME` after a frame that did not draw it (so a widget shown again,
//! a chooser reopened, is logged again), and `ui still` after a frame that left the UI at rest (no animation under
//! way) once anything changed. The input itself still comes through the window system; this only says where to
//! point, and when.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, OnceLock};
use std::time::Duration;

/// A frame after which egui wants no new frame sooner than this leaves the UI at rest.
pub const STILL: Duration = Duration::from_millis(100);

/// A widget's last logged rect and label, and whether this frame drew it.
struct Logged {
    name: &'static str,
    rect: egui::Rect,
    label: Option<String>,
    seen: bool,
}

static LAST: Mutex<Vec<Logged>> = Mutex::new(Vec::new());

/// Whether anything was logged, or the UI was under way, since the last `ui still`.
static CHANGED: AtomicBool = AtomicBool::new(true);

fn on() -> bool {
    static ON: OnceLock<bool> = OnceLock::new();
    *ON.get_or_init(|| std::env::var_os("VOLCAST_UI_RECTS").is_some_and(|v| !v.is_empty()))
}

/// Logs `rect` under `name` if logging is on and it is new or moved since the frame that last drew it.
pub fn log(name: &'static str, rect: egui::Rect) {
    log_labelled(name, rect, None);
}

/// Logs `rect` as [`log`] does, and `label` (what the widget shows) if it is new or changed.
pub fn log_labelled(name: &'static str, rect: egui::Rect, label: Option<&str>) {
    if !on() {
        return;
    }
    let Ok(mut last) = LAST.lock() else { return };
    let index = match last.iter().position(|l| l.name == name) {
        Some(i) => i,
        None => {
            last.push(Logged {
                name,
                rect: egui::Rect::NAN,
                label: None,
                seen: false,
            });
            last.len() - 1
        }
    };
    let logged = &mut last[index];
    logged.seen = true;
    // NaN never equals: a new entry is logged.
    if logged.rect != rect {
        logged.rect = rect;
        CHANGED.store(true, Ordering::Relaxed);
        eprintln!(
            "ui rect {name} {} {} {} {}",
            rect.left(),
            rect.top(),
            rect.right(),
            rect.bottom()
        );
    }
    if let Some(label) = label.filter(|l| logged.label.as_deref() != Some(l)) {
        logged.label = Some(label.to_string());
        CHANGED.store(true, Ordering::Relaxed);
        eprintln!("ui label {name} {label}");
    }
}

/// Ends a frame: forgets (`ui gone`) the widgets it did not draw, then, when `still` (egui asks for no frame
/// within [`STILL`]) and anything changed since the last time, says `ui still`: a rect logged before it is where
/// the widget rests.
pub fn end_frame(still: bool) {
    if !on() {
        return;
    }
    if let Ok(mut last) = LAST.lock() {
        last.retain_mut(|l| {
            if !l.seen {
                CHANGED.store(true, Ordering::Relaxed);
                eprintln!("ui gone {}", l.name);
            }
            std::mem::replace(&mut l.seen, false)
        });
    }
    if !still {
        CHANGED.store(true, Ordering::Relaxed);
    } else if CHANGED.swap(false, Ordering::Relaxed) {
        eprintln!("ui still");
    }
}
