//! Waiting for a widget the viewer draws in response to input (a combo box's popup, a panel scrolling): its
//! rectangle is logged when first drawn and again as it moves (a popup is placed a frame later, a scroll animates
//! over many frames), so a test clicks it only once it is at rest.

use super::x11::Viewer;
use std::time::{Duration, Instant};

/// Waits, for 30 s at most, until `done` holds for the viewer's whole stderr so far; `what` names the wait in the
/// failure. The viewer's output is read every 50 ms.
fn wait_until(viewer: &mut Viewer, what: &str, done: impl Fn(&str) -> bool) {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        viewer.drain();
        if done(&viewer.stderr) {
            return;
        }
        assert!(Instant::now() < deadline, "{what}:\n{}", viewer.stderr);
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The rectangle of widget `name` once the viewer has drawn it and come to rest: a `ui still` line (a frame after
/// which egui wanted no other, `widgets::rects`) follows the last line that placed or labelled it. (Watching the
/// rect stay put for a while instead took a slow frame for rest: a scroll still under way once gave a rect one
/// point off.)
pub fn settled_rect(viewer: &mut Viewer, name: &str) -> egui::Rect {
    let prefix = format!("ui rect {name} ");
    let labelled = format!("ui label {name} ");
    let gone = format!("ui gone {name}");
    wait_until(viewer, &format!("{name} never came to rest"), |stderr| {
        let mut placed = false;
        let mut rests = false;
        for line in stderr.lines() {
            if line.starts_with(&prefix) || line.starts_with(&labelled) {
                (placed, rests) = (true, false);
            } else if line == gone {
                (placed, rests) = (false, false);
            } else if line == "ui still" {
                rests = placed;
            }
        }
        rests
    });
    viewer.ui_rect(name)
}

/// The rectangle of widget `name` once it shows `label` (its last `ui label` line, not forgotten by a `ui gone`
/// since) and has come to rest ([`settled_rect`]). A popup's first frame is laid out invisibly and takes no
/// clicks, so a test clicks a chooser's row only once it rests, and a folder entered only once its rows show.
pub fn labelled_rect(viewer: &mut Viewer, name: &str, label: &str) -> egui::Rect {
    let prefix = format!("ui label {name} ");
    let gone = format!("ui gone {name}");
    wait_until(viewer, &format!("{name} never showed {label:?}"), |stderr| {
        let mut shown = None;
        for line in stderr.lines() {
            if let Some(l) = line.strip_prefix(&prefix) {
                shown = Some(l);
            } else if line == gone {
                shown = None;
            }
        }
        shown == Some(label)
    });
    settled_rect(viewer, name)
}
