//! `volcast.view`: the desktop viewer on a volume the caller holds, or on the one `volcast view`'s options name.
//! It runs on the calling thread (winit wants the main thread) with the GIL released, until the window closes.

use crate::errors::{to_py, While};
use crate::options::parse_view;
use crate::volume::PyVolume;
use pyo3::prelude::*;
use volcast::viewer::VolumeSource;

/// Opens the viewer with `volcast view`'s options (`argv`) on `volume`, or on what they name; returns when its
/// window closes.
#[pyfunction]
#[pyo3(signature = (volume, argv))]
pub fn view(py: Python<'_>, volume: Option<PyRef<'_, PyVolume>>, argv: Vec<String>) -> PyResult<()> {
    let args = parse_view(argv).map_err(|e| to_py(e, While::Rendering))?;
    let memory = volume.map(|v| VolumeSource::Memory(v.inner.clone()));
    py.detach(move || volcast::cli::commands::view_source(&args, memory))
        .map_err(|e| to_py(e, While::Rendering))
}
