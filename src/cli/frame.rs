//! `FrameArgs`: the options that say what a frame shows (camera, transfer function, compositing, lighting,
//! sampling, slicing), and which of them a command line gave. Shared by `render` and `compare`; how they become
//! `RenderSettings` is in `settings.rs`.

use super::parse::{
    parse_clip_plane, parse_colormap, parse_data_value, parse_gradients, parse_iso_color, parse_light, parse_mode,
    parse_preset, parse_quality, parse_shading, parse_size, parse_slice, parse_surface, parse_vec3, parse_view,
    parse_window, IsoColor, LightDirection,
};
use crate::scene::camera::ViewPreset;
use crate::scene::quality::{Gradients, Quality};
use crate::scene::settings::CompositeMode;
use crate::scene::values::DataValue;
use crate::transfer::Colormap;
use clap::parser::ValueSource;
use clap::{ArgMatches, Args};
use glam::Vec3;
use std::collections::BTreeSet;
use std::path::PathBuf;

/// What a frame shows, by the groups its options travel in. Shared by `render` and `compare`.
#[derive(Args, Clone)]
pub struct FrameArgs {
    #[command(flatten)]
    pub output: OutputArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub colour: ColourArgs,
    #[command(flatten)]
    pub compositing: CompositingArgs,
    #[command(flatten)]
    pub lighting: LightingArgs,
    #[command(flatten)]
    pub sampling: SamplingArgs,
    #[command(flatten)]
    pub cut: CutArgs,
    /// Which of these options the command line gave (the rest are defaults): see [`Given`].
    #[arg(skip)]
    pub given: Given,
}

/// The image: its size and what shows where no ray adds anything.
#[derive(Args, Clone)]
#[command(next_help_heading = "Output")]
pub struct OutputArgs {
    /// Image size WxH.
    #[arg(long, default_value = "512x512", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Background colour R,G,B in [0,1].
    #[arg(long, value_parser = parse_vec3, default_value = "0,0,0", hide_short_help = true)]
    pub background: Vec3,
}

/// Where the camera is, where it looks and how it projects; the box's placement (`--voxel-axes`).
#[derive(Args, Clone)]
#[command(next_help_heading = "View")]
pub struct CameraArgs {
    /// Camera azimuth in degrees (about +z, from +y) [default: 35, or 0 for an anatomical volume].
    #[arg(long, allow_negative_numbers = true, conflicts_with = "view")]
    pub azimuth: Option<f32>,
    /// Camera elevation in degrees [default: 25, or 0 for an anatomical volume].
    #[arg(long, allow_negative_numbers = true, conflicts_with = "view")]
    pub elevation: Option<f32>,
    /// Camera distance from the volume centre (the box's longest side is 1); default fits the volume.
    #[arg(long, hide_short_help = true)]
    pub distance: Option<f32>,
    /// Camera position X,Y,Z (world units: RAS for anatomical volumes, centred, the box's longest side 1),
    /// looking at --look-at (default the centre).
    #[arg(long, value_parser = parse_vec3, conflicts_with_all = ["azimuth", "elevation", "distance", "view", "view_dir"], allow_hyphen_values = true, hide_short_help = true)]
    pub eye: Option<Vec3>,
    /// The point the camera looks at, X,Y,Z in world units (default the volume's centre, 0,0,0); the orbit, --view
    /// and --view-dir cameras turn about it.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, hide_short_help = true)]
    pub look_at: Option<Vec3>,
    /// Look along direction X,Y,Z (world units) at --look-at from --distance (default: fitting the volume).
    #[arg(long, value_parser = parse_vec3, conflicts_with_all = ["azimuth", "elevation", "view"], allow_hyphen_values = true, hide_short_help = true)]
    pub view_dir: Option<Vec3>,
    /// View from a side of the patient: anterior, posterior, left, right, superior, inferior
    ///
    /// Head up; from above and below, anterior up. An anatomical volume is seen from anterior unless told
    /// otherwise.
    #[arg(long, value_parser = parse_view)]
    pub view: Option<ViewPreset>,
    /// Render in voxel index space (the box along the world's axes, the file's orientation ignored).
    #[arg(long, hide_short_help = true)]
    pub voxel_axes: bool,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = crate::scene::camera::DEFAULT_FOV_Y_DEG, hide_short_help = true)]
    pub fov: f32,
    /// Orthographic projection (same framing at the target as the perspective view).
    #[arg(long, hide_short_help = true)]
    pub ortho: bool,
}

