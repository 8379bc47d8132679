//! The subcommands' arguments (clap structs) and the option groups they share: which volume to load and how,
//! and which GPU to run on.

use super::budgets::BudgetArgs;
use super::frame::FrameArgs;
use super::parse::{
    parse_builtin, parse_fps, parse_gradients, parse_preset, parse_quality, parse_size, parse_turntable,
};
use crate::formats;
use crate::formats::RawOptions;
use crate::gpu::GpuOptions;
use crate::scene::quality::{Gradients, Quality};
use crate::volume::{self, Volume, VoxelType};
use anyhow::{bail, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Clone)]
#[command(next_help_heading = "Input")]
pub struct VolumeArgs {
    /// A volume file or folder (docs/formats.md)
    ///
    /// NRRD (.nrrd/.nhdr), NIfTI-1/2 (.nii/.nii.gz), Analyze 7.5 (.hdr/.img), MetaImage (.mha/.mhd), VTK (.vtk,
    /// .vti), OME-Zarr (a .zarr store), DICOM (a folder, or one file: its whole series opens), TIFF (a multi-page
    /// file or a folder of slices), or raw, with --dims and --type or a NAME_WxHxD_TYPE.raw name.
    pub file: Option<PathBuf>,
    /// A built-in volume: helix, box, colormap or marschner-lobb.
    #[arg(long, conflicts_with = "file", value_parser = parse_builtin)]
    pub builtin: Option<String>,
    /// Edge length of the built-in volume (default 256; 41 for marschner-lobb).
    #[arg(long, requires = "builtin", hide_short_help = true)]
    pub builtin_size: Option<u32>,
    /// Dimensions of a raw file: W H D.
    #[arg(long, num_args = 3, value_names = ["W", "H", "D"])]
    pub dims: Option<Vec<u32>>,
    /// Voxel type of a raw file: uint8, int8, uint16, int16, uint32, int32, float32, float64.
    #[arg(long = "type", value_name = "TYPE")]
    pub voxel_type: Option<String>,
    /// Voxel size SX SY SZ in mm, over the file's (default: the file's; 1 1 1 for raw files).
    #[arg(long, num_args = 3, value_names = ["SX", "SY", "SZ"])]
    pub spacing: Option<Vec<f32>>,
    /// Byte order of a raw file's voxels (default: little).
    #[arg(long, value_parser = ["little", "big"], hide_short_help = true)]
    pub endian: Option<String>,
    /// Bytes to skip at the start of a raw file (a header volcast does not read).
    #[arg(long, value_name = "N", hide_short_help = true)]
    pub header_bytes: Option<u64>,
    /// Largest dimension: a larger volume is downsampled 2x per axis until it fits (with a warning). Default: no
    /// limit but the budgets' and the device's.
    #[arg(long, value_name = "N", hide_short_help = true)]
    pub max_dim: Option<u32>,
    #[command(flatten)]
    pub budgets: BudgetArgs,
    /// Where levels read from large files are kept for the next open, as OME-Zarr stores (default:
    /// $XDG_CACHE_HOME/volcast, else ~/.cache/volcast); `volcast cache` shows and empties it.
    #[arg(long, value_name = "DIR", hide_short_help = true)]
    pub cache_dir: Option<PathBuf>,
    /// Neither read nor write the pyramid cache.
    #[arg(long, hide_short_help = true)]
    pub no_cache: bool,
    /// Refuse a volume larger than --max-dim or the budgets instead of downsampling it.
    #[arg(long, hide_short_help = true)]
    pub no_downsample: bool,
    /// The point array to load from a VTK file holding several (default: its active scalars, else the first
    /// one-component array); `volcast info` lists them.
    #[arg(long, value_name = "NAME", hide_short_help = true)]
    pub array: Option<String>,
    /// A DICOM folder's series, by number or UID (`info` lists them)
    ///
    /// The series to load from a DICOM folder holding several: its SeriesNumber or SeriesInstanceUID (default: the
    /// one with the most slices, or the series of the file given); `volcast info FOLDER` lists them.
    #[arg(long, value_name = "N|UID", hide_short_help = true)]
    pub series: Option<String>,
    /// The channel to load from an OME-Zarr image with a `c` axis, an ImageJ hyperstack, an OME-TIFF or a 5-D NIfTI,
    /// from 0 (default 0); `volcast info FILE` lists them.
    #[arg(long, value_name = "N", hide_short_help = true)]
    pub channel: Option<u32>,
    /// The time step of a 4-D series to show, from 0 (default 0)
    ///
    /// The value range stays the whole series'.
    #[arg(long, value_name = "N", hide_short_help = true)]
    pub time: Option<u32>,
}

