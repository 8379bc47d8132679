//! Waiting for work done on another thread with the GIL released, answering Ctrl+C: the wait returns
//! `KeyboardInterrupt` at once, and the work is told to stop where it can (a movie between frames).

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::Arc;
use std::time::Duration;

/// How often a wait looks for a signal.
const POLL: Duration = Duration::from_millis(50);

/// The value `rx` receives, waiting with the GIL released; on a signal (Ctrl+C's `KeyboardInterrupt`) sets `stop`
/// and returns the signal's exception.
pub fn wait<T: Send>(py: Python<'_>, mut rx: Receiver<T>, stop: Option<&Arc<AtomicBool>>) -> PyResult<T> {
    loop {
        // The receiver goes with the closure and comes back (a Receiver is Send, not Sync).
        let (back, got) = py.detach(move || {
            let got = rx.recv_timeout(POLL);
            (rx, got)
        });
        rx = back;
        match got {
            Ok(value) => return Ok(value),
            Err(RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    if let Some(stop) = stop {
                        stop.store(true, Ordering::Relaxed);
                    }
                    return Err(e);
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err(
                    "volcast's worker thread ended without an answer",
                ))
            }
        }
    }
}

/// Runs `work` on a thread of its own and waits for it as [`wait`] does (loading a file, converting an array).
pub fn on_thread<T: Send + 'static>(py: Python<'_>, work: impl FnOnce() -> T + Send + 'static) -> PyResult<T> {
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    std::thread::Builder::new()
        .name("volcast-load".into())
        .spawn(move || {
            let _ = tx.send(work());
        })
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start a thread: {e}")))?;
    wait(py, rx, None)
}
