//! The `volcast` command line: picks a subcommand, turns arguments into plain settings, reports errors.

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use glam::Vec3;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use volcast::camera::{Camera, ViewPreset};
use volcast::compare;
use volcast::gpu::{Gpu, GpuError, GpuOptions};
use volcast::headless::Headless;
use volcast::quality::{Gradients, Quality};
use volcast::settings::CompositeMode;
use volcast::settings::{PositionFormat, RaySetup, RenderSettings};
use volcast::tf::TransferFunction;
use volcast::transfer::Colormap;
use volcast::viewer::{self, ViewerError, ViewerOptions, VolumeSource};
use volcast::volume::{self, RawOptions, Volume, VoxelType};

#[derive(Parser)]
#[command(
    name = "volcast",
    version,
    about = "Volume ray caster on raw Vulkan",
    propagate_version = true
)]
struct Cli {
    /// Without a subcommand: `volcast view --builtin helix`.
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Open the desktop viewer (the default without a subcommand).
    View(Box<ViewArgs>),
    /// Render a volume to a PNG file without a window.
    Render(Box<RenderArgs>),
    /// Print a volume's dimensions, type, spacing, value range, placement in space and memory needs.
    Info(Box<InfoArgs>),
    /// Render built-in viewpoints with both ray setups and measure how they differ and what each costs.
    Compare(Box<CompareArgs>),
    /// Time a fixed set of scenes and the raw 3D-texture sample rate (see README, Performance).
    Bench(Box<BenchArgs>),
    /// List the Vulkan devices and which one volcast would pick.
    Devices,
}

#[derive(Args, Clone)]
struct VolumeArgs {
    /// A volume file: raw, VTK (.vtk, .vti), NRRD (.nrrd/.nhdr), NIfTI-1 (.nii/.nii.gz), MetaImage (.mha/.mhd), DICOM
    /// (a folder of slices or one file). Raw files take dims and type from --dims/--type or a NAME_WxHxD_TYPE name.
    file: Option<PathBuf>,
    /// A built-in volume: helix, box, colormap or marschner-lobb.
    #[arg(long, conflicts_with = "file")]
    builtin: Option<String>,
    /// Edge length of the built-in volume (default 256; 41 for marschner-lobb).
    #[arg(long, requires = "builtin")]
    builtin_size: Option<u32>,
    /// Dimensions of a raw file: W H D.
    #[arg(long, num_args = 3, value_names = ["W", "H", "D"])]
    dims: Option<Vec<u32>>,
    /// Voxel type of a raw file: uint8, uint16, int16, float32, float64.
    #[arg(long = "type")]
    voxel_type: Option<String>,
    /// Voxel spacing: SX SY SZ (default: from the file's header; 1 1 1 for raw files). Overrides the header.
    #[arg(long, num_args = 3, value_names = ["SX", "SY", "SZ"])]
    spacing: Option<Vec<f32>>,
    /// Byte order of a raw file's voxels.
    #[arg(long, value_parser = ["little", "big"])]
    endian: Option<String>,
    /// Bytes to skip at the start of a raw file (a header volcast does not read).
    #[arg(long, value_name = "N")]
    header_bytes: Option<u64>,
    /// Largest dimension: a larger volume is downsampled 2x per axis until it fits (with a warning).
    #[arg(long, value_name = "N", default_value_t = 2048)]
    max_dim: u32,
    /// Refuse a volume larger than --max-dim instead of downsampling it.
    #[arg(long)]
    no_downsample: bool,
    /// The point array to load from a VTK file holding several (default: its active scalars, else the first
    /// one-component array); `volcast info` lists them.
    #[arg(long, value_name = "NAME")]
    array: Option<String>,
    /// The time step of a 4-D series to show, from 0 (default 0); the value range stays the whole series'.
    #[arg(long, value_name = "N")]
    time: Option<u32>,
}

impl VolumeArgs {
    /// These arguments with the volume of a view state where none is given here.
    fn or_from(&self, r: &volcast::view_state::VolumeRef) -> VolumeArgs {
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
        a
    }

    fn load(&self) -> Result<Volume> {
        if let Some(name) = &self.builtin {
            let mut v = volume::builtin(name, self.builtin_size)?;
            // --spacing overrides every volume's own, the built-ins' included.
            if let Some(s) = &self.spacing {
                v = v.with_spacing([s[0], s[1], s[2]])?;
            }
            if let Some(t) = self.time {
                v.show_step(t)?;
            }
            return Ok(v);
        }
        let Some(path) = &self.file else {
            bail!(
                "no volume given: pass a FILE or --builtin NAME ({})",
                volume::BUILTIN_NAMES.join(", ")
            );
        };
        let opts = volume::OpenOptions {
            raw: self.raw_options()?,
            endian: match self.endian.as_deref() {
                Some("big") => volume::Endian::Big,
                _ => volume::Endian::Little,
            },
            header_bytes: self.header_bytes.unwrap_or(0),
            max_dim: Some(self.max_dim),
            no_downsample: self.no_downsample,
            array: self.array.clone(),
        };
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
        let loaded = volume::open_with_progress(path, &opts, &mut |f| bar.set_position((f * 1000.0) as u64));
        bar.finish_and_clear();
        let mut v = loaded?;
        for note in &v.notes {
            eprintln!("note: {note}");
        }
        if let Some(t) = self.time {
            v.show_step(t)?;
        }
        Ok(v)
    }

