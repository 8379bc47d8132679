//! The independent CPU ray caster the GPU images are proven against, written in f64 from the rendering rules in
//! `RenderSettings`'s docs.
//!
//! What it shares with the GPU path, and why that is safe:
//! - **Inputs only**: the voxel values (`Volume::value`, i.e. the stored values after the file's rescale), the
//!   volume's dims, voxel-to-world affine (`Volume::geometry`) and value range (`Volume::range`, the min/max the
//!   rules normalise by), and the `RenderSettings` (camera parameters, transfer function, window, steps, modes).
//!   These are what a file or a user gives; a bug in producing them is a loader bug, tested by the loaders' own
//!   tests against files written by other tools and read back by second libraries.
//! - **Documented constants**: the colormaps' control points (`volcast::transfer::colormap::tables`: Moreland's table,
//!   matplotlib's viridis and plasma), checked against their published values in tests/reference/classify.rs.
//!
//! Everything else is computed here and in the modules beside it (march.rs: one pixel's march; placement.rs): the
//! normalisation of values, the placement of the box in the world (the affine or the voxel axes, centred, longest
//! side 1: `Placement`), the rays (rays.rs, from eye/target/up/fov,
//! not `Camera::view`/`projection`), their passage into texture space and the slab method there, trilinear
//! filtering, gradients (central differences of the interpolant, or the grid gradients of `gradient_texture`),
//! the classification (classify.rs: window position, colormap interpolation, control points, data units, sRGB),
//! the jitter hash, opacity correction, every compositing mode, the isosurface bisection and the output encoding.
//! Pre-integration's segment integrals are the reference's own (segments.rs: the exact classification integrated
//! numerically), and so are rule 2's brick strides (strides.rs: brick value ranges and the stride rule). Where the GPU works in f32 or through a 4096-entry table, the two differ by rounding; the tests'
//! bounds (tests/common/bounds.rs) say by how much.

use super::classify::{encode, linear, Classifier};
use super::levels::{pyramid, Cut};
use super::march::Frame;
pub use super::placement::Placement;
use super::strides::BrickRanges;
use glam::{DMat4, DVec3};
use image::{Rgba, RgbaImage};
use volcast::scene::lighting::Light;
use volcast::scene::settings::{RenderSettings, Shading};
use volcast::volume::{Volume, VoxelType};

/// A ray segment inside the slab box, in world units along the unit direction `dir` from `origin` (the eye for a
/// perspective camera; for an orthographic one the pixel's point on the plane through the eye perpendicular to
/// the view direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub origin: DVec3,
    pub dir: DVec3,
    pub t_start: f64,
    pub t_end: f64,
    /// Whether rule 10's clipping plane moved the start (iso-surfaces are cut open there, not capped).
    pub clipped_start: bool,
}

impl Segment {
    pub fn length(&self) -> f64 {
        self.t_end - self.t_start
    }

    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.dir * t
    }
}

/// What one pixel's ray did, before 8-bit quantisation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelTrace {
    pub segment: Option<Segment>,
    /// Rule 2's start offset `o` of this pixel (0.5, or the jitter hash).
    pub offset: f64,
    /// Sample positions visited (rule 2), up to early termination or the isosurface hit.
    pub samples: u32,
    /// Samples that passed the NaN and window tests and were used (composited, or counted by MIP/MinIP/average;
    /// 1 for an isosurface hit).
    pub composited: u32,
    /// MIP/MinIP/average: the value m whose colour the pixel shows; None when no sample was visible.
    pub value: Option<f64>,
    /// Isosurface: the hit, as the distance along the ray from `segment.origin` (so `segment.at(hit)` is the point).
    pub hit: Option<f64>,
    /// Accumulated colour `C` (premultiplied by opacity), linear light.
    pub color: DVec3,
    /// Accumulated opacity `A`.
    pub alpha: f64,
    pub terminated_early: bool,
    /// Rule 8 in linear light: `C + (1 - A)·linear(background)`, clamped to [0,1].
    pub linear: DVec3,
    /// Rule 8 encoded to sRGB, before 8-bit rounding ([`quantise`] rounds it).
    pub output: DVec3,
}

