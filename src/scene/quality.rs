//! Quality levels (`--quality`): how finely rays are sampled, as a step length chosen per frame from the transfer
//! function. Each level is an error target against the converged image ([`Quality::target`], measured by `bench`
//! on its scenes: docs/performance.md, Quality levels), met by a base step and a segment depth: emission and density
//! frames shorten the base step where the classification is strong, so that no pre-integrated segment carries more
//! than the level's [`Quality::segment_depth`] of optical depth (0.25 for `normal`: about 22% opacity) — unless
//! that would take the step below a quarter of the base. A segment that opaque hides where inside it a surface
//! lies, and the image moves with the sample grid; fainter segments average that out.
//!
//! Within that step, faint bricks take longer strides (rule 2 of `RenderSettings`: segments of at most
//! `STRIDE_DEPTH` times the level's tolerance). The level resolves to an ordinary `RenderSettings::step_length`,
//! `max_stride` and `stride_tolerance` before a frame is rendered, so the GPU and the CPU reference render the same
//! rule. Measured errors against the converged image per level and scene are in docs/performance.md (Quality
//! levels).

use crate::scene::settings::{CompositeMode, RenderSettings};
use crate::transfer::function::{bake, LUT_SIZE};
use crate::transfer::preintegrate::extinction;

/// The converged image's step, in voxels: `converged` quality, and what fidelity measures against.
pub const CONVERGED_STEP: f32 = 0.125;

/// Optical depth one segment of `normal` may carry at most (where the step may still shrink): e^−0.25 ≈ 78%
/// transmitted.
pub const SEGMENT_DEPTH: f64 = 0.25;

/// How far below its base step a level may go for a strong transfer function.
pub const MIN_SCALE: f64 = 0.25;

/// The sharpest classification whose `draft` frames space their rays ([`opacity_edge`]). Measured on the bench
/// scenes at 512² (docs/performance.md, Quality levels): spaced, the helix (an edge of 0.1 at its window) errs
/// 7.0 / 86 and the CT head (0.6) 6.7 / 59, past `draft`'s target, while `vtk-helix` (0.003) errs 0.90 / 3 and
/// `dense` (0) 0.80 / 8; the MRI brain (0.05) stays within it (3.0 / 8), too close to count on.
pub const SOFT_EDGE: f32 = 0.02;