impl VolumeArgs {
    /// These arguments with the volume of a view state where none is given here.
    pub fn or_from(&self, r: &crate::scene::view_state::VolumeRef) -> VolumeArgs {
        let mut a = self.clone();
        if a.file.is_some() || a.builtin.is_some() {
            return a;
        }
        a.builtin = r.builtin.clone();
        a.builtin_size = r.builtin_size;
        a.file = r.path.clone();
        a.dims = a.dims.or(r.raw_dims.map(|d| d.to_vec()));
        a.voxel_type = a.voxel_type.or(r.raw_type.clone());
        a.spacing = a.spacing.or(r.raw_spacing.map(|s| s.to_vec()));
        a.time = a.time.or((r.time > 0).then_some(r.time));
        a.channel = a.channel.or(r.channel);
        a
    }

    /// The host budget (no device known yet).
    pub fn budgets(&self) -> crate::pyramid::budget::Budgets {
        self.budgets.host()
    }

    /// The budgets on `gpu`.
    pub fn budgets_on(&self, gpu: &crate::gpu::Gpu) -> crate::pyramid::budget::Budgets {
        self.budgets.on(gpu)
    }

    /// `v` at the finest pyramid level that `gpu` and the budgets take, its note said on stderr when that is not
    /// full resolution.
    pub fn fit_device(&self, gpu: &crate::gpu::Gpu, v: Volume) -> Result<Volume> {
        let before = v.notes.len();
        let v = crate::scale::fit(v, &self.budgets_on(gpu), self.no_downsample)?;
        for note in &v.notes[before.min(v.notes.len())..] {
            eprintln!("note: {note}");
        }
        Ok(v)
    }

    /// The volume, its notes (uneven spacing, skipped files, ...) said on stderr.
    pub fn load(&self) -> Result<Volume> {
        self.load_within(self.budgets())
    }

    fn load_within(&self, budgets: crate::pyramid::budget::Budgets) -> Result<Volume> {
        let v = self.load_without_notes_within(budgets)?;
        for note in &v.notes {
            eprintln!("note: {note}");
        }
        Ok(v)
    }

    /// Channel `k` of this file, read as the volume is (the same choice of level), its notes left out: a layer of
    /// `--channels`.
    pub fn channel(&self, k: u32) -> Result<Volume> {
        let mut a = self.clone();
        a.channel = Some(k);
        a.load_without_notes()
    }

    /// The volume, its notes left to the caller: `info` prints them with the rest, so saying them on stderr too
    /// showed each twice.
    pub fn load_without_notes(&self) -> Result<Volume> {
        self.load_without_notes_within(self.budgets())
    }

