//! `volcast.render` and `volcast.movie`: `volcast render`'s steps on the process's device, for a volume the caller
//! holds (placed once and kept while it is rendered again) or one the options read (a FILE, `--builtin`).

use crate::device::{Device, Shown};
use crate::errors::{to_py, While};
use crate::options::parse_render;
use crate::volume::PyVolume;
use crate::wait::wait;
use numpy::ndarray::Array3;
use numpy::PyArray3;
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use volcast::cli::args::RenderArgs;
use volcast::cli::render as steps;
use volcast::cli::UsageError;
use volcast::volume::Volume;

/// The options that say how a volume is read, which a volume already in memory cannot take.
const READING: &[&str] = &[
    "builtin",
    "builtin_size",
    "dims",
    "voxel_type",
    "spacing",
    "endian",
    "header_bytes",
    "array",
    "series",
    "channel",
    "time",
    "cache_dir",
    "no_cache",
];

/// A volume the caller holds, with the number that tells it from every other.
type Held = (u64, Arc<Volume>);

/// A call's arguments from `argv` (a transfer function as JSON counting as `--tf`), and the volume the caller holds,
/// if any, with its number. A held volume takes no file-reading option, and is classified as a file is (the
/// automatic transfer function), or as `--builtin` is (the colormap model) where `volcast.builtin` made it.
fn prepared(
    volume: Option<&PyVolume>,
    argv: Vec<String>,
    tf_json: Option<String>,
) -> PyResult<(RenderArgs, Option<Held>)> {
    let mut args = parse_render(argv, tf_json).map_err(|e| to_py(e, While::Rendering))?;
    let Some(v) = volume else {
        return Ok((args, None));
    };
    let given: Vec<&str> = READING
        .iter()
        .copied()
        .filter(|id| args.frame.given.has(id))
        .map(|id| if id == "voxel_type" { "type" } else { id })
        .collect();
    if !given.is_empty() || args.volume.file.is_some() {
        let e = UsageError(format!(
            "{} say how a file is read: give them to volcast.open (or Volume.from_array), not with a Volume",
            given.join(", ")
        ));
        return Err(to_py(e.into(), While::Rendering));
    }
    args.frame.given.from_file = !v.builtin;
    Ok((args, Some((v.id, v.inner.clone()))))
}

/// Places `volume` (number `id`) unless it is the one placed under the same placement options.
fn place<'d>(dev: &'d mut Device, args: &RenderArgs, id: u64, volume: &Volume) -> anyhow::Result<&'d Shown> {
    let v = &args.volume;
    let key = format!(
        "{id} {:?} {:?} {:?} {} {:?}",
        v.budgets.host_budget, v.budgets.gpu_budget, v.max_dim, v.no_downsample, args.level
    );
    if dev.shown.as_ref().is_none_or(|s| s.key != key) {
        dev.shown = None;
        let reduced = steps::place(&dev.gpu, &mut dev.headless, args, volume)?;
        dev.shown = Some(Shown { key, reduced });
    }
    Ok(dev.shown.as_ref().expect("placed above"))
}

/// What a call asked for besides the frame: `--timings`' medians over `--frames` frames (name, ms) and
/// `--memory`'s line.
type Report = (Vec<(String, f64)>, Option<String>);

