//! `volcast render`: one image (with timings, memory and a colour bar on request), or a movie (turntable or
//! keyframes).

use super::args::RenderArgs;
use super::with_gpu;
use crate::gpu::Gpu;
use crate::render::headless::Headless;
use crate::scene::settings::{RaySetup, RenderSettings};
use crate::volume::Volume;
use anyhow::{Context, Result};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(|a, b| a.total_cmp(b));
    v.get(v.len() / 2).copied()
}

/// `--timings`: medians in ms of `--frames` frames (default 5) drawn after the first: the wall time of each, and the
/// GPU's total and per pass where the device times them (entry and exit only with the entry/exit setup).
pub struct FrameTimes {
    pub frames: usize,
    pub wall: f64,
    pub gpu: Option<f64>,
    pub entry: Option<f64>,
    pub exit: Option<f64>,
    pub march: Option<f64>,
}

/// Renders `--frames` frames of `s` and takes their medians.
pub fn time_frames(gpu: &Gpu, headless: &mut Headless, args: &RenderArgs, s: &RenderSettings) -> Result<FrameTimes> {
    let (mut wall, mut march, mut entry, mut exit, mut total) = (vec![], vec![], vec![], vec![], vec![]);
    for _ in 0..args.frames.unwrap_or(5).max(1) {
        let t = Instant::now();
        let frame = headless.render(gpu, s)?;
        wall.push(t.elapsed().as_secs_f64() * 1e3);
        if let Some(tm) = frame.timings {
            march.push(tm.march_ms);
            total.push(tm.total_ms);
            entry.extend(tm.entry_ms);
            exit.extend(tm.exit_ms);
        }
    }
    Ok(FrameTimes {
        frames: wall.len(),
        wall: median(wall).unwrap_or(0.0),
        gpu: median(total),
        entry: median(entry),
        exit: median(exit),
        march: median(march),
    })
}

impl FrameTimes {
    /// The line `render --timings` prints.
    pub fn line(&self) -> String {
        let mut line = format!("median of {} frames: {:.2} ms wall", self.frames, self.wall);
        if let (Some(total), Some(march)) = (self.gpu, self.march) {
            line += &format!("; GPU {total:.2} ms total");
            match (self.entry, self.exit) {
                (Some(entry), Some(exit)) => {
                    line += &format!(" = entry {entry:.2} + exit {exit:.2} + march {march:.2}")
                }
                _ => line += &format!(" (march {march:.2})"),
            }
        }
        line
    }
}

/// The layers `render` shows: the options', or where they name none the saved view's (`--state`), whose looks
/// `s` then keeps; other looks in `s` are dropped, for the layers' own.
pub fn layer_args(args: &RenderArgs, s: &mut RenderSettings) -> Result<super::layers::LayerArgs> {
    let files = read_state(args)?.map(|st| st.layer_files).unwrap_or_default();
    let (layers, saved) = args.layers.or_from(&files);
    if !saved || layers.styled() {
        s.layers.clear();
    }
    Ok(layers)
}

/// The saved view `--state` names, if any.
fn read_state(args: &RenderArgs) -> Result<Option<crate::scene::view_state::ViewState>> {
    let Some(path) = &args.state else {
        return Ok(None);
    };
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Ok(Some(
        crate::scene::view_state::ViewState::from_json(&text, &path.display().to_string())
            .map_err(anyhow::Error::msg)?,
    ))
}

/// The volume and settings `render` shows: a saved view's, or the options'. The volume is read within the host
/// budget; the device decides later whether it is uploaded whole, streamed or reduced further.
pub fn render_view(args: &RenderArgs) -> Result<(Volume, RenderSettings)> {
    let state = read_state(args)?;
    let volume_args = match &state {
        Some(st) => args.volume.or_from(&st.volume),
        None => args.volume.clone(),
    };
    let volume = volume_args.load()?;
    let s = settings_of(args, state, &volume)?;
    Ok((volume, s))
}

/// The settings `render` shows `volume` with (the Python module's volumes and arrays): the options', over the
/// saved view where `--state` names one.
pub fn view_settings(args: &RenderArgs, volume: &Volume) -> Result<RenderSettings> {
    settings_of(args, read_state(args)?, volume)
}

fn settings_of(
    args: &RenderArgs,
    state: Option<crate::scene::view_state::ViewState>,
    volume: &Volume,
) -> Result<RenderSettings> {
    let mut s = match state {
        // The saved view (its method included), with the options given here over it.
        Some(st) => {
            let mut s = st.settings;
            let quality = st.viewer.and_then(|v| v.quality);
            args.frame.override_view(&mut s, volume, quality)?;
            s
        }
        None => args.frame.settings(volume)?,
    };
    if args.state.is_none() || args.frame.given.has("method") {
        s.pipeline.ray_setup = if args.method == "faces" {
            RaySetup::Faces
        } else {
            RaySetup::Analytic
        };
        s.pipeline.compute = args.method == "compute";
    }
    Ok(s)
}