/// How sharp the edges a classification draws can be: the largest change of its opacity (per voxel-length step)
/// across 1/64 of the value range, nothing showing outside the window (so a window edge with values beyond it
/// counts as a jump to its opacity there).
pub fn opacity_edge(s: &RenderSettings, range: [f64; 2]) -> f32 {
    let lut = bake(&s.classification(), s.colour.window, range);
    let last = (LUT_SIZE - 1) as f32;
    let alpha = |i: usize| {
        let shown = (s.colour.window[0]..=s.colour.window[1]).contains(&(i as f32 / last));
        if shown {
            lut[i][3]
        } else {
            0.0
        }
    };
    let span = LUT_SIZE / 64;
    (0..LUT_SIZE - span)
        .map(|i| (alpha(i + span) - alpha(i)).abs())
        .fold(0.0, f32::max)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quality {
    /// Base step 3 voxels, segments up to depth 0.75, strides at 4× rule 2's tolerance: for interaction, about the error of VTK's fixed-point caster at
    /// its default 1-voxel step (mean 3.5/255 on `vtk-helix`).
    Draft,
    /// Base step 1 voxel (volcast's default before quality levels; VTK's default sample distance), segments up to
    /// depth 0.5.
    Fast,
    /// Base step 0.4 voxel, the default: "visually converged", within mean 0.5/255 and p99 4/255 of the
    /// converged image on the test and bench scenes docs/performance.md lists (errors fall with the square of the step:
    /// at 1 voxel the small test volumes are 1–1.5/255 off on average).
    #[default]
    Normal,
    /// 1/8-voxel steps, no adaptive rule: the image every other level is measured against.
    Converged,
}

impl Quality {
    pub const ALL: [Quality; 4] = [Quality::Draft, Quality::Fast, Quality::Normal, Quality::Converged];

    pub fn name(self) -> &'static str {
        match self {
            Quality::Draft => "draft",
            Quality::Fast => "fast",
            Quality::Normal => "normal",
            Quality::Converged => "converged",
        }
    }

    pub fn parse(s: &str) -> Option<Quality> {
        Quality::ALL
            .into_iter()
            .find(|q| q.name() == s.trim().to_ascii_lowercase())
    }

    /// The error the level is made to stay within against the converged image, mean and p99 in 1/255 over object
    /// pixels, on the bench scenes (docs/performance.md lists each scene's; `normal`'s is held by
    /// tests/gpu/quality.rs on the test scenes): `normal` visually converged, `draft` about VTK's fixed-point
    /// caster's at its 1-voxel default on `vtk-helix` (3.47 / 9), `fast` between them.
    pub const fn target(self) -> (f64, f64) {
        match self {
            Quality::Draft => (3.5, 20.0),
            Quality::Fast => (1.5, 10.0),
            Quality::Normal => (0.5, 4.0),
            Quality::Converged => (0.0, 0.0),
        }
    }

    /// The most optical depth one pre-integrated segment of this level may carry before the step shrinks: the error
    /// of a segment grows with its depth (docs/performance.md, Quality levels).
    pub fn segment_depth(self) -> f64 {
        match self {
            Quality::Draft => 3.0 * SEGMENT_DEPTH,
            Quality::Fast => 2.0 * SEGMENT_DEPTH,
            Quality::Normal | Quality::Converged => SEGMENT_DEPTH,
        }
    }

    /// The level's step in voxels before the transfer function is looked at.
    pub fn base_step(self) -> f32 {
        match self {
            Quality::Draft => 3.0,
            Quality::Fast => 1.0,
            Quality::Normal => 0.4,
            Quality::Converged => CONVERGED_STEP,
        }
    }

    /// The step length (voxels) for frame `s` on data of value range `range`: the base step, shortened for
    /// emission and density frames to [`segment_depth`](Self::segment_depth)` / σ_max` (σ_max: the largest
    /// extinction per voxel the classification gives inside the window, `preintegrate::extinction`), but not below
    /// `MIN_SCALE` of the base.
    /// `Converged` is always 1/8 voxel.
    pub fn step_length(self, s: &RenderSettings, range: [f64; 2]) -> f32 {
        let base = self.base_step();
        let absorbing = matches!(s.compositing.mode, CompositeMode::Emission | CompositeMode::Density);
        // (An invalid window is refused by `RenderSettings::validate`; it must not get as far as the table.)
        let window_ok = s.colour.window[0] < s.colour.window[1];
        if self == Quality::Converged || !absorbing || !window_ok {
            return base;
        }
        let density = (s.compositing.mode == CompositeMode::Density).then_some(f64::from(s.compositing.density));
        let lut = bake(&s.classification(), s.colour.window, range);
        let last = (LUT_SIZE - 1) as f32;
        let sigma_max = lut
            .iter()
            .enumerate()
            .filter(|(i, _)| (s.colour.window[0]..=s.colour.window[1]).contains(&(*i as f32 / last)))
            .map(|(_, e)| extinction(f64::from(e[3]), density))
            .fold(0.0f64, f64::max);
        let (depth, bound) = (sigma_max * f64::from(base), self.segment_depth());
        if depth <= bound {
            return base;
        }
        (f64::from(base) * (bound / depth).max(MIN_SCALE)) as f32
    }

    /// The longest brick stride (rule 2 of `RenderSettings`) the level allows: faint bricks take every second
    /// or fourth sample, so the step is fine only where the classification is strong.
    pub fn max_stride(self) -> u32 {
        match self {
            Quality::Draft | Quality::Fast => 2,
            Quality::Normal => 4,
            Quality::Converged => 1,
        }
    }

    /// How far rule 2's stride bounds are loosened for this level (`RenderSettings::stride_tolerance`): faint bricks
    /// of `draft` and `fast` stride over segments four and two times deeper than `normal`'s.
    pub fn stride_tolerance(self) -> f32 {
        match self {
            Quality::Draft => 4.0,
            Quality::Fast => 2.0,
            Quality::Normal | Quality::Converged => 1.0,
        }
    }

    /// One ray per this many pixels along each axis (rule 12 of `RenderSettings`): `draft` marches a quarter of
    /// the rays and stretches them over the image where its classification draws no sharp edge (emission or
    /// density, no gradient opacity, [`opacity_edge`] at most [`SOFT_EDGE`]), which keeps it within its target
    /// (docs/performance.md, Quality levels); the others, and `draft` elsewhere, take every pixel.
    pub fn ray_spacing(self, s: &RenderSettings, range: [f64; 2]) -> u32 {
        let absorbing = matches!(s.compositing.mode, CompositeMode::Emission | CompositeMode::Density);
        let soft = || {
            absorbing
                && s.lighting.gradient_opacity.is_none()
                && s.colour.window[0] < s.colour.window[1]
                && opacity_edge(s, range) <= SOFT_EDGE
        };
        if self == Quality::Draft && soft() {
            2
        } else {
            1
        }
    }

    /// Applies the level to `s` (data of value range `range`): its step length, brick strides and ray spacing.
    pub fn apply(self, s: &mut RenderSettings, range: [f64; 2]) {
        s.sampling.step_length = self.step_length(s, range);
        s.sampling.max_stride = self.max_stride();
        s.sampling.stride_tolerance = self.stride_tolerance();
        s.sampling.ray_spacing = self.ray_spacing(s, range);
    }
}

