//! The independent CPU ray caster the GPU images are proven against.
//!
//! Written from the eight rules in `RenderSettings`'s docs, in f64, sharing no code with the GPU path: the ray is
//! built from the camera's eye/target/up/fov directly (not from `Camera::view`/`projection`), the box is
//! intersected with the slab method, and the volume is filtered here rather than by a sampler. Where the GPU works
//! in f32 the two differ by rounding only, which the image tolerances absorb.

#![allow(dead_code)]

use glam::DVec3;
use image::{Rgba, RgbaImage};
use volcast::settings::RenderSettings;
use volcast::volume::Volume;

/// A ray segment inside the slab box, in world units along the unit direction `dir` from `origin` (the eye).
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
    /// Sample positions visited (rule 2), up to early termination.
    pub samples: u32,
    /// Samples that passed the NaN and window tests and were composited.
    pub composited: u32,
    /// Accumulated colour `C` (premultiplied by opacity).
    pub color: DVec3,
    /// Accumulated opacity `A`.
    pub alpha: f64,
    pub terminated_early: bool,
    /// Rule 8 before quantisation: `C + (1 - A)·background`, clamped to [0,1].
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

/// The ray through the centre of pixel (x, y), row 0 at the top: the eye and a unit direction.
pub fn pixel_ray(s: &RenderSettings, x: u32, y: u32) -> (DVec3, DVec3) {
    let basis = CameraBasis::new(s);
    (basis.eye, basis.direction(x, y))
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

/// Renders `volume` with `s` by the CPU reference. Prefer [`Reference`] to render one volume several times.
pub fn render_reference(volume: &Volume, s: &RenderSettings) -> RgbaImage {
    Reference::new(volume).render(s)
}

/// Mean sample positions visited per pixel when rendering `volume` with `s`.
pub fn samples_per_pixel(volume: &Volume, s: &RenderSettings) -> f64 {
    Reference::new(volume).render_with_stats(s).1.samples_per_pixel()
}

/// A volume prepared for the reference: normalised values in f64 and the box it fills.
pub struct Reference {
    dims: [usize; 3],
    values: Vec<f64>,
    extent: DVec3,
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
        }
    }

    pub fn extent(&self) -> DVec3 {
        self.extent
    }

    /// Rule 2's step `h` in world units: `step_length` × the smallest voxel side.
    pub fn step_world(&self, s: &RenderSettings) -> f64 {
        let voxel = (0..3)
            .map(|a| self.extent[a] / self.dims[a] as f64)
            .fold(f64::INFINITY, f64::min);
        f64::from(s.step_length) * voxel
    }

    /// The slab box `[slab_lo, slab_hi]` (texture space) in world space.
    pub fn slab_box_world(&self, s: &RenderSettings) -> (DVec3, DVec3) {
        let to_world = |t: DVec3| (t - 0.5) * self.extent;
        (to_world(s.slab_lo.as_dvec3()), to_world(s.slab_hi.as_dvec3()))
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
}

/// Rule 8's storage: 8-bit unsigned normalised, rounded, opaque.
pub fn quantise(rgb: DVec3) -> Rgba<u8> {
    let q = |c: f64| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
    Rgba([q(rgb.x), q(rgb.y), q(rgb.z), 255])
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
}

impl CameraBasis {
    fn new(s: &RenderSettings) -> CameraBasis {
        let c = &s.camera;
        let eye = c.eye.as_dvec3();
        let forward = (c.target.as_dvec3() - eye).normalize();
        let right = forward.cross(c.up.as_dvec3()).normalize();
        let up = right.cross(forward);
        CameraBasis {
            eye,
            forward,
            right,
            up,
            tan_half_fov: (f64::from(c.fov_y_deg).to_radians() * 0.5).tan(),
            aspect: f64::from(s.width) / f64::from(s.height),
            width: f64::from(s.width),
            height: f64::from(s.height),
        }
    }

    /// Unit direction through the centre of pixel (x, y); normalised device y grows downwards with the row.
    fn direction(&self, x: u32, y: u32) -> DVec3 {
        let ndc_x = 2.0 * (f64::from(x) + 0.5) / self.width - 1.0;
        let ndc_y = 2.0 * (f64::from(y) + 0.5) / self.height - 1.0;
        (self.forward + ndc_x * self.tan_half_fov * self.aspect * self.right - ndc_y * self.tan_half_fov * self.up)
            .normalize()
    }
}