    fn raw_options(&self) -> Result<RawOptions> {
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
struct InfoArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    /// Print one JSON object (format, dims, type, spacing, value_range, timesteps, affine_ras, axes,
    /// handedness, ...) instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Clone)]
struct GpuArgs {
    /// Run under the Khronos validation layer with synchronization validation (also VOLCAST_VALIDATION=1);
    /// exits non-zero if it reports an error.
    #[arg(long)]
    validate: bool,
    /// Device index or part of its name (see `volcast devices`).
    #[arg(long)]
    device: Option<String>,
    /// How volumes are stored on the GPU: auto (on CPU devices such as lavapipe the fastest layout within 1 GiB:
    /// corner textures for 8/16-bit data, else a float texture; the data's own format on GPUs), native (least
    /// memory), float (4 bytes per voxel) or corners (4 or 8 bytes per voxel for 8/16-bit data).
    #[arg(long, default_value = "auto", value_parser = ["auto", "native", "float", "corners"])]
    texture: String,
}

impl GpuArgs {
    fn options(&self) -> GpuOptions {
        let env = std::env::var("VOLCAST_VALIDATION").is_ok_and(|v| !v.is_empty() && v != "0");
        GpuOptions {
            validation: self.validate || env,
            device: self.device.clone(),
            texel_policy: match self.texture.as_str() {
                "native" => volcast::gpu::TexelPolicy::Native,
                "float" => volcast::gpu::TexelPolicy::Float,
                "corners" => volcast::gpu::TexelPolicy::Corners,
                _ => volcast::gpu::TexelPolicy::Auto,
            },
            ..Default::default()
        }
    }
}

#[derive(Args, Clone)]
struct RenderArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    #[command(flatten)]
    frame: FrameArgs,
    /// Output PNG.
    #[arg(short, long, default_value = "volcast.png")]
    output: PathBuf,
    /// Ray setup: faces (entry/exit textures), analytic (ray/box intersection) or compute (analytic, marched in a
    /// compute pass instead of a fragment pass).
    #[arg(long, default_value = "faces", value_parser = ["faces", "analytic", "compute"])]
    method: String,
    /// Print GPU time per pass (after a warm-up frame; lavapipe compiles shaders on first use).
    #[arg(long)]
    timings: bool,
    /// Print peak resident memory and the GPU memory allocated (volume, targets, buffers).
    #[arg(long)]
    memory: bool,
    /// Append a colour bar (the transfer function's colours and opacity over the window, ticks in data units) as
    /// a strip at the right: the image grows by its width.
    #[arg(long)]
    colorbar: bool,
    /// Frames to time with --timings (the median is reported; default 5); with --keyframes, the movie's frame
    /// count (2 to 3600).
    #[arg(long)]
    frames: Option<u32>,
    /// Render a view the viewer saved (F12's JSON beside its screenshot): its settings, and its volume unless a
    /// FILE or --builtin is given. The view options (camera, transfer function, mode, size, method) come from the
    /// file.
    #[arg(long, value_name = "FILE.json")]
    state: Option<PathBuf>,
    /// A turntable movie of N frames (1 to 3600) once around the vertical axis (+z through the point looked at),
    /// starting at the view given: `-o NAME.png` writes NAME-0000.png … and a looping NAME.gif (README, Movies).
    #[arg(long, value_name = "N", value_parser = parse_turntable, group = "movie", conflicts_with = "timings")]
    turntable: Option<u32>,
    /// A movie along a camera path through view states (F12's JSON), --frames N in all: the first frame is the
    /// first state, the last the last; the volume is the first state's. Written like --turntable.
    #[arg(long, num_args = 2.., value_name = "STATE.json", group = "movie", conflicts_with_all = ["state", "timings"])]
    keyframes: Vec<PathBuf>,
    /// Frames per second of a movie's GIF (0.1 to 50).
    #[arg(long, value_name = "F", default_value_t = volcast::movie::gif::DEFAULT_FPS, value_parser = parse_fps, requires = "movie")]
    fps: f32,
}

#[derive(Args, Clone)]
struct ViewArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    /// Initial window size WxH.
    #[arg(long, default_value = "1280x800", value_parser = parse_size)]
    size: (u32, u32),
    /// Sampling quality of still frames, as `render --quality`: draft, fast, normal or converged (moving frames
    /// use draft's step; the panel and the Q key change it).
    #[arg(long, default_value = "normal", value_parser = parse_quality)]
    quality: Quality,
    /// Drive the window with a script (for tests), e.g. "frames:3;resize:320x240;screenshot:a.png;exit".
    #[arg(long, hide = true)]
    script: Option<String>,
    /// Start with the three slice views beside the 3D view (four-up; L toggles it).
    #[arg(long)]
    slices: bool,
    /// Restore a session (Ctrl+S's or F12's JSON): its volume, unless a FILE or --builtin is given here, and its
    /// view (transfer function, camera, slabs, clip plane, mode, lighting, time step, slice views).
    #[arg(long, value_name = "FILE.json")]
    state: Option<PathBuf>,
}

#[derive(Args, Clone)]
struct BenchArgs {
    #[command(flatten)]
    gpu: GpuArgs,
    /// Timed frames per configuration (median, min and max are reported).
    #[arg(long, default_value_t = 10)]
    frames: u32,
    /// Untimed frames first (lavapipe compiles shaders on first use).
    #[arg(long, default_value_t = 2)]
    warmup: u32,
    /// Folder with the CT head and MRI brain raw files (scenes whose file is missing are skipped).
    #[arg(long, default_value = "../shared/data/raw")]
    data: PathBuf,
    /// make_volume.py's helix_256x256x256_uint8.raw for the vtk-helix scene (default: the same field generated).
    #[arg(long)]
    vtk_raw: Option<PathBuf>,
    /// Only these scenes (repeatable): helix, dense, ct-head, mri-brain, vtk-helix, quick-helix.
    #[arg(long = "scene")]
    scenes: Vec<String>,
    /// Only these image sizes (repeatable), e.g. --size 512.
    #[arg(long = "size")]
    sizes: Vec<u32>,
    /// Only these shading variants (repeatable): off, on, shadows (shading with shadows and ambient occlusion;
    /// the helix and CT head scenes).
    #[arg(long = "shading")]
    shadings: Vec<String>,
    /// Only these methods (repeatable): faces, analytic, compute (the analytic ray setup in a compute pass).
    #[arg(long = "method", value_parser = ["faces", "analytic", "compute"])]
    methods: Vec<String>,
    /// CI smoke mode: a 64³ helix at 64x64, all three methods, shading off and on, tiny sample-only run.
    #[arg(long)]
    quick: bool,
    /// Only the sample-only micro-benchmark (all three texel formats).
    #[arg(long)]
    sample_only: bool,
    /// Only time-series playback as the viewer plays it: 64 steps of 128³ float32 at 512² (with --quick 6 steps
    /// of 24³ at 64²); each step is uploaded and rendered, the two timed apart.
    #[arg(long, conflicts_with_all = ["sample_only", "scenes"])]
    playback: bool,
    /// Sampling quality of every scene, as `render --quality`: draft, fast, normal or converged.
    #[arg(long, default_value = "normal", value_parser = parse_quality)]
    quality: Quality,
    /// Where shaded scenes take gradients, as `render --gradients`: auto, texture or samples.
    #[arg(long, default_value = "auto", value_parser = parse_gradients)]
    gradients: Gradients,
    /// Force this step length (in voxels) on every scene instead of its quality's; each frame's error is still
    /// taken against the scene's converged image (1/8-voxel steps).
    #[arg(long)]
    step_length: Option<f32>,
    /// Print the results as JSON on stdout (progress still goes to stderr).
    #[arg(long)]
    json: bool,
}

