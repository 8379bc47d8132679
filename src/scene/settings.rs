//! What a frame shows: the plain parameters the CLI (and later the viewer) edits and the renderer reads.
//! Pure data; the rules that turn it into pixels are written out once, in [`RenderSettings`]'s docs, and
//! implemented twice: by the GPU passes (`shaders/`) and by the independent CPU reference (`tests/common`).

use crate::scene::camera::{Camera, ViewPreset};
pub use crate::scene::groups::{
    Colour, CompositeMode, Compositing, Cut, Lighting, Pipeline, PositionFormat, RaySetup, Sampling, Shading,
    DEFAULT_EARLY_TERMINATION, DEFAULT_STEP_ALPHA, DEFAULT_WINDOW, STRIDES,
};
use crate::scene::layers::LayerStyle;
use crate::scene::lighting::IsoSurface;
use crate::transfer::function::Classification;
use crate::volume::Volume;
use glam::Vec3;

/// Rule 2's most optical depth one strided segment may carry (e^−0.05 ≈ 95% transmitted): strides lengthen
/// segments only where the classification is faint.
pub const STRIDE_DEPTH: f64 = 0.05;

/// [`STRIDE_DEPTH`] for frames that read gradients (shading, gradient opacity): the lit colour varies along a
/// segment where the opacity does not, so a strided segment's error is first-order in its opacity (one normal
/// for the whole segment). Measured: the shaded MRI bench scene erred 1.09/255 on average with strides at 0.05
/// (0.46 without); Marschner–Lobb under a faint flat table (0.012 depth per step), lit, erred p99 5/255, max 10
/// against every step at 0.025 (stride 2), beyond the strides bound (p99 4). Half that keeps such segments at
/// stride 1; docs/rendering.md, Sampling, skipping and strides, states the rule.
pub const STRIDE_DEPTH_LIT: f64 = 0.0125;

/// Rule 2's most optical depth by which a strided segment may vary between the brick's faintest and strongest
/// values: a stride may leap over a feature of the data (an edge, a thin peak) that finer steps would resolve,
/// and the depth it misses must stay small (1%: about 2.5/255 of colour).
pub const STRIDE_SPREAD: f64 = 0.01;

/// Rule 9's key light, used for shadows under a headlight: towards the eye, offset this much (per unit of the
/// view vector) up and to the left: about 40° off the view axis.
pub const KEY_LIGHT_OFFSET: f32 = 0.6;