/// The moving view's frame, one rule for the viewer's level of detail while the view moves and for `bench --scale`'s
/// drag: the still frame `still` at `1/divisor` of its size on each side (rounded up; upscaled where it is shown),
/// the draft quality's step (at least the still frame's; with a custom step, `quality` None, twice it) and at least
/// its brick strides. The divisor already spaces the rays, so rule 12's spacing is 1.
pub fn moving_view(still: &RenderSettings, divisor: u32, quality: Option<Quality>, range: [f64; 2]) -> RenderSettings {
    let mut s = still.clone();
    s.width = still.width.div_ceil(divisor).max(1);
    s.height = still.height.div_ceil(divisor).max(1);
    s.sampling.step_length = match quality {
        Some(_) => s.sampling.step_length.max(Quality::Draft.step_length(&s, range)),
        None => (s.sampling.step_length * 2.0).min(64.0),
    };
    s.sampling.max_stride = s.sampling.max_stride.max(Quality::Draft.max_stride());
    s.sampling.stride_tolerance = s.sampling.stride_tolerance.max(Quality::Draft.stride_tolerance());
    s.sampling.ray_spacing = 1;
    s
}

/// Where shaded and gradient-modulated frames take their gradients (`--gradients`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Gradients {
    /// The texture when it stays within [`GRADIENT_LIMIT`], else the samples.
    #[default]
    Auto,
    /// A precomputed gradient texture (the grid's gradients, Sobel for float data and a Gaussian derivative for
    /// integer data: `render::gradients`; RGBA16 SNORM, 8 bytes per voxel), one filtered fetch per gradient.
    /// Measured on lavapipe: shaded frames about 1.5× faster (docs/performance.md, Quality levels).
    Texture,
    /// Six samples of the interpolant per gradient (the rule the converged image follows).
    Samples,
}

/// The most memory `Gradients::Auto` spends on a gradient texture.
pub const GRADIENT_LIMIT: u64 = 1 << 30;

impl Gradients {
    pub const ALL: [Gradients; 3] = [Gradients::Auto, Gradients::Texture, Gradients::Samples];