impl PixelTrace {
    /// Whether the pixel shows the volume: some sample was composited (or the isosurface hit).
    pub fn shows_volume(&self) -> bool {
        self.composited > 0 && (self.alpha > 0.0 || self.value.is_some() || self.hit.is_some())
    }
}

/// Per-image statistics of a reference render.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Pixels whose ray has a segment inside the slab box.
    pub hit_pixels: u64,
    /// Sample positions visited over the whole image.
    pub samples: u64,
    pub composited: u64,
    pub terminated_early: u64,
    pub pixels: u64,
}

impl RenderStats {
    /// Mean sample positions visited per pixel of the image (misses count as zero).
    pub fn samples_per_pixel(&self) -> f64 {
        self.samples as f64 / self.pixels.max(1) as f64
    }

    fn add(&mut self, other: &RenderStats) {
        self.hit_pixels += other.hit_pixels;
        self.samples += other.samples;
        self.composited += other.composited;
        self.terminated_early += other.terminated_early;
        self.pixels += other.pixels;
    }
}

/// A reference image with what each pixel's ray did.
pub struct Rendered {
    pub image: RgbaImage,
    /// Per pixel (row-major): the ray showed the volume ([`PixelTrace::shows_volume`]).
    pub object: Vec<bool>,
    /// Per pixel: sample positions visited ([`PixelTrace::samples`]).
    pub samples: Vec<u32>,
    pub stats: RenderStats,
}

/// Rule 5's light at one point, prepared: the unit direction towards it (None: a headlight), its linear colour ×
/// intensity, and rule 9's shadow T (scales the light) and occlusion O (scales the ambient term) there.
#[derive(Clone, Copy, Debug)]
pub struct Lamp {
    pub direction: Option<DVec3>,
    pub color: DVec3,
    pub occlusion: f64,
}

impl Lamp {
    /// `light` from `direction` (rule 9's resolution of it: see light.rs), unshadowed.
    pub fn new(light: &Light, direction: Option<DVec3>) -> Lamp {
        Lamp {
            direction,
            color: linear(light.color.as_dvec3()) * f64::from(light.intensity),
            occlusion: 1.0,
        }
    }

    /// A white headlight of intensity 1.
    pub fn headlight() -> Lamp {
        Lamp::new(&Light::default(), None)
    }

    /// This lamp at a point with shadow `t` and occlusion `o`.
    pub fn at(&self, t: f64, o: f64) -> Lamp {
        Lamp {
            color: self.color * t,
            occlusion: o,
            ..*self
        }
    }
}

/// Rule 5's lighting, two-sided Blinn–Phong: `n` the normalised world gradient turned towards `view` (the unit
/// vector towards the eye), `l` the lamp's direction or `view`, `h = normalize(l + view)`;
/// `rgb·(ambient + diffuse·c·max(n·l, 0)) + specular·c·max(n·h, 0)^shininess` (no specular where n·l ≤ 0);
/// `rgb` unchanged where the world gradient vanishes.
pub fn shade(rgb: DVec3, world_gradient: DVec3, view: DVec3, shading: &Shading, lamp: &Lamp, fade: f64) -> DVec3 {
    let flat = rgb * (f64::from(shading.ambient) * lamp.occlusion + f64::from(shading.diffuse) * lamp.color);
    let len = world_gradient.length();
    if len < 1e-8 {
        return if fade < 1.0 { flat } else { rgb };
    }
    let mut n = world_gradient / len;
    if n.dot(view) < 0.0 {
        n = -n;
    }
    let l = lamp.direction.unwrap_or(view);
    let ndl = n.dot(l).max(0.0);
    let half = l + view;
    let ndh = if half.length() > 1e-6 {
        n.dot(half.normalize()).max(0.0)
    } else {
        0.0
    };
    let [ambient, diffuse, specular, shininess] =
        [shading.ambient, shading.diffuse, shading.specular, shading.shininess].map(f64::from);
    let spec = if ndl > 0.0 { ndh.powf(shininess) } else { 0.0 };
    let lit =
        rgb * (DVec3::splat(ambient * lamp.occlusion) + diffuse * ndl * lamp.color) + specular * spec * lamp.color;
    flat + (lit - flat) * fade
}

