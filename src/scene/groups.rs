//! The parts of [`RenderSettings`](crate::scene::settings::RenderSettings), grouped as they travel: what a value
//! looks like (colour), how samples combine (compositing), light, how densely a ray samples (sampling), what is
//! cut away (cut) and which GPU path draws it (pipeline). The CLI's flag groups (`cli/frame.rs`) and the viewer's
//! panels each edit one of them. Each part checks its own values; a session file keeps them flat (serde's
//! `flatten`), so files saved before the split load unchanged.

use crate::scene::clip::ClipPlane;
use crate::scene::lighting::{IsoSurface, Light, MAX_ISOSURFACES, NEUTRAL};
use crate::transfer::function::TransferFunction;
use crate::transfer::Colormap;
use glam::Vec3;

/// The strides rule 2 allows.
pub const STRIDES: [u32; 3] = [1, 2, 4];

pub const DEFAULT_STEP_ALPHA: f32 = 0.1;
pub const DEFAULT_WINDOW: [f32; 2] = [0.1, 1.0];
pub const DEFAULT_EARLY_TERMINATION: f32 = 0.99;

/// How each pixel's ray segment through the box is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RaySetup {
    /// The XNA article's method: front faces into an entry-position target, back faces into an exit-position
    /// target, then a march pass reads both.
    #[default]
    Faces,
    /// Analytic ray/box intersection in the march pass's fragment shader.
    Analytic,
}

/// Format of the entry/exit position targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PositionFormat {
    /// 16 bytes/pixel/target. Exact to float precision: the default, so the image matches the reference.
    #[default]
    Rgba32f,
    /// 8 bytes/pixel/target. 11-bit mantissa: positions near 1.0 are quantised to 1/2048 of the box.
    Rgba16f,
}

/// How samples along a ray combine into a pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CompositeMode {
    /// Emission–absorption, front to back (the default).
    #[default]
    Emission,
    /// Maximum intensity projection.
    Mip,
    /// Minimum intensity projection.
    MinIp,
    /// Mean of the visible samples.
    Average,
    /// First crossing of `iso_value`, refined by bisection and shaded.
    Isosurface,
    /// The OSG article's density-factor model: opacity `a × density × step`, linear (not exponential).
    Density,
}

impl CompositeMode {
    pub const ALL: [CompositeMode; 6] = [
        CompositeMode::Emission,
        CompositeMode::Mip,
        CompositeMode::MinIp,
        CompositeMode::Average,
        CompositeMode::Isosurface,
        CompositeMode::Density,
    ];

    pub fn name(self) -> &'static str {
        match self {
            CompositeMode::Emission => "emission",
            CompositeMode::Mip => "mip",
            CompositeMode::MinIp => "minip",
            CompositeMode::Average => "average",
            CompositeMode::Isosurface => "iso",
            CompositeMode::Density => "density",
        }
    }

    pub fn parse(s: &str) -> Option<CompositeMode> {
        CompositeMode::ALL
            .into_iter()
            .find(|m| m.name() == s.trim().to_ascii_lowercase())
    }

    /// MIP, MinIP and average: projections of values, never lit (no shading, shadows or occlusion).
    pub fn is_projection(self) -> bool {
        matches!(self, CompositeMode::Mip | CompositeMode::MinIp | CompositeMode::Average)
    }

    /// The index the shader switches on (`frame.mode.x`).
    pub fn index(self) -> u32 {
        CompositeMode::ALL.iter().position(|m| *m == self).unwrap_or(0) as u32
    }
}

/// Blinn–Phong with a headlight.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Shading {
    pub ambient: f32,
    pub diffuse: f32,
    pub specular: f32,
    pub shininess: f32,
}

impl Default for Shading {
    /// VTK's defaults as used by ../shared/tools/vtk_bench.py.
    fn default() -> Shading {
        Shading {
            ambient: 0.2,
            diffuse: 0.7,
            specular: 0.3,
            shininess: 20.0,
        }
    }
}

/// Rule 3's window and rule 4's classification: what colour and opacity a value gets.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Colour {
    /// The simple (Qt) model's colormap, used when `transfer_function` is None.
    pub colormap: Colormap,
    /// Visible value range in normalised units [0,1] (`window[0] < window[1]`).
    pub window: [f32; 2],
    /// The simple model's opacity of one voxel-length step.
    pub step_alpha: f32,
    /// The simple model: opacity = windowed value × step alpha.
    pub multiplied_alpha: bool,
    /// A transfer function replaces the simple model when given.
    pub transfer_function: Option<TransferFunction>,
}

impl Default for Colour {
    fn default() -> Colour {
        Colour {
            colormap: Colormap::CoolWarm,
            window: DEFAULT_WINDOW,
            step_alpha: DEFAULT_STEP_ALPHA,
            multiplied_alpha: false,
            transfer_function: None,
        }
    }
}