#[derive(Args, Clone)]
struct CompareArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    #[command(flatten)]
    gpu: GpuArgs,
    #[command(flatten)]
    frame: FrameArgs,
    /// Folder for the images and the tables (created if missing).
    #[arg(long, default_value = "cmp")]
    out: PathBuf,
    /// Timed frames per method and view after a warm-up frame (medians are reported).
    #[arg(long, default_value_t = 3)]
    frames: u32,
}

/// What a frame shows: camera, transfer function, slicing. Shared by `render` and `compare`.
#[derive(Args, Clone)]
struct FrameArgs {
    /// Image size WxH.
    #[arg(long, default_value = "512x512", value_parser = parse_size)]
    size: (u32, u32),
    /// Camera azimuth in degrees (about +z, from +y) [default: 35, or 0 for an anatomical volume].
    #[arg(long, allow_negative_numbers = true, conflicts_with = "view")]
    azimuth: Option<f32>,
    /// Camera elevation in degrees [default: 25, or 0 for an anatomical volume].
    #[arg(long, allow_negative_numbers = true, conflicts_with = "view")]
    elevation: Option<f32>,
    /// Camera distance from the volume centre (the box's longest side is 1); default fits the volume.
    #[arg(long)]
    distance: Option<f32>,
    /// Camera position X,Y,Z (world units: RAS for anatomical volumes, centred, the box's longest side 1),
    /// looking at --look-at (default the centre).
    #[arg(long, value_parser = parse_vec3, conflicts_with_all = ["azimuth", "elevation", "distance", "view", "view_dir"], allow_hyphen_values = true)]
    eye: Option<Vec3>,
    /// The point the camera looks at, X,Y,Z in world units (default the volume's centre, 0,0,0); the orbit, --view
    /// and --view-dir cameras turn about it.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    look_at: Option<Vec3>,
    /// Look along direction X,Y,Z (world units) at --look-at from --distance (default: fitting the volume).
    #[arg(long, value_parser = parse_vec3, conflicts_with_all = ["azimuth", "elevation", "view"], allow_hyphen_values = true)]
    view_dir: Option<Vec3>,
    /// View from a side of the patient: anterior, posterior, left, right, superior or inferior (head up; from
    /// above and below anterior up). An anatomical volume is seen from anterior unless told otherwise.
    #[arg(long)]
    view: Option<String>,
    /// Render in voxel index space (the box along the world's axes, the file's orientation ignored).
    #[arg(long)]
    voxel_axes: bool,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = volcast::camera::DEFAULT_FOV_Y_DEG)]
    fov: f32,
    /// Colormap: cool-warm, plasma, viridis, rainbow, gnuplot, grayscale.
    #[arg(long, default_value = "cool-warm")]
    colormap: String,
    /// Visible value range TMIN,TMAX in [0,1] of the data's range; values outside are transparent
    /// (default 0.1,1; with a transfer function 0,1).
    #[arg(long, value_parser = parse_pair)]
    window: Option<(f32, f32)>,
    /// A transfer-function preset: ct-bone, ct-soft-tissue, ct-lung, mr-default, qt-example, or auto (by
    /// modality: CT gets ct-bone, anything else a grey ramp over its histogram's percentiles).
    #[arg(long, conflicts_with = "tf")]
    preset: Option<String>,
    /// A transfer function from a JSON file (see README).
    #[arg(long)]
    tf: Option<PathBuf>,
    /// Write the transfer function in use (preset or file) as JSON, to start your own from.
    #[arg(long)]
    save_tf: Option<PathBuf>,
    /// Compositing: emission, mip, minip, average, iso, density.
    #[arg(long, default_value = "emission")]
    mode: String,
    /// Iso value for --mode iso, in [0,1] of the data range.
    #[arg(long, default_value_t = 0.5)]
    iso: f32,
    /// The iso-surface's colour R,G,B in [0,1] (sRGB), or "colormap" for the colour the colormap or transfer
    /// function gives its value (default: a light neutral).
    #[arg(long, value_parser = parse_iso_color)]
    iso_color: Option<IsoColor>,
    /// The iso-surface's opacity in (0,1]: below 1 the surfaces behind show through.
    #[arg(long, default_value_t = 1.0)]
    iso_opacity: f32,
    /// A further iso-surface VALUE[,R,G,B][,OPACITY] or VALUE,colormap[,OPACITY] (repeatable, 4 surfaces in all);
    /// surfaces are composited in the order a ray meets them. E.g. translucent skin over bone:
    /// --mode iso --iso 0.45 --surface 0.2,0.9,0.6,0.5,0.3.
    #[arg(long = "surface", value_parser = parse_surface)]
    surfaces: Vec<volcast::lighting::IsoSurface>,
    /// The light: "head" (a headlight, the default) or the direction X,Y,Z towards a light fixed to the volume, in
    /// world coordinates (RAS for anatomical volumes). Turns shading on.
    #[arg(long, value_parser = parse_light, allow_hyphen_values = true)]
    light: Option<LightDirection>,
    /// The light's colour R,G,B in [0,1] (sRGB). Turns shading on.
    #[arg(long, value_parser = parse_vec3)]
    light_color: Option<Vec3>,
    /// The light's intensity (scales its diffuse and specular terms). Turns shading on.
    #[arg(long)]
    light_intensity: Option<f32>,
    /// Shadows: light attenuated through the volume on its way to each point (a light grid computed on the GPU;
    /// with a headlight, a key light up and left of the view casts them). Turns shading on; not in MIP, MinIP or
    /// average.
    #[arg(long)]
    shadows: bool,
    /// Ambient occlusion: the ambient light dimmed where the surroundings are dense. Turns shading on; not in MIP,
    /// MinIP or average.
    #[arg(long)]
    ambient_occlusion: bool,
    /// Density factor for --mode density (the OSG article's model).
    #[arg(long, default_value_t = 1.0)]
    density: f32,
    /// Gradient shading (Blinn-Phong; a headlight unless --light says otherwise).
    #[arg(long)]
    shading: bool,
    /// Shading coefficients AMBIENT,DIFFUSE,SPECULAR,SHININESS.
    #[arg(long, value_parser = parse_shading, default_value = "0.2,0.7,0.3,20")]
    lighting: volcast::settings::Shading,
    /// Scale opacity by gradient magnitude, full at this value change per voxel (e.g. 0.05).
    #[arg(long)]
    gradient_opacity: Option<f32>,
    /// Sample at step midpoints instead of a per-pixel jittered start.
    #[arg(long)]
    no_jitter: bool,
    /// Seed of the jitter pattern.
    #[arg(long, default_value_t = 0)]
    jitter_seed: u32,
    /// Orthographic projection (same framing at the target as the perspective view).
    #[arg(long)]
    ortho: bool,
    /// March every brick, also those empty-space skipping would leap over (for comparisons).
    #[arg(long)]
    no_skip: bool,
    /// Longest brick stride (1, 2 or 4): faint bricks take every second or fourth sample (emission and density;
    /// default: the quality's, 1 with --step-length).
    #[arg(long)]
    max_stride: Option<u32>,
    /// Where shaded frames take gradients: auto (the texture while it stays within 1 GiB), texture (precomputed
    /// central differences on the grid, 8 bytes per voxel, one fetch) or samples (six samples of the interpolant).
    #[arg(long, default_value = "auto", value_parser = parse_gradients)]
    gradients: Gradients,
    /// The same as --gradients texture.
    #[arg(long, conflicts_with = "gradients")]
    gradient_texture: bool,
    /// Opacity of one voxel-length step.
    #[arg(long, default_value_t = volcast::settings::DEFAULT_STEP_ALPHA)]
    step_alpha: f32,
    /// Sampling quality: draft, fast, normal or converged (base steps 2, 1, 0.4, 1/8 voxel, shortened where the
    /// transfer function is strong).
    #[arg(long, default_value = "normal", value_parser = parse_quality)]
    quality: Quality,
    /// Step length in voxels, overriding the quality's (opacity is corrected for it): every sample is taken.
    #[arg(long)]
    step_length: Option<f32>,
    /// Opacity = windowed value × step alpha.
    #[arg(long)]
    multiplied_alpha: bool,
    /// Stop a ray once its opacity reaches this.
    #[arg(long, default_value_t = volcast::settings::DEFAULT_EARLY_TERMINATION)]
    early_termination: f32,
    /// Background colour R,G,B in [0,1].
    #[arg(long, value_parser = parse_vec3, default_value = "0,0,0")]
    background: Vec3,
    /// Slab slicing AXIS:POSITION:WIDTH in [0,1], e.g. x:0.5:0.2 (repeatable, one per axis).
    #[arg(long = "slice", value_parser = parse_slice)]
    slices: Vec<(usize, f32, f32)>,
    /// Clipping plane NX,NY,NZ[,OFFSET]: keeps the points p (world mm: RAS for anatomical volumes) with
    /// (p − centre)·N ≥ OFFSET, centre the volume box's centre; N points into what stays (default offset 0).
    #[arg(long, value_name = "NX,NY,NZ[,OFFSET]", allow_hyphen_values = true, value_parser = parse_clip_plane)]
    clip_plane: Option<volcast::clip::ClipPlane>,
    /// Entry/exit position target format: rgba32f or rgba16f.
    #[arg(long, default_value = "rgba32f", value_parser = ["rgba32f", "rgba16f"])]
    positions: String,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size '{s}' must look like 512x512"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("size '{s}' must look like 512x512"))
    };
    Ok((p(w)?, p(h)?))
}