/// Rule 5's shading fade for volume shading: smoothstep of |g| (value per voxel) over `shading_fade` of the
/// window's width (1 where the fade is off).
pub fn gradient_fade(g: DVec3, fade: f64, window: [f64; 2]) -> f64 {
    if fade <= 0.0 {
        return 1.0;
    }
    let x = (g.length() / (fade * (window[1] - window[0]))).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Renders `volume` with `s` by the CPU reference. Prefer [`Reference`] to render one volume several times.
pub fn render_reference(volume: &Volume, s: &RenderSettings) -> RgbaImage {
    Reference::new(volume).render(s)
}

/// Mean sample positions visited per pixel when rendering `volume` with `s`.
pub fn samples_per_pixel(volume: &Volume, s: &RenderSettings) -> f64 {
    Reference::new(volume).render_full(s).stats.samples_per_pixel()
}

/// Rule 8's storage of an sRGB-encoded colour ([`PixelTrace::output`], or see [`encode`]): 8-bit unsigned
/// normalised, rounded, opaque.
pub fn quantise(srgb: DVec3) -> Rgba<u8> {
    let q = |c: f64| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
    Rgba([q(srgb.x), q(srgb.y), q(srgb.z), 255])
}

/// The pixel a ray without volume shows: `background` (sRGB) decoded for compositing and encoded again.
pub fn background_pixel(background: glam::Vec3) -> Rgba<u8> {
    quantise(encode(linear(background.as_dvec3())))
}

/// A volume prepared for the reference: normalised values in f64, the box it fills and its data range.
pub struct Reference {
    pub(crate) dims: [usize; 3],
    pub(crate) values: Vec<f64>,
    /// Voxel index to millimetres, as the file places it.
    affine: DMat4,
    range: [f64; 2],
    /// Whether the data are integers (rule 5: the gradient texture's wider filter).
    quantised: bool,
    /// `gradient_texture`'s rule, made on first use: per voxel the filtered derivatives `2g` (see
    /// [`Reference::make_grid_gradients`]).
    grid_gradients: std::sync::OnceLock<Vec<DVec3>>,
    /// Rule 2's brick value ranges, made on first use by a frame with strides.
    pub(crate) brick_ranges: std::sync::OnceLock<BrickRanges>,
    /// The pyramid's levels 1.. and the level shown per brick (levels.rs); None: level 0 everywhere.
    levels: Option<(Vec<Reference>, Cut)>,
    /// How many voxels of its source one voxel spans (1, or k for a stand-in): a segment's opacity counts the
    /// source's voxels it crosses, so a stand-in keeps the source's optical depth (rule 6).
    pub(crate) source_voxels: f64,
    /// Rule 13's layers, styled by `RenderSettings::layers` in this order.
    pub(crate) layers: Vec<super::layers::RefLayer>,
}

impl Reference {
    pub fn new(volume: &Volume) -> Reference {
        let [nx, ny, nz] = volume.dims;
        let [min, max] = volume.range;
        let normalise = |value: f64| {
            if value.is_nan() {
                f64::NAN
            } else if max > min {
                (value - min) / (max - min)
            } else {
                0.0
            }
        };
        let mut values = Vec::with_capacity(nx as usize * ny as usize * nz as usize);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    values.push(normalise(volume.value(x, y, z)));
                }
            }
        }
        Reference {
            dims: volume.dims.map(|d| d as usize),
            values,
            affine: volume.geometry.affine,
            range: volume.range,
            quantised: !matches!(volume.source_type, VoxelType::F32 | VoxelType::F64),
            grid_gradients: std::sync::OnceLock::new(),
            brick_ranges: std::sync::OnceLock::new(),
            levels: None,
            source_voxels: volume.source_voxels,
            layers: Vec::new(),
        }
    }

    /// The reference for a GPU pool that shows `cut` of `volume`'s pyramid (levels.rs): each point's value from the
    /// level shown in the level-0 brick holding it, each gradient's samples from the level at its centre, and
    /// rule 2's brick ranges widened by every level up to the coarsest shown (as the GPU's skip grid is).
    pub fn with_levels(volume: &Volume, cut: Cut) -> Reference {
        let top = cut.level.iter().copied().max().unwrap_or(0);
        let mut base = Reference::new(volume);
        let levels: Vec<Reference> = pyramid(volume, top)
            .into_iter()
            .skip(1)
            .map(|level| Reference {
                dims: level.dims,
                values: level.values,
                grid_gradients: std::sync::OnceLock::new(),
                brick_ranges: std::sync::OnceLock::new(),
                levels: None,
                ..base.clone_header()
            })
            .collect();
        let mut ranges = BrickRanges::new(&base.values, base.dims);
        for (i, level) in levels.iter().enumerate() {
            ranges.widen(&BrickRanges::new(&level.values, level.dims), i + 1);
        }
        let _ = base.brick_ranges.set(ranges);
        base.levels = Some((levels, cut));
        base
    }

    fn clone_header(&self) -> Reference {
        Reference {
            dims: self.dims,
            values: Vec::new(),
            affine: self.affine,
            range: self.range,
            quantised: self.quantised,
            grid_gradients: std::sync::OnceLock::new(),
            brick_ranges: std::sync::OnceLock::new(),
            levels: None,
            source_voxels: self.source_voxels,
            layers: Vec::new(),
        }
    }

    /// The level shown at `tex` and, for a level L ≥ 1, that level's reference and `tex` in its texture
    /// coordinates (level L's voxel x = tex · dims0 / 2^L).
    fn level_at(&self, tex: DVec3) -> Option<(u32, &Reference, DVec3)> {
        let (refs, cut) = self.levels.as_ref()?;
        let l = cut.level_at(tex, self.dims);
        (l > 0).then(|| {
            let r = &refs[l as usize - 1];
            let scale =
                DVec3::from_array([0, 1, 2].map(|a| self.dims[a] as f64 / (f64::from(1u32 << l) * r.dims[a] as f64)));
            (l, r, scale)
        })
    }

    /// The finest level the cut shows (0 without one): the level of the step's voxel.
    pub(crate) fn finest_level(&self) -> u32 {
        self.levels
            .as_ref()
            .map_or(0, |(_, cut)| cut.level.iter().copied().min().unwrap_or(0))
    }

    /// Rule 2's level stride at `tex`: 2^(L − S) for the level L shown there and the finest level S =
    /// [`finest_level`](Self::finest_level) (1 without a cut): every brick is sampled at the step's length in
    /// voxels of its own level.
    pub(crate) fn level_stride(&self, tex: DVec3, finest: u32) -> u64 {
        self.levels
            .as_ref()
            .map_or(1, |(_, cut)| 1 << (cut.level_at(tex, self.dims) - finest))
    }

    /// This reference with `layers` (rule 13), which frames style by `RenderSettings::layers` in this order.
    pub fn with_layers(mut self, layers: Vec<super::layers::RefLayer>) -> Reference {
        self.layers = layers;
        self
    }

    /// The millimetre point of texture point `tex` (rule 13's layers are placed from it).
    /// Millimetres to the base's voxel index (centres at integers).
    pub(crate) fn mm_to_index(&self, mm: DVec3) -> DVec3 {
        self.affine.inverse().transform_point3(mm)
    }

    pub(crate) fn mm_at(&self, tex: DVec3) -> DVec3 {
        super::layers::base_mm(self.affine, self.dims, tex)
    }

    /// Millimetres per world unit under `placement` (`d mm / d world`): the base's affine of its voxel index, of
    /// texture space, of the world.
    pub(crate) fn mm_per_world(&self, placement: &Placement) -> glam::DMat3 {
        let n = DVec3::new(self.dims[0] as f64, self.dims[1] as f64, self.dims[2] as f64);
        let to_tex = glam::DMat3::from_cols(
            placement.dir_to_tex(DVec3::X),
            placement.dir_to_tex(DVec3::Y),
            placement.dir_to_tex(DVec3::Z),
        );
        glam::DMat3::from_mat4(self.affine) * glam::DMat3::from_diagonal(n) * to_tex
    }

    /// Where the box is for `s`: the rule-1 placement of the texture-space box in the world.
    pub fn placement(&self, s: &RenderSettings) -> Placement {
        Placement::new(self.affine, self.dims, s.voxel_axes)
    }

    /// The settings the march takes: a cut of the pyramid is marched at `step_length` voxels of the finest level it
    /// shows (render/resident.rs `step_level`, `VolumeInfo::stepped`), without strides where that level is coarser
    /// than the one held; a stand-in's stride bounds tightened by its `source_voxels`.
    pub(crate) fn stepped(&self, s: &RenderSettings) -> RenderSettings {
        let mut s = s.clone();
        if let Some((_, cut)) = &self.levels {
            let finest = self.finest_level();
            s.sampling.step_length *= (1u32 << finest) as f32;
            if finest > cut.held {
                s.sampling.max_stride = 1;
            }
        }
        // A stand-in's segment crosses `source_voxels` times as many of its source's voxels: rule 2's stride bounds
        // hold for that optical length.
        s.sampling.stride_tolerance /= self.source_voxels as f32;
        s
    }

    /// Rule 2's step `h` in world units: `step_length` × the smallest voxel side.
    pub fn step_world(&self, s: &RenderSettings) -> f64 {
        f64::from(s.sampling.step_length) * self.placement(s).voxel_sides().min_element()
    }

    fn at(&self, x: usize, y: usize, z: usize) -> f64 {
        self.values[x + self.dims[0] * (y + self.dims[1] * z)]
    }

    /// The two texels and the weight along each axis of rule 3's trilinear filter at texture coordinate `tex`:
    /// texel centres at (i + 0.5)/dim, clamped to the edge.
    fn corners(&self, tex: DVec3) -> ([[usize; 2]; 3], [f64; 3]) {
        let mut idx = [[0usize; 2]; 3];
        let mut w = [0f64; 3];
        for a in 0..3 {
            let n = self.dims[a];
            let u = tex[a] * n as f64 - 0.5;
            let i0 = u.floor();
            w[a] = u - i0;
            let clamp = |i: f64| i.clamp(0.0, (n - 1) as f64) as usize;
            idx[a] = [clamp(i0), clamp(i0 + 1.0)];
        }
        (idx, w)
    }

    /// Rule 3: trilinear interpolation at texture coordinate `tex`. A NaN among the eight texels gives NaN, as a
    /// filtering `a + w·(b - a)` does even at `w = 0`.
    pub fn sample(&self, tex: DVec3) -> f64 {
        match self.level_at(tex) {
            Some((_, level, scale)) => level.sample(tex * scale),
            None => self.sample_here(tex),
        }
    }

    fn sample_here(&self, tex: DVec3) -> f64 {
        let ([[x0, x1], [y0, y1], [z0, z1]], w) = self.corners(tex);
        let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
        let c00 = lerp(self.at(x0, y0, z0), self.at(x1, y0, z0), w[0]);
        let c10 = lerp(self.at(x0, y1, z0), self.at(x1, y1, z0), w[0]);
        let c01 = lerp(self.at(x0, y0, z1), self.at(x1, y0, z1), w[0]);
        let c11 = lerp(self.at(x0, y1, z1), self.at(x1, y1, z1), w[0]);
        lerp(lerp(c00, c10, w[1]), lerp(c01, c11, w[1]), w[2])
    }

    /// Rule 5's gradient at texture coordinate `tex`, in value per voxel (index space): central differences of
    /// rule 3's samples one voxel (1/dim_i in texture space) apart, `g_i = (v(p + e_i) − v(p − e_i))/2`. Zero
    /// when any of the six samples is NaN.
    pub fn gradient(&self, tex: DVec3) -> DVec3 {
        // With levels, all six samples in the level shown at the centre.
        let at = self.level_at(tex);
        let sample = |p: DVec3| match at {
            Some((_, level, scale)) => level.sample(p * scale),
            None => self.sample_here(p),
        };
        let mut g = DVec3::ZERO;
        for a in 0..3 {
            let mut e = DVec3::ZERO;
            e[a] = 1.0 / self.dims[a] as f64;
            g[a] = (sample(tex + e) - sample(tex - e)) / 2.0;
        }
        if g.is_nan() {
            DVec3::ZERO
        } else {
            g
        }
    }

    /// `gradient_texture`'s gradient at `tex`, in value per voxel: the grid gradients `G/2` (see
    /// [`Reference::grid_gradients`]) interpolated trilinearly like the values (rule 3's filter).
    pub fn grid_gradient(&self, tex: DVec3) -> DVec3 {
        // With levels: the level's own grid gradients, per voxel of that level (2^L level-0 voxels).
        if let Some((l, level, scale)) = self.level_at(tex) {
            return level.grid_gradient(tex * scale) / f64::from(1u32 << l);
        }
        let grid = self.grid_gradients.get_or_init(|| self.make_grid_gradients());
        let ([[x0, x1], [y0, y1], [z0, z1]], w) = self.corners(tex);
        let at = |x: usize, y: usize, z: usize| grid[x + self.dims[0] * (y + self.dims[1] * z)];
        let c00 = at(x0, y0, z0).lerp(at(x1, y0, z0), w[0]);
        let c10 = at(x0, y1, z0).lerp(at(x1, y1, z0), w[0]);
        let c01 = at(x0, y0, z1).lerp(at(x1, y0, z1), w[0]);
        let c11 = at(x0, y1, z1).lerp(at(x1, y1, z1), w[0]);
        c00.lerp(c10, w[1]).lerp(c01.lerp(c11, w[1]), w[2]) / 2.0
    }

    /// Rule 5's grid filter, 1-D (smoothing, derivative) weights over offsets −R..=R: integer data a Gaussian of
    /// σ = 1.5 voxels over −5..=5 (weights e^(−k²/2σ²) summing to 1; derivative k·w_k/Σj²w_j), float data Sobel
    /// ([1, 2, 1]/4 and [−1, 0, 1]/2).
    fn grid_filter(&self) -> (Vec<f64>, Vec<f64>) {
        if !self.quantised {
            return (vec![0.25, 0.5, 0.25], vec![-0.5, 0.0, 0.5]);
        }
        let sigma = 1.5f64;
        let gauss: Vec<f64> = (-5..=5)
            .map(|k| (-f64::from(k * k) / (2.0 * sigma * sigma)).exp())
            .collect();
        let total: f64 = gauss.iter().sum();
        let smooth: Vec<f64> = gauss.iter().map(|w| w / total).collect();
        let second: f64 = (-5..=5).zip(&smooth).map(|(k, w)| f64::from(k * k) * w).sum();
        let deriv = (-5..=5).zip(&smooth).map(|(k, w)| f64::from(k) * w / second).collect();
        (smooth, deriv)
    }

    /// Per voxel `2g`: g_i the derivative along axis i (weights `deriv`) smoothed along the other two (`smooth`),
    /// indices clamped to the edge, NaN voxels read as 0; three 1-D passes over the whole grid per component.
    fn make_grid_gradients(&self) -> Vec<DVec3> {
        let [nx, ny, nz] = self.dims;
        let (smooth, deriv) = self.grid_filter();
        let r = (smooth.len() / 2) as i64;
        let base: Vec<f64> = self.values.iter().map(|v| if v.is_nan() { 0.0 } else { *v }).collect();
        let index = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
        // One pass along `axis` with `weights`.
        let pass = |src: &[f64], axis: usize, weights: &[f64]| -> Vec<f64> {
            let mut out = vec![0.0; src.len()];
            for z in 0..nz {
                for y in 0..ny {
                    for x in 0..nx {
                        let p = [x, y, z];
                        let mut acc = 0.0;
                        for (k, w) in weights.iter().enumerate() {
                            let mut q = p;
                            q[axis] = (p[axis] as i64 + k as i64 - r).clamp(0, self.dims[axis] as i64 - 1) as usize;
                            acc += w * src[index(q[0], q[1], q[2])];
                        }
                        out[index(x, y, z)] = acc;
                    }
                }
            }
            out
        };
        let component = |axis: usize| {
            let mut v = base.clone();
            for a in 0..3 {
                v = pass(&v, a, if a == axis { &deriv } else { &smooth });
            }
            v
        };
        let [gx, gy, gz] = [0, 1, 2].map(component);
        (0..base.len()).map(|i| 2.0 * DVec3::new(gx[i], gy[i], gz[i])).collect()
    }

    pub fn render(&self, s: &RenderSettings) -> RgbaImage {
        self.render_full(s).image
    }

    pub fn render_with_stats(&self, s: &RenderSettings) -> (RgbaImage, RenderStats) {
        let r = self.render_full(s);
        (r.image, r.stats)
    }

    /// Renders rows in parallel bands, one per available core, keeping what each pixel's ray did.
    pub fn render_full(&self, s: &RenderSettings) -> Rendered {
        let frame = Frame::new(self, s);
        let marched = super::stretch::marched(s);
        let (width, height) = (marched.0 as usize, marched.1 as usize);
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(height)
            .max(1);
        let rows_per_band = height.div_ceil(threads);
        let bands: Vec<Vec<PixelTrace>> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..threads)
                .map(|band| {
                    let frame = &frame;
                    scope.spawn(move || {
                        let rows = band * rows_per_band..((band + 1) * rows_per_band).min(height);
                        rows.flat_map(|y| (0..width).map(move |x| frame.trace(x as u32, y as u32)))
                            .collect()
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("reference render thread panicked"))
                .collect()
        });
        let mut image = RgbaImage::new(marched.0, marched.1);
        let mut object = Vec::with_capacity(width * height);
        let mut samples = Vec::with_capacity(width * height);
        let mut stats = RenderStats::default();
        for (i, trace) in bands.iter().flatten().enumerate() {
            image.put_pixel((i % width) as u32, (i / width) as u32, quantise(trace.output));
            object.push(trace.shows_volume());
            samples.push(trace.samples);
            stats.add(&RenderStats {
                hit_pixels: u64::from(trace.segment.is_some()),
                samples: u64::from(trace.samples),
                composited: u64::from(trace.composited),
                terminated_early: u64::from(trace.terminated_early),
                pixels: 1,
            });
        }
        if marched != (s.width, s.height) {
            // Rule 12: the marched image stretched over the output (the stats stay the rays').
            image = super::stretch::stretch(&image, s.width, s.height);
            object = super::stretch::nearest(&object, marched, s.width, s.height);
            samples = super::stretch::nearest(&samples, marched, s.width, s.height);
        }
        Rendered {
            image,
            object,
            samples,
            stats,
        }
    }

    /// Traces one pixel, keeping the unquantised result (for checks against closed forms).
    pub fn trace(&self, s: &RenderSettings, x: u32, y: u32) -> PixelTrace {
        Frame::new(self, s).trace(x, y)
    }

    /// Prepares `s` once (the classification, the camera) for tracing many pixels with [`Tracer::trace`].
    pub fn tracer(&self, s: &RenderSettings) -> Tracer<'_> {
        Tracer(Frame::new(self, s))
    }

    /// The reference's classification of `s` on this volume (rule 4, classify.rs).
    pub fn classifier(&self, s: &RenderSettings) -> Classifier {
        Classifier::new(s, self.range)
    }
}

/// One frame's settings prepared for tracing single pixels.
pub struct Tracer<'a>(Frame<'a>);

impl Tracer<'_> {
    /// As [`Reference::trace`].
    pub fn trace(&self, x: u32, y: u32) -> PixelTrace {
        self.0.trace(x, y)
    }
}
