//! `volcast bench`: times a fixed table of scenes and measures the device's raw 3D-texture sampling rate, so
//! every frame time can be stated as samples per second and as a fraction of that limit (issue 7).
//!
//! What is measured, per scene × image size × ray setup (× shading, once it exists):
//! - wall ms per frame (render + readback, as `volcast render` does it) and GPU ms per pass (timestamp queries),
//!   median/min/max over `frames` frames after `warmup` untimed ones (lavapipe compiles shaders on first use);
//! - samples per pixel, counted on the CPU by replaying the march's rules (see [`SampleCounter`]): the march
//!   shader is left untouched, so the count costs the GPU nothing;
//! - effective samples per second (samples taken ÷ GPU frame time) and its fraction of the sample-only rate for the
//!   volume's texel format ([`sample_only`]).

use crate::camera::Camera;
use crate::fidelity::{converged, Fidelity, CONVERGED_STEP};
use crate::gpu::pipeline::{graphics_pipeline, shader, GraphicsDesc};
use crate::gpu::resources::{upload_image, Buffer, Image, ImageDesc};
use crate::gpu::sync::{image_barriers, Access, ImageTransition};
use crate::gpu::{Gpu, GpuError, VkContext};
use crate::headless::Headless;
use crate::render::skip::{self, BrickGrid};
use crate::render::{FrameUniforms, Renderer, VolumeInfo, VolumeLayout};
use crate::settings::{self, CompositeMode, RaySetup, RenderSettings};
use crate::tf;
use crate::transfer::Colormap;
use crate::volume::{self, Geometry, RawOptions, Volume, VolumeError};
use ash::vk;
use glam::{Mat3, Mat4, Vec3};
use gpu_allocator::MemoryLocation;
use std::path::{Path, PathBuf};
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

// ---------------------------------------------------------------------------------------------------------------
// The scene table.

/// Where a scene's volume comes from.
#[derive(Clone, Copy, Debug)]
pub enum Source {
    Builtin {
        name: &'static str,
        size: Option<u32>,
    },
    /// A raw file (open-scivis name) in the data folder (`--data`); the scene is skipped when it is missing.
    DataFile {
        file: &'static str,
        spacing: [f32; 3],
    },
    /// `../shared/tools/make_volume.py`'s helix: the file given with `--vtk-raw`, else the same field generated
    /// here by [`vtk_helix_volume`] (a port of the script; see there for how close it is).
    VtkHelix,
}

/// Shading variants every scene is timed with: off, and Blinn–Phong with VTK's coefficients (ambient 0.2,
/// diffuse 0.7, specular 0.3, power 20: `settings::Shading::default()`, as ../shared/tools/vtk_bench.py uses).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Shading {
    Off,
    On,
}

pub const SHADINGS: &[Shading] = &[Shading::Off, Shading::On];

impl Shading {
    pub fn apply(self, s: &mut RenderSettings) {
        s.shading = match self {
            Shading::Off => None,
            Shading::On => Some(settings::Shading::default()),
        };
    }

    pub fn name(self) -> &'static str {
        match self {
            Shading::Off => "off",
            Shading::On => "on",
        }
    }
}

/// One row of the scene table: a volume and how it is shown. Each scene is timed at every size in `sizes`, with
/// both ray setups and every shading variant in `shadings`.
#[derive(Clone, Copy)]
pub struct Scene {
    pub name: &'static str,
    pub about: &'static str,
    pub source: Source,
    /// Transfer function and camera on top of [`RenderSettings::new`]'s defaults for the volume.
    pub configure: fn(&mut RenderSettings, &Volume),
    pub sizes: &'static [u32],
    pub shadings: &'static [Shading],
}

const FULL_SIZES: &[u32] = &[512, 1024];

/// The full benchmark. Extend here.
pub fn scenes() -> Vec<Scene> {
    vec![
        Scene {
            name: "helix",
            about: "built-in helix 256³ uint8, default transfer function: sparse (most of the box is empty)",
            source: Source::Builtin {
                name: "helix",
                size: None,
            },
            configure: |_, _| {},
            sizes: FULL_SIZES,
            shadings: SHADINGS,
        },
        Scene {
            name: "dense",
            about: "built-in colormap ramp 256³ uint8, window 0–1, step alpha 0.02: every sample visible and \
                    composited, most rays run ≥ 200 samples (the march's worst case)",
            source: Source::Builtin {
                name: "colormap",
                size: None,
            },
            configure: |s, _| {
                s.window = [0.0, 1.0];
                s.step_alpha = 0.02;
            },
            sizes: FULL_SIZES,
            shadings: SHADINGS,
        },
        Scene {
            name: "ct-head",
            about: "CT head 256×256×108 int16 at 0.96×0.96×1.5 mm, window 0.33–0.9, plasma, step alpha 0.6, \
                    half-voxel steps (the README's picture)",
            source: Source::DataFile {
                file: "cranium_ct_256x256x108_int16.raw",
                spacing: [0.957031, 0.957031, 1.5],
            },
            configure: |s, v| {
                s.window = [0.33, 0.9];
                s.colormap = Colormap::Plasma;
                s.step_alpha = 0.6;
                s.step_length = 0.5;
                let d = Camera::fit_distance(v.extent().length() * 0.5, s.camera.fov_y_deg);
                s.camera = Camera::orbit(25.0, 10.0, d, Vec3::ZERO);
            },
            sizes: FULL_SIZES,
            shadings: SHADINGS,
        },
        Scene {
            name: "mri-brain",
            about: "MRI brain (colin27 T1) 181×217×181 uint8, window 0.2–1, grayscale, step alpha 0.05",
            source: Source::DataFile {
                file: "colin27_t1_181x217x181_uint8.raw",
                spacing: [1.0, 1.0, 1.0],
            },
            configure: |s, _| {
                s.window = [0.2, 1.0];
                s.colormap = Colormap::Grayscale;
                s.step_alpha = 0.05;
            },
            sizes: FULL_SIZES,
            shadings: SHADINGS,
        },
        Scene {
            name: "vtk-helix",
            about: "the scene of ../shared/tools/vtk_bench.py: make_volume.py's helix 256³ uint8, viridis, opacity \
                    0 at 0.08 of the range rising linearly to 0.2, 1-voxel steps, VTK's camera",
            source: Source::VtkHelix,
            configure: configure_vtk_helix,
            sizes: FULL_SIZES,
            shadings: SHADINGS,
        },
    ]
}