fn parse_floats(s: &str, n: usize, what: &str) -> Result<Vec<f32>, String> {
    let v: Result<Vec<f32>, _> = s.split(',').map(|x| x.trim().parse::<f32>()).collect();
    match v {
        Ok(v) if v.len() == n && v.iter().all(|x| x.is_finite()) => Ok(v),
        _ => Err(format!("'{s}' must be {n} comma-separated numbers ({what})")),
    }
}

fn parse_vec3(s: &str) -> Result<Vec3, String> {
    parse_floats(s, 3, "X,Y,Z").map(|v| Vec3::new(v[0], v[1], v[2]))
}

/// `--iso-color`: a colour or the classification's.
#[derive(Clone, Copy, Debug)]
enum IsoColor {
    Colormap,
    Rgb(Vec3),
}

fn parse_iso_color(s: &str) -> Result<IsoColor, String> {
    if s.trim().eq_ignore_ascii_case("colormap") {
        return Ok(IsoColor::Colormap);
    }
    parse_floats(s, 3, "R,G,B or colormap").map(|v| IsoColor::Rgb(Vec3::new(v[0], v[1], v[2])))
}

fn parse_surface(s: &str) -> Result<volcast::lighting::IsoSurface, String> {
    volcast::lighting::IsoSurface::parse(s)
}

/// `--light`: a headlight (None) or a direction towards the light.
#[derive(Clone, Copy, Debug)]
struct LightDirection(Option<Vec3>);

