//! The independent CPU ray caster the GPU images are proven against.
//!
//! Written from the eight rules in `RenderSettings`'s docs, in f64, sharing no rendering code with the GPU path:
//! the rays (perspective and orthographic) are built from the camera's eye/target/up/fov directly (not from
//! `Camera::view`/`projection`), the box is intersected with the slab method, the volume is filtered here rather
//! than by a sampler, and gradients, shading, every compositing mode, the isosurface bisection and the output
//! encoding are written out here. Shared with the GPU path are only the pure definitions the rules name:
//! `tf::bake` (the classification table, interpolated here in f64) and `settings::jitter_offset` (the per-pixel
//! hash). Where the GPU works in f32 the two differ by rounding only, which the image tolerances absorb.

#![allow(dead_code)]

use glam::DVec3;
use image::{Rgba, RgbaImage};
use volcast::settings::{jitter_offset, CompositeMode, RenderSettings, Shading};
use volcast::tf;
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

/// The ray of pixel (x, y), row 0 at the top: its origin (the eye, or for an orthographic camera the pixel's point
/// on the plane through the eye perpendicular to the view direction) and unit direction.
pub fn pixel_ray(s: &RenderSettings, x: u32, y: u32) -> (DVec3, DVec3) {
    let (origin, dir, _) = CameraBasis::new(s).ray(x, y);
    (origin, dir)
}

