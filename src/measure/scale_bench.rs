//! `volcast bench --scale`: volumes from 256³ to 2048³ (8 and 16 GiB), opened as a user opens them, within the
//! default budgets or the ones given (docs/large-volumes.md). Each scene is one procedural field (rings in a ball),
//! generated once into a cache folder as a raw file (never committed) and read in place from there.
//!
//! Per scene, in this process, after evicting the file from the page cache (`posix_fadvise(DONTNEED)`, a cold
//! read) and resetting the peak-RSS mark (`/proc/self/clear_refs`): time to the first image (the strided preview
//! the viewer shows, where the file gets one, else the volume), time to the volume at the level the budgets take
//! (read, uploaded, rendered), frame times at 512² at rest and as the viewer draws while dragging (half the
//! resolution, draft steps), peak RSS, GPU memory, and the bytes read from files (`rchar`) and from the disk
//! (`read_bytes`). Then the same open again with the file in the page cache (warm), both with an empty pyramid
//! cache (the time to write the level into it is reported apart), and once more from the pyramid cache, file and
//! cache evicted (cached).

use crate::formats::OpenOptions;
use crate::gpu::{Gpu, GpuError};
use crate::measure::bench::{gpu_allocated, peak_rss_bytes, Stats};
use crate::pyramid::budget::Budgets;
use crate::render::headless::Headless;
use crate::scale::cache::PyramidCache;
use crate::scene::quality::{moving_view, Quality};
use crate::scene::settings::RenderSettings;
use crate::volume::{Volume, VoxelType};
use rayon::prelude::*;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A scale scene: the field at `edge`³ voxels of `voxel_type`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScaleScene {
    pub edge: u32,
    pub voxel_type: VoxelType,
}

impl ScaleScene {
    /// The default scenes: 256³, 1024³ and 2048³ uint8, and 2048³ uint16.
    pub const DEFAULT: [ScaleScene; 4] = [
        ScaleScene::new(256, VoxelType::U8),
        ScaleScene::new(1024, VoxelType::U8),
        ScaleScene::new(2048, VoxelType::U8),
        ScaleScene::new(2048, VoxelType::U16),
    ];

    pub const fn new(edge: u32, voxel_type: VoxelType) -> ScaleScene {
        ScaleScene { edge, voxel_type }
    }

    /// `field_NxNxN_TYPE.raw`: a name volcast reads the layout from.
    pub fn file_name(&self) -> String {
        let n = self.edge;
        format!("field_{n}x{n}x{n}_{}.raw", self.voxel_type.name())
    }

    pub fn bytes(&self) -> u64 {
        u64::from(self.edge).pow(3) * self.voxel_type.size() as u64
    }
}

/// The field at normalised position p in [-1, 1]³: 0.3 of a ball's radial ramp plus rings (a tube of radius 0.08
/// about the circle of radius 0.55 around z, repeated along z), in [0, 1].
pub fn field(x: f32, y: f32, z: f32) -> f32 {
    let ball = (1.0 - (x * x + y * y + z * z).sqrt() / 0.9).clamp(0.0, 1.0);
    let ring_z = (z * 4.0).fract().abs() - 0.5;
    let d2 = ((x * x + y * y).sqrt() - 0.55).powi(2) + (ring_z * 0.25).powi(2);
    let tube = (1.0 - d2 / (0.08 * 0.08)).max(0.0);
    (0.3 * ball + 0.7 * tube * tube).min(1.0)
}

/// Writes `scene`'s file into `dir` unless it is there at its size; slabs of slices made on every core.
pub fn generate(scene: ScaleScene, dir: &Path, log: &mut dyn FnMut(&str)) -> std::io::Result<PathBuf> {
    let path = dir.join(scene.file_name());
    if std::fs::metadata(&path).is_ok_and(|m| m.len() == scene.bytes()) {
        return Ok(path);
    }
    std::fs::create_dir_all(dir)?;
    log(&format!(
        "scale: generating {} ({} MiB)",
        path.display(),
        scene.bytes() >> 20
    ));
    let n = scene.edge as usize;
    let size = scene.voxel_type.size();
    let file = File::create(&path)?;
    let coord = |i: usize| (i as f32 + 0.5) / n as f32 * 2.0 - 1.0;
    for z0 in (0..n).step_by(16) {
        let slices = 16.min(n - z0);
        let mut slab = vec![0u8; slices * n * n * size];
        slab.par_chunks_mut(n * size).enumerate().for_each(|(row, out)| {
            let (y, z) = (row % n, z0 + row / n);
            for x in 0..n {
                let v = field(coord(x), coord(y), coord(z));
                match scene.voxel_type {
                    VoxelType::U16 => out[2 * x..2 * x + 2].copy_from_slice(&((v * 65535.0) as u16).to_le_bytes()),
                    _ => out[x] = (v * 255.0) as u8,
                }
            }
        });
        file.write_all_at(&slab, (z0 * n * n * size) as u64)?;
    }
    Ok(path)
}

