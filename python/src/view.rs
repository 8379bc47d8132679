//! `volcast.view`: the desktop viewer on a volume the caller holds, or on the one `volcast view`'s options name.
//! It runs on the calling thread (winit wants the main thread) with the GIL released, until the window closes.

use crate::errors::{to_py, While};
use crate::options::parse_view;
use crate::volume::PyVolume;
use pyo3::prelude::*;
use volcast::viewer::VolumeSource;

/// Opens the viewer with `volcast view`'s options (`argv`) on `volume`, or on what they name, with the layers the
/// caller holds (each an overlay or, true, a label map) over it; returns when its window closes.
#[pyfunction]
#[pyo3(signature = (volume, argv, layers=Vec::new()))]
pub fn view(
    py: Python<'_>,
    volume: Option<PyRef<'_, PyVolume>>,
    argv: Vec<String>,
    layers: Vec<(PyRef<'_, PyVolume>, bool)>,
) -> PyResult<()> {
    let args = parse_view(argv).map_err(|e| to_py(e, While::Rendering))?;
    let memory = volume.map(|v| VolumeSource::Memory(v.inner.clone()));
    let held: Vec<_> = layers.iter().map(|(v, l)| (v.inner.as_ref().clone(), *l)).collect();
    py.detach(move || volcast::cli::commands::view_source(&args, memory, held))
        .map_err(|e| to_py(e, While::Rendering))
}