    fn load_without_notes_within(&self, budgets: crate::pyramid::budget::Budgets) -> Result<Volume> {
        if let Some(name) = &self.builtin {
            let mut v = volume::builtin(name, self.builtin_size)?;
            // --spacing overrides every volume's own, the built-ins' included.
            if let Some(s) = &self.spacing {
                v = v.with_spacing([s[0], s[1], s[2]])?;
            }
            v = crate::scale::fit(v, &budgets, self.no_downsample)?;
            if let Some(t) = self.time {
                v.show_step(t)?;
            }
            return Ok(v);
        }
        let Some(path) = &self.file else {
            // Exit 64: only the command line is to blame.
            bail!(super::UsageError(format!(
                "no volume given: pass a FILE or --builtin NAME ({})",
                volume::BUILTIN_NAMES.join(", ")
            )));
        };
        let opts = self.open_options()?;
        // A progress bar only where loading takes long enough to watch (files over 8 MiB).
        let big = std::fs::metadata(path).is_ok_and(|m| m.len() > 8 << 20);
        let bar = indicatif::ProgressBar::new(1000);
        if !big {
            bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
        }
        // indicatif's default style draws no message: the label needs a template that has one.
        if let Ok(style) = indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed}") {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_message(format!("loading {}", path.display()));
        let cache = (!self.no_cache).then(|| crate::scale::cache::PyramidCache::new(self.cache_dir.clone()));
        let loaded = crate::scale::open(path, &opts, budgets, cache.as_ref(), &mut |f| {
            bar.set_position((f * 1000.0) as u64)
        });
        bar.finish_and_clear();
        // A --series the folder does not hold is a usage error (exit 64), its message listing those it does.
        let mut v = loaded.map_err(|e| match e {
            volume::VolumeError::UnknownSeries { .. } => anyhow::Error::new(super::UsageError(e.to_string())),
            e => e.into(),
        })?;
        if let Some(t) = self.time {
            v.show_step(t)?;
        }
        Ok(v)
    }

    /// How to open the file these arguments name.
    pub fn open_options(&self) -> Result<formats::OpenOptions> {
        Ok(formats::OpenOptions {
            raw: self.raw_options()?,
            endian: match self.endian.as_deref() {
                Some("big") => formats::Endian::Big,
                _ => formats::Endian::Little,
            },
            header_bytes: self.header_bytes.unwrap_or(0),
            max_dim: self.max_dim,
            no_downsample: self.no_downsample,
            array: self.array.clone(),
            series: self.series.clone(),
            channel: self.channel,
        })
    }

    pub fn raw_options(&self) -> Result<RawOptions> {
        let voxel_type = match &self.voxel_type {
            Some(t) => Some(t.parse::<VoxelType>()?),
            None => None,
        };
        Ok(RawOptions {
            dims: self.dims.as_ref().map(|d| [d[0], d[1], d[2]]),
            voxel_type,
            spacing: self.spacing.as_ref().map(|s| [s[0], s[1], s[2]]),
        })
    }
}

#[derive(Args, Clone)]
pub struct CacheArgs {
    /// The cache folder (default: $XDG_CACHE_HOME/volcast, else ~/.cache/volcast).
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// Empty it.
    #[arg(long)]
    pub clear: bool,
}

#[derive(Args, Clone)]
pub struct InfoArgs {
    #[command(flatten)]
    pub volume: VolumeArgs,
    /// Print one JSON object (format, dims, type, spacing, value_range, timesteps, affine_ras, axes,
    /// handedness, ...) instead of text.
    #[arg(long, help_heading = "Options")]
    pub json: bool,
}

#[derive(Args, Clone)]
#[command(next_help_heading = "GPU")]
pub struct GpuArgs {
    /// Run under the Khronos validation layer; any message fails the command
    ///
    /// With synchronization validation (also VOLCAST_VALIDATION=1); exits non-zero if it reports an error or a
    /// warning.
    #[arg(long)]
    pub validate: bool,
    /// Device index or part of its name (see `volcast devices`).
    #[arg(long, hide_short_help = true)]
    pub device: Option<String>,
    /// How volumes are stored on the GPU: auto (on CPU devices such as lavapipe the fastest layout within 1 GiB:
    /// corner textures for 8/16-bit data, else a float texture; the data's own format on GPUs), native (least
    /// memory), float (4 bytes per voxel) or corners (4 or 8 bytes per voxel for 8/16-bit data).
    #[arg(long, default_value = "auto", value_parser = ["auto", "native", "float", "corners"], hide_short_help = true)]
    pub texture: String,
    /// Cut volumes into bricks of this many voxels per side in the GPU's brick pool (at least 8). By default a
    /// volume that fits the device's 3D texture limit is one brick, and larger ones are cut into 64^3 bricks.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(8..=1024), hide_short_help = true)]
    pub brick_size: Option<u32>,
}

impl GpuArgs {
    pub fn options(&self) -> GpuOptions {
        let env = std::env::var("VOLCAST_VALIDATION").is_ok_and(|v| !v.is_empty() && v != "0");
        GpuOptions {
            validation: self.validate || env,
            device: self.device.clone(),
            texel_policy: match self.texture.as_str() {
                "native" => crate::gpu::TexelPolicy::Native,
                "float" => crate::gpu::TexelPolicy::Float,
                "corners" => crate::gpu::TexelPolicy::Corners,
                _ => crate::gpu::TexelPolicy::Auto,
            },
            brick_side: self.brick_size,
            ..Default::default()
        }
    }
}