/// One scene's measurements (times in seconds, frames in ms, bytes).
#[derive(Clone, Debug, serde::Serialize)]
pub struct ScaleRow {
    pub scene: String,
    pub file_bytes: u64,
    /// "cold" (evicted from the page cache first), "warm" (in the page cache) or "cached" (read from the pyramid
    /// cache, evicted from the page cache first).
    pub cache: &'static str,
    /// The dims shown and the pyramid level (0: full resolution).
    pub shown: [u32; 3],
    pub level: u32,
    pub first_image_s: f64,
    /// Whether the first image was the strided preview.
    pub preview: bool,
    pub refined_s: f64,
    pub rest_ms: Stats,
    pub drag_ms: Stats,
    pub peak_rss_bytes: Option<u64>,
    pub gpu_bytes: u64,
    pub read_from_files: Option<u64>,
    pub read_from_disk: Option<u64>,
    /// Seconds to write the level into the pyramid cache, after it was shown (none when read from it).
    pub cache_write_s: Option<f64>,
    /// Over the GPU budget whole: streamed through a pool of this many bricks, and the levels shown at rest.
    pub streamed: Option<(usize, String)>,
    /// Streamed: the view four times closer, refined from the rest view's pool.
    pub close: Option<Close>,
}

/// A close view of a streamed volume: where the screen rule wants the file's finest levels.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Close {
    /// The levels shown once refined, and how long refining took from the rest view's pool.
    pub levels: String,
    pub refined_s: f64,
    pub rest_ms: Stats,
}

/// `rest` four times closer to its target.
fn closer(rest: &RenderSettings) -> RenderSettings {
    let mut s = rest.clone();
    let c = &mut s.camera;
    c.eye = c.target + (c.eye - c.target) / 4.0;
    s
}

/// (rchar, read_bytes) of this process.
fn io_counters() -> Option<(u64, u64)> {
    let text = std::fs::read_to_string("/proc/self/io").ok()?;
    let field = |name: &str| -> Option<u64> {
        let line = text.lines().find(|l| l.starts_with(name))?;
        line.split_whitespace().nth(1)?.parse().ok()
    };
    Some((field("rchar:")?, field("read_bytes:")?))
}

/// Drops every file under `dir` from the page cache.
fn evict_tree(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        match e.file_type() {
            Ok(t) if t.is_dir() => evict_tree(&e.path()),
            Ok(_) => evict(&e.path()),
            Err(_) => {}
        }
    }
}

/// Drops `path` from the page cache, so the next read comes from the disk.
fn evict(path: &Path) {
    if let Ok(f) = File::open(path) {
        use std::os::fd::AsRawFd;
        // SAFETY: fadvise only advises the kernel about an open descriptor's cached pages; no memory is touched.
        unsafe {
            libc::posix_fadvise(f.as_raw_fd(), 0, 0, libc::POSIX_FADV_DONTNEED);
        }
    }
}

/// Resets this process's peak-RSS mark (Linux: writing 5 to /proc/self/clear_refs); false where it cannot.
fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