/// One frame on the device thread: the volume placed (or kept), made resident for the view, rendered.
fn frame(
    dev: &mut Device,
    args: &RenderArgs,
    held: Option<(u64, Arc<Volume>)>,
    held_layers: Vec<(Arc<Volume>, bool)>,
) -> anyhow::Result<(image::RgbaImage, Report)> {
    let (id, volume, s) = match held {
        Some((id, v)) => {
            let s = steps::view_settings(args, &v)?;
            (id, v, s)
        }
        None => {
            let (v, s) = steps::render_view(args)?;
            (0, Arc::new(v), s)
        }
    };
    place(dev, args, id, &volume)?;
    let Device {
        gpu, headless, shown, ..
    } = dev;
    let reduced = shown.as_ref().and_then(|s| s.reduced.as_ref());
    let volume_shown = reduced.unwrap_or(&volume);
    // Rule 13's layers, as `volcast render` reads them, and the arrays given (none: the layers of an earlier call
    // are dropped).
    let mut s = s;
    let layer_args = steps::layer_args(args, &mut s)?;
    volcast::cli::layers::check(layer_args.any() || !held_layers.is_empty(), &s)?;
    let held_layers = held_layers
        .into_iter()
        .map(|(v, labels)| (v.as_ref().clone(), labels))
        .collect();
    let channels = layer_args.channels_of(&volume, |k| args.volume.channel(k))?;
    let layers = layer_args.load_all(channels, held_layers)?;
    volcast::cli::layers::show(&layers, gpu, headless, volume_shown, &mut s)?;
    steps::make_resident(gpu, headless, args, volume_shown, &s)?;
    let image = steps::image(gpu, headless, args, volume_shown, &s)?;
    let timings = if args.timings {
        let t = steps::time_frames(gpu, headless, args, &s)?;
        let passes = [
            ("gpu_ms", t.gpu),
            ("entry_ms", t.entry),
            ("exit_ms", t.exit),
            ("march_ms", t.march),
        ];
        let present = passes
            .into_iter()
            .filter_map(|(name, ms)| Some((name.to_string(), ms?)));
        std::iter::once(("wall_ms".to_string(), t.wall))
            .chain(present)
            .collect()
    } else {
        Vec::new()
    };
    let memory = if args.memory {
        Some(volcast::measure::bench::memory_line(gpu, headless, &s)?)
    } else {
        None
    };
    if id == 0 {
        // A volume read for this call only: the next call reads its own.
        *shown = None;
    }
    if args.frame.given.has("output") {
        volcast::render::save::save(&image, &args.output).map_err(anyhow::Error::msg)?;
    }
    Ok((image, (timings, memory)))
}

/// Renders one frame with `volcast render`'s options (`argv`) of `volume`, or of the volume they name; returns it
/// as an (H, W, 4) uint8 array of RGBA (sRGB, straight alpha) with what `--timings` and `--memory` asked for, and
/// writes it to `--output` where that is given.
#[pyfunction]
#[pyo3(signature = (volume, argv, tf_json=None, layers=Vec::new()))]
pub fn render<'py>(
    py: Python<'py>,
    volume: Option<PyRef<'_, PyVolume>>,
    argv: Vec<String>,
    tf_json: Option<String>,
    layers: Vec<(PyRef<'_, PyVolume>, bool)>,
) -> PyResult<(Bound<'py, PyArray3<u8>>, Report)> {
    let (args, held) = prepared(volume.as_deref(), argv, tf_json)?;
    // Layers the caller holds: each an overlay or (true) a label map.
    let held_layers: Vec<(Arc<Volume>, bool)> = layers.iter().map(|(v, l)| (v.inner.clone(), *l)).collect();
    let rx = crate::device::submit(move |slot| frame(slot.device(&args.gpu)?, &args, held, held_layers))?;
    let (image, report) = wait(py, rx, None)?.map_err(|e| to_py(e, While::Rendering))?;
    let (w, h) = image.dimensions();
    let pixels = Array3::from_shape_vec((h as usize, w as usize, 4), image.into_raw())
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    Ok((PyArray3::from_owned_array(py, pixels), report))
}