/// Places `volume` on the GPU within the budgets: whole, or streamed where it is over the GPU budget whole; a
/// budget without room for one brick takes the finest whole level that fits it, which is returned.
pub fn place(gpu: &Gpu, headless: &mut Headless, args: &RenderArgs, volume: &Volume) -> Result<Option<Volume>> {
    match headless
        .renderer
        .place_volume(gpu, volume, &args.volume.budgets_on(gpu))
    {
        Ok(_) => Ok(None),
        Err(crate::gpu::GpuError::NoRoom(_)) => {
            let volume = args.volume.fit_device(gpu, volume.clone())?;
            headless.set_volume(gpu, &volume)?;
            Ok(Some(volume))
        }
        Err(e) => Err(e.into()),
    }
}

/// Makes what the view `s` shows of `volume` (placed by [`place`]) resident: a streamed volume's cut (or
/// `--level` everywhere), and the gradient texture where `s` asks for one.
pub fn make_resident(
    gpu: &Gpu,
    headless: &mut Headless,
    args: &RenderArgs,
    volume: &Volume,
    s: &RenderSettings,
) -> Result<()> {
    if headless.renderer.stream().is_some() {
        let budgets = args.volume.budgets_on(gpu);
        let gpu_budget = budgets.gpu.map_or(gpu.device_local_bytes, |g| g.bytes);
        stream_in(gpu, headless, volume, s, args.level, gpu_budget)?;
    } else if let Some(level) = args.level {
        show_level(gpu, headless, volume, s, level)?;
    }
    if s.lighting.gradient_texture && !headless.renderer.has_gradient_texture() {
        headless.renderer.enable_gradient_texture(gpu, volume)?;
    }
    Ok(())
}

/// The frame of `s` (placed and made resident), with the colour bar and scale bar where `--colorbar` and
/// `--scale-bar` ask for them.
pub fn image(
    gpu: &Gpu,
    headless: &mut Headless,
    args: &RenderArgs,
    volume: &Volume,
    s: &RenderSettings,
) -> Result<image::RgbaImage> {
    let frame = headless.render(gpu, s)?;
    let figure = crate::render::figure::annotated;
    Ok(figure(frame.image, s, volume, args.colorbar, args.scale_bar))
}

/// What a movie shows: its volume where the options read one (none where `volume` is given), and its plan.
pub fn movie_plan(args: &RenderArgs, volume: Option<&Volume>) -> Result<(Option<Volume>, crate::movie::Plan)> {
    use crate::movie::{MovieError, MovieFiles, Plan};
    if args.keyframes.is_empty() {
        let frames = args.turntable.unwrap_or(1);
        MovieFiles::new(&args.output, frames)?;
        let (volume, base) = match volume {
            Some(v) => (None, view_settings(args, v)?),
            None => render_view(args).map(|(v, s)| (Some(v), s))?,
        };
        return Ok((
            volume,
            Plan::Turntable {
                base: Box::new(base),
                frames,
            },
        ));
    }
    let frames = args
        .frames
        .ok_or_else(|| MovieError::Usage("--keyframes needs --frames N, the movie's length in frames".into()))?;
    crate::movie::check_frames(frames, 2, "--frames")?;
    MovieFiles::new(&args.output, frames)?;
    let states = crate::movie::read_keyframes(&args.keyframes)?;
    let volume = match volume {
        Some(_) => None,
        None => Some(args.volume.or_from(&states[0].volume).load()?),
    };
    let keys = states.into_iter().map(|st| st.settings).collect();
    Ok((volume, Plan::Keyframes { keys, frames }))
}