fn timed_frames(gpu: &Gpu, headless: &mut Headless, s: &RenderSettings, frames: u32) -> Result<Stats, GpuError> {
    headless.render(gpu, s)?;
    let mut ms = Vec::new();
    for _ in 0..frames.max(1) {
        let t = Instant::now();
        headless.render(gpu, s)?;
        ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    Stats::of(&ms).ok_or(GpuError::Lost("no frames timed"))
}

/// The settings at `size`² for `v`: normal quality at rest; dragging as the viewer draws it (half the resolution,
/// the draft step and strides: [`moving_view`]).
fn settings(v: &Volume, size: u32) -> (RenderSettings, RenderSettings) {
    let mut rest = RenderSettings::new(size, size, v.extent());
    Quality::Normal.apply(&mut rest, v.range);
    let drag = moving_view(&rest, 2, Some(Quality::Normal), v.range);
    (rest, drag)
}

/// Opens, shows and times `path` once within `budgets` (see the module's description); `frames`: the frame's
/// edge and the frames timed per view.
pub fn measure(
    gpu: &Gpu,
    path: &Path,
    cache: &'static str,
    pyramids: &PyramidCache,
    budgets: Budgets,
    frames: (u32, u32),
) -> Result<ScaleRow, Box<dyn std::error::Error>> {
    forget(path, cache, pyramids)?;
    let marks = Marks {
        peak_known: reset_peak_rss(),
        io: io_counters(),
    };
    let mut headless = Headless::new(gpu)?;
    let result =
        measure_in(gpu, &mut headless, path, (pyramids, budgets), frames).and_then(|m| m.row(gpu, path, cache, &marks));
    headless.destroy(gpu);
    result
}

/// Empties or evicts what `cache` says a run starts without: the file from the page cache unless "warm", and the
/// pyramid cache unless "cached", where only its files leave the page cache.
fn forget(path: &Path, cache: &str, pyramids: &PyramidCache) -> std::io::Result<()> {
    if cache != "warm" {
        // SAFETY: sync(2) takes no arguments and touches no memory; dirty pages (a file just written) cannot be
        // evicted until they are written back.
        unsafe { libc::sync() };
        evict(path);
    }
    if cache == "cached" {
        evict_tree(&pyramids.root);
        Ok(())
    } else {
        pyramids.clear().map(drop)
    }
}

/// What a run reads before it opens the file: whether the peak-RSS mark was reset, and the I/O counters.
struct Marks {
    peak_known: bool,
    io: Option<(u64, u64)>,
}

/// What one open measured, before the row is made of it.
struct Measured {
    volume: Volume,
    first_s: Option<f64>,
    refined_s: f64,
    io_refined: Option<(u64, u64)>,
    rest_ms: Stats,
    drag_ms: Stats,
    streamed: Option<(usize, String)>,
    close: Option<Close>,
    peak: Option<u64>,
    cache_write_s: Option<f64>,
}

/// Opens `path` as the viewer does (the preview, then the level the budgets take), refines the rest view, and
/// times it at rest, dragging and four times closer; then writes the level into the pyramid cache. `frames`:
/// (the frame's edge, the frames timed per view).
fn measure_in(
    gpu: &Gpu,
    headless: &mut Headless,
    path: &Path,
    (pyramids, budgets): (&PyramidCache, Budgets),
    (size, frames): (u32, u32),
) -> Result<Measured, Box<dyn std::error::Error>> {
    let opts = OpenOptions::default();
    let start = Instant::now();
    // Read within the host budget; over the GPU budget whole, streamed as the viewer does.
    let read = Budgets { gpu: None, ..budgets };
    let preview = crate::scale::preview_within(path, &opts, read, Some(pyramids))?;
    let first_s = match preview {
        Some(p) => {
            headless.set_volume(gpu, &p)?;
            headless.render(gpu, &settings(&p, size).0)?;
            Some(start.elapsed().as_secs_f64())
        }
        None => None,
    };
    let opened = crate::scale::open_deferred(path, &opts, read, Some(pyramids), &mut |_| {})?;
    let v = opened.volume;
    headless.renderer.place_volume(gpu, &v, &budgets)?;
    let (rest, drag) = settings(&v, size);
    let at_rest = headless.renderer.refine(gpu, &v, &rest)?;
    headless.render(gpu, &rest)?;
    let refined_s = start.elapsed().as_secs_f64();
    let io_refined = io_counters();
    let rest_ms = timed_frames(gpu, headless, &rest, frames)?;
    // Dragging, the viewer wants one level coarser (factor 2) of the still view's cut.
    if let Some(wanted) = headless.renderer.stream_wanted(&v, &rest, 2.0) {
        headless.renderer.refine_to(gpu, &v, &wanted)?;
    }
    let drag_ms = timed_frames(gpu, headless, &drag, frames)?;
    let streamed = at_rest.map(|p| (headless.renderer.stream().map_or(0, |s| s.capacity()), p.levels_shown()));
    let close = match streamed {
        Some(_) => Some(close_view(gpu, headless, &v, &rest, frames)?),
        None => None,
    };
    let peak = peak_rss_bytes();
    let write = Instant::now();
    let cache_write_s = opened.keep.map(|k| {
        drop(k.write(v.clone()));
        write.elapsed().as_secs_f64()
    });
    Ok(Measured {
        volume: v,
        first_s,
        refined_s,
        io_refined,
        rest_ms,
        drag_ms,
        streamed,
        close,
        peak,
        cache_write_s,
    })
}

/// The view four times closer than `rest`, refined from the rest view's pool and timed.
fn close_view(
    gpu: &Gpu,
    headless: &mut Headless,
    v: &Volume,
    rest: &RenderSettings,
    frames: u32,
) -> Result<Close, GpuError> {
    let s = closer(rest);
    let t = Instant::now();
    let levels = headless
        .renderer
        .refine(gpu, v, &s)?
        .map(|p| p.levels_shown())
        .unwrap_or_default();
    headless.render(gpu, &s)?;
    let refined_s = t.elapsed().as_secs_f64();
    let rest_ms = timed_frames(gpu, headless, &s, frames)?;
    Ok(Close {
        levels,
        refined_s,
        rest_ms,
    })
}

impl Measured {
    /// The scene's row: `marks` as taken before the open.
    fn row(
        self,
        gpu: &Gpu,
        path: &Path,
        cache: &'static str,
        marks: &Marks,
    ) -> Result<ScaleRow, Box<dyn std::error::Error>> {
        let v = &self.volume;
        let level = v
            .notes
            .iter()
            .find_map(|n| n.strip_prefix("pyramid level ")?.split(' ').next()?.parse().ok());
        let io = marks.io.zip(self.io_refined);
        Ok(ScaleRow {
            scene: path
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
            file_bytes: std::fs::metadata(path)?.len(),
            cache,
            // The file's size where its finer levels stream from it.
            shown: v.finer.as_ref().map_or(v.dims, |f| f.dims()),
            level: level.unwrap_or(0),
            first_image_s: self.first_s.unwrap_or(self.refined_s),
            preview: self.first_s.is_some(),
            refined_s: self.refined_s,
            rest_ms: self.rest_ms,
            drag_ms: self.drag_ms,
            peak_rss_bytes: self.peak.filter(|_| marks.peak_known),
            gpu_bytes: gpu_allocated(gpu)?.0,
            read_from_files: io.map(|(a, b)| b.0 - a.0),
            read_from_disk: io.map(|(a, b)| b.1 - a.1),
            cache_write_s: self.cache_write_s,
            streamed: self.streamed,
            close: self.close,
        })
    }
}

/// Every scene, cold, warm and cached, within `budgets` at `frames.0`² (`frames.1` frames timed per view): files
/// generated into `dir` where missing.
pub fn run(
    gpu: &Gpu,
    scenes: &[ScaleScene],
    dir: &Path,
    budgets: Budgets,
    frames: (u32, u32),
    log: &mut dyn FnMut(&str),
) -> Result<Vec<ScaleRow>, Box<dyn std::error::Error>> {
    let mut rows = Vec::new();
    let pyramids = PyramidCache::new(Some(dir.join("pyramid-cache")));
    for scene in scenes {
        let path = generate(*scene, dir, log)?;
        for cache in ["cold", "warm", "cached"] {
            log(&format!("scale: {} ({cache})", scene.file_name()));
            rows.push(measure(gpu, &path, cache, &pyramids, budgets, frames)?);
        }
    }
    pyramids.clear()?;
    Ok(rows)
}

/// The table `bench --scale` prints.
pub fn table(rows: &[ScaleRow], device: &str, size: u32, budgets: Budgets) -> String {
    let mib = |b: u64| format!("{}", b >> 20);
    let opt = |b: Option<u64>| b.map_or("-".to_string(), mib);
    let mut out = format!(
        "scale scenes on {device} at {size}x{size}, budgets: host {} MiB, GPU {} MiB\n\
         | scene | cache | shown (level) | first image s | refined s | rest ms | drag ms | peak RSS MiB | GPU MiB | read MiB (disk) | cache write s |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
        budgets.host >> 20,
        budgets.gpu.map_or(0, |g| g.bytes >> 20)
    );
    for r in rows {
        let [x, y, z] = r.shown;
        let level = match &r.streamed {
            Some((slots, levels)) => format!("streamed, {slots} slots: {levels}"),
            None => r.level.to_string(),
        };
        out += &format!(
            "| {} | {} | {x}x{y}x{z} ({level}) | {:.2}{} | {:.2} | {:.0} | {:.0} | {} | {} | {} ({}) | {} |\n",
            r.scene,
            r.cache,
            r.first_image_s,
            if r.preview { " (preview)" } else { "" },
            r.refined_s,
            r.rest_ms.median,
            r.drag_ms.median,
            opt(r.peak_rss_bytes),
            mib(r.gpu_bytes),
            opt(r.read_from_files),
            opt(r.read_from_disk),
            r.cache_write_s.map_or("-".to_string(), |s| format!("{s:.1}")),
        );
    }
    let close: Vec<&ScaleRow> = rows.iter().filter(|r| r.close.is_some()).collect();
    if !close.is_empty() {
        out += "\nstreamed scenes four times closer (refined from the rest view's pool)\n\
                | scene | cache | shown (levels of the file's level-0 bricks) | refined s | rest ms |\n|---|---|---|---|---|\n";
        for r in close {
            let c = r.close.as_ref().expect("filtered");
            out += &format!(
                "| {} | {} | {} | {:.2} | {:.0} |\n",
                r.scene, r.cache, c.levels, c.refined_s, c.rest_ms.median
            );
        }
    }
    out
}
