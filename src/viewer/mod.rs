//! The desktop viewer: a winit window, a swapchain, the same `Renderer` as `volcast render` drawing into an
//! offscreen view image that is blitted to the swapchain, and an egui panel on top (egui-ash-renderer records
//! into our command buffer; we own submission and lifetimes).
//!
//! Four rooms, data flowing one way:
//! - [`model`]: what the viewer shows and the user edits, as plain data with its pure logic (no egui context, no
//!   GPU);
//! - [`widgets`]: the egui UI, editing the model and asking for the rest with `UiAction`s;
//! - `present`: the GPU side — device, swapchain, frames in flight, the volume's pass, egui's renderer, the slice
//!   views' textures, read-back;
//! - `app`: the event loop, loads, sessions, captures, the script, and a frame's steps (`app::frame`): poll → UI →
//!   settings → record, blit, present.
//!
//! [`run`] and [`ViewerOptions`] are the way in; [`session`] reads the session files `volcast view --state` takes.

mod app;
pub mod model;
mod present;
pub mod session;
pub mod widgets;

pub use app::script::{parse_script, ScriptStep};

use crate::formats::RawOptions;
use crate::gpu::{GpuError, GpuOptions, ValidationLog};
use std::path::PathBuf;
use std::sync::Arc;
use winit::event_loop::EventLoop;

#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    #[error("no display to open a window on ({0}); use `volcast render` to render to a PNG without one")]
    NoDisplay(String),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("{0}")]
    Other(String),
}

/// Where the first volume comes from.
#[derive(Clone, Debug)]
pub enum VolumeSource {
    Builtin(String, Option<u32>),
    File(PathBuf, RawOptions),
    /// A volume already in memory (the Python module's arrays), shown as it is; a session records no file for it.
    Memory(Arc<crate::volume::Volume>),
}

pub struct ViewerOptions {
    pub source: VolumeSource,
    /// The series to load from a DICOM folder holding several (`--series`; `None`: the largest).
    pub series: Option<String>,
    /// The channel of an OME-Zarr image (`--channel`; `None`: channel 0); it applies to every store the viewer opens.
    pub channel: Option<u32>,
    pub gpu: GpuOptions,
    pub size: (u32, u32),
    pub script: Vec<ScriptStep>,
    /// The step of a time series to show first (`--time`).
    pub time: Option<u32>,
    /// Host and device memory the volume may take (`--host-budget`, `--gpu-budget`; `None`: a quarter of the
    /// machine's memory, the device's largest heap) and `--max-dim`.
    pub host_budget: Option<u64>,
    pub gpu_budget: Option<u64>,
    pub max_dim: Option<u32>,
    /// The pyramid cache's folder (`--cache-dir`; `None`: the default) and `--no-cache`.
    pub cache_dir: Option<std::path::PathBuf>,
    pub no_cache: bool,
    /// Sampling quality of still frames (`--quality`; the panel and Q change it).
    pub quality: crate::scene::quality::Quality,
    /// Start in the four-up layout with the slice views (`--slices`; L toggles it).
    pub slices: bool,
    /// A session to restore once its volume (`source`) is shown (`--state`).
    pub restore: Option<crate::scene::view_state::ViewState>,
    /// A transfer function to open with, locked (`--preset`, `--tf`); None: the one chosen by modality.
    pub transfer_function: Option<crate::transfer::function::TransferFunction>,
    /// The layers to show with the volume (`--overlay`, `--labels`, `--channels`), read before the window opens.
    pub layers: crate::scene::layer_set::Layers,
    /// How layers added in the panel look (the command line's look options).
    pub layer_looks: crate::scene::layer_set::Looks,
}

/// Opens the viewer and runs until the window closes. Returns the validation log for the caller to report.
pub fn run(opts: ViewerOptions) -> Result<Arc<ValidationLog>, ViewerError> {
    let unset = |v: &str| std::env::var_os(v).is_none_or(|x| x.is_empty());
    if cfg!(all(unix, not(target_os = "macos")))
        && unset("DISPLAY")
        && unset("WAYLAND_DISPLAY")
        && unset("WAYLAND_SOCKET")
    {
        return Err(ViewerError::NoDisplay(
            "neither DISPLAY nor WAYLAND_DISPLAY is set".into(),
        ));
    }
    // winit makes one event loop per process; it is kept on this thread and run again for the next window (the
    // Python module's `volcast.view`, called more than once).
    thread_local! {
        static EVENT_LOOP: std::cell::RefCell<Option<EventLoop<()>>> = const { std::cell::RefCell::new(None) };
    }
    let mut event_loop = match EVENT_LOOP.with(|l| l.borrow_mut().take()) {
        Some(l) => l,
        None => EventLoop::new().map_err(|e| ViewerError::NoDisplay(e.to_string()))?,
    };
    let result = app::run(&mut event_loop, opts);
    EVENT_LOOP.with(|l| *l.borrow_mut() = Some(event_loop));
    result
}