#[derive(Args, Clone)]
pub struct RenderArgs {
    #[command(flatten)]
    pub volume: VolumeArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[command(flatten)]
    pub layers: super::layers::LayerArgs,
    /// The image to write: PNG, JPEG or TIFF by its extension
    #[arg(short, long, default_value = "volcast.png", help_heading = "Output")]
    pub output: PathBuf,
    /// Ray setup: faces (entry/exit textures), analytic (ray/box intersection) or compute (analytic, marched in a
    /// compute pass instead of a fragment pass).
    #[arg(long, default_value = "faces", value_parser = ["faces", "analytic", "compute"], hide_short_help = true, help_heading = "Output")]
    pub method: String,
    /// Print GPU time per pass (after a warm-up frame; lavapipe compiles shaders on first use).
    #[arg(long, hide_short_help = true, help_heading = "Output")]
    pub timings: bool,
    /// Print peak resident memory and the GPU memory allocated (volume, targets, buffers).
    #[arg(long, hide_short_help = true, help_heading = "Output")]
    pub memory: bool,
    /// Append a colour bar with ticks in data units
    ///
    /// The transfer function's colours and opacity over the window, as a strip at the right: the image grows by
    /// its width.
    #[arg(long, help_heading = "Output")]
    pub colorbar: bool,
    /// Draw a scale bar (mm, or µm under 1 mm) at the bottom left
    ///
    /// A round length at the depth of the camera's target (the point the view orbits): exact there, and at every
    /// depth with --ortho.
    #[arg(long, help_heading = "Output")]
    pub scale_bar: bool,
    /// Frames to time with --timings (the median is reported; default 5); with --keyframes, the movie's frame
    /// count (2 to 3600).
    #[arg(long, hide_short_help = true, help_heading = "Output")]
    pub frames: Option<u32>,
    /// Render a view the viewer saved (F12's or a session's JSON)
    ///
    /// Its settings, and its volume unless a FILE or --builtin is given. Options given beside it override its
    /// values and keep the rest.
    #[arg(long, value_name = "FILE.json", help_heading = "Output")]
    pub state: Option<PathBuf>,
    /// Show level L of the volume's resolution pyramid everywhere, through the GPU's brick pool (level 0's box and
    /// placement; docs/large-volumes.md). A level past the coarsest (one brick) shows the coarsest.
    #[arg(
        long,
        value_name = "L",
        conflicts_with = "movie",
        hide_short_help = true,
        help_heading = "Output"
    )]
    pub level: Option<u32>,
    /// A turntable movie of N frames: NAME-0000.png … and NAME.gif
    ///
    /// N from 1 to 3600, once around the vertical axis (+z through the point looked at), starting at the view
    /// given: `-o NAME.png` writes NAME-0000.png … and a looping NAME.gif (docs/cli.md, Movies).
    #[arg(long, value_name = "N", value_parser = parse_turntable, group = "movie", conflicts_with = "timings", help_heading = "Output")]
    pub turntable: Option<u32>,
    /// A movie along a camera path through view states (F12's JSON)
    ///
    /// --frames N in all: the first frame is the first state, the last the last; the volume is the first state's.
    /// Written like --turntable.
    #[arg(long, num_args = 2.., value_name = "STATE.json", group = "movie", conflicts_with_all = ["state", "timings"], help_heading = "Output", hide_short_help = true)]
    pub keyframes: Vec<PathBuf>,
    /// Frames per second of a movie's GIF (0.1 to 50).
    #[arg(long, value_name = "F", default_value_t = crate::movie::gif::DEFAULT_FPS, value_parser = parse_fps, requires = "movie", hide_short_help = true, help_heading = "Output")]
    pub fps: f32,
}