/// `--quick` (CI smoke mode): a tiny helix, both ray setups, a few seconds in all.
pub fn quick_scenes() -> Vec<Scene> {
    vec![Scene {
        name: "quick-helix",
        about: "built-in helix 64³, 64×64 (smoke test)",
        source: Source::Builtin {
            name: "helix",
            size: Some(64),
        },
        configure: |_, _| {},
        sizes: &[64],
        shadings: SHADINGS,
    }]
}

/// vtk_bench.py's camera and transfer function in volcast's terms.
///
/// - Opacity: VTK ramps 0 at 0.08 of the range to 0.2 at the top, per unit distance 1 voxel at 1-voxel steps.
///   With `multiplied_alpha`, window [0.08, 1] and step alpha 0.2, α = c·0.2 with c = (v − 0.08)/0.92: the same ramp.
/// - Colour: viridis. VTK spreads it over the whole scalar range, volcast over the window, so colours of the same
///   value differ slightly (a value at 0.5 of the range shows viridis(0.46) here).
/// - Camera: vtk_bench.py starts on the −y side of the focal point (position = focal − 1000·y) and turns by
///   Azimuth(35), Elevation(25); `Camera::orbit`'s azimuth 0 is on +y, so VTK's 35° is 215° here. VTK's
///   `ResetCamera` fits the sphere around the *points'* bounding box ((dims − 1)·spacing) at its default 30° view
///   angle; `Zoom(1.45)` then narrows the angle to 30°/1.45.
pub fn configure_vtk_helix(s: &mut RenderSettings, v: &Volume) {
    s.colormap = Colormap::Viridis;
    s.window = [0.08, 1.0];
    s.multiplied_alpha = true;
    s.step_alpha = 0.2;
    s.step_length = 1.0;
    s.background = Vec3::ZERO;
    let spacing = v.spacing();
    let world_per_unit = v.extent().x / (v.dims[0] as f32 * spacing[0]);
    let points = Vec3::from_array([0, 1, 2].map(|i| (v.dims[i] as f32 - 1.0) * spacing[i]));
    let radius = 0.5 * points.length() * world_per_unit;
    let distance = radius / 15f32.to_radians().sin();
    s.camera = Camera::orbit(VTK_AZIMUTH_HERE, 25.0, distance, Vec3::ZERO);
    s.camera.fov_y_deg = 30.0 / 1.45;
}

/// vtk_bench.py's azimuth 35° in `Camera::orbit`'s convention (see [`configure_vtk_helix`]).
pub const VTK_AZIMUTH_HERE: f32 = 215.0;

/// make_volume.py's field (helix tube + radial gradient ball), computed in f64. numpy computes it in float32
/// (partly float64), so a few voxels on rounding boundaries may differ by one level; pass the script's own file
/// with `--vtk-raw` to compare exactly like for like.
pub fn vtk_helix_volume(n: u32) -> Result<Volume, VolumeError> {
    use std::f64::consts::PI;
    let (big_r, turns, z0, z1, sigma) = (0.55f64, 3.0f64, -0.85f64, 0.85f64, 0.12f64);
    let pitch = (z1 - z0) / turns;
    let c_ = pitch / (2.0 * PI);
    let cos_alpha = big_r / (big_r * big_r + c_ * c_).sqrt();
    let coord = |i: u32| (f64::from(i) + 0.5) / f64::from(n) * 2.0 - 1.0;
    let mut data = Vec::with_capacity((n as usize).pow(3));
    for zi in 0..n {
        let z = coord(zi);
        for yi in 0..n {
            let y = coord(yi);
            for xi in 0..n {
                let x = coord(xi);
                let rho = (x * x + y * y + z * z).sqrt();
                let ball = (1.0 - rho / 0.9).clamp(0.0, 1.0);
                let r = x.hypot(y);
                let phi = y.atan2(x);
                let t = (z - z0) / c_ - phi;
                let k = (t / (2.0 * PI)).round_ties_even();
                let dz = z - (z0 + c_ * (phi + 2.0 * PI * k));
                let d = ((r - big_r).powi(2) + (dz * cos_alpha).powi(2)).sqrt();
                let over = (z0 - z).max(z - z1).max(0.0);
                let tube = (-(d / sigma).powi(2)).exp() * (-(over / 0.05).powi(2)).exp();
                let v = (0.30 * ball + tube).clamp(0.0, 1.0);
                let u = (v * 255.0).round_ties_even() as u8;
                data.push(if u < 2 { 0 } else { u });
            }
        }
    }
    let mut v = Volume::new(
        "vtk-helix",
        [n; 3],
        [1.0; 3],
        volume::VoxelType::U8,
        volume::VoxelData::U8(data),
    )?;
    v.format = "generated (port of make_volume.py)".into();
    Ok(v)
}

