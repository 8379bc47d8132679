//! Waiting for a widget the viewer draws in response to input (a combo box's popup, a panel scrolling): its
//! rectangle is logged when first drawn and again as it moves (a popup is placed a frame later, a scroll animates
//! over many frames), so a test clicks it only once it is at rest.

use super::x11::Viewer;
use std::time::{Duration, Instant};

/// The rectangle of widget `name` once the viewer has drawn it and come to rest: a `ui still` line (a frame after
/// which egui wanted no other, `widgets::rects`) follows the last line that placed it. (Watching the rect stay put
/// for a while instead took a slow frame for rest: a scroll still under way once gave a rect one point off.)
pub fn settled_rect(viewer: &mut Viewer, name: &str) -> egui::Rect {
    let deadline = Instant::now() + Duration::from_secs(30);
    let prefix = format!("ui rect {name} ");
    let gone = format!("ui gone {name}");
    loop {
        viewer.drain();
        let mut placed = false;
        let mut rests = false;
        for line in viewer.stderr.lines() {
            if line.starts_with(&prefix) {
                (placed, rests) = (true, false);
            } else if line == gone {
                (placed, rests) = (false, false);
            } else if line == "ui still" {
                rests = placed;
            }
        }
        if rests {
            return viewer.ui_rect(name);
        }
        assert!(
            Instant::now() < deadline,
            "{name} never came to rest:\n{}",
            viewer.stderr
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}