fn parse_light(s: &str) -> Result<LightDirection, String> {
    if s.trim().eq_ignore_ascii_case("head") {
        return Ok(LightDirection(None));
    }
    parse_vec3(s).map(|d| LightDirection(Some(d)))
}

fn parse_pair(s: &str) -> Result<(f32, f32), String> {
    parse_floats(s, 2, "TMIN,TMAX").map(|v| (v[0], v[1]))
}

fn parse_shading(s: &str) -> Result<volcast::settings::Shading, String> {
    let v = parse_floats(s, 4, "AMBIENT,DIFFUSE,SPECULAR,SHININESS")?;
    Ok(volcast::settings::Shading {
        ambient: v[0],
        diffuse: v[1],
        specular: v[2],
        shininess: v[3],
    })
}

fn parse_clip_plane(s: &str) -> Result<volcast::clip::ClipPlane, String> {
    volcast::clip::ClipPlane::parse(s).map_err(|e| e.to_string())
}

fn parse_slice(s: &str) -> Result<(usize, f32, f32), String> {
    let parts: Vec<&str> = s.split(':').collect();
    let bad = || format!("slice '{s}' must look like x:0.5:0.2 (axis x|y|z, position, width in [0,1])");
    if parts.len() != 3 {
        return Err(bad());
    }
    let axis = match parts[0].trim() {
        "x" | "X" => 0,
        "y" | "Y" => 1,
        "z" | "Z" => 2,
        _ => return Err(bad()),
    };
    let pos: f32 = parts[1].trim().parse().map_err(|_| bad())?;
    let width: f32 = parts[2].trim().parse().map_err(|_| bad())?;
    if !((0.0..=1.0).contains(&pos) && width > 0.0 && width <= 1.0) {
        return Err(bad());
    }
    Ok((axis, pos, width))
}

impl FrameArgs {
    fn settings(&self, volume: &Volume) -> Result<RenderSettings> {
        let extent = volume.extent();
        let mut s = RenderSettings::new(self.size.0, self.size.1, extent);
        s.voxel_axes = self.voxel_axes;
        let distance = self
            .distance
            .unwrap_or_else(|| Camera::fit_distance(extent.length() * 0.5, self.fov));
        let anatomical = volume.geometry.anatomical && !self.voxel_axes;
        let view = match &self.view {
            Some(name) => Some(ViewPreset::parse(name).with_context(|| {
                let names: Vec<&str> = ViewPreset::ALL.iter().map(|v| v.name()).collect();
                format!("unknown view '{name}'; choose one of {}", names.join(", "))
            })?),
            None if anatomical && self.azimuth.is_none() && self.elevation.is_none() => Some(ViewPreset::Anterior),
            None => None,
        };
        let target = self.look_at.unwrap_or(Vec3::ZERO);
        s.camera = match (self.eye, self.view_dir, view) {
            (Some(eye), _, _) => Camera::looking_at(eye, target),
            (None, Some(dir), _) => {
                if !(dir.is_finite() && dir.length() > 1e-6) {
                    bail!("--view-dir {dir} must be a non-zero direction");
                }
                Camera::looking_at(target - dir.normalize() * distance, target)
            }
            (None, None, Some(view)) => view.camera(distance, target),
            (None, None, None) => Camera::orbit(
                self.azimuth.unwrap_or(if anatomical { 0.0 } else { 35.0 }),
                self.elevation.unwrap_or(if anatomical { 0.0 } else { 25.0 }),
                distance,
                target,
            ),
        };
        s.camera.fov_y_deg = self.fov;
        s.colormap = Colormap::parse(&self.colormap).with_context(|| {
            let names: Vec<&str> = Colormap::ALL.iter().map(|c| c.name()).collect();
            format!(
                "unknown colormap '{}'; choose one of {}",
                self.colormap,
                names.join(", ")
            )
        })?;
        let tf = match (&self.preset, &self.tf) {
            (Some(name), _) if name == "auto" => Some(volcast::tf_auto::auto_for_volume(volume)),
            (Some(name), _) => Some(TransferFunction::preset(name)?),
            (None, Some(path)) => Some(TransferFunction::load(path)?),
            (None, None) => None,
        };
        if let (Some(path), Some(tf)) = (&self.save_tf, &tf) {
            std::fs::write(path, tf.to_json()).with_context(|| format!("writing {}", path.display()))?;
        }
        s.window = match (self.window, &tf) {
            (Some(w), _) => [w.0, w.1],
            (None, Some(_)) => [0.0, 1.0],
            (None, None) => volcast::settings::DEFAULT_WINDOW,
        };
        s.transfer_function = tf;
        s.mode = CompositeMode::parse(&self.mode).with_context(|| {
            let names: Vec<&str> = CompositeMode::ALL.iter().map(|m| m.name()).collect();
            format!("unknown mode '{}'; choose one of {}", self.mode, names.join(", "))
        })?;
        s.iso_value = self.iso;
        match self.iso_color {
            Some(IsoColor::Colormap) => s.iso_color = None,
            Some(IsoColor::Rgb(c)) => s.iso_color = Some(c),
            None => {}
        }
        s.iso_opacity = self.iso_opacity;
        s.extra_isosurfaces = self.surfaces.clone();
        s.density = self.density;
        let lit = self.light.is_some()
            || self.light_color.is_some()
            || self.light_intensity.is_some()
            || self.shadows
            || self.ambient_occlusion;
        s.shadows = self.shadows;
        s.ambient_occlusion = self.ambient_occlusion;
        if (s.shadows || s.ambient_occlusion) && s.mode.is_projection() {
            eprintln!(
                "note: {} is not lit: shadows and ambient occlusion do not apply",
                s.mode.name()
            );
        }
        s.shading = (self.shading || lit).then_some(self.lighting);
        s.light = volcast::lighting::Light {
            direction: self.light.and_then(|l| l.0),
            color: self.light_color.unwrap_or(Vec3::ONE),
            intensity: self.light_intensity.unwrap_or(1.0),
        };
        s.gradient_opacity = self.gradient_opacity;
        s.jitter = (!self.no_jitter).then_some(self.jitter_seed);
        s.camera.ortho = self.ortho;
        s.skip_empty = !self.no_skip;
        s.step_alpha = self.step_alpha;
        s.multiplied_alpha = self.multiplied_alpha;
        s.early_termination = self.early_termination;
        s.background = self.background;
        for &(axis, pos, width) in &self.slices {
            s.set_slab(axis, pos, width);
        }
        s.clip_plane = self.clip_plane;
        s.position_format = if self.positions == "rgba16f" {
            PositionFormat::Rgba16f
        } else {
            PositionFormat::Rgba32f
        };
        // The quality's step depends on the classification, so it is resolved last, from valid settings.
        s.validate().map_err(anyhow::Error::msg)?;
        self.quality.apply(&mut s, volume.range);
        if let Some(step) = self.step_length {
            s.step_length = step;
            s.max_stride = 1;
        }
        if let Some(stride) = self.max_stride {
            s.max_stride = stride;
        }
        let gradients = if self.gradient_texture {
            Gradients::Texture
        } else {
            self.gradients
        };
        gradients.apply(&mut s, volume.voxel_count() as u64);
        s.validate().map_err(anyhow::Error::msg)?;
        Ok(s)
    }
}