    pub fn name(self) -> &'static str {
        match self {
            Gradients::Auto => "auto",
            Gradients::Texture => "texture",
            Gradients::Samples => "samples",
        }
    }

    pub fn parse(s: &str) -> Option<Gradients> {
        Gradients::ALL
            .into_iter()
            .find(|g| g.name() == s.trim().to_ascii_lowercase())
    }

    /// The gradient texture's size for a volume of `voxels` (8 bytes per voxel).
    pub fn texture_bytes(voxels: u64) -> u64 {
        voxels.saturating_mul(8)
    }

    /// Whether `Auto` takes the texture for a volume of `voxels`: it stays within [`GRADIENT_LIMIT`].
    pub fn texture_fits(voxels: u64) -> bool {
        Gradients::texture_bytes(voxels) <= GRADIENT_LIMIT
    }

    /// Sets `s.gradient_texture` for a volume of `voxels`: only frames that read gradients (iso-surfaces, and
    /// emission or density with shading or gradient opacity) take the texture, so no other frame pays for making it.
    pub fn apply(self, s: &mut RenderSettings, voxels: u64) {
        let reads = s.compositing.mode == CompositeMode::Isosurface
            || (matches!(s.compositing.mode, CompositeMode::Emission | CompositeMode::Density)
                && (s.lighting.shading.is_some() || s.lighting.gradient_opacity.is_some()));
        s.lighting.gradient_texture = reads
            && match self {
                Gradients::Auto => Gradients::texture_fits(voxels),
                Gradients::Texture => true,
                Gradients::Samples => false,
            };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn draft_spaces_its_rays_only_where_the_classification_draws_no_sharp_edge() {
        let range = [0.0, 1.0];
        // The helix's default: opacity 0.1 from the window's lower edge, values below it: a sharp edge.
        let mut s = RenderSettings::new(8, 8, Vec3::ONE);
        assert!((opacity_edge(&s, range) - 0.1).abs() < 1e-6);
        assert_eq!(Quality::Draft.ray_spacing(&s, range), 1);
        // vtk-helix's ramp from 0 at the window's edge: soft.
        s.colour.multiplied_alpha = true;
        s.colour.step_alpha = 0.2;
        s.colour.window = [0.08, 1.0];
        assert!(opacity_edge(&s, range) < 0.004, "{}", opacity_edge(&s, range));
        assert_eq!(Quality::Draft.ray_spacing(&s, range), 2);
        for q in [Quality::Fast, Quality::Normal, Quality::Converged] {
            assert_eq!(q.ray_spacing(&s, range), 1, "{q:?}");
        }
        // A window from 0 has no values below it: no edge there.
        s.colour.multiplied_alpha = false;
        s.colour.step_alpha = 0.02;
        s.colour.window = [0.0, 1.0];
        assert_eq!(opacity_edge(&s, range), 0.0);
        assert_eq!(Quality::Draft.ray_spacing(&s, range), 2);
        // Surfaces and maxima draw sharp edges whatever the table.
        s.compositing.mode = CompositeMode::Mip;
        assert_eq!(Quality::Draft.ray_spacing(&s, range), 1);
    }

    #[test]
    fn faint_classifications_keep_the_base_step_strong_ones_shorten_it() {
        let mut s = RenderSettings::new(8, 8, Vec3::ONE);
        s.colour.step_alpha = 0.1;
        assert_eq!(Quality::Normal.step_length(&s, [0.0, 1.0]), 0.4);
        assert_eq!(Quality::Draft.step_length(&s, [0.0, 1.0]), 3.0);
        // Opacity 0.6 per voxel: extinction 0.916, so 0.5 / 0.916 of a voxel for fast, 0.25 / 0.916 for normal.
        s.colour.step_alpha = 0.6;
        let sigma = -(0.4f64).ln();
        let step = Quality::Fast.step_length(&s, [0.0, 1.0]);
        assert!((step - (0.5 / sigma) as f32).abs() < 1e-5, "{step}");
        let normal = Quality::Normal.step_length(&s, [0.0, 1.0]);
        assert!((normal - (SEGMENT_DEPTH / sigma) as f32).abs() < 1e-5, "{normal}");
        let draft = Quality::Draft.step_length(&s, [0.0, 1.0]);
        assert!((draft - (0.75 / sigma) as f32).abs() < 1e-5, "{draft}");
        // Opacity 1: not below a quarter of the base.
        s.colour.step_alpha = 1.0;
        assert_eq!(Quality::Fast.step_length(&s, [0.0, 1.0]), 0.25);
        assert_eq!(Quality::Converged.step_length(&s, [0.0, 1.0]), CONVERGED_STEP);
        // Projections keep the base step.
        s.compositing.mode = CompositeMode::Mip;
        assert_eq!(Quality::Fast.step_length(&s, [0.0, 1.0]), 1.0);
    }

    #[test]
    fn gradients_go_to_the_texture_only_for_frames_that_read_them_and_fit() {
        let mut s = RenderSettings::new(8, 8, Vec3::ONE);
        let n256 = 256u64 * 256 * 256;
        Gradients::Auto.apply(&mut s, n256);
        assert!(!s.lighting.gradient_texture, "an unshaded frame reads no gradient");
        s.lighting.shading = Some(crate::scene::settings::Shading::default());
        Gradients::Auto.apply(&mut s, n256);
        assert!(s.lighting.gradient_texture);
        Gradients::Auto.apply(&mut s, 1024 * 1024 * 512);
        assert!(!s.lighting.gradient_texture, "4 GiB of gradients is over the limit");
        Gradients::Texture.apply(&mut s, 1024 * 1024 * 512);
        assert!(s.lighting.gradient_texture);
        Gradients::Samples.apply(&mut s, 8);
        assert!(!s.lighting.gradient_texture);
        s.compositing.mode = CompositeMode::Mip;
        Gradients::Texture.apply(&mut s, 8);
        assert!(!s.lighting.gradient_texture, "MIP reads no gradient");
        s.compositing.mode = CompositeMode::Emission;
        s.lighting.shading = None;
        s.lighting.gradient_opacity = Some(0.1);
        Gradients::Auto.apply(&mut s, 8);
        assert!(s.lighting.gradient_texture, "gradient opacity reads one");
        for g in Gradients::ALL {
            assert_eq!(Gradients::parse(g.name()), Some(g));
        }
    }

    #[test]
    fn names_round_trip() {
        for q in Quality::ALL {
            assert_eq!(Quality::parse(q.name()), Some(q));
        }
        assert_eq!(Quality::parse("best"), None);
    }
}
