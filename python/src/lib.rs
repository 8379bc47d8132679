//! `volcast._volcast`, the native half of the Python package `volcast` (python/volcast/ is the other half, the API
//! users call). It parses `volcast render`'s own options (`volcast::cli`) and renders through the same steps, on
//! one device per process owned by one thread (`device.rs`); the caller's thread waits with the GIL released and
//! answers Ctrl+C (`wait.rs`).

mod device;
mod errors;
mod options;
mod render;
mod view;
mod volume;
mod wait;

use pyo3::prelude::*;

#[pymodule]
fn _volcast(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<volume::PyVolume>()?;
    m.add_function(wrap_pyfunction!(volume::open, m)?)?;
    m.add_function(wrap_pyfunction!(volume::from_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(volume::builtin, m)?)?;
    m.add_function(wrap_pyfunction!(options::render_options, m)?)?;
    m.add_function(wrap_pyfunction!(options::view_options, m)?)?;
    m.add_function(wrap_pyfunction!(options::open_options, m)?)?;
    m.add_function(wrap_pyfunction!(options::check_tf, m)?)?;
    m.add_function(wrap_pyfunction!(options::preset_tf, m)?)?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_function(wrap_pyfunction!(render::movie, m)?)?;
    m.add_function(wrap_pyfunction!(render::view_state, m)?)?;
    m.add_function(wrap_pyfunction!(view::view, m)?)?;
    m.add_function(wrap_pyfunction!(device::shutdown, m)?)?;
    m.add_function(wrap_pyfunction!(device::validation_counts, m)?)?;
    m.add_function(wrap_pyfunction!(device::device_name, m)?)?;
    Ok(())
}