#[derive(Args, Clone)]
pub struct ViewArgs {
    #[command(flatten)]
    pub volume: VolumeArgs,
    #[command(flatten)]
    pub layers: super::layers::LayerArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
    /// Initial window size WxH.
    #[arg(long, default_value = "1280x800", value_parser = parse_size, help_heading = "Options")]
    pub size: (u32, u32),
    /// Sampling quality of still frames, as `render --quality`: draft, fast, normal or converged (moving frames
    /// use draft's step; the panel and the Q key change it).
    #[arg(long, default_value = "normal", value_parser = parse_quality, help_heading = "Options")]
    pub quality: Quality,
    /// Drive the window with a script (for tests), e.g. "frames:3;resize:320x240;screenshot:a.png;exit".
    #[arg(long, hide = true)]
    pub script: Option<String>,
    /// Start with the three slice views beside the 3D view (four-up; L toggles it).
    #[arg(long, help_heading = "Options")]
    pub slices: bool,
    /// Restore a session (Ctrl+S's or F12's JSON): its volume, unless a FILE or --builtin is given here, and its
    /// view (transfer function, camera, slabs, clip plane, mode, lighting, time step, slice views).
    #[arg(long, value_name = "FILE.json", help_heading = "Options")]
    pub state: Option<PathBuf>,
    /// Open with this transfer-function preset (ct-bone, ct-soft-tissue, ct-lung, mr-default, qt-example) and
    /// lock it, instead of the one chosen by modality (auto, the default).
    #[arg(long, conflicts_with = "tf", value_parser = parse_preset, help_heading = "Options")]
    pub preset: Option<String>,
    /// Open with the transfer function in this JSON file (docs/rendering.md, The JSON format), locked.
    #[arg(long, value_name = "FILE.json", help_heading = "Options")]
    pub tf: Option<PathBuf>,
}

#[derive(Args, Clone)]
pub struct BenchArgs {
    #[command(flatten)]
    pub gpu: GpuArgs,
    /// Timed frames per configuration (median, min and max are reported).
    #[arg(long, default_value_t = 10, help_heading = "Options")]
    pub frames: u32,
    /// Untimed frames first (lavapipe compiles shaders on first use).
    #[arg(long, default_value_t = 2, help_heading = "Options")]
    pub warmup: u32,
    /// Folder with the CT head and MRI brain raw files (scenes whose file is missing are skipped).
    #[arg(long, default_value = "../shared/data/raw", help_heading = "Options")]
    pub data: PathBuf,
    /// make_volume.py's helix_256x256x256_uint8.raw for the vtk-helix scene (default: the same field generated).
    #[arg(long, help_heading = "Options")]
    pub vtk_raw: Option<PathBuf>,
    /// Only these scenes (repeatable): helix, dense, ct-head, mri-brain, vtk-helix, quick-helix.
    #[arg(long = "scene", help_heading = "Options")]
    pub scenes: Vec<String>,
    /// Only these image sizes (repeatable), e.g. --size 512.
    #[arg(long = "size", help_heading = "Options")]
    pub sizes: Vec<u32>,
    /// Only these shading variants (repeatable): off, on, shadows (shading with shadows and ambient occlusion;
    /// the helix and CT head scenes).
    #[arg(long = "shading", help_heading = "Options")]
    pub shadings: Vec<String>,
    /// Only these methods (repeatable): faces, analytic, compute (the analytic ray setup in a compute pass).
    #[arg(long = "method", value_parser = ["faces", "analytic", "compute"], help_heading = "Options")]
    pub methods: Vec<String>,
    /// CI smoke mode: a 64³ helix at 64x64, all three methods, shading off and on, tiny sample-only run.
    #[arg(long, help_heading = "Options")]
    pub quick: bool,
    /// Only the sample-only micro-benchmark (all three texel formats).
    #[arg(long, help_heading = "Options")]
    pub sample_only: bool,
    /// Only time-series playback as the viewer plays it: 64 steps of 128³ float32 at 512² (with --quick 6 steps
    /// of 24³ at 64²); each step is uploaded and rendered, the two timed apart.
    #[arg(long, conflicts_with_all = ["sample_only", "scenes"], help_heading = "Options")]
    pub playback: bool,
    /// Only the scale scenes (docs/large-volumes.md): a procedural field at 256³, 1024³ and 2048³ uint8 and 2048³
    /// uint16, generated once into --cache, opened cold and warm within the default budgets at 512² (or --size).
    #[arg(long, conflicts_with_all = ["sample_only", "scenes", "playback"], help_heading = "Options")]
    pub scale: bool,
    /// With --scale: only these edges (repeatable), e.g. --scale-edge 1024, of --scale-type voxels.
    #[arg(long = "scale-edge", requires = "scale", help_heading = "Options")]
    pub scale_edges: Vec<u32>,
    /// With --scale-edge: the voxel type, uint8 or uint16.
    #[arg(long, requires = "scale_edges", value_parser = ["uint8", "uint16"], default_value = "uint8", help_heading = "Options")]
    pub scale_type: String,
    /// Where --scale keeps its generated files (default: $XDG_CACHE_HOME/volcast/bench, else ~/.cache/volcast/bench).
    #[arg(long, requires = "scale", help_heading = "Options")]
    pub cache: Option<PathBuf>,
    /// The memory budgets: `bench --scale` opens its scenes within them (a scene over the GPU budget streams
    /// through a pool of half of it, as `render --gpu-budget` does); the other benchmarks refuse them.
    #[command(flatten)]
    pub budgets: BudgetArgs,
    /// Sampling quality of every scene, as `render --quality`: draft, fast, normal or converged. Repeat it to
    /// time each level against the same converged image (default: normal).
    #[arg(long = "quality", value_parser = parse_quality, help_heading = "Options")]
    pub qualities: Vec<Quality>,
    /// Where shaded scenes take gradients, as `render --gradients`: auto, texture or samples.
    #[arg(long, default_value = "auto", value_parser = parse_gradients, help_heading = "Options")]
    pub gradients: Gradients,
    /// Force this step length (in voxels) on every scene instead of its quality's; each frame's error is still
    /// taken against the scene's converged image (1/8-voxel steps).
    #[arg(long, help_heading = "Options")]
    pub step_length: Option<f32>,
    /// Print the results as JSON on stdout (progress still goes to stderr).
    #[arg(long, help_heading = "Options")]
    pub json: bool,
}

