//! What the bench measures and how it is reported: options, statistics, one result per configuration, the
//! text table and the JSON.

use super::{SampleRate, Shading};
use crate::gpu::{Gpu, GpuError};
use crate::measure::fidelity::Fidelity;
use crate::render::headless::Headless;
use crate::render::Renderer;
use crate::scene::settings::{RaySetup, RenderSettings};
use std::path::PathBuf;

#[derive(Clone, Debug)]
pub struct BenchOptions {
    pub frames: u32,
    pub warmup: u32,
    /// Folder holding the raw files of [`Source::DataFile`] scenes.
    pub data_dir: PathBuf,
    /// make_volume.py's output for the `vtk-helix` scene (else generated).
    pub vtk_raw: Option<PathBuf>,
    pub quick: bool,
    /// Scene names (exact); empty = all.
    pub scenes: Vec<String>,
    /// Image sizes to keep (square); empty = each scene's own.
    pub sizes: Vec<u32>,
    /// Shading variants to keep ("off", "on", "shadows"); empty = each scene's own.
    pub shadings: Vec<String>,
    /// Methods to keep ("faces", "analytic", "compute"); empty = all three.
    pub methods: Vec<String>,
    /// Only the sample-only micro-benchmark.
    pub sample_only: bool,
    /// The sampling qualities every scene is timed at (`--quality`, repeatable), as `render` applies them, each
    /// against the same converged image.
    pub qualities: Vec<crate::scene::quality::Quality>,
    /// Where shaded scenes take gradients (`--gradients`), as `render` applies it.
    pub gradients: crate::scene::quality::Gradients,
    /// A step length (voxels) forced on every scene, overriding the quality's.
    pub step_length: Option<f32>,
}

/// Median, min and max of a set of measurements.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Stats {
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Stats {
    /// None for an empty set.
    pub fn of(values: &[f64]) -> Option<Stats> {
        let mut v: Vec<f64> = values.to_vec();
        v.sort_by(|a, b| a.total_cmp(b));
        let n = v.len();
        if n == 0 {
            return None;
        }
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        };
        Some(Stats {
            median,
            min: v[0],
            max: v[n - 1],
        })
    }
}

pub(super) fn median(values: &[f64]) -> Option<f64> {
    Stats::of(values).map(|s| s.median)
}

/// One timed configuration.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SceneResult {
    pub scene: String,
    /// name, dims, type.
    pub volume: String,
    /// How the volume is stored on the GPU (`VolumeLayout::name`: a texture format, or corners8/corners16).
    pub format: &'static str,
    pub width: u32,
    pub height: u32,
    pub method: Method,
    pub shading: Shading,
    /// The quality level (`--quality`), or "step L" where `--step-length` forced the step.
    pub quality: String,
    pub frames: u32,
    pub wall_ms: Stats,
    /// Whole frame on the GPU (all passes), from timestamps.
    pub gpu_ms: Option<Stats>,
    pub entry_ms: Option<f64>,
    pub exit_ms: Option<f64>,
    pub march_ms: Option<f64>,
    /// Samples on the pixels' ray segments before early termination (an upper bound), per pixel of the image.
    pub segment_samples_per_pixel: f64,
    /// Samples the march takes per pixel of the image, early termination included (counted by CPU replay).
    pub samples_per_pixel: f64,
    /// Samples taken per second of median GPU frame time, in 10⁹.
    pub effective_gsamples_per_s: f64,
    /// `effective_gsamples_per_s` ÷ the sample-only rate for `format` (None when that was not measured).
    pub fraction_of_raw: Option<f64>,
    /// gpu-allocator's total allocated bytes while this configuration rendered: volume, targets, buffers, LUT.
    pub gpu_allocated_bytes: u64,
    /// /proc/loadavg (1, 5, 15 min) right after the timed frames.
    pub load: Option<[f64; 3]>,
    /// The step length the frames were rendered with, in voxels.
    pub step_length: f32,
    /// The longest brick stride allowed (rule 2; 1: every sample).
    pub max_stride: u32,
    /// Shadows and occlusion: how long the light grid took to fill (once per transfer function, light or volume).
    pub light_grid_ms: Option<f64>,
    /// The last timed frame against the scene's converged image (`fidelity`), in 1/255.
    pub error: Fidelity,
    /// The quality level's error target (mean, p99 in 1/255: `Quality::target`); None for a forced step.
    pub target: Option<[f64; 2]>,
}