impl Colour {
    pub fn validate(&self) -> Result<(), String> {
        let [lo, hi] = self.window;
        if !(0.0..=1.0).contains(&lo) || !(0.0..=1.0).contains(&hi) || lo >= hi {
            return Err(format!("value window {lo},{hi} must satisfy 0 <= TMIN < TMAX <= 1"));
        }
        if !(0.0..=1.0).contains(&self.step_alpha) {
            return Err(format!("step alpha {} must be in [0,1]", self.step_alpha));
        }
        if let Some(tf) = &self.transfer_function {
            tf.validate().map_err(|e| e.to_string())?;
        }
        Ok(())
    }
}

/// Rules 6 and 7: how samples combine into a pixel, with the iso-surfaces and the density factor.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Compositing {
    pub mode: CompositeMode,
    /// Normalised iso value of the isosurface mode's first surface (`--iso`, the viewer's slider).
    pub iso_value: f32,
    /// The first surface's material: sRGB, or `None` for the classification's colour at the value.
    pub iso_color: Option<Vec3>,
    /// The first surface's opacity in (0,1].
    pub iso_opacity: f32,
    /// Further surfaces (at most `MAX_ISOSURFACES` in all): `RenderSettings::isosurfaces` is the whole list.
    pub extra_isosurfaces: Vec<IsoSurface>,
    /// Density factor of the density mode.
    pub density: f32,
    pub early_termination: f32,
}

impl Default for Compositing {
    fn default() -> Compositing {
        Compositing {
            mode: CompositeMode::Emission,
            iso_value: 0.5,
            iso_color: Some(NEUTRAL),
            iso_opacity: 1.0,
            extra_isosurfaces: Vec::new(),
            density: 1.0,
            early_termination: DEFAULT_EARLY_TERMINATION,
        }
    }
}

impl Compositing {
    /// Rule 7's iso-surfaces: the first (`iso_value`, `iso_color`, `iso_opacity`) and the extra ones, by value.
    pub fn isosurfaces(&self) -> Vec<IsoSurface> {
        let first = IsoSurface {
            value: self.iso_value,
            color: self.iso_color,
            opacity: self.iso_opacity,
        };
        crate::scene::lighting::sorted(&[&[first][..], &self.extra_isosurfaces].concat())
    }

    pub fn validate(&self) -> Result<(), String> {
        // Above 0: with 0, "stop after the first visible sample" would hinge on whether it is transparent.
        if !(self.early_termination > 0.0 && self.early_termination <= 1.0) {
            return Err(format!(
                "early termination opacity {} must be in (0,1]",
                self.early_termination
            ));
        }
        if self.extra_isosurfaces.len() + 1 > MAX_ISOSURFACES {
            return Err(format!("at most {MAX_ISOSURFACES} iso-surfaces at once"));
        }
        for surface in self.isosurfaces() {
            surface.validate()?;
        }
        if !(self.density.is_finite() && self.density >= 0.0) {
            return Err(format!("density factor {} must be a non-negative number", self.density));
        }
        Ok(())
    }
}

/// Rules 5 and 9: shading, its light, gradients, shadows and occlusion.
#[derive(Clone, Debug, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Lighting {
    /// Rule 5's light.
    pub light: Light,
    /// Rule 9's shadows: light attenuated on its way through the volume (lit frames; not MIP/MinIP/average).
    pub shadows: bool,
    /// Rule 9's ambient occlusion: the ambient term scaled by how open each point's surroundings are.
    pub ambient_occlusion: bool,
    pub shading: Option<Shading>,
    /// Gradient-magnitude-modulated opacity: full opacity from this gradient (value per voxel) up.
    pub gradient_opacity: Option<f32>,
    /// Rule 5's shading fade (`--shading-fade`): volume lighting reaches full strength where the gradient is this
    /// fraction of the window's width per voxel, and fades to flat light below (0: off).
    pub shading_fade: f32,
    /// Shade from a precomputed gradient texture (one sample instead of six; 8 bytes per voxel): rule 5's filtered
    /// grid gradients, smoothed for integer data. `Gradients::Auto` takes it for every frame that reads gradients
    /// while it stays within 1 GiB.
    pub gradient_texture: bool,
}

impl Lighting {
    pub fn validate(&self) -> Result<(), String> {
        self.light.validate()?;
        if !(self.shading_fade.is_finite() && self.shading_fade >= 0.0) {
            return Err(format!("shading fade {} must be 0 or more", self.shading_fade));
        }
        if let Some(r) = self.gradient_opacity {
            if !(r.is_finite() && r > 0.0) {
                return Err(format!("gradient opacity reference {r} must be positive"));
            }
        }
        if let Some(sh) = &self.shading {
            let ok = [sh.ambient, sh.diffuse, sh.specular]
                .iter()
                .all(|v| (0.0..=4.0).contains(v))
                && (1.0..=1000.0).contains(&sh.shininess);
            if !ok {
                return Err("shading: ambient, diffuse and specular must be in [0,4], shininess in [1,1000]".into());
            }
        }
        Ok(())
    }
}