#[derive(Args, Clone)]
pub struct CompareArgs {
    #[command(flatten)]
    pub volume: VolumeArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[command(flatten)]
    pub layers: super::layers::LayerArgs,
    /// Folder for the images and the tables (created if missing).
    #[arg(long, default_value = "cmp", help_heading = "Options")]
    pub out: PathBuf,
    /// Timed frames per method and view after a warm-up frame (medians are reported).
    #[arg(long, default_value_t = 3, help_heading = "Options")]
    pub frames: u32,
}

#[derive(Args, Clone)]
pub struct ConvertArgs {
    #[command(flatten)]
    pub volume: VolumeArgs,
    /// The OME-Zarr store to write (a folder, conventionally NAME.ome.zarr); refused if it exists.
    #[arg(
        value_name = "OUT.ome.zarr",
        required_unless_present = "output_option",
        conflicts_with = "output_option",
        help_heading = "Options"
    )]
    pub output: Option<PathBuf>,
    /// The store to write, as an option: needed with --builtin, which takes no FILE (so one path would be FILE).
    #[arg(short = 'o', long = "output", value_name = "OUT.ome.zarr", help_heading = "Options")]
    pub output_option: Option<PathBuf>,
    /// OME-Zarr version: 0.5 (Zarr v3) or 0.4 (Zarr v2).
    #[arg(long, default_value = "0.5", value_parser = ["0.5", "0.4"], help_heading = "Options")]
    pub ome_zarr_version: String,
    /// Chunk edge in voxels (chunks of N³).
    #[arg(long, value_name = "N", default_value_t = 64, help_heading = "Options")]
    pub chunk: u64,
    /// Shard edge in voxels (shards of N³ holding --chunk chunks; a multiple of --chunk; OME-Zarr 0.5 only).
    #[arg(long, value_name = "N", help_heading = "Options")]
    pub shard: Option<u64>,
    /// Chunk compression: zstd (level 1), blosc (blosc with lz4 inside, level 5, byte shuffle for multi-byte
    /// types) or none.
    #[arg(long, default_value = "zstd", value_parser = ["zstd", "blosc", "none"], help_heading = "Options")]
    pub compression: String,
    /// Label data: coarser levels take each 2x2x2 block's most common value (ties: the smallest), or with
    /// `--labels nearest` the block's first voxel, instead of the mean.
    #[arg(long, value_name = "RULE", num_args = 0..=1, default_missing_value = "mode", value_parser = ["mode", "nearest"], help_heading = "Options")]
    pub labels: Option<String>,
    /// Replace OUT if it is a Zarr store (nothing else is ever removed).
    #[arg(long, help_heading = "Options")]
    pub overwrite: bool,
}

impl ConvertArgs {
    /// The store to write, given either way.
    pub fn out(&self) -> &std::path::Path {
        self.output
            .as_deref()
            .or(self.output_option.as_deref())
            .expect("clap requires one")
    }
}