/// The classification: the colormap model or a transfer function, and the value window.
#[derive(Args, Clone)]
#[command(next_help_heading = "Colour")]
pub struct ColourArgs {
    /// The colormap model's colormap: cool-warm, plasma, viridis, rainbow, gnuplot, grayscale
    ///
    /// Default: a file gets the automatic transfer function (--preset auto) unless --colormap, --step-alpha or
    /// --multiplied-alpha is given; a built-in volume gets cool-warm.
    #[arg(long, default_value = "cool-warm", hide_default_value = true, value_parser = parse_colormap)]
    pub colormap: Colormap,
    /// Visible values LO,HI in the data's units (HU for a CT), or percentages of its range (10%,100%)
    ///
    /// Values outside are transparent. Default: the whole range with a transfer function (a file's automatic one
    /// included), else 10%,100%.
    #[arg(long, value_name = "LO,HI", value_parser = parse_window, allow_hyphen_values = true)]
    pub window: Option<(DataValue, DataValue)>,
    /// A transfer-function preset, or auto (by modality)
    ///
    /// ct-bone, ct-soft-tissue, ct-lung, mr-default, qt-example, or auto (by modality: CT gets ct-bone, anything
    /// else a grey ramp over its histogram's percentiles). A file is shown with auto unless --preset, --tf,
    /// --colormap, --step-alpha or --multiplied-alpha says otherwise; a built-in volume with the colormap.
    #[arg(long, conflicts_with = "tf", value_parser = parse_preset)]
    pub preset: Option<String>,
    /// A transfer function from a JSON file (docs/rendering.md, The JSON format).
    #[arg(long)]
    pub tf: Option<PathBuf>,
    /// Write the transfer function in use (preset or file) as JSON, to start your own from.
    #[arg(long, hide_short_help = true)]
    pub save_tf: Option<PathBuf>,
    /// The colormap model's opacity of one voxel-length step.
    #[arg(long, default_value_t = crate::scene::settings::DEFAULT_STEP_ALPHA)]
    pub step_alpha: f32,
    /// The colormap model: opacity = windowed value × step alpha.
    #[arg(long, hide_short_help = true)]
    pub multiplied_alpha: bool,
    /// A transfer function given as a value instead of a file (the Python module's `tf=TransferFunction`); it
    /// counts as `--tf` (given has "tf").
    #[arg(skip)]
    pub tf_value: Option<crate::transfer::function::TransferFunction>,
}

/// How samples combine into a pixel: the mode, its iso-surfaces and density, and when a ray stops.
#[derive(Args, Clone)]
#[command(next_help_heading = "Compositing")]
pub struct CompositingArgs {
    /// Compositing: emission, mip, minip, average, iso, density.
    #[arg(long, default_value = "emission", value_parser = parse_mode)]
    pub mode: CompositeMode,
    /// Iso value for --mode iso, in the data's units or a percentage of its range (default 50%).
    #[arg(long, default_value = "50%", value_parser = parse_data_value, allow_hyphen_values = true)]
    pub iso: DataValue,
    /// The iso-surface's colour R,G,B in [0,1] (sRGB), or "colormap" for the colour the colormap or transfer
    /// function gives its value (default: a light neutral).
    #[arg(long, value_parser = parse_iso_color, hide_short_help = true)]
    pub iso_color: Option<IsoColor>,
    /// The iso-surface's opacity in (0,1]: below 1 the surfaces behind show through.
    #[arg(long, default_value_t = 1.0, hide_short_help = true)]
    pub iso_opacity: f32,
    /// A further iso-surface VALUE[,R,G,B][,OPACITY] or VALUE,colormap[,OPACITY] (repeatable, 4 surfaces in all);
    /// surfaces are composited in the order a ray meets them. E.g. translucent skin over bone:
    /// --mode iso --iso 45% --surface 20%,0.9,0.6,0.5,0.3 (VALUE as --iso takes it).
    #[arg(long = "surface", value_parser = parse_surface, allow_hyphen_values = true, hide_short_help = true)]
    pub surfaces: Vec<(DataValue, crate::scene::lighting::IsoSurface)>,
    /// Density factor for --mode density (the OSG article's model).
    #[arg(long, default_value_t = 1.0, hide_short_help = true)]
    pub density: f32,
    /// Stop a ray once its opacity reaches this.
    #[arg(long, default_value_t = crate::scene::settings::DEFAULT_EARLY_TERMINATION, hide_short_help = true)]
    pub early_termination: f32,
}

