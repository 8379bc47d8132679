//! What a frame shows: the plain parameters the CLI (and later the viewer) edits and the renderer reads.
//! Pure data; the rules that turn it into pixels are written out once, in [`RenderSettings`]'s docs, and
//! implemented twice: by the GPU passes (`shaders/`) and by the independent CPU reference (`tests/common`).

use crate::camera::Camera;
use crate::transfer::Colormap;
use glam::Vec3;

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

/// Everything that decides a frame's pixels.
///
/// The rendering rules (the GPU and the CPU reference both follow exactly these):
/// 1. **Ray.** Pixel (x, y), row 0 at the top, shoots a ray from the camera's eye through its centre
///    (x + 0.5, y + 0.5). The segment used is the part of that ray inside the *slab box* (texture-space box
///    `[slab_lo, slab_hi]` ⊆ [0,1]³ of the volume) and beyond the camera's near plane. No segment: background.
/// 2. **Samples.** With world-space segment length `L` and step `h = step_length × voxel` (`voxel` = the
///    smallest voxel side in world units), samples lie at `t = (k + 0.5)·h`, k = 0, 1, … while `t < L`.
/// 3. **Value.** Trilinear interpolation (texel centres at (i + 0.5)/dim, clamped to the edge) of the voxel values
///    normalised by the data range: `v = (raw - min) / (max - min)`. NaN is transparent.
/// 4. **Window.** Samples with `v < window[0]` or `v > window[1]` are transparent; otherwise
///    `c = (v - window[0]) / (window[1] - window[0])`.
/// 5. **Colour.** The colormap's 256-entry RGBA8 table is interpolated linearly at index `c × 255`.
/// 6. **Opacity.** `α = step_alpha`, or `c × step_alpha` with `multiplied_alpha`. `step_alpha` is the opacity of one
///    voxel-length step; opacity correction for the actual step: `α' = 1 - (1 - α)^step_length`.
/// 7. **Compositing**, front to back: `C += (1 - A)·α'·rgb`, `A += (1 - A)·α'`; stop once `A ≥ early_termination`.
/// 8. **Output**: `C + (1 - A)·background`, opaque, stored as 8-bit unsigned normalised (rounded).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub camera: Camera,
    pub colormap: Colormap,
    /// Visible value range in normalised units [0,1] (`window[0] < window[1]`).
    pub window: [f32; 2],
    pub step_alpha: f32,
    /// Step length in voxels (of the smallest voxel side).
    pub step_length: f32,
    pub multiplied_alpha: bool,
    pub early_termination: f32,
    /// Linear RGB in [0,1].
    pub background: Vec3,
    /// Slab box in texture space; [0,0,0]..[1,1,1] shows everything.
    pub slab_lo: Vec3,
    pub slab_hi: Vec3,
    pub ray_setup: RaySetup,
    pub position_format: PositionFormat,
}

pub const DEFAULT_STEP_ALPHA: f32 = 0.1;
pub const DEFAULT_WINDOW: [f32; 2] = [0.1, 1.0];
pub const DEFAULT_EARLY_TERMINATION: f32 = 0.99;

impl RenderSettings {
    /// Defaults for a volume with box `extent`: the camera orbits at azimuth 35°, elevation 25° and fits the box.
    pub fn new(width: u32, height: u32, extent: Vec3) -> RenderSettings {
        let radius = extent.length() * 0.5;
        let distance = Camera::fit_distance(radius, crate::camera::DEFAULT_FOV_Y_DEG);
        RenderSettings {
            width,
            height,
            camera: Camera::orbit(35.0, 25.0, distance, Vec3::ZERO),
            colormap: Colormap::CoolWarm,
            window: DEFAULT_WINDOW,
            step_alpha: DEFAULT_STEP_ALPHA,
            step_length: 1.0,
            multiplied_alpha: false,
            early_termination: DEFAULT_EARLY_TERMINATION,
            background: Vec3::ZERO,
            slab_lo: Vec3::ZERO,
            slab_hi: Vec3::ONE,
            ray_setup: RaySetup::Faces,
            position_format: PositionFormat::Rgba32f,
        }
    }

    /// Sets the slab along `axis` (0 = x) to `position ± width / 2`, clamped to [0,1].
    pub fn set_slab(&mut self, axis: usize, position: f32, width: f32) {
        self.slab_lo[axis] = (position - width * 0.5).clamp(0.0, 1.0);
        self.slab_hi[axis] = (position + width * 0.5).clamp(0.0, 1.0);
    }

    /// Checks the values a user can set; the message names the offending setting.
    pub fn validate(&self) -> Result<(), String> {
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            return Err(format!(
                "image size {}x{} must be between 1 and 16384 on each side",
                self.width, self.height
            ));
        }
        let [lo, hi] = self.window;
        if !(0.0..=1.0).contains(&lo) || !(0.0..=1.0).contains(&hi) || lo >= hi {
            return Err(format!("value window {lo},{hi} must satisfy 0 <= TMIN < TMAX <= 1"));
        }
        if !(0.0..=1.0).contains(&self.step_alpha) {
            return Err(format!("step alpha {} must be in [0,1]", self.step_alpha));
        }
        if !(0.05..=64.0).contains(&self.step_length) {
            return Err(format!("step length {} voxels must be in [0.05, 64]", self.step_length));
        }
        if !(0.0..=1.0).contains(&self.early_termination) {
            return Err(format!(
                "early termination opacity {} must be in [0,1]",
                self.early_termination
            ));
        }
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
        let c = &self.camera;
        if !(c.eye - c.target).length().is_normal() || !(1.0..=170.0).contains(&c.fov_y_deg) {
            return Err("camera eye must differ from its target and the field of view be in 1..170 degrees".into());
        }
        Ok(())
    }

    /// World-space step length for a box `extent` sampled by `dims` voxels.
    pub fn step_world(&self, extent: Vec3, dims: [u32; 3]) -> f32 {
        self.step_length * voxel_size(extent, dims)
    }
}

/// The smallest voxel side in world units.
pub fn voxel_size(extent: Vec3, dims: [u32; 3]) -> f32 {
    (0..3).map(|i| extent[i] / dims[i] as f32).fold(f32::INFINITY, f32::min)
}