/// Records the movie of `plan` with `volume` on `headless` (placed here), with the layers of `args` and `held`
/// (volumes the caller holds, each an overlay or, with `true`, a label map) in every frame, saying on stderr when
/// it is streamed; `progress` hears each frame and stops the movie by returning false. Returns the files' summary.
pub fn record_movie(
    gpu: &Gpu,
    headless: &mut Headless,
    (args, held): (&RenderArgs, Vec<(Volume, bool)>),
    volume: &Volume,
    plan: &crate::movie::Plan,
    progress: &mut dyn FnMut(u32) -> bool,
) -> Result<String> {
    let files = crate::movie::MovieFiles::new(&args.output, plan.frame_count())?;
    let mut first = plan.first().clone();
    let layer_args = layer_args(args, &mut first)?;
    super::layers::check(layer_args.any() || !held.is_empty(), plan.first())?;
    let channels = layer_args.channels_of(volume, |k| args.volume.channel(k))?;
    let layers = layer_args.load_all(channels, held)?;
    let reduced = place(gpu, headless, args, volume)?;
    let volume = reduced.as_ref().unwrap_or(volume);
    // Rule 13's layers in every frame (none where no --overlay or --labels was given).
    super::layers::upload(&layers, gpu, headless, volume)?;
    let plan = &plan.clone().with_layers(&layers.looks(&first.layers));
    if let Some(st) = headless.renderer.stream() {
        let gpu_budget = args
            .volume
            .budgets_on(gpu)
            .gpu
            .map_or(gpu.device_local_bytes, |g| g.bytes);
        eprintln!(
            "note: {} {}; each frame is streamed through a pool of {} bricks",
            volume.name,
            crate::render::placement::streamed_because(volume, gpu_budget),
            st.capacity()
        );
    }
    crate::movie::record(gpu, headless, volume, plan, &files, args.fps, progress)?;
    Ok(files.summary(args.fps))
}

/// `render --turntable` and `render --keyframes`: the frames of `crate::movie`, as PNGs and a GIF.
fn movie(args: &RenderArgs) -> Result<()> {
    let (volume, plan) = movie_plan(args, None)?;
    let volume = volume.context("the movie's volume was not read")?;
    let label = if args.keyframes.is_empty() {
        "turntable"
    } else {
        "keyframes"
    };
    with_gpu(&args.gpu, |gpu| {
        let mut headless = Headless::new(gpu)?;
        let mut progress = crate::movie::Progress::stderr(label, plan.frame_count());
        let done = record_movie(gpu, &mut headless, (args, Vec::new()), &volume, &plan, &mut |k| {
            progress.update(k);
            true
        });
        headless.destroy(gpu);
        println!("{}", done?);
        Ok(())
    })
}

/// `--level`: level `level` (at most the coarsest) everywhere, with a note saying which.
fn show_level(gpu: &Gpu, headless: &mut Headless, volume: &Volume, s: &RenderSettings, level: u32) -> Result<()> {
    use crate::pyramid::bricks::top_level;
    use crate::render::levels::LevelChoice;
    headless
        .renderer
        .show_levels(gpu, volume, s, LevelChoice::Forced(level))?;
    let Some(pool) = headless.renderer.pool() else {
        return Ok(());
    };
    let [bx, by, bz] = pool.brick;
    let top = top_level(volume.dims, pool.brick);
    if level > top {
        eprintln!("note: --level {level} is past the coarsest level of bricks of {bx}x{by}x{bz} ({top})");
    }
    let shown = level.min(top);
    let [x, y, z] = pool.levels[shown as usize];
    eprintln!("note: showing level {shown} ({x}x{y}x{z}) of the pyramid everywhere, through bricks of {bx}x{by}x{bz}");
    Ok(())
}

/// Streams `volume` (placed streamed) until the screen rule's cut for `s` (or `level` everywhere) is resident,
/// with a note saying what was shown.
fn stream_in(
    gpu: &Gpu,
    headless: &mut Headless,
    volume: &Volume,
    s: &RenderSettings,
    level: Option<u32>,
    budget: u64,
) -> Result<()> {
    use crate::render::levels::Cut;
    let r = &mut headless.renderer;
    let per_step = r.stream_uploads_within(crate::render::placement::UPLOAD_PER_STEP);
    let (capacity, top, grid) = match (r.stream(), r.pool()) {
        (Some(st), Some(p)) => (st.capacity(), st.top, p.grid),
        _ => anyhow::bail!("{}: the stream did not start", volume.name),
    };
    let last = match level.map(|l| Cut::uniform(grid, l.min(top))) {
        Some(cut) => {
            let n = cut.shown().len();
            anyhow::ensure!(
                n < capacity,
                "{}: --level {} needs {n} bricks and the GPU budget holds {capacity} (--gpu-budget, or a coarser \
                 --level)",
                volume.name,
                cut.level[0]
            );
            r.refine_to(gpu, volume, &cut)?
        }
        None => r.refine(gpu, volume, s)?.context("the stream did not start")?,
    };
    let [bx, by, bz] = r.pool().map_or([0; 3], |p| p.brick);
    eprintln!(
        "note: {} {}; streamed through a pool of {capacity} bricks of {bx}x{by}x{bz} in {} step(s) of at most \
         {per_step} uploads: {} of its {} level-0 bricks shown",
        volume.name,
        crate::render::placement::streamed_because(volume, budget),
        last.steps,
        last.levels_shown(),
        last.per_level.iter().sum::<usize>()
    );
    Ok(())
}