/// Shading, the light, shadows and ambient occlusion, and what the gradient does to a frame.
#[derive(Args, Clone)]
#[command(next_help_heading = "Lighting")]
pub struct LightingArgs {
    /// The light: "head" (the default), or the direction X,Y,Z towards it
    ///
    /// A headlight, or a light fixed to the volume in world coordinates (RAS for anatomical volumes). Turns
    /// shading on.
    #[arg(long, value_parser = parse_light, allow_hyphen_values = true)]
    pub light: Option<LightDirection>,
    /// The light's colour R,G,B in [0,1] (sRGB). Turns shading on.
    #[arg(long, value_parser = parse_vec3, hide_short_help = true)]
    pub light_color: Option<Vec3>,
    /// The light's intensity (scales its diffuse and specular terms). Turns shading on.
    #[arg(long, hide_short_help = true)]
    pub light_intensity: Option<f32>,
    /// Shadows cast through the volume (turns shading on)
    ///
    /// Light attenuated through the volume on its way to each point (a light grid computed on the GPU; with a
    /// headlight, a key light up and left of the view casts them). Not in MIP, MinIP or average.
    #[arg(long)]
    pub shadows: bool,
    /// Ambient occlusion (turns shading on)
    ///
    /// The ambient light dimmed where the surroundings are dense. Not in MIP, MinIP or average.
    #[arg(long)]
    pub ambient_occlusion: bool,
    /// Gradient shading (Blinn-Phong; a headlight unless --light says otherwise).
    #[arg(long)]
    pub shading: bool,
    /// Shading coefficients AMBIENT,DIFFUSE,SPECULAR,SHININESS.
    #[arg(long, value_parser = parse_shading, default_value = "0.2,0.7,0.3,20", hide_short_help = true)]
    pub lighting: crate::scene::settings::Shading,
    /// Scale opacity by gradient magnitude, full at this value change per voxel (e.g. 0.05).
    #[arg(long, hide_short_help = true)]
    pub gradient_opacity: Option<f32>,
    /// Fade lighting to flat light where the gradient is below this fraction of the window per voxel (e.g. 0.05):
    /// flat, noisy regions then show no speckled highlights (docs/rendering.md, Lighting).
    #[arg(long, hide_short_help = true)]
    pub shading_fade: Option<f32>,
}