impl SceneResult {
    /// Whether the error is within the quality level's target (None for a forced step).
    pub fn target_met(&self) -> Option<bool> {
        self.target
            .map(|[mean, p99]| self.error.mean <= mean && self.error.p99 <= p99)
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Skipped {
    pub scene: String,
    pub reason: String,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct BenchReport {
    pub device: String,
    pub quick: bool,
    pub frames: u32,
    pub warmup: u32,
    pub load_before: Option<[f64; 3]>,
    pub load_after: Option<[f64; 3]>,
    pub sample_only: Vec<SampleRate>,
    pub results: Vec<SceneResult>,
    pub skipped: Vec<Skipped>,
    /// VmHWM of this process at the end (all scenes together).
    pub peak_rss_bytes: Option<u64>,
}

/// The columns of [`BenchReport::text`]'s table, in order (tests parse the table by these).
pub const TABLE_COLUMNS: [&str; 24] = [
    "scene",
    "size",
    "method",
    "shading",
    "quality",
    "wall_med",
    "wall_min",
    "wall_max",
    "gpu_med",
    "gpu_min",
    "gpu_max",
    "entry",
    "exit",
    "march",
    "seg_spp",
    "spp",
    "Gsamples/s",
    "of_raw",
    "step",
    "stride",
    "err_mean",
    "err_p99",
    "err_max",
    "target",
];

/// Each column's width in [`BenchReport::text`]'s table (a cell that is wider pushes the rest of its row along).
const TABLE_WIDTHS: [usize; 24] = [12, 5, 9, 7, 9, 9, 9, 9, 9, 9, 9, 7, 7, 9, 8, 8, 10, 7, 6, 6, 8, 7, 7, 6];

/// What the table's columns mean, printed above it.
const TABLE_LEGEND: &str = "\nms per frame (wall: render + readback; gpu: timestamps, entry + exit + march); \
    seg_spp: samples on the ray segments per pixel, before early termination; spp: 3D-texture \
    samples taken per pixel, gradients included (CPU replay of the march rules); Gsamples/s: spp x pixels / gpu_med; of_raw: that / \
    sample-only rate of the volume's format; quality: --quality's level (or the --step-length forced); step: in voxels; stride: the longest brick stride; err_mean/p99/max: the last frame \
    against the same scene converged (1/8-voxel steps, approximations off), in 1/255 over object \
    pixels; target: whether err_mean and err_p99 are within the quality level's error target (docs/performance.md, \
    Quality levels): met or over\n";

impl BenchReport {
    /// A human-readable report: the sample-only rates, then one table row per configuration.
    pub fn text(&self) -> String {
        let mut out = self.heading();
        if !self.sample_only.is_empty() {
            out += &self.sample_only_text();
        }
        if !self.results.is_empty() {
            out += TABLE_LEGEND;
            out += &self.table();
            out += &self.layers_text();
            out += &self.memory_text();
        }
        for s in &self.skipped {
            out += &format!("skipped {}: {}\n", s.scene, s.reason);
        }
        if let Some(p) = self.peak_rss_bytes {
            out += &format!("peak resident memory of this run (VmHWM): {:.1} MiB\n", p as f64 / MIB);
        }
        out
    }

    /// The device, the frame counts and the load average around the run.
    fn heading(&self) -> String {
        let load = |l: Option<[f64; 3]>| match l {
            Some([a, b, c]) => format!("{a:.2} {b:.2} {c:.2}"),
            None => "unknown".into(),
        };
        format!(
            "volcast bench on {}: {} timed frames after {} warm-up; load average before {}, after {}\n",
            self.device,
            self.frames,
            self.warmup,
            load(self.load_before),
            load(self.load_after)
        )
    }

    fn sample_only_text(&self) -> String {
        let mut out = String::from("\nsample-only (raw trilinear 3D-texture samples, nothing else):\n");
        for r in &self.sample_only {
            out += &format!(
                "  {:<10} {}^3 texture, {}x{} x {} samples: {:.3} G samples/s (GPU median {:.1} ms, min {:.1}, max {:.1})\n",
                r.format.name(),
                r.texture,
                r.width,
                r.height,
                r.samples_per_pixel,
                r.gsamples_per_s,
                r.gpu_ms.median,
                r.gpu_ms.min,
                r.gpu_ms.max
            );
        }
        out
    }

    /// The header row of [`TABLE_COLUMNS`], then one row per result.
    fn table(&self) -> String {
        let mut out = table_row(TABLE_COLUMNS.iter().map(|s| s.to_string()).collect());
        for r in &self.results {
            out += &table_row(r.table_cells());
        }
        out
    }

    /// Each layered scene's frame time as a multiple of the same scene's without its layers, in this run (rule 13's
    /// cost; the issue asks ≤ 1.5× for one overlay or one label map over the T1, ≤ 2.5× for four channels).
    fn layers_text(&self) -> String {
        let ms = |r: &SceneResult| r.gpu_ms.map_or(r.wall_ms.median, |g| g.median);
        let mut out = String::new();
        for (layered, without) in super::layered::PAIRS {
            for r in self.results.iter().filter(|r| r.scene == layered) {
                let alone = self.results.iter().find(|a| {
                    a.scene == without
                        && (a.width, a.method, a.shading) == (r.width, r.method, r.shading)
                        && a.quality == r.quality
                });
                if let Some(a) = alone {
                    out += &format!(
                        "  {:<13} {:<5} {:<9} {:<9} {:.2}x {without} ({:.1} ms / {:.1} ms)\n",
                        r.scene,
                        r.width,
                        r.method.name(),
                        r.quality,
                        ms(r) / ms(a),
                        ms(r),
                        ms(a)
                    );
                }
            }
        }
        if out.is_empty() {
            return out;
        }
        "\nlayers (rule 13), frame time against the same scene without its layers in this run:\n".to_string() + &out
    }

    /// Each scene × size × method's volume, its GPU layout and the GPU memory allocated, once.
    fn memory_text(&self) -> String {
        let mut out = String::from("\nvolumes and GPU memory:\n");
        let mut seen = Vec::new();
        for r in &self.results {
            if !seen.contains(&(&r.scene, r.width, r.method)) {
                seen.push((&r.scene, r.width, r.method));
                out += &format!(
                    "  {:<12} {:<5} {:<9} {} ({}); GPU allocated {:.1} MiB\n",
                    r.scene,
                    r.width,
                    r.method.name(),
                    r.volume,
                    r.format,
                    r.gpu_allocated_bytes as f64 / MIB
                );
            }
        }
        out
    }
}

/// One line of the table: each cell left-aligned in its column's width.
fn table_row(cells: Vec<String>) -> String {
    let mut line = String::new();
    for (c, w) in cells.iter().zip(TABLE_WIDTHS) {
        line += &format!("{c:<w$} ");
    }
    line.trim_end().to_string() + "\n"
}

impl SceneResult {
    /// This result's cells under [`TABLE_COLUMNS`], in order.
    fn table_cells(&self) -> Vec<String> {
        let opt = |v: Option<f64>, prec: usize| v.map_or("-".to_string(), |x| format!("{x:.prec$}"));
        let gpu = self.gpu_ms;
        vec![
            self.scene.clone(),
            format!("{}", self.width),
            self.method.name().into(),
            self.shading.name().into(),
            self.quality.clone(),
            format!("{:.2}", self.wall_ms.median),
            format!("{:.2}", self.wall_ms.min),
            format!("{:.2}", self.wall_ms.max),
            opt(gpu.map(|g| g.median), 2),
            opt(gpu.map(|g| g.min), 2),
            opt(gpu.map(|g| g.max), 2),
            opt(self.entry_ms, 2),
            opt(self.exit_ms, 2),
            opt(self.march_ms, 2),
            format!("{:.1}", self.segment_samples_per_pixel),
            format!("{:.1}", self.samples_per_pixel),
            format!("{:.4}", self.effective_gsamples_per_s),
            opt(self.fraction_of_raw, 3),
            format!("{}", self.step_length),
            format!("{}", self.max_stride),
            format!("{:.3}", self.error.mean),
            format!("{:.0}", self.error.p99),
            format!("{:.0}", self.error.max),
            match self.target_met() {
                Some(true) => "met".into(),
                Some(false) => "over".into(),
                None => "-".into(),
            },
        ]
    }
}

const MIB: f64 = (1u64 << 20) as f64;

/// How a frame is marched: the two ray setups, and the analytic one in a compute pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    Faces,
    Analytic,
    Compute,
}

impl Method {
    pub const ALL: [Method; 3] = [Method::Faces, Method::Analytic, Method::Compute];

    pub fn name(self) -> &'static str {
        match self {
            Method::Faces => "faces",
            Method::Analytic => "analytic",
            Method::Compute => "compute",
        }
    }

    pub(super) fn apply(self, s: &mut RenderSettings) {
        s.pipeline.ray_setup = match self {
            Method::Faces => RaySetup::Faces,
            Method::Analytic | Method::Compute => RaySetup::Analytic,
        };
        s.pipeline.compute = self == Method::Compute;
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Memory.

/// Peak resident set size of this process (VmHWM in /proc/self/status); None where that file does not exist.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// /proc/loadavg's three averages; None where unavailable.
pub fn load_average() -> Option<[f64; 3]> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    let mut it = text.split_whitespace().map(|x| x.parse::<f64>().ok());
    Some([it.next()??, it.next()??, it.next()??])
}

/// What the allocator holds: bytes in live allocations, and bytes in the memory blocks it got from the driver.
pub fn gpu_allocated(gpu: &Gpu) -> Result<(u64, u64), GpuError> {
    let report = gpu.allocator()?.generate_report();
    Ok((report.total_allocated_bytes, report.total_capacity_bytes))
}

/// The `volcast render --memory` line: peak resident memory and the GPU memory of the frame just rendered, split
/// into the volume texture, the ray setup's position targets, the output image and its readback buffer, and the
/// rest (colormap table, uniform buffers).
pub fn memory_line(gpu: &Gpu, headless: &Headless, s: &RenderSettings) -> Result<String, GpuError> {
    let (allocated, capacity) = gpu_allocated(gpu)?;
    let volume = headless.renderer.volume_bytes();
    let targets = Renderer::extra_target_bytes(s);
    let output = 2 * 4 * u64::from(s.width) * u64::from(s.height);
    let rest = allocated.saturating_sub(volume + targets + output);
    let rss = peak_rss_bytes().map_or("unknown".to_string(), |b| format!("{:.1} MiB", b as f64 / MIB));
    Ok(format!(
        "memory: peak resident {rss} (VmHWM); GPU allocated {:.1} MiB = volume {:.1} + position targets {:.1} + \
         output and readback {:.1} + other {:.2} (in {:.1} MiB of allocator blocks)",
        allocated as f64 / MIB,
        volume as f64 / MIB,
        targets as f64 / MIB,
        output as f64 / MIB,
        rest as f64 / MIB,
        capacity as f64 / MIB
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_take_the_middle() {
        let s = Stats::of(&[3.0, 1.0, 2.0]).unwrap();
        assert_eq!((s.median, s.min, s.max), (2.0, 1.0, 3.0));
        assert_eq!(Stats::of(&[1.0, 2.0, 4.0, 3.0]).unwrap().median, 2.5);
        assert!(Stats::of(&[]).is_none());
    }
}