// ---------------------------------------------------------------------------------------------------------------
// Options and results.

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
    /// Shading variants to keep ("off", "on"); empty = each scene's own.
    pub shadings: Vec<String>,
    /// Methods to keep ("faces", "analytic", "compute"); empty = all three.
    pub methods: Vec<String>,
    /// Only the sample-only micro-benchmark.
    pub sample_only: bool,
    /// A step length (voxels) forced on every scene.
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

fn median(values: &[f64]) -> Option<f64> {
    Stats::of(values).map(|s| s.median)
}

/// The GPU formats volcast stores volumes in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum TexelFormat {
    #[serde(rename = "R8_UNORM")]
    R8Unorm,
    #[serde(rename = "R16_UNORM")]
    R16Unorm,
    #[serde(rename = "R32_SFLOAT")]
    R32Sfloat,
}

impl TexelFormat {
    pub const ALL: [TexelFormat; 3] = [TexelFormat::R8Unorm, TexelFormat::R16Unorm, TexelFormat::R32Sfloat];

    pub fn name(self) -> &'static str {
        match self {
            TexelFormat::R8Unorm => "R8_UNORM",
            TexelFormat::R16Unorm => "R16_UNORM",
            TexelFormat::R32Sfloat => "R32_SFLOAT",
        }
    }

    fn vk(self) -> vk::Format {
        match self {
            TexelFormat::R8Unorm => vk::Format::R8_UNORM,
            TexelFormat::R16Unorm => vk::Format::R16_UNORM,
            TexelFormat::R32Sfloat => vk::Format::R32_SFLOAT,
        }
    }

    /// `n`³ texels of a pattern with texel-to-texel variation, so a filter cannot shortcut equal neighbours.
    fn test_texels(self, n: u32) -> Vec<u8> {
        let level = |x: u32, y: u32, z: u32| ((x * 7) ^ (y * 13) ^ (z * 29)) & 255;
        let mut out = Vec::with_capacity((n as usize).pow(3) * 4);
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let l = level(x, y, z);
                    match self {
                        TexelFormat::R8Unorm => out.push(l as u8),
                        TexelFormat::R16Unorm => out.extend_from_slice(&((l * 257) as u16).to_ne_bytes()),
                        TexelFormat::R32Sfloat => out.extend_from_slice(&(l as f32 / 255.0).to_ne_bytes()),
                    }
                }
            }
        }
        out
    }
}

/// One result of the sample-only micro-benchmark.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SampleRate {
    pub format: TexelFormat,
    /// Edge of the cubic test texture.
    pub texture: u32,
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    pub frames: u32,
    pub gpu_ms: Stats,
    pub wall_ms: Stats,
    /// Trilinear samples per second from the median GPU time, in 10⁹.
    pub gsamples_per_s: f64,
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
    /// The last timed frame against the scene's converged image (`fidelity`), in 1/255.
    pub error: Fidelity,
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
pub const TABLE_COLUMNS: [&str; 21] = [
    "scene",
    "size",
    "method",
    "shading",
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
    "err_mean",
    "err_p99",
    "err_max",
];

