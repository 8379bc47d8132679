//! The X tests' turns (`common::x11::xvfb`): this binary runs its tests on several threads, but the X tests
//! take turns, and one that fails during its turn does not keep the others from theirs.

use crate::common;

use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Two X sessions asked for at once: the second starts only after the first has ended.
#[test]
fn x_sessions_take_turns() {
    let spans: Vec<_> = (0..2)
        .map(|_| {
            std::thread::spawn(|| {
                let x = common::x11::xvfb()?;
                let start = Instant::now();
                std::thread::sleep(Duration::from_millis(300));
                let end = Instant::now();
                drop(x);
                Some((start, end))
            })
        })
        .collect::<Vec<_>>()
        .into_iter()
        .map(|t| t.join().expect("a session thread"))
        .collect();
    let [Some(a), Some(b)] = spans[..] else { return };
    let (first, second) = if a.0 <= b.0 { (a, b) } else { (b, a) };
    assert!(first.1 <= second.0, "the sessions overlapped: {first:?} and {second:?}");
}

/// A test that panics in its turn gives the turn back as it unwinds, and the next test takes it.
#[test]
fn a_failed_x_test_passes_its_turn_on() {
    let failed = std::thread::spawn(|| {
        let _x = common::x11::xvfb();
        panic!("an X test failing in its turn (deliberately)");
    })
    .join();
    assert!(failed.is_err(), "the failing test failed");
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(common::x11::xvfb().is_some());
    });
    let started = rx
        .recv_timeout(Duration::from_secs(120))
        .expect("the next X test got its turn");
    assert!(started, "Xvfb started for the next test");
}
