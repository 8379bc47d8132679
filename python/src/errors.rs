//! volcast's errors as Python exceptions, with the command line's messages: `OSError` for what a file holds or
//! lacks, `ValueError` for bad arrays and option values, `RuntimeError` for no usable Vulkan device (saying what
//! to install) and for the rest.

use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyRuntimeError, PyValueError};
use pyo3::PyErr;
use volcast::volume::VolumeError;

/// What the failing call was doing, which decides the exception a volume error becomes.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum While {
    /// Reading a file: its errors are `OSError`.
    Reading,
    /// Making a volume of an array (or a transfer function of points): its errors are `ValueError`.
    Converting,
    /// Rendering: a file named by the options is read here too.
    Rendering,
}

/// What to install where no Vulkan device was found.
const INSTALL: &str = "volcast needs a Vulkan driver: on Debian or Ubuntu `sudo apt-get install \
                       mesa-vulkan-drivers` (lavapipe, no GPU needed), or your GPU's driver";

/// The command line's usage errors, and what only Python meets as one: a transfer function given as points that
/// is not one (`TfError` other than a file's).
fn usage(e: &anyhow::Error) -> bool {
    use volcast::transfer::function::TfError;
    volcast::cli::is_usage(e)
        || e.downcast_ref::<TfError>()
            .is_some_and(|t| !matches!(t, TfError::Io { .. }))
}

fn stopped(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<volcast::movie::MovieError>()
            .is_some_and(|m| matches!(m, volcast::movie::MovieError::Stopped(_)))
    })
}

/// `e` as the Python exception a user of `while_` expects.
pub fn to_py(e: anyhow::Error, while_: While) -> PyErr {
    let text = volcast::cli::error_text(&e);
    if volcast::cli::is_unavailable(&e) {
        let display = e
            .downcast_ref::<volcast::viewer::ViewerError>()
            .is_some_and(|v| matches!(v, volcast::viewer::ViewerError::NoDisplay(_)));
        return PyRuntimeError::new_err(if display { text } else { format!("{text}. {INSTALL}") });
    }
    if stopped(&e) {
        return PyKeyboardInterrupt::new_err(text);
    }
    if usage(&e) {
        return PyValueError::new_err(text);
    }
    let volume = e.chain().any(|c| c.downcast_ref::<VolumeError>().is_some());
    let io = e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some());
    match while_ {
        While::Converting => PyValueError::new_err(text),
        While::Reading | While::Rendering if volume || io => PyOSError::new_err(text),
        _ => PyRuntimeError::new_err(text),
    }
}