/// Everything that decides a frame's pixels.
///
/// The rendering rules (the GPU and the CPU reference both follow exactly these):
/// 0. **Placement.** The volume's texture-space box [0,1]³ (voxel centres at (i + 0.5)/dim) is placed in the world
///    by its voxel-to-world affine (RAS+ millimetres; with `voxel_axes`, along the world's axes by the voxel
///    sizes alone), then moved so the box's centre is the origin and scaled so its longest side is 1. Lengths,
///    steps and directions below are in this world.
/// 1. **Ray.** Pixel (x, y), row 0 at the top, at its centre (x + 0.5, y + 0.5), ndc = 2·centre/size − 1.
///    Perspective: from the eye through the pixel. Orthographic (`camera.ortho`): parallel to the view direction,
///    starting on the plane through the eye perpendicular to it, the view `2·d·tan(fov/2)` high (d = |eye −
///    target|). The segment used is the part inside the *slab box* (texture-space `[slab_lo, slab_hi]` ⊆ [0,1]³)
///    and at view depth ≥ `camera.near`, and kept by the clipping plane (rule 10). No segment: background.
/// 2. **Samples.** World segment length `L`, step `h = step_length × voxel` (`voxel` = the smallest voxel side in
///    world units, the shortest column of M); samples at `t = (k + o)·h`, k = 0, 1, … while `t < L`. `o = 0.5`, or with `jitter = Some(seed)`
///    `o = jitter_offset(x, y, seed)` ∈ [0, 1).
///    **Brick strides** (emission/density with `max_stride` > 1): the box is cut into 8³-voxel bricks (the point p
///    lies in brick `floor(p·dim/8)`, texture space). A brick's values are those of its voxels and a one-voxel
///    apron, [lo, hi] (normalised); clipped to the window they reach the table entries e = floor(lo·4095) …
///    ceil(hi·4095); `σ_b` and `σ_min` are the largest and smallest extinction (rule 6) of the classification at
///    e/4095 (clamped to the window) over them, `σ_min = 0` where [lo, hi] reaches beyond the window. A brick
///    none of whose entries is visible is empty. Any other brick's stride is the largest s in {1, 2, 4},
///    s ≤ `max_stride`, with `σ_b·s·step_length ≤ D` and `(σ_b − σ_min)·s·step_length ≤ STRIDE_SPREAD·t` (at
///    least 1); `D` = `STRIDE_DEPTH·t`, or `STRIDE_DEPTH_LIT·t` with `shading` or `gradient_opacity`, where
///    `t` = `stride_tolerance`. Sample k is
///    taken only where k is a multiple of the stride of the brick holding it (in empty bricks every sample is
///    taken; none adds anything).
///    **Level strides** (emission/density, a pool of mixed levels: docs/large-volumes.md): the step is
///    `step_length` voxels of the finest level S the cut shows; a sample in a level-0 brick shown at level L
///    is also taken only where k is a multiple of 2^(L − S), so every brick is sampled at `step_length` of its
///    own voxels, on the one lattice (the two strides multiply).
/// 3. **Value.** Trilinear interpolation (texel centres at (i + 0.5)/dim, clamped to the edge) of the values
///    normalised by the data range: `v = (raw − min)/(max − min)`. NaN samples are skipped. Samples outside the
///    `window` are skipped (every mode but isosurface).
/// 4. **Classification** ([`RenderSettings::classification`]) of a value v inside the window [lo, hi], with window
///    position c = (v − lo)/(hi − lo): the simple model gives colour `colormap(c)` and opacity `step_alpha` (or
///    `c·step_alpha` when multiplied); a transfer function gives its colour and opacity points interpolated
///    linearly at x = v (normalised units) or x = min + v·(max − min) (data units), constant beyond its ends,
///    or its colormap at c when it has no colour points. Colormaps are `Colormap::srgb`'s definitions. Colours
///    are sRGB and decoded to linear light: `(rgb, a)`, `a` per voxel-length step. The GPU reads this from a
///    4096-entry table (`function::bake`, interpolated at v·4095), which follows the definition except within one
///    entry of a jump in a transfer function.
/// 5. **Shading** (with `shading`, in emission/density modes; always in isosurface mode): gradient `g` by central
///    differences of v one voxel apart along each texture axis, `g_i = (v(p + e_i) − v(p − e_i))/2` (value per
///    voxel); world normal `n = normalize(M⁻ᵀ·g)` with M the world step of one voxel along each index axis (rule
///    0), turned towards the viewer (`n ← −n` where `n·V < 0`, V = −ray direction: two-sided); `L` = `light`'s
///    direction, or V for a headlight; `H = normalize(L + V)` (0 where L = −V); light colour `c` = linear(colour)
///    × intensity; `rgb ← rgb·(ambient + diffuse·c·max(n·L, 0)) + specular·c·max(n·H, 0)^shininess` (specular
///    0 where n·L ≤ 0). `|g| = 0`: rgb kept. (A white headlight of intensity 1 gives
///    `rgb·(ambient + diffuse·|n·V|) + specular·|n·V|^shininess`.)
///    In emission/density modes a segment (rule 6) is lit by the gradient at its midpoint; with `shading_fade`
///    F > 0, lighting fades with the gradient: with `x = clamp(|g| / (F·(window[1] − window[0])), 0, 1)` and
///    `w = x²(3 − 2x)`, `rgb ← (1 − w)·rgb·(ambient + diffuse·c) + w·(the lit colour above)` (|g| = 0: the first
///    term alone). Where the data is flat its gradient is noise whose direction turns with every shift of the
///    samples, and a highlight follows it.
///    With `gradient_opacity = Some(r)`: the segment's extinction `σ̄ ← σ̄·min(1, |g|/r)`. With `gradient_texture`
///    (every mode that reads gradients), `g` is instead the grid's filtered gradient, interpolated trilinearly like
///    the values: per voxel the derivative along axis i by weights `d_k` over the neighbours k = −R..=R along i,
///    smoothed by weights `w_k` along each other axis (indices clamped to the edge, NaN voxels read as 0). Float
///    data: Sobel, `w = [1, 2, 1]/4`, `d = [−1, 0, 1]/2`. Integer data (quantised: terraces): a Gaussian of
///    σ = 1.5 voxels, k = −5..=5, `w_k ∝ e^(−k²/2σ²)` with Σw = 1 and `d_k = k·w_k/Σ j²w_j`
///    (`render::gradients::GradientFilter`).
/// 6. **Segments, pre-integrated** (emission/density; Engel, Kraus and Ertl 2001). The ray is cut at its start
///    (t = 0), its samples and its end (t = L); each segment between consecutive points, of length `s` voxels
///    (`s = step_length` between samples), is taken as a value varying linearly from the value at its near end
///    `v_a` to the value at its far end `v_b`. The extinction per voxel length of a value is `σ(v) = −ln(1 − a)`
///    (emission) or `a·density` (density), at most 32 (opacity 1), zero outside the window; the segment's mean
///    extinction is `σ̄ = ∫σ dv / (v_b − v_a)` over [v_a, v_b] (`σ(v_b)` where they coincide) and its colour the
///    extinction-weighted mean `c̄ = ∫σ·rgb dv / ∫σ dv`. Its opacity: emission `α = 1 − e^(−σ̄·s)`, density
///    `α = min(1, σ̄·s)`. A segment with a NaN end adds nothing. A constant value thus gives rule 4's opacity
///    corrected to the segment's length, `1 − (1 − a)^s`. The GPU integrates the 4096-entry table and uses its
///    slope where |v_b − v_a| is under one entry (`preintegrate`). **Stand-ins:** `s` counts voxels of the
///    volume's *source* (`Volume::source_voxels` = k for a preview of every k-th voxel, a coarser level read
///    under a budget or `--max-dim`; 1 for a file's own voxels), so a stand-in keeps its source's optical depth;
///    rule 2's stride bounds `D` and `STRIDE_SPREAD·t` are divided by k to hold for that length.
/// 7. **Compositing.** Emission/density, front to back, segment by segment: `C += (1 − A)·α·c̄`, `A += (1 − A)·α`;
///    stop once `A ≥ early_termination`. MIP/MinIP/average: m = max/min/mean of the visible samples' v; none: background;
///    else `C` = the colour of m, `A = 1`. Isosurface: the surfaces ([`RenderSettings::isosurfaces`], by value;
///    a NaN sample counts as below every one) are met where the samples cross them: for sample k > 0 with
///    values `v_{k−1}`, `v_k`, every surface `v_{k−1} < iso ≤ v_k` (rising, lowest first) or `v_k < iso ≤ v_{k−1}`
///    (falling, highest first); for k = 0 every surface `iso ≤ v_0`, highest first, met at `t_0` (not where the clipping plane starts the ray, rule 10). A crossing at k > 0 is placed
///    by 8 bisection steps on [t_{k−1}, t_k] keeping the side of `t_{k−1}` at lo (`v ≥ iso` there or not), at the
///    final midpoint. Each is composited front to back like a segment, `C += (1 − A)·α·c`, `A += (1 − A)·α`,
///    with α its opacity and c its colour (sRGB decoded, or the classification's colour at the value clamped
///    into the window) shaded (rule 5, with `shading` or its defaults) at the crossing; stop once
///    `A ≥ early_termination`.
/// 8. **Output**: `C + (1 − A)·linear(background)` (background given in sRGB), encoded to sRGB once, stored as
///    8-bit unsigned normalised (rounded). Compositing happens in linear light (gamma-correct).
/// 9. **Shadows and ambient occlusion** (`shadows`, `ambient_occlusion`; lit frames only,
///    [`RenderSettings::uses_light_volume`]) come from a *light grid* of `n_i = ceil(dims_i / f)` cells,
///    `f = max(1, ceil(max dims / 128))`, cell c centred at texture coordinate `(c + 0.5)/n`. Extinction per voxel
///    length `σ(v)`: emission `−ln(1 − a(v))`, density `a(v)·density` (rule 6, at most 32); iso-surfaces 32 where
///    `v ≥` the lowest opaque (opacity 1) surface, else 0 (translucent surfaces cast nothing); NaN 0. A cell's
///    σ is that of rule 3's value at its centre. The light's direction in cell units is
///    `d = diag(n)·M⁻¹·L` (L: [`RenderSettings::light_direction`], M the linear part of the placement); the sweep
///    axis a is the largest |d_i| (the first on ties) and the step `Δ = d/|d_a|`.
///    **Shadow** `T`: cells whose a-index is nearest the light (n_a − 1 where d_a > 0, else 0) have T = 1; any
///    other cell c takes `T(c) = T(c + Δ)·e^(−σ_c·ℓ)`, T(c + Δ) bilinear in the previous slice over the other two
///    axes with cells beyond the grid reading 1, and ℓ the world length of Δ (one cell is `1/n_i` of texture
///    space) in voxels (of the smallest voxel side). **Ambient occlusion** `O`: the mean over the 14 directions u
///    (±x, ±y, ±z and the 8 diagonals normalised, in cell units) of `e^(−Σ_{k=1..4} σ(v(c + k·u))·ℓ_u)`, v
///    trilinear in the volume (rule 3) at those cell positions, σ = 0 outside the box, ℓ_u the world length of u
///    in voxels. At a lit point p the grid is interpolated trilinearly (rule 3's filter over cell centres): O at
///    p, and T at `p + 1.5·Δ` (cells, towards the light: a surface does not shadow itself); rule 5 becomes
///    `rgb·(ambient·O + diffuse·c·T·max(n·L, 0)) + specular·c·T·max(n·H, 0)^shininess` (O = 1 without
///    occlusion, T = 1 without shadows).
/// 10. **Clipping plane** (`clip_plane`, [`crate::scene::clip::ClipPlane`]): a unit normal n and an offset d in mm, in
///     the millimetre world the box is placed in by rule 0 (with `voxel_axes` the voxel box), before centring and
///     scaling. A point p is kept where `(p − c)·n ≥ d`, c the box's centre there; n points into what stays. Rule
///     1's segment is cut to the kept part exactly (the ray's first sample, rule 2, counts from where the plane
///     cuts it), with the slab box and the near plane. Unlike the slab box's faces, the plane *cuts*
///     iso-surfaces rather than capping them: where the plane starts a ray, sample 0 meets no surface (rule 7's
///     k = 0 case) and only serves as `v_{k−1}` for sample 1, so a cut surface shows its inside (a mesh cut
///     open), not a lid. Rule 9's light grid ignores the plane, as it ignores the slab box: material clipped away
///     still casts shadows and occludes.
/// 11. **A rank's share** of each ray in a distributed render: `render::part` and docs/distributed.md.
/// 12. **Ray spacing** (`ray_spacing` k): rules 1–8 make an image of `w_k × h_k = ceil(width/k) × ceil(height/k)`
///     pixels (rule 1's ndc from that size), framed as the output is (its projection takes the output's
///     `width/height`). Output pixel (x, y) is that image filtered bilinearly at `((x + 0.5)·w_k/width,
///     (y + 0.5)·h_k/height)`, its pixel centres at i + 0.5 and its edge repeated beyond them, in the 8-bit values
///     rule 8 stores: vkCmdBlitImage's linear filter. k = 1 is rules 1–8 alone.
/// 13. **Layers**: further volumes on their own grids, mixed into the base's segments at each sample; the rule is
///     written out in [`crate::scene::layers`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub camera: Camera,
    /// Render in voxel index space: the box along the world's axes by its voxel sizes, ignoring the file's
    /// orientation (what volcast showed before it read orientations; `--voxel-axes`).
    pub voxel_axes: bool,
    /// sRGB in [0,1].
    pub background: Vec3,
    #[serde(flatten)]
    pub colour: Colour,
    #[serde(flatten)]
    pub compositing: Compositing,
    #[serde(flatten)]
    pub lighting: Lighting,
    #[serde(flatten)]
    pub sampling: Sampling,
    #[serde(flatten)]
    pub cut: Cut,
    #[serde(flatten)]
    pub pipeline: Pipeline,
    /// How each layer the renderer holds looks, in its order (rule 13, `scene::layers`); empty: the base alone.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub layers: Vec<LayerStyle>,
}