/// `parse(s)`, or an error listing the names of `all` (`what` says what the value is).
fn parse_named<T: Copy>(
    s: &str,
    parse: fn(&str) -> Option<T>,
    all: &[T],
    name: fn(T) -> &'static str,
    what: &str,
) -> Result<T, String> {
    parse(s).ok_or_else(|| {
        let names: Vec<&str> = all.iter().map(|&v| name(v)).collect();
        format!("unknown {what} '{s}'; choose one of {}", names.join(", "))
    })
}

/// `--turntable`'s frame count.
fn parse_turntable(s: &str) -> Result<u32, String> {
    let max = volcast::movie::MAX_FRAMES;
    match s.trim().parse::<u32>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!("a turntable has 1 to {max} frames")),
    }
}

/// `--fps`: a GIF's frame rate.
fn parse_fps(s: &str) -> Result<f32, String> {
    let fps = s
        .trim()
        .parse::<f32>()
        .map_err(|_| format!("'{s}' is not a number of frames per second"))?;
    volcast::movie::gif::check_fps(fps).map(|()| fps)
}

/// `--gradients`' value, for render and bench alike.
fn parse_gradients(s: &str) -> Result<Gradients, String> {
    parse_named(s, Gradients::parse, &Gradients::ALL, Gradients::name, "gradient source")
}

/// `--quality`'s value, for render, view and bench alike.
fn parse_quality(s: &str) -> Result<Quality, String> {
    parse_named(s, Quality::parse, &Quality::ALL, Quality::name, "quality")
}

/// Runs `body` with a GPU and reports validation messages at the end; any validation error or warning fails the
/// command.
fn with_gpu<T>(args: &GpuArgs, body: impl FnOnce(&Gpu) -> Result<T>) -> Result<T> {
    let gpu = Gpu::new(&args.options())?;
    let validating = gpu.validation_enabled();
    let log = gpu.log.clone();
    let result = body(&gpu);
    drop(gpu);
    if validating {
        let (errors, warnings) = (log.error_count(), log.warning_count());
        eprintln!("validation: {errors} errors, {warnings} warnings");
        if errors + warnings > 0 && result.is_ok() {
            bail!("the validation layer reported {errors} error(s) and {warnings} warning(s)");
        }
    }
    result
}

/// The exit status of a malformed command line.
const USAGE_EXIT: u8 = 64;

/// `e` and its causes, each cause added only where the text so far does not already say it (errors that embed
/// their source in their own message would otherwise print it twice: "…(os error 2): …(os error 2)").
fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let part = cause.to_string();
        if text.is_empty() {
            text = part;
        } else if !text.contains(&part) {
            text = format!("{text}: {part}");
        }
    }
    text
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// The volume and settings `render` shows: a saved view's, or the options'.
fn render_view(args: &RenderArgs) -> Result<(Volume, RenderSettings)> {
    let state = match &args.state {
        Some(path) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
            Some(
                volcast::view_state::ViewState::from_json(&text, &path.display().to_string())
                    .map_err(anyhow::Error::msg)?,
            )
        }
        None => None,
    };
    let volume = match &state {
        Some(st) => args.volume.or_from(&st.volume).load()?,
        None => args.volume.load()?,
    };
    let s = match state {
        // The saved view as it was (its method included).
        Some(st) => st.settings,
        None => {
            let mut s = args.frame.settings(&volume)?;
            s.ray_setup = if args.method == "faces" {
                RaySetup::Faces
            } else {
                RaySetup::Analytic
            };
            s.compute = args.method == "compute";
            s
        }
    };
    Ok((volume, s))
}

/// `render --turntable` and `render --keyframes`: the frames of `volcast::movie`, as PNGs and a GIF.
fn movie(args: &RenderArgs) -> Result<()> {
    use volcast::movie::{MovieError, MovieFiles, Plan};
    let (volume, plan) = if args.keyframes.is_empty() {
        let frames = args.turntable.unwrap_or(1);
        MovieFiles::new(&args.output, frames)?;
        let (volume, base) = render_view(args)?;
        (
            volume,
            Plan::Turntable {
                base: Box::new(base),
                frames,
            },
        )
    } else {
        let frames = args
            .frames
            .ok_or_else(|| MovieError::Usage("--keyframes needs --frames N, the movie's length in frames".into()))?;
        volcast::movie::check_frames(frames, 2, "--frames")?;
        MovieFiles::new(&args.output, frames)?;
        let states = volcast::movie::read_keyframes(&args.keyframes)?;
        let volume = args.volume.or_from(&states[0].volume).load()?;
        let keys = states.into_iter().map(|st| st.settings).collect();
        (volume, Plan::Keyframes { keys, frames })
    };
    let files = MovieFiles::new(&args.output, plan.frame_count())?;
    let label = if args.keyframes.is_empty() {
        "turntable"
    } else {
        "keyframes"
    };
    with_gpu(&args.gpu, |gpu| {
        let mut headless = Headless::new(gpu)?;
        let mut progress = volcast::movie::Progress::stderr(label, plan.frame_count());
        let done = volcast::movie::record(gpu, &mut headless, &volume, &plan, &files, args.fps, &mut |k| {
            progress.update(k)
        });
        headless.destroy(gpu);
        done?;
        println!("{}", files.summary(args.fps));
        Ok(())
    })
}

