//! The independent CPU ray caster the GPU images are proven against, written in f64 from the rendering rules in
//! `RenderSettings`'s docs.
//!
//! What it shares with the GPU path, and why that is safe:
//! - **Inputs only**: the voxel values (`Volume::value`, i.e. the stored values after the file's rescale), the
//!   volume's dims, voxel-to-world affine (`Volume::geometry`) and value range (`Volume::range`, the min/max the
//!   rules normalise by), and the `RenderSettings` (camera parameters, transfer function, window, steps, modes).
//!   These are what a file or a user gives; a bug in producing them is a loader bug, tested by the loaders' own
//!   tests against files written by other tools and read back by second libraries.
//! - **Documented constants**: the colormaps' control points (`volcast::transfer::tables`: Moreland's table,
//!   matplotlib's viridis and plasma), checked against their published values in tests/reference_selftest.rs.
//!
//! Everything else is computed here: the normalisation of values, the placement of the box in the world (the
//! affine or the voxel axes, centred, longest side 1: `Placement`), the rays (rays.rs, from eye/target/up/fov,
//! not `Camera::view`/`projection`), their passage into texture space and the slab method there, trilinear
//! filtering, gradients (central differences of the interpolant, or the grid gradients of `gradient_texture`),
//! the classification (classify.rs: window position, colormap interpolation, control points, data units, sRGB),
//! the jitter hash, opacity correction, every compositing mode, the isosurface bisection and the output encoding.
//! Pre-integration's segment integrals are the reference's own (segments.rs: the exact classification integrated
//! numerically), and so are rule 2's brick strides (strides.rs: brick value ranges and the stride rule). Where the GPU works in f32 or through a 4096-entry table, the two differ by rounding; the tests'
//! bounds (tests/common/bounds.rs) say by how much.

#![allow(dead_code)]

use super::classify::{encode, jitter_offset, linear, Classifier};
use super::rays::{ray_segment, CameraBasis};
use super::segments::Segments;
use super::strides::{BrickRanges, Strides};
use glam::{DMat3, DMat4, DVec3};
use image::{Rgba, RgbaImage};
use volcast::settings::{CompositeMode, RenderSettings, Shading};
use volcast::volume::Volume;

/// A ray segment inside the slab box, in world units along the unit direction `dir` from `origin` (the eye for a
/// perspective camera; for an orthographic one the pixel's point on the plane through the eye perpendicular to
/// the view direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub origin: DVec3,
    pub dir: DVec3,
    pub t_start: f64,
    pub t_end: f64,
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