/// The count a `count_samples` frame stores in an RGBA8 pixel.
pub fn decode_sample_count(pixel: [u8; 4]) -> u32 {
    u32::from(pixel[0]) | u32::from(pixel[1]) << 8 | u32::from(pixel[2]) << 16
}

impl Default for RenderSettings {
    fn default() -> RenderSettings {
        RenderSettings::new(512, 512, Vec3::ONE)
    }
}

/// The per-pixel start offset of jittered rays, in [0, 1): a PCG hash of pixel and seed (the shader computes the
/// same in 32-bit integer arithmetic).
pub fn jitter_offset(x: u32, y: u32, seed: u32) -> f32 {
    let v = x
        .wrapping_mul(1973)
        .wrapping_add(y.wrapping_mul(9277))
        .wrapping_add(seed.wrapping_mul(26699))
        | 1;
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    let h = (word >> 22) ^ word;
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

impl RenderSettings {
    /// Defaults for a volume with box `extent`: the camera orbits at azimuth 35°, elevation 25° and fits the box.
    pub fn new(width: u32, height: u32, extent: Vec3) -> RenderSettings {
        let radius = extent.length() * 0.5;
        let distance = Camera::fit_distance(radius, crate::scene::camera::DEFAULT_FOV_Y_DEG);
        RenderSettings {
            width,
            height,
            camera: Camera::orbit(35.0, 25.0, distance, Vec3::ZERO),
            voxel_axes: false,
            background: Vec3::ZERO,
            colour: Colour::default(),
            compositing: Compositing::default(),
            lighting: Lighting::default(),
            sampling: Sampling::default(),
            cut: Cut::default(),
            pipeline: Pipeline::default(),
            layers: Vec::new(),
        }
    }

    /// Defaults for `volume`: as [`RenderSettings::new`], except that a volume whose file says which way the
    /// patient lies is seen from the front, head up ([`ViewPreset::Anterior`]).
    pub fn for_volume(width: u32, height: u32, volume: &Volume) -> RenderSettings {
        let mut s = RenderSettings::new(width, height, volume.extent());
        if volume.geometry.anatomical {
            s.camera = ViewPreset::Anterior.camera(s.camera.eye.length(), Vec3::ZERO);
        }
        s
    }

    /// The classification rule 4 bakes: the transfer function if given, else the simple model.
    pub fn classification(&self) -> Classification {
        match &self.colour.transfer_function {
            Some(tf) => Classification::Function(tf.clone()),
            None => Classification::Simple {
                colormap: self.colour.colormap,
                step_alpha: self.colour.step_alpha,
                multiplied: self.colour.multiplied_alpha,
            },
        }
    }

    /// Rule 7's iso-surfaces, by value: [`Compositing::isosurfaces`].
    pub fn isosurfaces(&self) -> Vec<IsoSurface> {
        self.compositing.isosurfaces()
    }

    /// An isosurface frame that can see past a surface (several, or a translucent one): a ray may cross a surface
    /// downwards, leaving bricks above it for bricks below every surface, which leaping would miss.
    pub fn layered_isosurfaces(&self) -> bool {
        self.compositing.mode == CompositeMode::Isosurface
            && (!self.compositing.extra_isosurfaces.is_empty() || self.compositing.iso_opacity < 1.0)
    }

    /// Whether rule 9's light volume applies: shadows or ambient occlusion on a lit frame (emission or density
    /// with shading, or iso-surfaces). MIP, MinIP and average are never lit.
    pub fn uses_light_volume(&self) -> bool {
        let lit = match self.compositing.mode {
            CompositeMode::Isosurface => true,
            CompositeMode::Emission | CompositeMode::Density => self.lighting.shading.is_some(),
            _ => false,
        };
        lit && (self.lighting.shadows || self.lighting.ambient_occlusion)
    }

    /// Rule 5's light direction (unit, world, towards the light) as the frame uses it: the light's own, or with
    /// shadows and a headlight the key light (rule 9: up and to the left of the view, following the camera);
    /// `None`: a headlight.
    pub fn light_direction(&self) -> Option<Vec3> {
        if let Some(d) = self.lighting.light.direction {
            return Some(d.normalize());
        }
        if !(self.lighting.shadows && self.uses_light_volume()) {
            return None;
        }
        let view = (self.camera.eye - self.camera.target).normalize();
        let right = (-view).cross(self.camera.up).normalize();
        let up = right.cross(-view);
        Some((view + KEY_LIGHT_OFFSET * (up - right)).normalize())
    }

    /// Whether the march looks up the brick grid: to leap over empty bricks, or for rule 2's strides. Layered
    /// iso-surfaces march every sample.
    pub fn looks_up_bricks(&self) -> bool {
        (self.sampling.skip_empty || self.sampling.max_stride > 1) && !self.layered_isosurfaces()
    }

    /// Rule 2's depth bound `D` for strided segments, times `stride_tolerance`.
    pub fn stride_depth(&self) -> f64 {
        let d = if self.lighting.shading.is_some() || self.lighting.gradient_opacity.is_some() {
            STRIDE_DEPTH_LIT
        } else {
            STRIDE_DEPTH
        };
        d * f64::from(self.sampling.stride_tolerance)
    }

    /// Rule 2's spread bound for strided segments: `STRIDE_SPREAD` times `stride_tolerance`.
    pub fn stride_spread(&self) -> f64 {
        STRIDE_SPREAD * f64::from(self.sampling.stride_tolerance)
    }

    /// The size of the image rules 1–8 make (rule 12): the output's, divided by the ray spacing and rounded up.
    pub fn marched_size(&self) -> (u32, u32) {
        let k = self.spacing();
        (self.width.div_ceil(k), self.height.div_ceil(k))
    }

    /// Rule 12's k as frames take it: 1 for a `count_samples` frame, whose counts are not colours to filter.
    pub fn spacing(&self) -> u32 {
        if self.pipeline.count_samples {
            1
        } else {
            self.sampling.ray_spacing.max(1)
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            return Err(format!(
                "image size {}x{} must be between 1 and 16384 on each side",
                self.width, self.height
            ));
        }
        self.colour.validate()?;
        self.compositing.validate()?;
        self.lighting.validate()?;
        self.sampling.validate()?;
        self.cut.validate()?;
        self.pipeline.validate()?;
        let c = &self.camera;
        if !(c.eye - c.target).length().is_normal() {
            return Err(format!(
                "the camera's eye {} must differ from the point it looks at",
                c.eye
            ));
        }
        if !(1.0..=170.0).contains(&c.fov_y_deg) {
            return Err(format!("field of view {}° must be in 1..170 degrees", c.fov_y_deg));
        }
        Ok(())
    }
}
