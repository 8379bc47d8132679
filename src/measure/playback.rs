//! `volcast bench --playback`: a time series played step after step as the viewer plays it. Each frame shows
//! the step due, renders it, and uploads the step after it ahead of display (`Renderer::prepare_volume`: the
//! volume in the device's layout, its brick grid and occupancy), so that showing a step is only an install. The
//! three are timed apart, so a shortfall says which to work on. The series (default 64 steps of 128³ float32, the case) is generated:
//! the helix field moving along z by two voxels a step and brightening, every step different.

use crate::gpu::{Gpu, GpuError};
use crate::measure::bench::{load_average, Stats};
use crate::render::headless::Headless;
use crate::render::PreparedVolume;
use crate::scene::settings::RenderSettings;
use crate::volume::{self, Volume, VolumeError, VoxelData, VoxelType};
use std::time::Instant;

/// What to play.
#[derive(Clone, Debug)]
pub struct PlaybackOptions {
    pub steps: u32,
    /// Edge of the cubic float32 volume.
    pub edge: u32,
    /// Edge of the square image.
    pub image: u32,
    /// Times the series is played; the first pass is a warm-up (lavapipe compiles shaders on first use).
    pub loops: u32,
}

impl PlaybackOptions {
    /// The target case: 64 steps of 128³ float32 at 512².
    pub const FULL: PlaybackOptions = PlaybackOptions {
        steps: 64,
        edge: 128,
        image: 512,
        loops: 2,
    };
    /// CI smoke mode: 6 steps of 24³ at 64².
    pub const QUICK: PlaybackOptions = PlaybackOptions {
        steps: 6,
        edge: 24,
        image: 64,
        loops: 2,
    };
}

/// Per-frame times over the timed passes.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PlaybackReport {
    pub steps: u32,
    pub edge: u32,
    pub image: u32,
    pub frames: u32,
    /// Showing the step due, uploaded ahead by the previous frame (an install: descriptor update), ms.
    pub show_ms: Stats,
    /// Uploading the next step ahead (layout conversion, copy, brick grid), ms.
    pub upload_ms: Stats,
    /// Render (with readback) per step, ms.
    pub render_ms: Stats,
    /// All three, per step, ms.
    pub frame_ms: Stats,
    /// 1000 / median frame.
    pub steps_per_second: f64,
    /// The series in memory, MiB.
    pub series_mib: f64,
    pub device: String,
    pub load_average: Option<[f64; 3]>,
}

impl PlaybackReport {
    pub fn text(&self) -> String {
        let s = |x: &Stats| format!("{:.1} ms (min {:.1}, max {:.1})", x.median, x.min, x.max);
        format!(
            "playback: {} steps of {e}x{e}x{e} float32 ({:.0} MiB) at {i}x{i} on {}, {} timed frames\n  \
             show step {}\n  render {}\n  upload next step ahead {}\n  frame  {}\n  => {:.1} steps/s{}\n",
            self.steps,
            self.series_mib,
            self.device,
            self.frames,
            s(&self.show_ms),
            s(&self.render_ms),
            s(&self.upload_ms),
            s(&self.frame_ms),
            self.steps_per_second,
            self.load_average.map_or(String::new(), |l| format!(
                " (load average {:.2} {:.2} {:.2})",
                l[0], l[1], l[2]
            )),
            e = self.edge,
            i = self.image,
        )
    }
}

/// The generated series: the helix moved along z by two voxels and scaled up 1% per step.
pub fn series(steps: u32, edge: u32) -> Result<Volume, VolumeError> {
    let base = volume::builtin("helix", Some(edge))?;
    let [w, h, d] = base.dims;
    let plane = (w * h) as usize;
    let step_data = |t: u32| {
        let mut v = Vec::with_capacity(plane * d as usize);
        for z in 0..d {
            let src = (z + d - (2 * t) % d) % d;
            for y in 0..h {
                for x in 0..w {
                    v.push(base.value(x, y, src) as f32 * (1.0 + 0.01 * t as f32));
                }
            }
        }
        VoxelData::F32(v)
    };
    let first = Volume::new(
        "playback-helix",
        base.dims,
        base.spacing(),
        VoxelType::F32,
        step_data(0),
    )?;
    first.with_time_steps((1..steps).map(step_data).collect())
}