impl BenchReport {
    /// A human-readable report: the sample-only rates, then one table row per configuration.
    pub fn text(&self) -> String {
        let mut out = String::new();
        let load = |l: Option<[f64; 3]>| match l {
            Some([a, b, c]) => format!("{a:.2} {b:.2} {c:.2}"),
            None => "unknown".into(),
        };
        out += &format!(
            "volcast bench on {}: {} timed frames after {} warm-up; load average before {}, after {}\n",
            self.device,
            self.frames,
            self.warmup,
            load(self.load_before),
            load(self.load_after)
        );
        if !self.sample_only.is_empty() {
            out += "\nsample-only (raw trilinear 3D-texture samples, nothing else):\n";
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
        }
        if !self.results.is_empty() {
            out += "\nms per frame (wall: render + readback; gpu: timestamps, entry + exit + march); \
                    seg_spp: samples on the ray segments per pixel, before early termination; spp: 3D-texture \
                    samples taken per pixel, gradients included (CPU replay of the march rules); Gsamples/s: spp x pixels / gpu_med; of_raw: that / \
                    sample-only rate of the volume's format; step: in voxels; err_mean/p99/max: the last frame \
                    against the same scene converged (1/8-voxel steps, approximations off), in 1/255 over object \
                    pixels\n";
            let widths = [12, 5, 9, 7, 9, 9, 9, 9, 9, 9, 7, 7, 9, 8, 8, 10, 7, 6, 8, 7, 7];
            let row = |cells: Vec<String>| -> String {
                let mut line = String::new();
                for (c, w) in cells.iter().zip(widths) {
                    line += &format!("{c:<w$} ");
                }
                line.trim_end().to_string() + "\n"
            };
            out += &row(TABLE_COLUMNS.iter().map(|s| s.to_string()).collect());
            let opt = |v: Option<f64>, prec: usize| v.map_or("-".to_string(), |x| format!("{x:.prec$}"));
            for r in &self.results {
                let gpu = r.gpu_ms;
                out += &row(vec![
                    r.scene.clone(),
                    format!("{}", r.width),
                    r.method.name().into(),
                    r.shading.name().into(),
                    format!("{:.2}", r.wall_ms.median),
                    format!("{:.2}", r.wall_ms.min),
                    format!("{:.2}", r.wall_ms.max),
                    opt(gpu.map(|g| g.median), 2),
                    opt(gpu.map(|g| g.min), 2),
                    opt(gpu.map(|g| g.max), 2),
                    opt(r.entry_ms, 2),
                    opt(r.exit_ms, 2),
                    opt(r.march_ms, 2),
                    format!("{:.1}", r.segment_samples_per_pixel),
                    format!("{:.1}", r.samples_per_pixel),
                    format!("{:.4}", r.effective_gsamples_per_s),
                    opt(r.fraction_of_raw, 3),
                    format!("{}", r.step_length),
                    format!("{:.3}", r.error.mean),
                    format!("{:.0}", r.error.p99),
                    format!("{:.0}", r.error.max),
                ]);
            }
            out += "\nvolumes and GPU memory:\n";
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
        }
        for s in &self.skipped {
            out += &format!("skipped {}: {}\n", s.scene, s.reason);
        }
        if let Some(p) = self.peak_rss_bytes {
            out += &format!("peak resident memory of this run (VmHWM): {:.1} MiB\n", p as f64 / MIB);
        }
        out
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

    fn apply(self, s: &mut RenderSettings) {
        s.ray_setup = match self {
            Method::Faces => RaySetup::Faces,
            Method::Analytic | Method::Compute => RaySetup::Analytic,
        };
        s.compute = self == Method::Compute;
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

// ---------------------------------------------------------------------------------------------------------------
// Counting samples without touching the march shader.

/// Counts the samples the march takes by replaying its rules on the CPU (settings.rs rules 1–7) in the shader's
/// f32 arithmetic: the analytic ray setup built from the camera basis as `FrameUniforms::new` builds it, samples at
/// `(k + o)·h` (jitter included), trilinear values, the window, the baked classification table, the compositing
/// mode and early termination. Two counts per pixel:
/// - *segment*: sample positions on the ray segment, before early termination (an upper bound);
/// - *taken*: 3D-texture samples the march actually takes: one per step until the ray ends, plus six per step
///   that computes a gradient (shading or gradient opacity, on steps with opacity > 0) and, in isosurface mode,
///   the bisection's eight and the hit's gradient.
///
/// Approximations, all small: the entry/exit method finds the same segments to float precision (README, "Two ray
/// setups"), so one count serves both setups; lavapipe filters 8-bit textures with 8-bit weights, so a ray may end
/// a step earlier or later than here; gradient opacity is not modelled (its rays may run longer on the GPU).
/// When the march changes how many samples it takes (empty-space skipping, adaptive steps), change
/// [`SampleCounter::pixel`] with it.
pub struct SampleCounter {
    dims: [usize; 3],
    values: Vec<f32>,
    geometry: Geometry,
    range: [f64; 2],
    /// The renderer's brick grid, for the occupancy empty-space skipping leaps by.
    bricks: BrickGrid,
}

/// Mean samples per pixel of the image (pixels that miss the box count as zero).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SampleCount {
    pub segment_per_pixel: f64,
    pub taken_per_pixel: f64,
}

/// What every pixel's replay shares, in texture space (the fields of `FrameUniforms` the march reads).
struct RayFrame {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    down: Vec3,
    near: f32,
    slab_lo: Vec3,
    slab_hi: Vec3,
    /// Texture space to world (its linear part measures the ray).
    to_world: Mat3,
    h: f32,
    max_steps: u64,
    viewport: [f32; 2],
    window: [f32; 2],
    lut: Vec<[f32; 4]>,
    step_length: f32,
    mode: CompositeMode,
    density: f32,
    iso_value: f32,
    gradients: bool,
    jitter: Option<u32>,
    early_termination: f32,
    /// Per brick 0 where empty-space skipping leaps (None: skipping off).
    occupancy: Option<Vec<u8>>,
}

/// Texture samples one central-difference gradient takes.
const GRADIENT_SAMPLES: u64 = 6;
/// Bisection steps of the isosurface mode.
const ISO_BISECTIONS: u64 = 8;

impl SampleCounter {
    pub fn new(volume: &Volume) -> SampleCounter {
        let [nx, ny, nz] = volume.dims;
        let mut values = Vec::with_capacity(volume.voxel_count());
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    values.push(volume.normalized(x, y, z) as f32);
                }
            }
        }
        SampleCounter {
            dims: volume.dims.map(|d| d as usize),
            values,
            geometry: volume.geometry,
            range: volume.range,
            bricks: BrickGrid::new(volume),
        }
    }

    /// Whether the march takes the sample at `p` (texture space): not when it lies in a brick empty-space
    /// skipping leaps over. Every sample of a span lies in a brick of the span's class (render/skip.rs), so
    /// this is the march's choice up to float rounding at brick faces.
    fn in_occupied_brick(&self, f: &RayFrame, p: Vec3) -> bool {
        let Some(occupancy) = &f.occupancy else {
            return true;
        };
        let b = self.bricks.bricks;
        let brick = |a: usize| {
            let i = (p[a] * self.dims[a] as f32 / skip::BRICK as f32).floor();
            i.clamp(0.0, (b[a] - 1) as f32) as usize
        };
        occupancy[brick(0) + b[0] as usize * (brick(1) + b[1] as usize * brick(2))] != 0
    }

    fn sample(&self, p: Vec3) -> f32 {
        let mut idx = [[0usize; 2]; 3];
        let mut w = [0f32; 3];
        for a in 0..3 {
            let n = self.dims[a];
            let u = p[a] * n as f32 - 0.5;
            let i0 = u.floor();
            w[a] = u - i0;
            let clamp = |i: f32| i.clamp(0.0, (n - 1) as f32) as usize;
            idx[a] = [clamp(i0), clamp(i0 + 1.0)];
        }
        let [nx, ny, _] = self.dims;
        let at = |x: usize, y: usize, z: usize| self.values[x + nx * (y + ny * z)];
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        let [x0, x1] = idx[0];
        let [y0, y1] = idx[1];
        let [z0, z1] = idx[2];
        let c00 = lerp(at(x0, y0, z0), at(x1, y0, z0), w[0]);
        let c10 = lerp(at(x0, y1, z0), at(x1, y1, z0), w[0]);
        let c01 = lerp(at(x0, y0, z1), at(x1, y0, z1), w[0]);
        let c11 = lerp(at(x0, y1, z1), at(x1, y1, z1), w[0]);
        lerp(lerp(c00, c10, w[1]), lerp(c01, c11, w[1]), w[2])
    }

    fn frame(&self, s: &RenderSettings) -> RayFrame {
        // The march's own rays: the uniforms the shader reads.
        let info = VolumeInfo {
            dims: self.dims.map(|d| d as u32),
            geometry: self.geometry,
            scale_bias: (1.0, 0.0),
            range: self.range,
        };
        let u = FrameUniforms::new(s, &info);
        let v3 = |a: [f32; 4]| Vec3::new(a[0], a[1], a[2]);
        let lut = tf::bake(&s.classification(), s.window, self.range);
        RayFrame {
            eye: v3(u.eye_tex),
            forward: v3(u.ray_forward),
            right: v3(u.ray_right),
            down: v3(u.ray_down),
            near: s.camera.near,
            slab_lo: s.slab_lo,
            slab_hi: s.slab_hi,
            to_world: Mat3::from_mat4(Mat4::from_cols_array(&u.tex_to_world)),
            h: u.extent[3],
            max_steps: u.viewport[2] as u64,
            viewport: [s.width as f32, s.height as f32],
            window: s.window,
            occupancy: s
                .skip_empty
                .then(|| self.bricks.classify(&lut, s.mode, s.window, s.iso_value, false)),
            lut,
            step_length: s.step_length,
            mode: s.mode,
            density: s.density,
            iso_value: s.iso_value,
            gradients: s.shading.is_some() || s.gradient_opacity.is_some(),
            jitter: s.jitter,
            early_termination: s.early_termination,
        }
    }

    /// (segment, taken) samples of pixel (x, y); mirrors march_analytic.frag and march.glsl.
    fn pixel(&self, f: &RayFrame, x: u32, y: u32) -> (u64, u64) {
        let ndc_x = (x as f32 + 0.5) / f.viewport[0] * 2.0 - 1.0;
        let ndc_y = (y as f32 + 0.5) / f.viewport[1] * 2.0 - 1.0;
        let dir = f.forward + ndc_x * f.right + ndc_y * f.down;
        let inv = Vec3::ONE / dir;
        let t_lo = (f.slab_lo - f.eye) * inv;
        let t_hi = (f.slab_hi - f.eye) * inv;
        let t0 = t_lo.min(t_hi).max_element().max(f.near);
        let t1 = t_lo.max(t_hi).min_element();
        // NaN (a ray along a face) misses, as in the shader's `!(t1 > t0)`.
        if t1.is_nan() || t0.is_nan() || t1 <= t0 {
            return (0, 0);
        }
        let a = f.eye + dir * t0;
        let d = dir * (t1 - t0);
        let len = (f.to_world * d).length();
        let o = f.jitter.map_or(0.5, |seed| settings::jitter_offset(x, y, seed));
        let segment = ((len / f.h - o).ceil().max(0.0) as u64).min(f.max_steps);
        let [win_lo, win_hi] = f.window;
        let mut opacity = 0f32;
        let mut taken = 0u64;
        for k in 0..f.max_steps {
            let t = (k as f32 + o) * f.h;
            if t >= len {
                break;
            }
            let p = a + d * (t / len);
            if !self.in_occupied_brick(f, p) {
                // Leapt over: nothing there can be visible (nor reach the iso value), so the replay goes on.
                continue;
            }
            taken += 1;
            let v = self.sample(p);
            match f.mode {
                CompositeMode::Mip | CompositeMode::MinIp | CompositeMode::Average => continue,
                CompositeMode::Isosurface => {
                    if !v.is_nan() && v >= f.iso_value {
                        let bisection = if k > 0 { ISO_BISECTIONS } else { 0 };
                        return (segment, taken + bisection + GRADIENT_SAMPLES);
                    }
                    continue;
                }
                CompositeMode::Emission | CompositeMode::Density => {}
            }
            if v.is_nan() || v < win_lo || v > win_hi {
                continue;
            }
            let alpha = tf::lookup(&f.lut, v)[3];
            if alpha <= 0.0 {
                continue;
            }
            if f.gradients {
                taken += GRADIENT_SAMPLES;
            }
            let a_step = if f.mode == CompositeMode::Density {
                (alpha * f.density * f.step_length).min(1.0)
            } else {
                1.0 - (1.0 - alpha).powf(f.step_length)
            };
            opacity += (1.0 - opacity) * a_step;
            if opacity >= f.early_termination {
                break;
            }
        }
        (segment, taken)
    }

    /// Counts over the whole image of `s`, rows split across the available cores.
    pub fn count(&self, s: &RenderSettings) -> SampleCount {
        let frame = self.frame(s);
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .clamp(1, s.height as usize);
        let totals: Vec<(u64, u64)> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..threads)
                .map(|t| {
                    let frame = &frame;
                    scope.spawn(move || {
                        let mut sum = (0u64, 0u64);
                        for y in (t as u32..s.height).step_by(threads) {
                            for x in 0..s.width {
                                let (seg, taken) = self.pixel(frame, x, y);
                                sum.0 += seg;
                                sum.1 += taken;
                            }
                        }
                        sum
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap_or((0, 0))).collect()
        });
        let pixels = (u64::from(s.width) * u64::from(s.height)).max(1) as f64;
        let (seg, taken) = totals.iter().fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        SampleCount {
            segment_per_pixel: seg as f64 / pixels,
            taken_per_pixel: taken as f64 / pixels,
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// The sample-only micro-benchmark.

/// The uniform block `Params` in shaders/sample_only.frag.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct SampleParams {
    start: [f32; 4],
    step: [f32; 4],
    viewport: [f32; 4],
}

/// Size of one sample-only run.
#[derive(Clone, Copy, Debug)]
pub struct SampleOnlyConfig {
    pub texture: u32,
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    pub frames: u32,
    pub warmup: u32,
}

impl SampleOnlyConfig {
    /// 256³ textures, 512² pixels × 256 samples (67 M samples, ~0.3 s a frame on lavapipe).
    pub fn full(frames: u32) -> SampleOnlyConfig {
        SampleOnlyConfig {
            texture: 256,
            width: 512,
            height: 512,
            samples_per_pixel: 256,
            frames: frames.clamp(1, 5),
            warmup: 1,
        }
    }

    pub fn quick() -> SampleOnlyConfig {
        SampleOnlyConfig {
            texture: 64,
            width: 64,
            height: 64,
            samples_per_pixel: 64,
            frames: 2,
            warmup: 1,
        }
    }
}

const SAMPLE_TARGET_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

/// Pipeline, descriptor set, target and queries of the sample-only pass. Null handles are skipped on destroy, so a
/// half-built one can be destroyed.
struct SamplePass {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    sampler: vk::Sampler,
    query_pool: vk::QueryPool,
    uniforms: Option<Buffer>,
    target: Option<Image>,
}

impl SamplePass {
    fn new(gpu: &Gpu, width: u32, height: u32) -> Result<SamplePass, GpuError> {
        let mut p = SamplePass {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            sampler: vk::Sampler::null(),
            query_pool: vk::QueryPool::null(),
            uniforms: None,
            target: None,
        };
        match p.init(gpu, width, height) {
            Ok(()) => Ok(p),
            Err(e) => {
                p.destroy(gpu);
                Err(e)
            }
        }
    }

    fn init(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<(), GpuError> {
        use vk::DescriptorType as D;
        let dev = &gpu.device;
        let frag = vk::ShaderStageFlags::FRAGMENT;
        let bindings: Vec<vk::DescriptorSetLayoutBinding> = [D::UNIFORM_BUFFER, D::SAMPLED_IMAGE, D::SAMPLER]
            .into_iter()
            .enumerate()
            .map(|(i, ty)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(frag)
            })
            .collect();
        // SAFETY: valid create info on a live device.
        self.set_layout = unsafe {
            dev.create_descriptor_set_layout(&vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings), None)
        }
        .ctx("vkCreateDescriptorSetLayout")?;
        let set_layouts = [self.set_layout];
        // SAFETY: the set layout is live.
        self.layout = unsafe {
            dev.create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts), None)
        }
        .ctx("vkCreatePipelineLayout")?;
        self.pipeline = graphics_pipeline(
            gpu,
            &GraphicsDesc {
                vertex: &shader!("fullscreen.vert"),
                fragment: &shader!("sample_only.frag"),
                layout: self.layout,
                color_format: SAMPLE_TARGET_FORMAT,
                cull: vk::CullModeFlags::NONE,
            },
        )?;
        let sizes = [D::UNIFORM_BUFFER, D::SAMPLED_IMAGE, D::SAMPLER].map(|ty| vk::DescriptorPoolSize {
            ty,
            descriptor_count: 1,
        });
        // SAFETY: valid create info on a live device.
        self.pool = unsafe {
            dev.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes),
                None,
            )
        }
        .ctx("vkCreateDescriptorPool")?;
        // SAFETY: the pool has room for this one set.
        self.set = unsafe {
            dev.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(self.pool)
                    .set_layouts(&set_layouts),
            )
        }
        .ctx("vkAllocateDescriptorSets")?[0];
        let sampler_info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0);
        // SAFETY: valid create info on a live device.
        self.sampler = unsafe { dev.create_sampler(&sampler_info, None) }.ctx("vkCreateSampler")?;
        let query_info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(2);
        // SAFETY: valid create info on a live device.
        self.query_pool = unsafe { dev.create_query_pool(&query_info, None) }.ctx("vkCreateQueryPool")?;
        self.uniforms = Some(Buffer::new(
            gpu,
            std::mem::size_of::<SampleParams>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            MemoryLocation::CpuToGpu,
            "sample-only uniforms",
        )?);
        self.target = Some(Image::new(
            gpu,
            ImageDesc::d2(
                SAMPLE_TARGET_FORMAT,
                width,
                height,
                vk::ImageUsageFlags::COLOR_ATTACHMENT,
            ),
            "sample-only target",
        )?);
        Ok(())
    }

    /// Points the descriptor set at `texture`. No submitted work may be using the set.
    fn bind(&self, gpu: &Gpu, texture: &Image) -> Result<(), GpuError> {
        let uniforms = self.uniforms.as_ref().ok_or(GpuError::Lost("sample-only uniforms"))?;
        let buffer_info = [vk::DescriptorBufferInfo::default()
            .buffer(uniforms.raw)
            .offset(0)
            .range(vk::WHOLE_SIZE)];
        let image_info = [vk::DescriptorImageInfo::default()
            .image_view(texture.view)
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        let sampler_info = [vk::DescriptorImageInfo::default().sampler(self.sampler)];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .buffer_info(&buffer_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&image_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(2)
                .descriptor_type(vk::DescriptorType::SAMPLER)
                .image_info(&sampler_info),
        ];
        // SAFETY: every frame is waited for (submit_and_wait), so nothing uses the set now.
        unsafe { gpu.device.update_descriptor_sets(&writes, &[]) };
        Ok(())
    }

    /// Draws one frame and returns (GPU ms from timestamps, wall ms). `first`: the target's old state is undefined.
    fn frame(&self, gpu: &Gpu, first: bool) -> Result<(f64, f64), GpuError> {
        let target = self.target.as_ref().ok_or(GpuError::Lost("sample-only target"))?;
        let dev = &gpu.device;
        let extent = vk::Extent2D {
            width: target.desc.extent.width,
            height: target.desc.extent.height,
        };
        let t = Instant::now();
        gpu.submit_and_wait(|cb| {
            // SAFETY: `cb` is recording, outside any rendering scope.
            unsafe { dev.cmd_reset_query_pool(cb, self.query_pool, 0, 2) };
            image_barriers(
                dev,
                cb,
                &[ImageTransition {
                    image: target.raw,
                    from: if first {
                        Access::Undefined
                    } else {
                        Access::ColorAttachmentWrite
                    },
                    to: Access::ColorAttachmentWrite,
                    discard: true,
                }],
            );
            let scissor = vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent,
            };
            let viewport = vk::Viewport {
                x: 0.0,
                y: 0.0,
                width: extent.width as f32,
                height: extent.height as f32,
                min_depth: 0.0,
                max_depth: 1.0,
            };
            let attachment = [vk::RenderingAttachmentInfo::default()
                .image_view(target.view)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::DONT_CARE)
                .store_op(vk::AttachmentStoreOp::STORE)];
            let info = vk::RenderingInfo::default()
                .render_area(scissor)
                .layer_count(1)
                .color_attachments(&attachment);
            // SAFETY: the target is in COLOR_ATTACHMENT_OPTIMAL (barrier above); pipeline, layout and set match and
            // hold live resources; the queries were reset above.
            unsafe {
                dev.cmd_write_timestamp2(cb, vk::PipelineStageFlags2::ALL_COMMANDS, self.query_pool, 0);
                dev.cmd_begin_rendering(cb, &info);
                dev.cmd_set_viewport(cb, 0, &[viewport]);
                dev.cmd_set_scissor(cb, 0, &[scissor]);
                dev.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, self.pipeline);
                dev.cmd_bind_descriptor_sets(cb, vk::PipelineBindPoint::GRAPHICS, self.layout, 0, &[self.set], &[]);
                dev.cmd_draw(cb, 3, 1, 0, 0);
                dev.cmd_end_rendering(cb);
                dev.cmd_write_timestamp2(cb, vk::PipelineStageFlags2::ALL_COMMANDS, self.query_pool, 1);
            }
        })?;
        let wall = t.elapsed().as_secs_f64() * 1e3;
        let mut ticks = [0u64; 2];
        // SAFETY: both queries were written by the submission that just completed.
        unsafe {
            dev.get_query_pool_results(
                self.query_pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .ctx("vkGetQueryPoolResults")?;
        let period_ns = f64::from(gpu.properties.limits.timestamp_period);
        Ok((ticks[1].saturating_sub(ticks[0]) as f64 * period_ns * 1e-6, wall))
    }

    fn destroy(mut self, gpu: &Gpu) {
        if let Some(t) = self.target.take() {
            t.destroy(gpu);
        }
        if let Some(u) = self.uniforms.take() {
            u.destroy(gpu);
        }
        // SAFETY: every frame was waited for; Vulkan ignores null handles.
        unsafe {
            let d = &gpu.device;
            d.destroy_query_pool(self.query_pool, None);
            d.destroy_sampler(self.sampler, None);
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_pipeline(self.pipeline, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// Measures trilinear 3D-texture samples per second for each of `formats`: a full-screen pass whose fragments
/// only take `samples_per_pixel` samples along a fixed direction (shaders/sample_only.frag).
pub fn sample_only(
    gpu: &Gpu,
    formats: &[TexelFormat],
    cfg: SampleOnlyConfig,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<SampleRate>, GpuError> {
    let mut pass = SamplePass::new(gpu, cfg.width, cfg.height)?;
    let result = (|| {
        let k = cfg.samples_per_pixel.max(1);
        // Rays cross 0.8 of the texture along a skew direction, starting in a 0.4-wide square: they stay inside
        // the texture (no clamped samples) and take steps of 0.8·n/k texels.
        let dir = Vec3::new(1.0, 2.0, 3.0).normalize() * (0.8 / k as f32);
        let params = SampleParams {
            start: [0.05, 0.05, 0.1, 0.4],
            step: [dir.x, dir.y, dir.z, k as f32],
            viewport: [cfg.width as f32, cfg.height as f32, 0.0, 0.0],
        };
        pass.uniforms
            .as_mut()
            .ok_or(GpuError::Lost("sample-only uniforms"))?
            .write(bytemuck::bytes_of(&params))?;
        let pass = &pass;
        let mut out = Vec::new();
        let mut first = true;
        for &format in formats {
            log(&format!(
                "sample-only {}: uploading a {}^3 texture",
                format.name(),
                cfg.texture
            ));
            let n = cfg.texture;
            let desc = ImageDesc {
                format: format.vk(),
                extent: vk::Extent3D {
                    width: n,
                    height: n,
                    depth: n,
                },
                usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            };
            let texture = Image::new(gpu, desc, "sample-only texture")?;
            let measured = (|| -> Result<SampleRate, GpuError> {
                upload_image(gpu, &texture, &format.test_texels(n))?;
                pass.bind(gpu, &texture)?;
                let (mut gpu_ms, mut wall_ms) = (Vec::new(), Vec::new());
                for i in 0..cfg.warmup + cfg.frames.max(1) {
                    let (g, w) = pass.frame(gpu, first)?;
                    first = false;
                    if i >= cfg.warmup {
                        gpu_ms.push(g);
                        wall_ms.push(w);
                    }
                }
                let gpu_stats = Stats::of(&gpu_ms).ok_or(GpuError::Lost("no frames timed"))?;
                let wall_stats = Stats::of(&wall_ms).ok_or(GpuError::Lost("no frames timed"))?;
                let samples = f64::from(cfg.width) * f64::from(cfg.height) * f64::from(k);
                Ok(SampleRate {
                    format,
                    texture: n,
                    width: cfg.width,
                    height: cfg.height,
                    samples_per_pixel: k,
                    frames: gpu_ms.len() as u32,
                    gpu_ms: gpu_stats,
                    wall_ms: wall_stats,
                    gsamples_per_s: samples / (gpu_stats.median.max(1e-6) * 1e-3) / 1e9,
                })
            })();
            texture.destroy(gpu);
            let rate = measured?;
            log(&format!(
                "sample-only {}: {:.3} G samples/s",
                format.name(),
                rate.gsamples_per_s
            ));
            out.push(rate);
        }
        Ok(out)
    })();
    pass.destroy(gpu);
    result
}

// ---------------------------------------------------------------------------------------------------------------
// The benchmark.

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
        .find(|w| !SHADINGS.iter().any(|v| v.name() == w.as_str()))
    {
        return Err(BenchError::Usage(format!("unknown shading '{bad}'; use off or on")));
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
            // The layout the renderer chose (TexelPolicy::Auto: corner buffers or float textures on CPU devices).
            // Corner buffers bypass the sampler; their rate is stated against the fastest texture format's.
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
                if let Some(step) = opts.step_length {
                    base.step_length = step;
                }
                let shadings = scene
                    .shadings
                    .iter()
                    .filter(|v| opts.shadings.is_empty() || opts.shadings.iter().any(|w| w == v.name()));
                for &shading in shadings {
                    let mut s = base.clone();
                    shading.apply(&mut s);
                    // Counted before timing, so the count's CPU work never overlaps a timed frame.
                    let count = counter.count(&s);
                    log(&format!(
                        "{} {size}x{size} shading {}: converged image (step {CONVERGED_STEP})",
                        scene.name,
                        shading.name()
                    ));
                    let converged_image = headless.render(gpu, &converged(&s))?.image;
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
                            last = Some(frame.image.clone());
                            if let Some(tm) = frame.timings {
                                total.push(tm.total_ms);
                                march.push(tm.march_ms);
                                entry.extend(tm.entry_ms);
                                exit.extend(tm.exit_ms);
                            }
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

    #[test]
    fn counter_counts_the_segment_of_an_axis_aligned_ray() {
        // A ray straight down the box's axis crosses 64 voxels of a 64³ volume: 64 samples at 1-voxel steps.
        let v = volume::builtin("box", Some(64)).unwrap();
        let mut s = RenderSettings::new(1, 1, v.extent());
        s.camera = Camera::orbit(0.0, 0.0, 3.0, Vec3::ZERO);
        s.step_alpha = 0.0;
        s.skip_empty = false;
        let counter = SampleCounter::new(&v);
        let c = counter.count(&s);
        assert_eq!(c.segment_per_pixel, 64.0);
        assert_eq!(c.taken_per_pixel, 64.0, "nothing is opaque, so no ray ends early");
        s.skip_empty = true;
        let c = counter.count(&s);
        assert_eq!(c.segment_per_pixel, 64.0);
        assert_eq!(
            c.taken_per_pixel, 0.0,
            "nothing is visible: skipping leaps over every brick"
        );
        s.step_alpha = 1.0;
        s.window = [0.0, 1.0];
        let c = counter.count(&s);
        assert_eq!(c.taken_per_pixel, 1.0, "an opaque first sample ends the ray");
    }

    #[test]
    fn vtk_camera_frames_the_box_like_vtk() {
        let v = volume::builtin("helix", Some(8)).unwrap();
        let mut s = RenderSettings::new(512, 512, v.extent());
        configure_vtk_helix(&mut s, &v);
        assert!((s.camera.fov_y_deg - 20.69).abs() < 0.01);
        // Eye on the −y side, turned towards +x by VTK's positive azimuth, lifted by the elevation.
        let e = s.camera.eye.normalize();
        assert!(e.x > 0.0 && e.y < 0.0 && e.z > 0.0, "{e}");
        assert!((e.z - 25f32.to_radians().sin()).abs() < 1e-5);
        assert!((e.x / -e.y - 35f32.to_radians().tan()).abs() < 1e-5);
    }
}
