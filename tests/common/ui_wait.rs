//! Waiting for a widget the viewer draws in response to input (a combo box's popup): its rectangle is logged when
//! first drawn and again when the popup is placed a frame later, so a test clicks it only once it stays put.

use super::x11::Viewer;
use std::time::{Duration, Instant};

/// The rectangle of widget `name` once the viewer has drawn it and it has not moved for half a second.
pub fn settled_rect(viewer: &mut Viewer, name: &str) -> egui::Rect {
    let deadline = Instant::now() + Duration::from_secs(30);
    let prefix = format!("ui rect {name} ");
    let mut last = None;
    loop {
        viewer.drain();
        if viewer.stderr.lines().any(|l| l.starts_with(&prefix)) {
            let rect = viewer.ui_rect(name);
            if last == Some(rect) {
                return rect;
            }
            last = Some(rect);
        }
        assert!(Instant::now() < deadline, "{name} never settled:\n{}", viewer.stderr);
        std::thread::sleep(Duration::from_millis(500));
    }
}