/// The part of the ray `origin + t·dir` (t in world units, `dir` a unit vector) inside the axis-aligned box
/// `[lo, hi]` and at `t ≥ t_min`, by the slab method; `None` if empty.
pub fn ray_segment(origin: DVec3, dir: DVec3, lo: DVec3, hi: DVec3, t_min: f64) -> Option<(f64, f64)> {
    let mut t0 = t_min;
    let mut t1 = f64::INFINITY;
    for a in 0..3 {
        if dir[a] == 0.0 {
            // Parallel to this slab: inside it everywhere or nowhere (avoids 0/0 on the boundary).
            if origin[a] < lo[a] || origin[a] > hi[a] {
                return None;
            }
            continue;
        }
        let ta = (lo[a] - origin[a]) / dir[a];
        let tb = (hi[a] - origin[a]) / dir[a];
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    (t0 < t1).then_some((t0, t1))
}

/// The sRGB decoding (IEC 61966-2-1), in f64.
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB encoding, in f64.
pub fn linear_to_srgb(c: f64) -> f64 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Rule 8's encoding of a linear-light colour: clamped to [0,1], then sRGB-encoded (not yet rounded).
pub fn encode(linear: DVec3) -> DVec3 {
    let c = linear.clamp(DVec3::ZERO, DVec3::ONE);
    DVec3::new(linear_to_srgb(c.x), linear_to_srgb(c.y), linear_to_srgb(c.z))
}

/// Rule 4's lookup in f64 over the baked (f32) table: linear interpolation at `v`·(N − 1), `v` clamped to [0,1].
pub fn lookup(lut: &[[f32; 4]], v: f64) -> [f64; 4] {
    let u = v.clamp(0.0, 1.0) * (lut.len() - 1) as f64;
    let i0 = (u.floor() as usize).min(lut.len() - 2);
    let f = u - i0 as f64;
    std::array::from_fn(|k| {
        let (a, b) = (f64::from(lut[i0][k]), f64::from(lut[i0 + 1][k]));
        a + (b - a) * f
    })
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
    Reference::new(volume).render_with_stats(s).1.samples_per_pixel()
}

/// A volume prepared for the reference: normalised values in f64, the box it fills and its data range.
pub struct Reference {
    dims: [usize; 3],
    values: Vec<f64>,
    extent: DVec3,
    range: [f64; 2],
}

impl Reference {
    pub fn new(volume: &Volume) -> Reference {
        let [nx, ny, nz] = volume.dims;
        let mut values = Vec::with_capacity(nx as usize * ny as usize * nz as usize);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    values.push(volume.normalized(x, y, z));
                }
            }
        }
        Reference {
            dims: volume.dims.map(|d| d as usize),
            values,
            extent: volume.extent().as_dvec3(),
            range: volume.range,
        }
    }

    pub fn extent(&self) -> DVec3 {
        self.extent
    }

    /// A voxel's world size along each axis: `extent_i / dims_i`.
    pub fn voxel_world(&self) -> DVec3 {
        DVec3::new(
            self.extent.x / self.dims[0] as f64,
            self.extent.y / self.dims[1] as f64,
            self.extent.z / self.dims[2] as f64,
        )
    }

    /// Rule 2's step `h` in world units: `step_length` × the smallest voxel side.
    pub fn step_world(&self, s: &RenderSettings) -> f64 {
        f64::from(s.step_length) * self.voxel_world().min_element()
    }

    /// Rule 4's table for `s` and this volume's data range.
    pub fn table(&self, s: &RenderSettings) -> Vec<[f32; 4]> {
        tf::bake(&s.classification(), s.window, self.range)
    }

    /// The slab box `[slab_lo, slab_hi]` (texture space) in world space.
    pub fn slab_box_world(&self, s: &RenderSettings) -> (DVec3, DVec3) {
        let to_world = |t: DVec3| (t - 0.5) * self.extent;
        (to_world(s.slab_lo.as_dvec3()), to_world(s.slab_hi.as_dvec3()))
    }

    /// Texture coordinate of world point `p`.
    pub fn tex_of(&self, p: DVec3) -> DVec3 {
        p / self.extent + 0.5
    }

    /// Rule 3: trilinear interpolation at texture coordinate `tex`, texel centres at (i + 0.5)/dim, clamped to
    /// the edge. A NaN among the eight texels gives NaN, as a filtering `a + w·(b - a)` does even at `w = 0`.
    pub fn sample(&self, tex: DVec3) -> f64 {
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
        let [nx, ny, _] = self.dims;
        let at = |x: usize, y: usize, z: usize| self.values[x + nx * (y + ny * z)];
        let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
        let [x0, x1] = idx[0];
        let [y0, y1] = idx[1];
        let [z0, z1] = idx[2];
        let c00 = lerp(at(x0, y0, z0), at(x1, y0, z0), w[0]);
        let c10 = lerp(at(x0, y1, z0), at(x1, y1, z0), w[0]);
        let c01 = lerp(at(x0, y0, z1), at(x1, y0, z1), w[0]);
        let c11 = lerp(at(x0, y1, z1), at(x1, y1, z1), w[0]);
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

    pub fn render(&self, s: &RenderSettings) -> RgbaImage {
        self.render_with_stats(s).0
    }

    /// Renders rows in parallel bands, one per available core.
    pub fn render_with_stats(&self, s: &RenderSettings) -> (RgbaImage, RenderStats) {
        let frame = Frame::new(self, s);
        let (width, height) = (s.width, s.height);
        let mut image = RgbaImage::new(width, height);
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(height as usize)
            .max(1);
        let rows_per_band = (height as usize).div_ceil(threads);
        let row_bytes = width as usize * 4;
        let mut stats = RenderStats::default();
        std::thread::scope(|scope| {
            let bands: Vec<_> = image
                .chunks_mut(rows_per_band * row_bytes)
                .enumerate()
                .map(|(band, pixels)| {
                    let frame = &frame;
                    scope.spawn(move || {
                        let mut stats = RenderStats::default();
                        let first_row = band * rows_per_band;
                        for (i, pixel) in pixels.chunks_exact_mut(4).enumerate() {
                            let x = (i % width as usize) as u32;
                            let y = (first_row + i / width as usize) as u32;
                            let trace = frame.trace(x, y);
                            stats.pixels += 1;
                            stats.hit_pixels += u64::from(trace.segment.is_some());
                            stats.samples += u64::from(trace.samples);
                            stats.composited += u64::from(trace.composited);
                            stats.terminated_early += u64::from(trace.terminated_early);
                            pixel.copy_from_slice(&quantise(trace.output).0);
                        }
                        stats
                    })
                })
                .collect();
            for band in bands {
                stats.add(&band.join().expect("reference render thread panicked"));
            }
        });
        (image, stats)
    }

    /// Traces one pixel, keeping the unquantised result (for checks against closed forms).
    pub fn trace(&self, s: &RenderSettings, x: u32, y: u32) -> PixelTrace {
        Frame::new(self, s).trace(x, y)
    }

    /// Prepares `s` once (the table, the camera) for tracing many pixels with [`Tracer::trace`].
    pub fn tracer(&self, s: &RenderSettings) -> Tracer<'_> {
        Tracer(Frame::new(self, s))
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

/// Rule 8's storage of an sRGB-encoded colour ([`PixelTrace::output`], or see [`encode`]): 8-bit unsigned
/// normalised, rounded, opaque.
pub fn quantise(srgb: DVec3) -> Rgba<u8> {
    let q = |c: f64| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
    Rgba([q(srgb.x), q(srgb.y), q(srgb.z), 255])
}

/// The camera as an orthonormal basis: `forward` towards the target, `right`, and `up` completing it.
struct CameraBasis {
    eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    tan_half_fov: f64,
    aspect: f64,
    width: f64,
    height: f64,
    /// Orthographic: half the view's height, `|eye − target|·tan(fov/2)`.
    ortho_half_height: Option<f64>,
    near: f64,
}

impl CameraBasis {
    fn new(s: &RenderSettings) -> CameraBasis {
        let c = &s.camera;
        let eye = c.eye.as_dvec3();
        let target = c.target.as_dvec3();
        let forward = (target - eye).normalize();
        let right = forward.cross(c.up.as_dvec3()).normalize();
        let up = right.cross(forward);
        let tan_half_fov = (f64::from(c.fov_y_deg).to_radians() * 0.5).tan();
        CameraBasis {
            eye,
            forward,
            right,
            up,
            tan_half_fov,
            aspect: f64::from(s.width) / f64::from(s.height),
            width: f64::from(s.width),
            height: f64::from(s.height),
            ortho_half_height: c.ortho.then(|| (target - eye).length() * tan_half_fov),
            near: f64::from(c.near),
        }
    }

    /// Normalised device coordinates of pixel (x, y)'s centre; y grows downwards with the row.
    fn ndc(&self, x: u32, y: u32) -> (f64, f64) {
        (
            2.0 * (f64::from(x) + 0.5) / self.width - 1.0,
            2.0 * (f64::from(y) + 0.5) / self.height - 1.0,
        )
    }

    /// Rule 1: pixel (x, y)'s ray origin, unit direction, and the distance along it at which the view depth
    /// `dot(p − eye, forward)` reaches the near plane.
    fn ray(&self, x: u32, y: u32) -> (DVec3, DVec3, f64) {
        let (nx, ny) = self.ndc(x, y);
        match self.ortho_half_height {
            Some(half_h) => {
                // Parallel to the view direction from the plane through the eye perpendicular to it: the view
                // depth of origin + t·forward is t itself.
                let origin = self.eye + nx * half_h * self.aspect * self.right - ny * half_h * self.up;
                (origin, self.forward, self.near)
            }
            None => {
                let dir = (self.forward + nx * self.tan_half_fov * self.aspect * self.right
                    - ny * self.tan_half_fov * self.up)
                    .normalize();
                // A unit ray from the eye reaches view depth `near` after near / cos(angle to forward).
                (self.eye, dir, self.near / dir.dot(self.forward))
            }
        }
    }
}

/// Everything per-frame that `trace` needs, computed once.
struct Frame<'a> {
    volume: &'a Reference,
    camera: CameraBasis,
    box_lo: DVec3,
    box_hi: DVec3,
    step: f64,
    /// Rule 4's table: linear RGB and per-voxel-step opacity.
    lut: Vec<[f32; 4]>,
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
    jitter: Option<u32>,
    early_termination: f64,
    /// Linear light.
    background: DVec3,
    voxel_world: DVec3,
}