/// Plays the series `opts.loops` times, timing every frame after the first pass.
pub fn run(gpu: &Gpu, opts: &PlaybackOptions, log: &mut dyn FnMut(&str)) -> Result<PlaybackReport, GpuError> {
    log(&format!(
        "playback: generating {} steps of {e}x{e}x{e} float32",
        opts.steps,
        e = opts.edge
    ));
    let mut series = series(opts.steps, opts.edge).map_err(|e| GpuError::TooLarge(e.to_string()))?;
    let mut headless = Headless::new(gpu)?;
    let result = play(gpu, &mut headless, &mut series, opts, log);
    headless.destroy(gpu);
    result
}

fn play(
    gpu: &Gpu,
    headless: &mut Headless,
    series: &mut Volume,
    opts: &PlaybackOptions,
    log: &mut dyn FnMut(&str),
) -> Result<PlaybackReport, GpuError> {
    let mut ahead: Option<PreparedVolume> = None;
    let result = play_steps(gpu, headless, series, opts, &mut ahead, log);
    if let Some(p) = ahead {
        p.destroy(gpu);
    }
    result
}

/// As the viewer plays: the step due is shown (installed, uploaded ahead by the previous frame), rendered, and
/// the step after it uploaded ahead.
fn play_steps(
    gpu: &Gpu,
    headless: &mut Headless,
    series: &mut Volume,
    opts: &PlaybackOptions,
    ahead: &mut Option<PreparedVolume>,
    log: &mut dyn FnMut(&str),
) -> Result<PlaybackReport, GpuError> {
    let settings = RenderSettings::new(opts.image, opts.image, series.extent());
    let steps = series.timesteps();
    let volume_error = |e: VolumeError| GpuError::TooLarge(e.to_string());
    let (mut show, mut upload, mut render, mut frame) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for pass in 0..opts.loops.max(2) {
        log(&format!("playback: pass {} of {}", pass + 1, opts.loops.max(2)));
        for t in 0..steps {
            let start = Instant::now();
            series.show_step(t).map_err(volume_error)?;
            match ahead.take() {
                Some(prepared) => headless.renderer.install_volume(gpu, prepared),
                None => headless.set_volume(gpu, series)?,
            }
            let shown = Instant::now();
            headless.render(gpu, &settings)?;
            let rendered = Instant::now();
            series.show_step((t + 1) % steps).map_err(volume_error)?;
            *ahead = Some(headless.renderer.prepare_volume(gpu, series)?);
            let done = Instant::now();
            if pass > 0 {
                let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
                show.push(ms(start, shown));
                render.push(ms(shown, rendered));
                upload.push(ms(rendered, done));
                frame.push(ms(start, done));
            }
        }
    }
    let none = GpuError::Lost("no playback frames timed");
    let frame_ms = Stats::of(&frame).ok_or(none)?;
    let bytes = series.voxel_count() as f64 * 4.0 * f64::from(series.timesteps());
    Ok(PlaybackReport {
        steps: series.timesteps(),
        edge: opts.edge,
        image: opts.image,
        frames: frame.len() as u32,
        show_ms: Stats::of(&show).ok_or(GpuError::Lost("no step change timed"))?,
        upload_ms: Stats::of(&upload).ok_or(GpuError::Lost("no upload timed"))?,
        render_ms: Stats::of(&render).ok_or(GpuError::Lost("no render timed"))?,
        frame_ms,
        steps_per_second: 1e3 / frame_ms.median.max(1e-6),
        series_mib: bytes / f64::from(1 << 20),
        device: gpu.device_name.clone(),
        load_average: load_average(),
    })
}
