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
mod report;
mod sample_only;
mod scenes;

pub use counter::*;
pub use report::*;
pub use sample_only::*;
pub use scenes::*;

use crate::gpu::{Gpu, GpuError};
use crate::measure::fidelity::{converged, Fidelity};
use crate::render::headless::Headless;
use crate::render::VolumeLayout;
use crate::scene::quality::CONVERGED_STEP;
use crate::scene::settings::RenderSettings;
use crate::volume::{self, RawOptions, Volume, VolumeError};
use ash::vk;
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
            Ok(Ok(volume::load_raw(&path, &raw)?))
        }
        Source::VtkHelix => match &opts.vtk_raw {
            Some(path) => {
                let raw = RawOptions {
                    dims: Some([256; 3]),
                    voxel_type: Some(volume::VoxelType::U8),
                    spacing: Some([1.0; 3]),
                };
                let mut v = volume::load_raw(path, &raw)?;
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
    if opts.sample_only {
        report.load_after = load_average();
        report.peak_rss_bytes = peak_rss_bytes();
        return Ok(report);
    }

    let mut headless = Headless::new(gpu)?;
    let result = (|| -> Result<(), BenchError> {
        for scene in &chosen {
            let volume = match load_scene_volume(scene, opts)? {
                Ok(v) => v,
                Err(reason) => {
                    log(&format!("{}: skipped: {reason}", scene.name));
                    report.skipped.push(Skipped {
                        scene: scene.name.into(),
                        reason,
                    });
                    continue;
                }
            };
            headless.set_volume(gpu, &volume)?;
            // The layout the renderer chose (TexelPolicy::Auto: corner or float textures on CPU devices).
            // Corner textures bypass the sampler; their rate is stated against the fastest texture format's.
            let layout = headless.renderer.volume_layout();
            let format = layout.map_or("none", |l| l.name());
            let raw_format = match layout {
                Some(VolumeLayout::Texture(vk::Format::R8_UNORM)) => TexelFormat::R8Unorm,
                Some(VolumeLayout::Texture(vk::Format::R16_UNORM)) => TexelFormat::R16Unorm,
                _ => TexelFormat::R32Sfloat,
            };
            let described = format!(
                "{} {}x{}x{} {}",
                volume.name, volume.dims[0], volume.dims[1], volume.dims[2], volume.source_type
            );
            let raw_rate = report
                .sample_only
                .iter()
                .find(|r| r.format == raw_format)
                .map(|r| r.gsamples_per_s);
            let counter = SampleCounter::new(&volume);
            let sizes: Vec<u32> = scene
                .sizes
                .iter()
                .copied()
                .filter(|s| opts.sizes.is_empty() || opts.sizes.contains(s))
                .collect();
            for &size in &sizes {
                let mut base = RenderSettings::new(size, size, volume.extent());
                (scene.configure)(&mut base, &volume);
                opts.quality.apply(&mut base, volume.range);
                if let Some(step) = opts.step_length {
                    base.step_length = step;
                    base.max_stride = 1;
                }
                let shadings = scene
                    .shadings
                    .iter()
                    .filter(|v| opts.shadings.is_empty() || opts.shadings.iter().any(|w| w == v.name()));
                for &shading in shadings {
                    let mut s = base.clone();
                    shading.apply(&mut s);
                    opts.gradients.apply(&mut s, volume.voxel_count() as u64);
                    if s.gradient_texture {
                        headless.renderer.enable_gradient_texture(gpu, &volume)?;
                    }
                    // Counted before timing, so the count's CPU work never overlaps a timed frame.
                    let count = counter.count(&s);
                    log(&format!(
                        "{} {size}x{size} shading {}: converged image (step {CONVERGED_STEP})",
                        scene.name,
                        shading.name()
                    ));
                    let converged_image = headless.render(gpu, &converged(&s))?.image;
                    // The converged frame made rule 9's light grid (the step is not part of it): its cost, once per
                    // transfer function, light or volume.
                    let light_grid_ms = s
                        .uses_light_volume()
                        .then(|| headless.renderer.light_grid_ms())
                        .flatten();
                    if let Some(ms) = light_grid_ms {
                        log(&format!("{} {size}x{size}: light grid {ms:.0} ms", scene.name));
                    }
                    let methods = Method::ALL
                        .into_iter()
                        .filter(|m| opts.methods.is_empty() || opts.methods.iter().any(|n| n == m.name()));
                    for method in methods {
                        method.apply(&mut s);
                        log(&format!(
                            "{} {size}x{size} {} shading {}: {} warm-up + {} frames",
                            scene.name,
                            method.name(),
                            shading.name(),
                            opts.warmup,
                            opts.frames
                        ));
                        let (mut wall, mut total, mut entry, mut exit, mut march) =
                            (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
                        let mut last = None;
                        for i in 0..opts.warmup + opts.frames {
                            let t = Instant::now();
                            let frame = headless.render(gpu, &s)?;
                            let ms = t.elapsed().as_secs_f64() * 1e3;
                            if i < opts.warmup {
                                continue;
                            }
                            wall.push(ms);
                            if let Some(tm) = frame.timings {
                                total.push(tm.total_ms);
                                march.push(tm.march_ms);
                                entry.extend(tm.entry_ms);
                                exit.extend(tm.exit_ms);
                            }
                            last = Some(frame.image);
                        }
                        let wall_ms = Stats::of(&wall).ok_or(GpuError::Lost("no frames timed"))?;
                        let gpu_ms = Stats::of(&total);
                        let frame_ms = gpu_ms.map_or(wall_ms.median, |g| g.median).max(1e-6);
                        let pixels = f64::from(size) * f64::from(size);
                        let effective = count.taken_per_pixel * pixels / (frame_ms * 1e-3) / 1e9;
                        let (allocated, _) = gpu_allocated(gpu)?;
                        report.results.push(SceneResult {
                            scene: scene.name.into(),
                            volume: described.clone(),
                            format,
                            width: size,
                            height: size,
                            method,
                            shading,
                            frames: wall.len() as u32,
                            wall_ms,
                            gpu_ms,
                            entry_ms: median(&entry),
                            exit_ms: median(&exit),
                            march_ms: median(&march),
                            segment_samples_per_pixel: count.segment_per_pixel,
                            samples_per_pixel: count.taken_per_pixel,
                            effective_gsamples_per_s: effective,
                            fraction_of_raw: raw_rate.map(|r| effective / r),
                            gpu_allocated_bytes: allocated,
                            load: load_average(),
                            step_length: s.step_length,
                            max_stride: s.max_stride,
                            light_grid_ms,
                            error: Fidelity::of(&last.ok_or(GpuError::Lost("no frames timed"))?, &converged_image, &s),
                        });
                    }
                }
            }
        }
        Ok(())
    })();
    headless.destroy(gpu);
    result?;
    report.load_after = load_average();
    report.peak_rss_bytes = peak_rss_bytes();
    Ok(report)
}