/// How finely rays are sampled: the quality level or its overrides, jitter, skipping, gradients and the position
/// targets' precision.
#[derive(Args, Clone)]
#[command(next_help_heading = "Quality")]
pub struct SamplingArgs {
    /// Sampling quality: draft, fast, normal or converged
    ///
    /// Base steps 2, 1, 0.4 and 1/8 voxel, shortened where the transfer function is strong; draft also casts one
    /// ray per 2×2 pixels.
    #[arg(long, default_value = "normal", value_parser = parse_quality)]
    pub quality: Quality,
    /// Step length in voxels, overriding the quality's
    ///
    /// Opacity is corrected for it, and every sample is taken.
    #[arg(long, hide_short_help = true)]
    pub step_length: Option<f32>,
    /// Longest brick stride (1, 2 or 4): faint bricks take every second or fourth sample (emission and density;
    /// default: the quality's, 1 with --step-length).
    #[arg(long, hide_short_help = true)]
    pub max_stride: Option<u32>,
    /// One ray per N×N pixels (1, 2 or 4), stretched bilinearly over the image: about N² times faster on a CPU
    /// device, softer edges (default: the quality's, 2 for draft; VTK's ImageSampleDistance).
    #[arg(long, hide_short_help = true)]
    pub ray_spacing: Option<u32>,
    /// March every brick, also those empty-space skipping would leap over (for comparisons).
    #[arg(long, hide_short_help = true)]
    pub no_skip: bool,
    /// Sample at step midpoints instead of a per-pixel jittered start.
    #[arg(long, hide_short_help = true)]
    pub no_jitter: bool,
    /// Seed of the jitter pattern.
    #[arg(long, default_value_t = 0, hide_short_help = true)]
    pub jitter_seed: u32,
    /// Where shaded frames take gradients: auto (the texture while it stays within 1 GiB), texture (gradients
    /// precomputed on the grid, smoothed for integer data; 8 bytes per voxel, one fetch) or samples (six samples of
    /// the interpolant).
    #[arg(long, default_value = "auto", value_parser = parse_gradients, hide_short_help = true)]
    pub gradients: Gradients,
    /// The same as --gradients texture.
    #[arg(long, conflicts_with = "gradients", hide_short_help = true)]
    pub gradient_texture: bool,
    /// Entry/exit position target format: rgba32f or rgba16f.
    #[arg(long, default_value = "rgba32f", value_parser = ["rgba32f", "rgba16f"], hide_short_help = true)]
    pub positions: String,
}

/// What is cut away: slabs along the axes and a clipping plane.
#[derive(Args, Clone)]
#[command(next_help_heading = "Cut")]
pub struct CutArgs {
    /// Slab slicing AXIS:POSITION:WIDTH in [0,1], e.g. x:0.5:0.2 (repeatable, one per axis).
    #[arg(long = "slice", value_parser = parse_slice)]
    pub slices: Vec<(usize, f32, f32)>,
    /// A clipping plane: keeps the side its normal N points to
    ///
    /// Keeps the points p (world mm: RAS for anatomical volumes) with (p − centre)·N ≥ OFFSET, centre the volume
    /// box's centre; N points into what stays (default offset 0).
    #[arg(long, value_name = "NX,NY,NZ[,OFFSET]", allow_hyphen_values = true, value_parser = parse_clip_plane)]
    pub clip_plane: Option<crate::scene::clip::ClipPlane>,
}

/// The options a command line gave, by clap id (the field's name), and whether the volume is a file. `render
/// --state` applies only these over the saved view; a file without a classification option gets the automatic
/// transfer function.
#[derive(Clone, Debug, Default)]
pub struct Given {
    ids: BTreeSet<String>,
    pub from_file: bool,
}

impl Given {
    /// The options given on the command line of `matches` (not defaults, not the environment).
    pub fn from_matches(matches: &ArgMatches) -> Given {
        let ids = matches
            .ids()
            .filter(|id| matches.value_source(id.as_str()) == Some(ValueSource::CommandLine))
            .map(|id| id.as_str().to_string())
            .collect();
        Given { ids, from_file: false }
    }

    /// Marks option `id` as given (an option given other than on a command line).
    pub fn insert(&mut self, id: &str) {
        self.ids.insert(id.to_string());
    }

    pub fn has(&self, id: &str) -> bool {
        self.ids.contains(id)
    }

    pub fn any(&self, ids: &[&str]) -> bool {
        ids.iter().any(|id| self.has(id))
    }

    #[cfg(test)]
    pub fn for_test(ids: &[&str], from_file: bool) -> Given {
        Given {
            ids: ids.iter().map(|s| s.to_string()).collect(),
            from_file,
        }
    }
}