/// Rules 2 and 12: where a ray takes its samples, which it may leap over, and how many rays a frame casts.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Sampling {
    /// Step length in voxels (of the smallest voxel side).
    pub step_length: f32,
    /// Jittered ray start with this seed (stable per seed); None: samples at the step midpoints.
    pub jitter: Option<u32>,
    /// Leap over 8³ bricks that hold nothing visible. Changes which samples are taken, not the image.
    pub skip_empty: bool,
    /// Rule 2's brick strides: the longest stride (1, 2 or 4 steps) a brick of faint opacity may take. 1 takes
    /// every sample; the quality levels set it (`Quality::apply`).
    pub max_stride: u32,
    /// Rule 2's tolerance: the stride bounds `D` and `STRIDE_SPREAD` are multiplied by it (1: as rule 2 states
    /// them). The quality levels set it from their error target (`Quality::apply`).
    pub stride_tolerance: f32,
    /// Rule 12's ray spacing: one ray per `ray_spacing`² output pixels (1, 2 or 4). The quality levels set it
    /// (`draft` 2, as VTK's `ImageSampleDistance` while interacting; `Quality::apply`).
    pub ray_spacing: u32,
}

impl Default for Sampling {
    fn default() -> Sampling {
        Sampling {
            step_length: 1.0,
            jitter: Some(0),
            skip_empty: true,
            max_stride: 1,
            stride_tolerance: 1.0,
            ray_spacing: 1,
        }
    }
}

impl Sampling {
    pub fn validate(&self) -> Result<(), String> {
        if !(0.05..=64.0).contains(&self.step_length) {
            return Err(format!("step length {} voxels must be in [0.05, 64]", self.step_length));
        }
        if !(self.stride_tolerance.is_finite() && self.stride_tolerance > 0.0) {
            return Err(format!("stride tolerance {} must be above 0", self.stride_tolerance));
        }
        if !STRIDES.contains(&self.ray_spacing) {
            return Err(format!("ray spacing {} must be 1, 2 or 4", self.ray_spacing));
        }
        if !STRIDES.contains(&self.max_stride) {
            return Err(format!("max stride {} must be 1, 2 or 4", self.max_stride));
        }
        Ok(())
    }
}

/// Rules 1 and 10: the slab box and the clipping plane.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Cut {
    /// Slab box in texture space; [0,0,0]..[1,1,1] shows everything.
    pub slab_lo: Vec3,
    pub slab_hi: Vec3,
    /// Rule 10's clipping plane (None: keep everything).
    pub clip_plane: Option<ClipPlane>,
}

impl Default for Cut {
    fn default() -> Cut {
        Cut {
            slab_lo: Vec3::ZERO,
            slab_hi: Vec3::ONE,
            clip_plane: None,
        }
    }
}

impl Cut {
    /// Sets the slab along `axis` (0 = x) to `position ± width / 2`, clamped to [0,1].
    pub fn set_slab(&mut self, axis: usize, position: f32, width: f32) {
        self.slab_lo[axis] = (position - width * 0.5).clamp(0.0, 1.0);
        self.slab_hi[axis] = (position + width * 0.5).clamp(0.0, 1.0);
    }

    pub fn validate(&self) -> Result<(), String> {
        for a in 0..3 {
            if self.slab_lo[a] >= self.slab_hi[a] {
                return Err(format!(
                    "slab along {} is empty ({}..{})",
                    ["x", "y", "z"][a],
                    self.slab_lo[a],
                    self.slab_hi[a]
                ));
            }
        }
        Ok(())
    }
}

/// Which GPU path draws the frame: the same rules either way, except `count_samples`, which draws counts.
#[derive(Clone, Debug, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct Pipeline {
    pub ray_setup: RaySetup,
    pub position_format: PositionFormat,
    /// March in a compute pass instead of a fullscreen fragment pass (analytic ray setup only; the output image
    /// must allow storage). The same rays and rules: a measured alternative for lavapipe (docs/performance.md).
    pub compute: bool,
    /// Output, instead of each pixel's colour, the number of sample positions its ray visited (rule 2's samples
    /// actually taken: those that empty-space skipping leaps over, gradient and bisection samples not counted),
    /// as a 24-bit integer in the R, G, B bytes. For tests and measurement; see
    /// [`decode_sample_count`](crate::scene::settings::decode_sample_count).
    pub count_samples: bool,
}

impl Pipeline {
    pub fn validate(&self) -> Result<(), String> {
        if self.compute && self.ray_setup != RaySetup::Analytic {
            return Err("the compute march uses the analytic ray setup (--method compute)".into());
        }
        Ok(())
    }
}