/// Records `volcast render --turntable N` or `--keyframes …` with `argv` (its `--output` naming the frames and the
/// GIF) of `volume` or of the volume they name; returns the summary line the command prints. Ctrl+C stops it after
/// the frame being drawn, and removes what it wrote.
#[pyfunction]
#[pyo3(signature = (volume, argv, tf_json=None, layers=Vec::new()))]
pub fn movie(
    py: Python<'_>,
    volume: Option<PyRef<'_, PyVolume>>,
    argv: Vec<String>,
    tf_json: Option<String>,
    layers: Vec<(PyRef<'_, PyVolume>, bool)>,
) -> PyResult<String> {
    let (args, held) = prepared(volume.as_deref(), argv, tf_json)?;
    // Layers the caller holds, in every frame: each an overlay or (true) a label map.
    let held_layers: Vec<(Volume, bool)> = layers.iter().map(|(v, l)| (v.inner.as_ref().clone(), *l)).collect();
    if args.turntable.is_none() && args.keyframes.is_empty() {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "a movie needs turntable=N or keyframes=[...]",
        ));
    }
    let stop = Arc::new(AtomicBool::new(false));
    let stopping = stop.clone();
    let rx = crate::device::submit(move |slot| -> anyhow::Result<String> {
        let dev = slot.device(&args.gpu)?;
        dev.shown = None;
        let (read, plan) = steps::movie_plan(&args, held.as_ref().map(|(_, v)| v.as_ref()))?;
        let volume = match (&read, &held) {
            (Some(v), _) => v,
            (None, Some((_, v))) => v.as_ref(),
            (None, None) => anyhow::bail!("the movie's volume was not read"),
        };
        let mut progress = |_: u32| !stopping.load(Ordering::Relaxed);
        steps::record_movie(
            &dev.gpu,
            &mut dev.headless,
            (&args, held_layers),
            volume,
            &plan,
            &mut progress,
        )
    })?;
    wait(py, rx, Some(&stop))?.map_err(|e| to_py(e, While::Rendering))
}

/// Where the options say the volume comes from, as a view state records it (nothing for a volume held in Python).
fn volume_ref(args: &RenderArgs, spacing: [f32; 3]) -> volcast::scene::view_state::VolumeRef {
    let a = &args.volume;
    volcast::scene::view_state::VolumeRef {
        path: a
            .file
            .as_ref()
            .map(|p| std::fs::canonicalize(p).unwrap_or_else(|_| p.clone())),
        builtin: a.builtin.clone(),
        builtin_size: a.builtin_size,
        raw_dims: a.dims.as_ref().map(|d| [d[0], d[1], d[2]]),
        raw_type: a.voxel_type.clone(),
        raw_spacing: a.spacing.as_ref().map(|s| [s[0], s[1], s[2]]),
        spacing,
        time: a.time.unwrap_or(0),
        channel: a.channel,
    }
}

/// The view state of `argv`'s options shown on `volume` or on the volume they name: the JSON the viewer's F12
/// writes, which `--state` and `--keyframes` read.
#[pyfunction]
#[pyo3(signature = (volume, argv, tf_json=None))]
pub fn view_state(
    py: Python<'_>,
    volume: Option<PyRef<'_, PyVolume>>,
    argv: Vec<String>,
    tf_json: Option<String>,
) -> PyResult<String> {
    let (args, held) = prepared(volume.as_deref(), argv, tf_json)?;
    let state = crate::wait::on_thread(py, move || -> anyhow::Result<String> {
        let (volume, mut settings) = match held {
            Some((_, v)) => {
                let s = steps::view_settings(&args, &v)?;
                (v, s)
            }
            None => steps::render_view(&args).map(|(v, s)| (Arc::new(v), s))?,
        };
        // The layers' files and looks, which `--state` shows again.
        let layer_args = steps::layer_args(&args, &mut settings)?;
        let channels = layer_args.channels_of(&volume, |k| args.volume.channel(k))?;
        settings.layers = layer_args.load_all(channels, Vec::new())?.looks(&settings.layers);
        let state = volcast::scene::view_state::ViewState {
            volume: volume_ref(&args, volume.spacing()),
            settings,
            viewer: None,
            layer_files: layer_args.files(),
        };
        Ok(state.to_json())
    })?;
    state.map_err(|e| to_py(e, While::Rendering))
}