fn render(args: &RenderArgs) -> Result<()> {
    if args.turntable.is_some() || !args.keyframes.is_empty() {
        return movie(args);
    }
    volcast::image_out::check_name(&args.output).map_err(anyhow::Error::msg)?;
    let t_load = Instant::now();
    let (volume, s) = render_view(args)?;
    let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
    let t_device = Instant::now();
    with_gpu(&args.gpu, |gpu| {
        let mut headless = Headless::new(gpu)?;
        let device_ms = t_device.elapsed().as_secs_f64() * 1e3;
        let result = (|| -> Result<()> {
            let t_upload = Instant::now();
            headless.set_volume(gpu, &volume)?;
            if s.gradient_texture {
                headless.renderer.enable_gradient_texture(gpu, &volume)?;
            }
            let upload_ms = t_upload.elapsed().as_secs_f64() * 1e3;
            let t0 = Instant::now();
            let mut frame = headless.render(gpu, &s)?;
            let first_ms = t0.elapsed().as_secs_f64() * 1e3;
            let mut timing_line = String::new();
            if args.timings {
                let (mut wall, mut march, mut entry, mut exit, mut total) = (vec![], vec![], vec![], vec![], vec![]);
                for _ in 0..args.frames.unwrap_or(5).max(1) {
                    let t = Instant::now();
                    frame = headless.render(gpu, &s)?;
                    wall.push(t.elapsed().as_secs_f64() * 1e3);
                    if let Some(tm) = frame.timings {
                        march.push(tm.march_ms);
                        total.push(tm.total_ms);
                        entry.extend(tm.entry_ms);
                        exit.extend(tm.exit_ms);
                    }
                }
                timing_line = format!("median of {} frames: {:.2} ms wall", wall.len(), median(&mut wall));
                if !total.is_empty() {
                    timing_line += &format!("; GPU {:.2} ms total", median(&mut total));
                    if !entry.is_empty() {
                        timing_line += &format!(" = entry {:.2} + exit {:.2}", median(&mut entry), median(&mut exit));
                        timing_line += &format!(" + march {:.2}", median(&mut march));
                    } else {
                        timing_line += &format!(" (march {:.2})", median(&mut march));
                    }
                }
            }
            if args.colorbar {
                frame.image = with_colorbar(&frame.image, &s, &volume);
            }
            volcast::image_out::save(&frame.image, &args.output).map_err(anyhow::Error::msg)?;
            println!(
                "rendered {} ({}x{}x{} {}, spacing {}x{}x{}) at {}x{} with {} ray setup on {} -> {}",
                volume.name,
                volume.dims[0],
                volume.dims[1],
                volume.dims[2],
                volume.source_type,
                volume.spacing()[0],
                volume.spacing()[1],
                volume.spacing()[2],
                s.width,
                s.height,
                match (s.ray_setup, s.compute) {
                    (RaySetup::Faces, _) => "entry/exit faces",
                    (RaySetup::Analytic, false) => "analytic",
                    (RaySetup::Analytic, true) => "analytic (compute pass)",
                },
                gpu.device_name,
                args.output.display()
            );
            println!(
                "load {load_ms:.0} ms; device {device_ms:.0} ms; upload {upload_ms:.0} ms; first frame {first_ms:.0} \
                 ms (includes shader compilation on lavapipe)"
            );
            if !timing_line.is_empty() {
                println!("{timing_line}");
            }
            if let Some(ms) = headless.renderer.light_grid_ms() {
                println!("light grid (shadows, occlusion): {ms:.0} ms");
            }
            if args.memory {
                println!("{}", volcast::bench::memory_line(gpu, &headless, &s)?);
            }
            Ok(())
        })();
        headless.destroy(gpu);
        result
    })
}

/// `image` with the colour bar of `s`'s classification appended (unit "HU" for CT).
fn with_colorbar(image: &image::RgbaImage, s: &RenderSettings, volume: &Volume) -> image::RgbaImage {
    let classification = s.classification();
    let to_u8 = |c: f32| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
    let spec = volcast::colorbar::ColorbarSpec {
        classification: &classification,
        window: s.window,
        range: volume.range,
        unit: volcast::tf_auto::VolumeFacts::of(volume).kind().unit(),
        background: [to_u8(s.background.x), to_u8(s.background.y), to_u8(s.background.z)],
    };
    volcast::colorbar::append_colorbar(image, &spec)
}

fn view(args: &ViewArgs) -> Result<()> {
    let restore = match &args.state {
        Some(path) => Some(viewer::session::read(path).map_err(anyhow::Error::msg)?),
        None => None,
    };
    let from_session = restore.as_ref().and_then(|s| viewer::session::source_of(&s.volume));
    let source = match (&args.volume.builtin, &args.volume.file, from_session) {
        (Some(name), _, _) => VolumeSource::Builtin(name.clone(), args.volume.builtin_size),
        (None, Some(path), _) => VolumeSource::File(path.clone(), args.volume.raw_options()?),
        (None, None, Some(source)) => source,
        (None, None, None) => VolumeSource::Builtin("helix".into(), None),
    };
    let script = match &args.script {
        Some(s) => viewer::parse_script(s).map_err(anyhow::Error::msg)?,
        None => Vec::new(),
    };
    let opts = ViewerOptions {
        source,
        gpu: args.gpu.options(),
        size: args.size,
        script,
        time: args.volume.time.or(restore.as_ref().map(|s| s.volume.time)),
        quality: args.quality,
        slices: args.slices,
        restore,
    };
    let log = viewer::run(opts)?;
    if args.gpu.options().validation {
        let (errors, warnings) = (log.error_count(), log.warning_count());
        eprintln!("validation: {errors} errors, {warnings} warnings");
        if errors + warnings > 0 {
            bail!("the validation layer reported {errors} error(s) and {warnings} warning(s)");
        }
    }
    Ok(())
}