/// Rule 5's lighting: `rgb·(ambient + diffuse·|n·L|) + specular·|n·L|^shininess` with `n` the normalised world
/// gradient and `light` the unit vector towards the eye; `rgb` unchanged where the world gradient vanishes.
pub fn shade(rgb: DVec3, world_gradient: DVec3, light: DVec3, shading: &Shading) -> DVec3 {
    let len = world_gradient.length();
    if len < 1e-8 {
        return rgb;
    }
    let ndl = (world_gradient / len).dot(light).abs();
    let [ambient, diffuse, specular, shininess] =
        [shading.ambient, shading.diffuse, shading.specular, shading.shininess].map(f64::from);
    rgb * (ambient + diffuse * ndl) + DVec3::splat(specular * ndl.powf(shininess))
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
    dims: [usize; 3],
    values: Vec<f64>,
    /// Voxel index to millimetres, as the file places it.
    affine: DMat4,
    range: [f64; 2],
    /// `gradient_texture`'s rule, made on first use: per voxel `G_i = v(x + e_i) − v(x − e_i)` on the grid,
    /// indices clamped to the edge, NaN voxels read as 0.
    grid_gradients: std::sync::OnceLock<Vec<DVec3>>,
    /// Rule 2's brick value ranges, made on first use by a frame with strides.
    brick_ranges: std::sync::OnceLock<BrickRanges>,
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
            grid_gradients: std::sync::OnceLock::new(),
            brick_ranges: std::sync::OnceLock::new(),
        }
    }

    /// Where the box is for `s`: the rule-1 placement of the texture-space box in the world.
    pub fn placement(&self, s: &RenderSettings) -> Placement {
        Placement::new(self.affine, self.dims, s.voxel_axes)
    }

    /// Rule 2's step `h` in world units: `step_length` × the smallest voxel side.
    pub fn step_world(&self, s: &RenderSettings) -> f64 {
        f64::from(s.step_length) * self.placement(s).voxel_sides().min_element()
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
        let mut g = DVec3::ZERO;
        for a in 0..3 {
            let mut e = DVec3::ZERO;
            e[a] = 1.0 / self.dims[a] as f64;
            g[a] = (self.sample(tex + e) - self.sample(tex - e)) / 2.0;
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
        let grid = self.grid_gradients.get_or_init(|| self.make_grid_gradients());
        let ([[x0, x1], [y0, y1], [z0, z1]], w) = self.corners(tex);
        let at = |x: usize, y: usize, z: usize| grid[x + self.dims[0] * (y + self.dims[1] * z)];
        let c00 = at(x0, y0, z0).lerp(at(x1, y0, z0), w[0]);
        let c10 = at(x0, y1, z0).lerp(at(x1, y1, z0), w[0]);
        let c01 = at(x0, y0, z1).lerp(at(x1, y0, z1), w[0]);
        let c11 = at(x0, y1, z1).lerp(at(x1, y1, z1), w[0]);
        c00.lerp(c10, w[1]).lerp(c01.lerp(c11, w[1]), w[2]) / 2.0
    }

    fn make_grid_gradients(&self) -> Vec<DVec3> {
        let [nx, ny, nz] = self.dims;
        let value = |x: i64, y: i64, z: i64| {
            let c = |i: i64, n: usize| i.clamp(0, n as i64 - 1) as usize;
            let v = self.at(c(x, nx), c(y, ny), c(z, nz));
            if v.is_nan() {
                0.0
            } else {
                v
            }
        };
        let mut out = Vec::with_capacity(self.values.len());
        for z in 0..nz as i64 {
            for y in 0..ny as i64 {
                for x in 0..nx as i64 {
                    out.push(DVec3::new(
                        value(x + 1, y, z) - value(x - 1, y, z),
                        value(x, y + 1, z) - value(x, y - 1, z),
                        value(x, y, z + 1) - value(x, y, z - 1),
                    ));
                }
            }
        }
        out
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
        let (width, height) = (s.width as usize, s.height as usize);
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
        let mut image = RgbaImage::new(s.width, s.height);
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

/// Everything per-frame that `trace` needs, computed once.
struct Frame<'a> {
    volume: &'a Reference,
    camera: CameraBasis,
    placement: Placement,
    /// The slab box, texture space.
    box_lo: DVec3,
    box_hi: DVec3,
    step: f64,
    classifier: Classifier,
    /// Rule 6's segment integrals (emission and density modes).
    segments: Option<Segments>,
    window: [f64; 2],
    /// Exponent of rule 6's opacity correction (and factor of the density model).
    step_length: f64,
    mode: CompositeMode,
    iso_value: f64,
    density: f64,
    /// Rule 5's lighting where it applies: `shading` in emission/density modes, `shading` or its defaults in
    /// isosurface mode.
    shading: Option<Shading>,
    gradient_opacity: Option<f64>,
    /// `gradient_texture`: shade from the grid gradients instead of central differences of the interpolant.
    grid_gradients: bool,
    jitter: Option<u32>,
    /// Rule 2's brick strides (None: every sample).
    strides: Option<Strides>,
    early_termination: f64,
    /// Linear light.
    background: DVec3,
}

/// The result of one mode's march: colour and opacity before rule 8.
struct Composite {
    color: DVec3,
    alpha: f64,
}

impl<'a> Frame<'a> {
    fn new(volume: &'a Reference, s: &RenderSettings) -> Frame<'a> {
        let placement = volume.placement(s);
        let shading = match s.mode {
            CompositeMode::Isosurface => Some(s.shading.unwrap_or_default()),
            _ => s.shading,
        };
        let segments = match s.mode {
            CompositeMode::Emission => Some(Segments::new(volume.classifier(s), s.window.map(f64::from), None)),
            CompositeMode::Density => Some(Segments::new(
                volume.classifier(s),
                s.window.map(f64::from),
                Some(f64::from(s.density)),
            )),
            _ => None,
        };
        let strides = segments.as_ref().and_then(|segments| {
            let ranges = volume
                .brick_ranges
                .get_or_init(|| BrickRanges::new(&volume.values, volume.dims));
            Strides::new(ranges, volume.dims, s, segments)
        });
        Frame {
            volume,
            camera: CameraBasis::new(s),
            step: f64::from(s.step_length) * placement.voxel_sides().min_element(),
            placement,
            box_lo: s.slab_lo.as_dvec3(),
            box_hi: s.slab_hi.as_dvec3(),
            classifier: volume.classifier(s),
            segments,
            window: s.window.map(f64::from),
            step_length: f64::from(s.step_length),
            mode: s.mode,
            iso_value: f64::from(s.iso_value),
            density: f64::from(s.density),
            shading,
            gradient_opacity: s.gradient_opacity.map(f64::from),
            grid_gradients: s.gradient_texture && matches!(s.mode, CompositeMode::Emission | CompositeMode::Density),
            jitter: s.jitter,
            strides,
            early_termination: f64::from(s.early_termination),
            background: linear(s.background.as_dvec3()),
        }
    }

    /// Rule 3's visibility test (every mode but isosurface).
    fn visible(&self, v: f64) -> bool {
        !v.is_nan() && v >= self.window[0] && v <= self.window[1]
    }

    fn gradient(&self, tex: DVec3) -> DVec3 {
        if self.grid_gradients {
            self.volume.grid_gradient(tex)
        } else {
            self.volume.gradient(tex)
        }
    }

    fn trace(&self, x: u32, y: u32) -> PixelTrace {
        let (origin, dir, t_near) = self.camera.ray(x, y);
        let offset = self.jitter.map_or(0.5, |seed| jitter_offset(x, y, seed));
        let background = self.background.clamp(DVec3::ZERO, DVec3::ONE);
        let mut trace = PixelTrace {
            segment: None,
            offset,
            samples: 0,
            composited: 0,
            value: None,
            hit: None,
            color: DVec3::ZERO,
            alpha: 0.0,
            terminated_early: false,
            linear: background,
            output: encode(background),
        };
        // The slab box is a box in texture space: intersect there, with t still in world units along `dir`.
        let (origin_tex, dir_tex) = (self.placement.to_tex(origin), self.placement.dir_to_tex(dir));
        let Some((t_start, t_end)) = ray_segment(origin_tex, dir_tex, self.box_lo, self.box_hi, t_near) else {
            return trace;
        };
        let segment = Segment {
            origin,
            dir,
            t_start,
            t_end,
        };
        trace.segment = Some(segment);
        let result = match self.mode {
            CompositeMode::Emission | CompositeMode::Density => self.absorb(&segment, &mut trace),
            CompositeMode::Mip | CompositeMode::MinIp | CompositeMode::Average => self.extremum(&segment, &mut trace),
            CompositeMode::Isosurface => self.isosurface(&segment, &mut trace),
        };
        trace.color = result.color;
        trace.alpha = result.alpha;
        trace.linear = (result.color + (1.0 - result.alpha) * self.background).clamp(DVec3::ZERO, DVec3::ONE);
        trace.output = encode(trace.linear);
        trace
    }

    /// Rule 2's sample distances from the segment's start: `(k + o)·h` while below the segment's length.
    fn sample_offsets(&self, segment: &Segment, offset: f64) -> impl Iterator<Item = f64> + '_ {
        let (length, step) = (segment.length(), self.step);
        (0u32..)
            .map(move |k| (f64::from(k) + offset) * step)
            .take_while(move |&t| t < length)
    }

    /// Texture coordinate of the point at distance `t` from the segment's start.
    fn tex_at(&self, segment: &Segment, t: f64) -> DVec3 {
        self.placement.to_tex(segment.at(segment.t_start + t))
    }

    /// Rules 5–7 for emission–absorption and the density model: the ray is composited segment by segment
    /// between consecutive points — its start, the samples, its end — each segment pre-integrated (segments.rs).
    fn absorb(&self, segment: &Segment, trace: &mut PixelTrace) -> Composite {
        let segments = self.segments.as_ref().expect("segments for emission and density");
        let (mut color, mut alpha) = (DVec3::ZERO, 0.0f64);
        let light = -segment.dir;
        let (mut t_prev, mut v_prev) = (0.0, self.volume.sample(self.tex_at(segment, 0.0)));
        // Rule 2's strides: sample k only where k is a multiple of its brick's stride.
        let samples: Vec<f64> = self
            .sample_offsets(segment, trace.offset)
            .enumerate()
            .filter(|&(k, t)| {
                self.strides
                    .as_ref()
                    .is_none_or(|b| (k as u64).is_multiple_of(b.at(self.tex_at(segment, t))))
            })
            .map(|(_, t)| t)
            .collect();
        let ends = samples
            .iter()
            .map(|&t| (t, true))
            .chain(std::iter::once((segment.length(), false)));
        for (t, is_sample) in ends {
            if is_sample {
                trace.samples += 1;
            }
            let tex = self.tex_at(segment, t);
            let v = self.volume.sample(tex);
            let (vp, t_mid_prev, length) = (v_prev, t_prev, (t - t_prev) / self.step * self.step_length);
            (t_prev, v_prev) = (t, v);
            if v.is_nan() || vp.is_nan() {
                continue;
            }
            let (mut sigma, mut rgb) = segments.mean(vp, v);
            if sigma <= 0.0 {
                continue;
            }
            if self.shading.is_some() || self.gradient_opacity.is_some() {
                let grad = self.gradient(self.tex_at(segment, 0.5 * (t + t_mid_prev)));
                if let Some(reference) = self.gradient_opacity {
                    sigma *= (grad.length() / reference).min(1.0);
                }
                if let Some(shading) = &self.shading {
                    rgb = shade(rgb, self.placement.normal(grad), light, shading);
                }
            }
            let a_step = match self.mode {
                CompositeMode::Density => (sigma * length).min(1.0),
                _ => 1.0 - (-sigma * length).exp(),
            };
            color += (1.0 - alpha) * a_step * rgb;
            alpha += (1.0 - alpha) * a_step;
            trace.composited += 1;
            if alpha >= self.early_termination {
                trace.terminated_early = true;
                break;
            }
        }
        Composite { color, alpha }
    }

    /// Rule 7 for MIP, MinIP and average: the colour of the max/min/mean of the visible samples.
    fn extremum(&self, segment: &Segment, trace: &mut PixelTrace) -> Composite {
        let mut visible = Vec::new();
        for t in self.sample_offsets(segment, trace.offset) {
            trace.samples += 1;
            let v = self.volume.sample(self.tex_at(segment, t));
            if self.visible(v) {
                visible.push(v);
            }
        }
        trace.composited = visible.len() as u32;
        if visible.is_empty() {
            return Composite {
                color: DVec3::ZERO,
                alpha: 0.0,
            };
        }
        let m = match self.mode {
            CompositeMode::Mip => visible.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            CompositeMode::MinIp => visible.iter().copied().fold(f64::INFINITY, f64::min),
            _ => visible.iter().sum::<f64>() / visible.len() as f64,
        };
        trace.value = Some(m);
        Composite {
            color: self.classifier.rgb(m),
            alpha: 1.0,
        }
    }

    /// Rule 7 for the isosurface: the first sample at or above the iso value (window ignored, NaN never counts),
    /// refined by 8 bisection steps on the step before it, coloured by the classification at the iso value
    /// clamped into the window, and shaded.
    fn isosurface(&self, segment: &Segment, trace: &mut PixelTrace) -> Composite {
        let iso = self.iso_value;
        let reaches = |t: f64| {
            let v = self.volume.sample(self.tex_at(segment, t));
            !v.is_nan() && v >= iso
        };
        let mut previous: Option<f64> = None;
        for t in self.sample_offsets(segment, trace.offset) {
            trace.samples += 1;
            if !reaches(t) {
                previous = Some(t);
                continue;
            }
            let t_hit = match previous {
                None => t,
                Some(t_prev) => {
                    let (mut lo, mut hi) = (t_prev, t);
                    for _ in 0..8 {
                        let mid = (lo + hi) / 2.0;
                        if reaches(mid) {
                            hi = mid;
                        } else {
                            lo = mid;
                        }
                    }
                    (lo + hi) / 2.0
                }
            };
            trace.composited = 1;
            trace.hit = Some(segment.t_start + t_hit);
            let shading = self.shading.unwrap_or_default();
            let grad = self.gradient(self.tex_at(segment, t_hit));
            let color = shade(
                self.classifier.iso_rgb(iso),
                self.placement.normal(grad),
                -segment.dir,
                &shading,
            );
            return Composite { color, alpha: 1.0 };
        }
        Composite {
            color: DVec3::ZERO,
            alpha: 0.0,
        }
    }
}

/// Rule 1's placement of the volume's texture-space box [0, 1]³ in the world: voxel centres at (i + ½)/dims,
/// through the file's affine to millimetres (or, with `voxel_axes`, along the world's axes by the voxel sizes),
/// then moved so the box's centre is the origin and scaled so its longest side (voxels × voxel size) is 1.
pub struct Placement {
    /// Texture space to world.
    to_world: DMat4,
    to_tex: DMat4,
    /// Voxel index steps in world units (the columns: one voxel along i, j, k).
    index_to_world: DMat3,
}

impl Placement {
    pub fn new(affine: DMat4, dims: [usize; 3], voxel_axes: bool) -> Placement {
        let n = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64);
        let linear = DMat3::from_mat4(affine);
        let sides = DVec3::new(linear.x_axis.length(), linear.y_axis.length(), linear.z_axis.length());
        let (a, t) = if voxel_axes {
            (DMat3::from_diagonal(sides), DVec3::ZERO)
        } else {
            (linear, affine.w_axis.truncate())
        };
        // mm(tex) = a·(tex ⊙ n − ½) + t; its centre (tex = ½) is a·(n − 1)/2 + t.
        let centre = a * ((n - 1.0) / 2.0) + t;
        let scale = 1.0 / (n * sides).max_element();
        let linear_tex = a * DMat3::from_diagonal(n) * scale;
        let offset = (a * DVec3::splat(-0.5) + t - centre) * scale;
        let to_world = DMat4::from_mat3_translation(linear_tex, offset);
        Placement {
            to_tex: to_world.inverse(),
            to_world,
            index_to_world: a * scale,
        }
    }

    pub fn to_world(&self, tex: DVec3) -> DVec3 {
        self.to_world.transform_point3(tex)
    }

    pub fn to_tex(&self, world: DVec3) -> DVec3 {
        self.to_tex.transform_point3(world)
    }

    /// A world direction (per world unit) in texture space.
    pub fn dir_to_tex(&self, dir: DVec3) -> DVec3 {
        self.to_tex.transform_vector3(dir)
    }

    /// A voxel's side along each index axis, in world units.
    pub fn voxel_sides(&self) -> DVec3 {
        let m = self.index_to_world;
        DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length())
    }

    /// Rule 5: the world gradient of a gradient in value per voxel: `(index_to_world)⁻ᵀ·g`.
    pub fn normal(&self, g: DVec3) -> DVec3 {
        self.index_to_world.inverse().transpose() * g
    }

    /// Whether the placement mirrors (a left-handed affine).
    pub fn mirrors(&self) -> bool {
        self.index_to_world.determinant() < 0.0
    }
}