/// The result of one mode's march: colour and opacity before rule 8.
struct Composite {
    color: DVec3,
    alpha: f64,
}

impl<'a> Frame<'a> {
    fn new(volume: &'a Reference, s: &RenderSettings) -> Frame<'a> {
        let (box_lo, box_hi) = volume.slab_box_world(s);
        let shading = match s.mode {
            CompositeMode::Isosurface => Some(s.shading.unwrap_or_default()),
            _ => s.shading,
        };
        let bg = s.background.as_dvec3();
        Frame {
            volume,
            camera: CameraBasis::new(s),
            box_lo,
            box_hi,
            step: volume.step_world(s),
            lut: volume.table(s),
            window: s.window.map(f64::from),
            step_length: f64::from(s.step_length),
            mode: s.mode,
            iso_value: f64::from(s.iso_value),
            density: f64::from(s.density),
            shading,
            gradient_opacity: s.gradient_opacity.map(f64::from),
            jitter: s.jitter,
            early_termination: f64::from(s.early_termination),
            background: DVec3::new(srgb_to_linear(bg.x), srgb_to_linear(bg.y), srgb_to_linear(bg.z)),
            voxel_world: volume.voxel_world(),
        }
    }

    fn rgb(&self, v: f64) -> DVec3 {
        let [r, g, b, _] = lookup(&self.lut, v);
        DVec3::new(r, g, b)
    }

    /// Rule 3's visibility test (every mode but isosurface).
    fn visible(&self, v: f64) -> bool {
        !v.is_nan() && v >= self.window[0] && v <= self.window[1]
    }

    fn trace(&self, x: u32, y: u32) -> PixelTrace {
        let (origin, dir, t_near) = self.camera.ray(x, y);
        let offset = self.jitter.map_or(0.5, |seed| f64::from(jitter_offset(x, y, seed)));
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
        let Some((t_start, t_end)) = ray_segment(origin, dir, self.box_lo, self.box_hi, t_near) else {
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
        self.volume.tex_of(segment.at(segment.t_start + t))
    }

    /// Rules 5–7 for emission–absorption and the density model.
    fn absorb(&self, segment: &Segment, trace: &mut PixelTrace) -> Composite {
        let (mut color, mut alpha) = (DVec3::ZERO, 0.0f64);
        let light = -segment.dir;
        for t in self.sample_offsets(segment, trace.offset) {
            trace.samples += 1;
            let tex = self.tex_at(segment, t);
            let v = self.volume.sample(tex);
            if !self.visible(v) {
                continue;
            }
            let [r, g, b, mut a] = lookup(&self.lut, v);
            let mut rgb = DVec3::new(r, g, b);
            if self.shading.is_some() || self.gradient_opacity.is_some() {
                let grad = self.volume.gradient(tex);
                if let Some(reference) = self.gradient_opacity {
                    a *= (grad.length() / reference).min(1.0);
                }
                if let Some(shading) = &self.shading {
                    rgb = shade(rgb, grad / self.voxel_world, light, shading);
                }
            }
            let a_step = match self.mode {
                CompositeMode::Density => (a * self.density * self.step_length).min(1.0),
                _ => 1.0 - (1.0 - a).powf(self.step_length),
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
            color: self.rgb(m),
            alpha: 1.0,
        }
    }

    /// Rule 7 for the isosurface: the first sample at or above the iso value (window ignored, NaN never counts),
    /// refined by 8 bisection steps on the step before it, coloured by the table at the iso value and shaded.
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
            let grad = self.volume.gradient(self.tex_at(segment, t_hit));
            let color = shade(self.rgb(iso), grad / self.voxel_world, -segment.dir, &shading);
            return Composite { color, alpha: 1.0 };
        }
        Composite {
            color: DVec3::ZERO,
            alpha: 0.0,
        }
    }
}
