//! `volcast bench`: times a fixed table of scenes and measures the device's raw 3D-texture sampling rate, so
//! every frame time can be stated as samples per second and as a fraction of that limit (issue 7).
//!
//! What is measured, per scene × image size × ray setup (× shading, once it exists):
//! - wall ms per frame (render + readback, as `volcast render` does it) and GPU ms per pass (timestamp queries),
//!   median/min/max over `frames` frames after `warmup` untimed ones (lavapipe compiles shaders on first use);
//! - samples per pixel, counted on the CPU by replaying the march's rules (see [`SampleCounter`]): the march
//!   shader is left untouched, so the count costs the GPU nothing;
//! - effective samples per second (samples taken ÷ GPU frame time) and its fraction of the sample-only rate for the
//!   volume's texel format ([`sample_only`]);
//! - each configuration's error against the same scene rendered converged ([`crate::measure::fidelity`]).

mod counter;
mod layered;
mod report;
mod sample_only;
mod scenes;

pub use counter::*;
pub use report::*;
pub use sample_only::*;
pub use scenes::*;

use crate::formats;
use crate::formats::RawOptions;
use crate::gpu::{Gpu, GpuError};
use crate::measure::fidelity::{converged, Fidelity};
use crate::render::headless::Headless;
use crate::render::VolumeLayout;
use crate::scene::quality::{Quality, CONVERGED_STEP};
use crate::scene::settings::RenderSettings;
use crate::volume::{self, Volume, VolumeError};
use ash::vk;
use image::RgbaImage;
use std::path::Path;
use std::time::Instant;

#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Volume(#[from] VolumeError),
    #[error("{0}")]
    Usage(String),
}

/// Loads a scene's volume; `Ok(None)` with a reason when its file is missing.
fn load_scene_volume(scene: &Scene, opts: &BenchOptions) -> Result<Result<Volume, String>, VolumeError> {
    match scene.source {
        Source::Builtin { name, size } => Ok(Ok(volume::builtin(name, size)?)),
        Source::DataFile { file, spacing } => {
            let path = opts.data_dir.join(file);
            if !path.is_file() {
                return Ok(Err(format!(
                    "{} not found (point --data at the folder holding {file})",
                    path.display()
                )));
            }
            let raw = RawOptions {
                spacing: Some(spacing),
                ..Default::default()
            };
            Ok(Ok(formats::load_raw(&path, &raw)?))
        }
        Source::Native { file } => {
            let path = layered::native_path(&opts.data_dir, file);
            if !path.is_file() {
                return Ok(Err(format!("{} not found", path.display())));
            }
            Ok(Ok(Volume::open(&path)?))
        }
        Source::Channel => Ok(Ok(layered::channel_volume(0))),
        Source::VtkHelix => match &opts.vtk_raw {
            Some(path) => {
                let raw = RawOptions {
                    dims: Some([256; 3]),
                    voxel_type: Some(volume::VoxelType::U8),
                    spacing: Some([1.0; 3]),
                };
                let mut v = formats::load_raw(path, &raw)?;
                v.name = format!("vtk-helix from {}", file_name(path));
                Ok(Ok(v))
            }
            None => Ok(Ok(vtk_helix_volume(256)?)),
        },
    }
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// The scenes `opts` selects, or an error naming the known ones.
pub fn selected_scenes(opts: &BenchOptions) -> Result<Vec<Scene>, BenchError> {
    let all = if opts.quick { quick_scenes() } else { scenes() };
    if opts.scenes.is_empty() {
        return Ok(all);
    }
    let known: Vec<&str> = scenes().iter().chain(quick_scenes().iter()).map(|s| s.name).collect();
    for wanted in &opts.scenes {
        if !known.contains(&wanted.as_str()) {
            return Err(BenchError::Usage(format!(
                "unknown scene '{wanted}'; scenes: {}",
                known.join(", ")
            )));
        }
    }
    Ok(scenes()
        .into_iter()
        .chain(quick_scenes())
        .filter(|s| opts.scenes.iter().any(|w| w == s.name))
        .collect())
}

/// Runs the benchmark: the sample-only rates for the formats the selected scenes use (all three with
/// `sample_only`), then every scene × size × ray setup × shading. Progress goes to `log`.
pub fn run(gpu: &Gpu, opts: &BenchOptions, log: &mut dyn FnMut(&str)) -> Result<BenchReport, BenchError> {
    if opts.frames == 0 {
        return Err(BenchError::Usage("--frames must be at least 1".into()));
    }
    let chosen = selected_scenes(opts)?;
    if let Some(bad) = opts
        .shadings
        .iter()
        .find(|w| !Shading::ALL.iter().any(|v| v.name() == w.as_str()))
    {
        return Err(BenchError::Usage(format!(
            "unknown shading '{bad}'; use off, on or shadows"
        )));
    }
    let mut report = BenchReport {
        device: gpu.device_name.clone(),
        quick: opts.quick,
        frames: opts.frames,
        warmup: opts.warmup,
        load_before: load_average(),
        load_after: None,
        sample_only: Vec::new(),
        results: Vec::new(),
        skipped: Vec::new(),
        peak_rss_bytes: None,
    };
    let sample_cfg = if opts.quick {
        SampleOnlyConfig::quick()
    } else {
        SampleOnlyConfig::full(opts.frames)
    };

    // Every format: which one a scene's volume is stored in depends on the data and on `TexelPolicy::Auto`.
    let formats = TexelFormat::ALL;
    report.sample_only = sample_only(gpu, &formats, sample_cfg, log)?;
    if !opts.sample_only {
        let mut bench = Bench {
            gpu,
            opts,
            headless: Headless::new(gpu)?,
            report,
            log,
        };
        let result = chosen.iter().try_for_each(|scene| bench.scene(scene));
        bench.headless.destroy(gpu);
        result?;
        report = bench.report;
    }
    report.load_after = load_average();
    report.peak_rss_bytes = peak_rss_bytes();
    Ok(report)
}

/// A run through the scenes: the renderer that times them, the report it fills and where progress goes.
struct Bench<'a> {
    gpu: &'a Gpu,
    opts: &'a BenchOptions,
    headless: Headless,
    report: BenchReport,
    log: &'a mut dyn FnMut(&str),
}