fn compare(args: &CompareArgs) -> Result<()> {
    let volume = args.volume.load()?;
    let base = args.frame.settings(&volume)?;
    let mut views = compare::builtin_views(&base, volume.extent());
    if args.frame.eye.is_some() {
        views.push(compare::View {
            name: "eye".into(),
            settings: base.clone(),
        });
    }
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    with_gpu(&args.gpu, |gpu| {
        let mut headless = Headless::new(gpu)?;
        let result = (|| -> Result<Vec<compare::Row>> {
            headless.set_volume(gpu, &volume)?;
            let mut rows = Vec::new();
            for view in &views {
                let c = compare::compare_view(gpu, &mut headless, view, args.frames)?;
                let diff = compare::amplified_diff(&c.faces.image, &c.analytic.image, 10);
                let save = |suffix: &str, img: &image::RgbaImage| -> Result<()> {
                    let path = args.out.join(format!("{}-{suffix}.png", view.name));
                    volcast::image_out::save(img, &path).map_err(anyhow::Error::msg)
                };
                save("faces", &c.faces.image)?;
                save("analytic", &c.analytic.image)?;
                save("diff", &diff)?;
                save(
                    "side-by-side",
                    &compare::side_by_side(&[&c.faces.image, &c.analytic.image, &diff]),
                )?;
                println!("{:>15}: {}", view.name, c.verdict());
                rows.push(compare::Row::from(&c));
            }
            Ok(rows)
        })();
        headless.destroy(gpu);
        let rows = result?;
        let table = compare::markdown_table(&rows);
        println!(
            "\n{} ({}x{}x{} {}) at {}x{} on {}; images are faces | analytic | difference x10\n\n{table}",
            volume.name,
            volume.dims[0],
            volume.dims[1],
            volume.dims[2],
            volume.source_type,
            base.width,
            base.height,
            gpu.device_name
        );
        std::fs::write(args.out.join("compare.md"), &table)?;
        std::fs::write(args.out.join("compare.json"), serde_json::to_string_pretty(&rows)?)?;
        println!(
            "wrote {}/compare.md, compare.json and 4 images per view",
            args.out.display()
        );
        let differing = rows.iter().filter(|r| !r.agree).count();
        if differing > 0 {
            println!("{differing} view(s) differ beyond the bound");
        }
        Ok(())
    })
}

fn bench(args: &BenchArgs) -> Result<()> {
    let opts = volcast::bench::BenchOptions {
        frames: if args.quick { args.frames.min(2) } else { args.frames },
        warmup: if args.quick { args.warmup.min(1) } else { args.warmup },
        data_dir: args.data.clone(),
        vtk_raw: args.vtk_raw.clone(),
        quick: args.quick,
        scenes: args.scenes.clone(),
        sizes: args.sizes.clone(),
        shadings: args.shadings.clone(),
        methods: args.methods.clone(),
        sample_only: args.sample_only,
        quality: args.quality,
        gradients: args.gradients,
        step_length: args.step_length,
    };
    if args.playback {
        let play = if args.quick {
            volcast::playback::PlaybackOptions::QUICK
        } else {
            volcast::playback::PlaybackOptions::FULL
        };
        return with_gpu(&args.gpu, |gpu| {
            let report = volcast::playback::run(gpu, &play, &mut |line| eprintln!("{line}"))?;
            if args.json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", report.text());
            }
            Ok(())
        });
    }
    with_gpu(&args.gpu, |gpu| {
        let report = volcast::bench::run(gpu, &opts, &mut |line| eprintln!("{line}"))?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&report)?);
        } else {
            print!("{}", report.text());
        }
        Ok(())
    })
}

fn info(args: &InfoArgs) -> Result<()> {
    let v = args.volume.load()?;
    let info = volcast::info::Info::of(&v);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&info)?);
    } else {
        print!("{}", info.text(&v));
    }
    Ok(())
}

fn devices() -> Result<()> {
    let list = volcast::gpu::list_devices()?;
    if list.is_empty() {
        return Err(GpuError::NoDevice("the Vulkan loader found no physical device".into()).into());
    }
    for d in &list {
        println!("{d}");
    }
    Ok(())
}

fn main() -> ExitCode {
    // Usage errors exit 64 (sysexits' EX_USAGE), not clap's 2: 2 says "no usable Vulkan".
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { USAGE_EXIT } else { 0 });
        }
    };
    let result = match &cli.command {
        None => view(&ViewArgs {
            volume: VolumeArgs {
                file: None,
                builtin: Some("helix".into()),
                builtin_size: None,
                dims: None,
                voxel_type: None,
                spacing: None,
                endian: None,
                header_bytes: None,
                max_dim: 2048,
                no_downsample: false,
                array: None,
                time: None,
            },
            gpu: GpuArgs {
                validate: false,
                device: None,
                texture: "auto".into(),
            },
            size: (1280, 800),
            quality: Quality::Normal,
            script: None,
            slices: false,
            state: None,
        }),
        Some(Command::View(a)) => view(a),
        Some(Command::Render(a)) => render(a),
        Some(Command::Compare(a)) => compare(a),
        Some(Command::Bench(a)) => bench(a),
        Some(Command::Info(a)) => info(a),
        Some(Command::Devices) => devices(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_text(&e));
            let unavailable = e.downcast_ref::<GpuError>().is_some_and(|g| g.is_unavailable())
                || e.downcast_ref::<ViewerError>().is_some_and(|v| match v {
                    ViewerError::NoDisplay(_) => true,
                    ViewerError::Gpu(g) => g.is_unavailable(),
                    ViewerError::Other(_) => false,
                });
            let usage = e
                .downcast_ref::<volcast::movie::MovieError>()
                .is_some_and(|m| matches!(m, volcast::movie::MovieError::Usage(_)));
            ExitCode::from(if unavailable {
                2
            } else if usage {
                USAGE_EXIT
            } else {
                1
            })
        }
    }
}