/// Everything per-frame that `trace` needs, computed once.
struct Frame<'a> {
    volume: &'a Reference,
    camera: CameraBasis,
    near: f64,
    box_lo: DVec3,
    box_hi: DVec3,
    step: f64,
    lut: [[f64; 3]; 256],
    window: [f64; 2],
    step_alpha: f64,
    /// Exponent of rule 6's opacity correction.
    step_length: f64,
    multiplied_alpha: bool,
    early_termination: f64,
    background: DVec3,
}

impl<'a> Frame<'a> {
    fn new(volume: &'a Reference, s: &RenderSettings) -> Frame<'a> {
        // Rule 5 takes colour only from the table; opacity comes from rule 6, so the table's alpha is unused.
        let lut = s
            .colormap
            .lut()
            .map(|[r, g, b, _]| [r, g, b].map(|c| f64::from(c) / 255.0));
        let (box_lo, box_hi) = volume.slab_box_world(s);
        Frame {
            volume,
            camera: CameraBasis::new(s),
            near: f64::from(s.camera.near),
            box_lo,
            box_hi,
            step: volume.step_world(s),
            lut,
            window: s.window.map(f64::from),
            step_alpha: f64::from(s.step_alpha),
            step_length: f64::from(s.step_length),
            multiplied_alpha: s.multiplied_alpha,
            early_termination: f64::from(s.early_termination),
            background: s.background.as_dvec3(),
        }
    }

    fn lut_rgb(&self, c: f64) -> DVec3 {
        let index = c * 255.0;
        let i0 = (index.floor() as usize).min(254);
        let t = index - i0 as f64;
        let (a, b) = (DVec3::from_array(self.lut[i0]), DVec3::from_array(self.lut[i0 + 1]));
        a + t * (b - a)
    }

    fn trace(&self, x: u32, y: u32) -> PixelTrace {
        let dir = self.camera.direction(x, y);
        // The near plane is at view depth `near`, which a unit ray reaches after near / cos(angle to forward).
        let t_near = self.near / dir.dot(self.camera.forward);
        let mut trace = PixelTrace {
            segment: None,
            samples: 0,
            composited: 0,
            color: DVec3::ZERO,
            alpha: 0.0,
            terminated_early: false,
            output: self.background.clamp(DVec3::ZERO, DVec3::ONE),
        };
        let Some((t_start, t_end)) = ray_segment(self.camera.eye, dir, self.box_lo, self.box_hi, t_near) else {
            return trace;
        };
        let segment = Segment {
            origin: self.camera.eye,
            dir,
            t_start,
            t_end,
        };
        trace.segment = Some(segment);
        let length = segment.length();
        let [w_lo, w_hi] = self.window;
        let inv_extent = 1.0 / self.volume.extent;
        let (mut color, mut alpha) = (DVec3::ZERO, 0.0f64);
        let mut k = 0u32;
        loop {
            let t = (f64::from(k) + 0.5) * self.step;
            if t >= length {
                break;
            }
            k += 1;
            trace.samples += 1;
            let tex = segment.at(t_start + t) * inv_extent + 0.5;
            let v = self.volume.sample(tex);
            if v.is_nan() || v < w_lo || v > w_hi {
                continue;
            }
            let c = (v - w_lo) / (w_hi - w_lo);
            let a = if self.multiplied_alpha {
                c * self.step_alpha
            } else {
                self.step_alpha
            };
            let a = 1.0 - (1.0 - a).powf(self.step_length);
            color += (1.0 - alpha) * a * self.lut_rgb(c);
            alpha += (1.0 - alpha) * a;
            trace.composited += 1;
            if alpha >= self.early_termination {
                trace.terminated_early = true;
                break;
            }
        }
        trace.color = color;
        trace.alpha = alpha;
        trace.output = (color + (1.0 - alpha) * self.background).clamp(DVec3::ZERO, DVec3::ONE);
        trace
    }
}