pub fn render(args: &RenderArgs) -> Result<()> {
    if args.turntable.is_some() || !args.keyframes.is_empty() {
        return movie(args);
    }
    // Exit 64 before anything is rendered: a name volcast cannot write, or a folder that does not exist.
    crate::render::save::check_name(&args.output).map_err(super::UsageError)?;
    let t_device = Instant::now();
    with_gpu(&args.gpu, |gpu| {
        let mut headless = Headless::new(gpu)?;
        let device_ms = t_device.elapsed().as_secs_f64() * 1e3;
        // Read at the finest level the host budget holds; the GPU budget decides below whether it is uploaded
        // whole or streamed brick by brick.
        let t_load = Instant::now();
        let loaded = render_view(args);
        let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
        let loaded = loaded.and_then(|(v, mut s)| {
            let layer_args = layer_args(args, &mut s)?;
            super::layers::check(layer_args.any(), &s)?;
            let channels = layer_args.channels_of(&v, |k| args.volume.channel(k))?;
            let layers = layer_args.load_all(channels, Vec::new())?;
            Ok((v, s, layers))
        });
        let (mut volume, mut s, layers) = match loaded {
            Ok(v) => v,
            Err(e) => {
                headless.destroy(gpu);
                return Err(e);
            }
        };
        let result = (|| -> Result<()> {
            let t_upload = Instant::now();
            if let Some(reduced) = place(gpu, &mut headless, args, &volume)? {
                volume = reduced;
            }
            super::layers::show(&layers, gpu, &mut headless, &volume, &mut s)?;
            make_resident(gpu, &mut headless, args, &volume, &s)?;
            let upload_ms = t_upload.elapsed().as_secs_f64() * 1e3;
            let t0 = Instant::now();
            let mut frame = headless.render(gpu, &s)?;
            let first_ms = t0.elapsed().as_secs_f64() * 1e3;
            let timing_line = if args.timings {
                time_frames(gpu, &mut headless, args, &s)?.line()
            } else {
                String::new()
            };
            let figure = crate::render::figure::annotated;
            frame.image = figure(frame.image, &s, &volume, args.colorbar, args.scale_bar);
            crate::render::save::save(&frame.image, &args.output).map_err(anyhow::Error::msg)?;
            let [sx, sy, sz] = volume.geometry.spacing().map(crate::volume::geometry::shortest);
            println!(
                "rendered {} ({}x{}x{} {}, spacing {sx}x{sy}x{sz}) at {}x{} with {} ray setup on {} -> {}",
                volume.name,
                volume.dims[0],
                volume.dims[1],
                volume.dims[2],
                volume.source_type,
                s.width,
                s.height,
                match (s.pipeline.ray_setup, s.pipeline.compute) {
                    (RaySetup::Faces, _) => "entry/exit faces",
                    (RaySetup::Analytic, false) => "analytic",
                    (RaySetup::Analytic, true) => "analytic (compute pass)",
                },
                gpu.device_name,
                args.output.display()
            );
            println!(
                "load {load_ms:.0} ms; device {device_ms:.0} ms; upload {upload_ms:.0} ms; first frame {first_ms:.0} \
                 ms (includes compiling its pipelines)"
            );
            println!("classification: {}", classification_text(&s));
            if !timing_line.is_empty() {
                println!("{timing_line}");
            }
            if let Some(ms) = headless.renderer.light_grid_ms() {
                println!("light grid (shadows, occlusion): {ms:.0} ms");
            }
            if args.memory {
                println!("{}", crate::measure::bench::memory_line(gpu, &headless, &s)?);
            }
            Ok(())
        })();
        headless.destroy(gpu);
        result
    })
}

/// What `s` classifies with, in words: the transfer function's name, or the colormap model's parts.
fn classification_text(s: &RenderSettings) -> String {
    match &s.colour.transfer_function {
        Some(tf) => format!(
            "transfer function '{}' (window {:.2}-{:.2}; --preset, --tf or --colormap choose another)",
            tf.name, s.colour.window[0], s.colour.window[1]
        ),
        None => format!(
            "colormap {}, window {:.2}-{:.2}, step alpha {}{}",
            s.colour.colormap.name(),
            s.colour.window[0],
            s.colour.window[1],
            s.colour.step_alpha,
            if s.colour.multiplied_alpha { " x value" } else { "" }
        ),
    }
}