/// A scene's volume on the GPU, and what all its configurations share.
struct LoadedScene<'a> {
    scene: &'a Scene,
    volume: Volume,
    /// Name, dims and voxel type, as the report states them.
    described: String,
    /// The layout the renderer chose (`VolumeLayout::name`).
    format: &'static str,
    /// The sample-only rate the frames are stated against (None when it was not measured).
    raw_rate: Option<f64>,
    counter: SampleCounter,
}

/// What a scene × size × shading's frames under each quality and method are measured against.
struct Reference {
    size: u32,
    shading: Shading,
    converged_image: RgbaImage,
    /// How long rule 9's light grid took to fill, for scenes with shadows or occlusion.
    light_grid_ms: Option<f64>,
}

/// What the timed frames of one configuration measured, in ms (GPU passes from timestamps, where the device has
/// them), and the last frame.
struct TimedFrames {
    wall: Vec<f64>,
    total: Vec<f64>,
    entry: Vec<f64>,
    exit: Vec<f64>,
    march: Vec<f64>,
    last: Option<RgbaImage>,
}

impl Bench<'_> {
    /// Every size × shading × method of `scene`; a scene whose file is missing is logged and listed as skipped.
    fn scene(&mut self, scene: &Scene) -> Result<(), BenchError> {
        let loaded = load_scene_volume(scene, self.opts)?;
        let layers = layered::load(scene.layers, &self.opts.data_dir)?;
        let (volume, layers) = match (loaded, layers) {
            (Ok(v), Ok(l)) => (v, l),
            (Err(reason), _) | (_, Err(reason)) => {
                (self.log)(&format!("{}: skipped: {reason}", scene.name));
                self.report.skipped.push(Skipped {
                    scene: scene.name.into(),
                    reason,
                });
                return Ok(());
            }
        };
        self.headless.set_volume(self.gpu, &volume)?;
        layers.upload(self.gpu, &mut self.headless.renderer)?;
        let loaded = self.loaded(scene, volume);
        let opts = self.opts;
        let sizes = scene
            .sizes
            .iter()
            .copied()
            .filter(|s| opts.sizes.is_empty() || opts.sizes.contains(s));
        for size in sizes {
            let mut base = RenderSettings::new(size, size, loaded.volume.extent());
            (scene.configure)(&mut base, &loaded.volume);
            base.layers = layers.styles.clone();
            let shadings = scene
                .shadings
                .iter()
                .filter(|v| opts.shadings.is_empty() || opts.shadings.iter().any(|w| w == v.name()));
            for &shading in shadings {
                self.shading(&loaded, size, base.clone(), shading)?;
            }
        }
        Ok(())
    }

    /// What every configuration of the scene just uploaded shares.
    fn loaded<'s>(&self, scene: &'s Scene, volume: Volume) -> LoadedScene<'s> {
        // The layout the renderer chose (TexelPolicy::Auto: corner or float textures on CPU devices).
        // Corner textures bypass the sampler; their rate is stated against the fastest texture format's.
        let layout = self.headless.renderer.volume_layout();
        let raw_format = match layout {
            Some(VolumeLayout::Texture(vk::Format::R8_UNORM)) => TexelFormat::R8Unorm,
            Some(VolumeLayout::Texture(vk::Format::R16_UNORM)) => TexelFormat::R16Unorm,
            _ => TexelFormat::R32Sfloat,
        };
        LoadedScene {
            scene,
            described: format!(
                "{} {}x{}x{} {}",
                volume.name, volume.dims[0], volume.dims[1], volume.dims[2], volume.source_type
            ),
            format: layout.map_or("none", |l| l.name()),
            raw_rate: self
                .report
                .sample_only
                .iter()
                .find(|r| r.format == raw_format)
                .map(|r| r.gsamples_per_s),
            counter: SampleCounter::new(&volume),
            volume,
        }
    }

    /// One shading variant of a scene at one size: its reference (sample count, converged image), then each
    /// method's timed frames.
    fn shading(
        &mut self,
        loaded: &LoadedScene,
        size: u32,
        mut s: RenderSettings,
        shading: Shading,
    ) -> Result<(), BenchError> {
        let (gpu, name) = (self.gpu, loaded.scene.name);
        shading.apply(&mut s);
        self.opts.gradients.apply(&mut s, loaded.volume.voxel_count() as u64);
        if s.lighting.gradient_texture {
            self.headless.renderer.enable_gradient_texture(gpu, &loaded.volume)?;
        }
        (self.log)(&format!(
            "{name} {size}x{size} shading {}: converged image (step {CONVERGED_STEP})",
            shading.name()
        ));
        let converged_image = self.headless.render(gpu, &converged(&s))?.image;
        // The converged frame made rule 9's light grid (the step is not part of it): its cost, once per
        // transfer function, light or volume.
        let light_grid_ms = s
            .uses_light_volume()
            .then(|| self.headless.renderer.light_grid_ms())
            .flatten();
        if let Some(ms) = light_grid_ms {
            (self.log)(&format!("{name} {size}x{size}: light grid {ms:.0} ms"));
        }
        let reference = Reference {
            size,
            shading,
            converged_image,
            light_grid_ms,
        };
        for (quality, s) in self.variants(&s, loaded.volume.range) {
            self.methods(loaded, &reference, &quality, s)?;
        }
        Ok(())
    }

    /// The frames timed against one converged image: `s` at each `--quality`, or at the `--step-length` forced.
    fn variants(&self, s: &RenderSettings, range: [f64; 2]) -> Vec<(String, RenderSettings)> {
        if let Some(step) = self.opts.step_length {
            let mut forced = s.clone();
            forced.sampling.step_length = step;
            forced.sampling.max_stride = 1;
            return vec![(format!("step {step}"), forced)];
        }
        let apply = |q: Quality| {
            let mut s = s.clone();
            q.apply(&mut s, range);
            (q.name().to_string(), s)
        };
        self.opts.qualities.iter().map(|&q| apply(q)).collect()
    }

    /// Each method's timed frames of `s` at one quality.
    fn methods(
        &mut self,
        loaded: &LoadedScene,
        reference: &Reference,
        quality: &str,
        mut s: RenderSettings,
    ) -> Result<(), BenchError> {
        let (opts, name, size) = (self.opts, loaded.scene.name, reference.size);
        // Counted before timing, so the count's CPU work never overlaps a timed frame.
        let count = loaded.counter.count(&s);
        let methods = Method::ALL
            .into_iter()
            .filter(|m| opts.methods.is_empty() || opts.methods.iter().any(|n| n == m.name()));
        for method in methods {
            method.apply(&mut s);
            (self.log)(&format!(
                "{name} {size}x{size} {} shading {} {quality}: {} warm-up + {} frames",
                method.name(),
                reference.shading.name(),
                opts.warmup,
                opts.frames
            ));
            let frames = self.time_frames(&s)?;
            let result = self.result(loaded, reference, (method, quality, count), &s, frames)?;
            self.report.results.push(result);
        }
        Ok(())
    }

    /// Renders `s` `warmup` times untimed, then `frames` times timed.
    fn time_frames(&mut self, s: &RenderSettings) -> Result<TimedFrames, BenchError> {
        let opts = self.opts;
        let mut timed = TimedFrames {
            wall: Vec::new(),
            total: Vec::new(),
            entry: Vec::new(),
            exit: Vec::new(),
            march: Vec::new(),
            last: None,
        };
        for i in 0..opts.warmup + opts.frames {
            let t = Instant::now();
            let frame = self.headless.render(self.gpu, s)?;
            let ms = t.elapsed().as_secs_f64() * 1e3;
            if i < opts.warmup {
                continue;
            }
            timed.wall.push(ms);
            if let Some(tm) = frame.timings {
                timed.total.push(tm.total_ms);
                timed.march.push(tm.march_ms);
                timed.entry.extend(tm.entry_ms);
                timed.exit.extend(tm.exit_ms);
            }
            timed.last = Some(frame.image);
        }
        Ok(timed)
    }

    /// One configuration's row: its times, sample rates, memory and error against the converged image.
    fn result(
        &self,
        loaded: &LoadedScene,
        reference: &Reference,
        (method, quality, count): (Method, &str, SampleCount),
        s: &RenderSettings,
        frames: TimedFrames,
    ) -> Result<SceneResult, BenchError> {
        let size = reference.size;
        let wall_ms = Stats::of(&frames.wall).ok_or(GpuError::Lost("no frames timed"))?;
        let gpu_ms = Stats::of(&frames.total);
        let frame_ms = gpu_ms.map_or(wall_ms.median, |g| g.median).max(1e-6);
        let pixels = f64::from(size) * f64::from(size);
        let effective = count.taken_per_pixel * pixels / (frame_ms * 1e-3) / 1e9;
        let (allocated, _) = gpu_allocated(self.gpu)?;
        Ok(SceneResult {
            scene: loaded.scene.name.into(),
            volume: loaded.described.clone(),
            format: loaded.format,
            width: size,
            height: size,
            method,
            shading: reference.shading,
            quality: quality.to_string(),
            frames: frames.wall.len() as u32,
            wall_ms,
            gpu_ms,
            entry_ms: median(&frames.entry),
            exit_ms: median(&frames.exit),
            march_ms: median(&frames.march),
            segment_samples_per_pixel: count.segment_per_pixel,
            samples_per_pixel: count.taken_per_pixel,
            effective_gsamples_per_s: effective,
            fraction_of_raw: loaded.raw_rate.map(|r| effective / r),
            gpu_allocated_bytes: allocated,
            load: load_average(),
            step_length: s.sampling.step_length,
            max_stride: s.sampling.max_stride,
            light_grid_ms: reference.light_grid_ms,
            error: Fidelity::of(
                &frames.last.ok_or(GpuError::Lost("no frames timed"))?,
                &reference.converged_image,
                s,
            ),
            target: Quality::parse(quality)
                .filter(|&q| q != Quality::Converged)
                .map(|q| q.target().into()),
        })
    }
}
