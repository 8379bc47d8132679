//! Counting the march's samples on the CPU by replaying its rules, so the march shader is left untouched.

use crate::render::skip::{self, BrickGrid};
use crate::render::{FrameUniforms, PoolInfo, VolumeInfo};
use crate::scene::settings::{self, CompositeMode, RenderSettings};
use crate::transfer::function as tf;
use crate::transfer::preintegrate;
use crate::volume::{Geometry, Volume};
use glam::{Mat3, Mat4, Vec3};

/// Counts the samples the march takes by replaying its rules on the CPU (settings.rs rules 1–7) in the shader's
/// f32 arithmetic: the analytic ray setup built from the camera basis as `FrameUniforms::new` builds it, samples at
/// `(k + o)·h` (jitter included), trilinear values, the window, the baked classification table, the compositing
/// mode, pre-integration and early termination. Two counts per pixel:
/// - *segment*: sample positions on the ray segment, before early termination (an upper bound);
/// - *taken*: 3D-texture samples the march actually takes: one per step until the ray ends, one more where the
///   emission/density march resumes after a leap (its first segment's start), plus six per step that computes a
///   gradient (shading or gradient opacity, on steps with opacity > 0) and, in isosurface mode,
///   the bisection's eight and the hit's gradient.
///
/// Approximations, all small: the entry/exit method finds the same segments to float precision (docs/rendering.md, "Two ray
/// setups"), so one count serves both setups; lavapipe filters 8-bit textures with 8-bit weights, so a ray may end
/// a step earlier or later than here; gradient opacity is not modelled (its rays may run longer on the GPU).
/// When the march changes how many samples it takes (empty-space skipping, adaptive steps), change
/// [`SampleCounter::pixel`] with it.
pub struct SampleCounter {
    dims: [usize; 3],
    values: Vec<f32>,
    geometry: Geometry,
    range: [f64; 2],
    /// The renderer's brick grid, for the occupancy empty-space skipping leaps by.
    bricks: BrickGrid,
}

/// Mean samples per pixel of the image (pixels that miss the box count as zero).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SampleCount {
    pub segment_per_pixel: f64,
    pub taken_per_pixel: f64,
}

/// What every pixel's replay shares, in texture space (the fields of `FrameUniforms` the march reads).
struct RayFrame {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    down: Vec3,
    near: f32,
    slab_lo: Vec3,
    slab_hi: Vec3,
    /// Texture space to world (its linear part measures the ray).
    to_world: Mat3,
    h: f32,
    max_steps: u64,
    viewport: [f32; 2],
    window: [f32; 2],
    /// The pre-integration table the emission/density march reads.
    integrals: Vec<[f32; 4]>,
    step_length: f32,
    mode: CompositeMode,
    /// Rule 7's surfaces by value: (value, opacity).
    surfaces: Vec<(f32, f32)>,
    gradients: bool,
    jitter: Option<u32>,
    early_termination: f32,
    /// Per brick 0 where empty-space skipping leaps, else its stride (None: no lookups, every sample taken).
    classes: Option<Vec<u8>>,
}

/// Texture samples one central-difference gradient takes.
const GRADIENT_SAMPLES: u64 = 6;
/// Bisection steps of the isosurface mode.
const ISO_BISECTIONS: u64 = 8;

/// Where one pixel's ray crosses the slab box, in texture space (`FrameUniforms`' analytic setup); named as
/// march.glsl names its ray.
struct PixelRay {
    /// Where the ray enters the box (or starts, past the near plane).
    a: Vec3,
    /// From `a` to where the ray leaves the box.
    d: Vec3,
    /// The length of `d` in the world.
    len: f32,
    /// The samples' offset: sample k lies at `(k + o)·h` (0.5, or the pixel's jitter).
    o: f32,
}

impl PixelRay {
    /// Pixel (x, y)'s ray; None where it misses the box.
    fn of(f: &RayFrame, x: u32, y: u32) -> Option<PixelRay> {
        let ndc_x = (x as f32 + 0.5) / f.viewport[0] * 2.0 - 1.0;
        let ndc_y = (y as f32 + 0.5) / f.viewport[1] * 2.0 - 1.0;
        let dir = f.forward + ndc_x * f.right + ndc_y * f.down;
        let inv = Vec3::ONE / dir;
        let t_lo = (f.slab_lo - f.eye) * inv;
        let t_hi = (f.slab_hi - f.eye) * inv;
        let t0 = t_lo.min(t_hi).max_element().max(f.near);
        let t1 = t_lo.max(t_hi).min_element();
        // NaN (a ray along a face) misses, as in the shader's `!(t1 > t0)`.
        if t1.is_nan() || t0.is_nan() || t1 <= t0 {
            return None;
        }
        let d = dir * (t1 - t0);
        Some(PixelRay {
            a: f.eye + dir * t0,
            d,
            len: (f.to_world * d).length(),
            o: f.jitter.map_or(0.5, |seed| settings::jitter_offset(x, y, seed)),
        })
    }

    /// The point at world distance `t` from the ray's start.
    fn at(&self, t: f32) -> Vec3 {
        self.a + self.d * (t / self.len)
    }
}

/// The march's state between the samples it takes.
struct Replay {
    opacity: f32,
    taken: u64,
    /// The previous point (the segment's start): its value, where it is, whether the march took it and whether
    /// its brick was occupied.
    previous: f32,
    t_prev: f32,
    previous_taken: bool,
    previous_occupied: bool,
}

impl Replay {
    /// The isosurface march's step from value `vp` to `v` at sample `k`; true where the ray ends.
    fn cross_surfaces(&mut self, f: &RayFrame, k: u64, vp: f32, v: f32, had_previous: bool) -> bool {
        // Every surface crossed (NaN, and samples leapt over, below all) costs its bisection and gradient, and
        // adds its opacity.
        let below = |v: f32| if v.is_nan() { f32::NEG_INFINITY } else { v };
        let (vp, v) = (if had_previous { below(vp) } else { f32::NEG_INFINITY }, below(v));
        for &(iso, alpha) in &f.surfaces {
            if (vp < iso) != (v < iso) {
                self.taken += if k > 0 { ISO_BISECTIONS } else { 0 } + GRADIENT_SAMPLES;
                self.opacity += (1.0 - self.opacity) * alpha;
            }
        }
        self.opacity >= f.early_termination
    }

    /// The emission/density march's segment from value `vp` to `v`, `length` steps long; true where the ray ends.
    fn absorb(&mut self, f: &RayFrame, vp: f32, v: f32, length: f32) -> bool {
        let mean = preintegrate::segment_mean(&f.integrals, f.window, vp, v);
        if v.is_nan() || vp.is_nan() || mean[3] <= 0.0 {
            return false;
        }
        if f.gradients {
            self.taken += GRADIENT_SAMPLES;
        }
        let (_, a_step) = preintegrate::segment(mean, length, f.mode == CompositeMode::Density);
        self.opacity += (1.0 - self.opacity) * a_step;
        self.opacity >= f.early_termination
    }
}

impl SampleCounter {
    pub fn new(volume: &Volume) -> SampleCounter {
        let [nx, ny, nz] = volume.dims;
        let mut values = Vec::with_capacity(volume.voxel_count());
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    values.push(volume.normalized(x, y, z) as f32);
                }
            }
        }
        SampleCounter {
            dims: volume.dims.map(|d| d as usize),
            values,
            geometry: volume.geometry,
            range: volume.range,
            bricks: BrickGrid::new(volume),
        }
    }

    /// The class of the brick holding the sample at `p` (texture space): 0 where empty-space skipping leaps,
    /// else the stride (rule 2). Every sample of a span lies in a brick of the span's class (render/skip.rs), so
    /// this is the march's choice up to float rounding at brick faces.
    fn brick_class(&self, f: &RayFrame, p: Vec3) -> u8 {
        let Some(classes) = &f.classes else {
            return 1;
        };
        let b = self.bricks.bricks;
        let brick = |a: usize| {
            let i = (p[a] * self.dims[a] as f32 / skip::BRICK as f32).floor();
            i.clamp(0.0, (b[a] - 1) as f32) as usize
        };
        classes[brick(0) + b[0] as usize * (brick(1) + b[1] as usize * brick(2))]
    }

    fn sample(&self, p: Vec3) -> f32 {
        let mut idx = [[0usize; 2]; 3];
        let mut w = [0f32; 3];
        for a in 0..3 {
            let n = self.dims[a];
            let u = p[a] * n as f32 - 0.5;
            let i0 = u.floor();
            w[a] = u - i0;
            let clamp = |i: f32| i.clamp(0.0, (n - 1) as f32) as usize;
            idx[a] = [clamp(i0), clamp(i0 + 1.0)];
        }
        let [nx, ny, _] = self.dims;
        let at = |x: usize, y: usize, z: usize| self.values[x + nx * (y + ny * z)];
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        let [x0, x1] = idx[0];
        let [y0, y1] = idx[1];
        let [z0, z1] = idx[2];
        let c00 = lerp(at(x0, y0, z0), at(x1, y0, z0), w[0]);
        let c10 = lerp(at(x0, y1, z0), at(x1, y1, z0), w[0]);
        let c01 = lerp(at(x0, y0, z1), at(x1, y0, z1), w[0]);
        let c11 = lerp(at(x0, y1, z1), at(x1, y1, z1), w[0]);
        lerp(lerp(c00, c10, w[1]), lerp(c01, c11, w[1]), w[2])
    }

    fn frame(&self, s: &RenderSettings) -> RayFrame {
        // The march's own rays: the uniforms the shader reads.
        let info = VolumeInfo {
            dims: self.dims.map(|d| d as u32),
            geometry: self.geometry,
            scale_bias: (1.0, 0.0),
            range: self.range,
            pool: PoolInfo::whole(self.dims.map(|d| d as u32)),
            held: 0,
            step_level: 0,
            part: None,
            source_voxels: 1.0,
        };
        let u = FrameUniforms::new(s, &info);
        let v3 = |a: [f32; 4]| Vec3::new(a[0], a[1], a[2]);
        let lut = tf::bake(&s.classification(), s.colour.window, self.range);
        RayFrame {
            eye: v3(u.eye_tex),
            forward: v3(u.ray_forward),
            right: v3(u.ray_right),
            down: v3(u.ray_down),
            near: s.camera.near,
            slab_lo: s.cut.slab_lo,
            slab_hi: s.cut.slab_hi,
            to_world: Mat3::from_mat4(Mat4::from_cols_array(&u.tex_to_world)),
            h: u.extent[3],
            max_steps: u.viewport[2] as u64,
            viewport: [s.marched_size().0 as f32, s.marched_size().1 as f32],
            window: s.colour.window,
            classes: s.looks_up_bricks().then(|| self.bricks.classify(&lut, s)),
            integrals: preintegrate::integral_table(
                &lut,
                (s.compositing.mode == CompositeMode::Density).then_some(s.compositing.density),
            ),
            step_length: s.sampling.step_length,
            mode: s.compositing.mode,
            surfaces: s.isosurfaces().iter().map(|x| (x.value, x.opacity)).collect(),
            gradients: s.lighting.shading.is_some() || s.lighting.gradient_opacity.is_some(),
            jitter: s.sampling.jitter,
            early_termination: s.compositing.early_termination,
        }
    }

    /// (segment, taken) samples of pixel (x, y); mirrors march_analytic.frag and march.glsl.
    fn pixel(&self, f: &RayFrame, x: u32, y: u32) -> (u64, u64) {
        let Some(ray) = PixelRay::of(f, x, y) else {
            return (0, 0);
        };
        let segment = ((ray.len / f.h - ray.o).ceil().max(0.0) as u64).min(f.max_steps);
        (segment, self.taken(f, &ray))
    }

    /// The samples the march takes on `ray`: the march loop of march.glsl, replayed.
    fn taken(&self, f: &RayFrame, ray: &PixelRay) -> u64 {
        // The emission/density march composites segments between the ray's start, its samples and its end.
        let absorbing = matches!(f.mode, CompositeMode::Emission | CompositeMode::Density);
        let mut m = Replay {
            opacity: 0.0,
            taken: u64::from(absorbing),
            previous: self.sample(ray.a),
            t_prev: 0.0,
            previous_taken: true,
            previous_occupied: true,
        };
        let mut reached_end = false;
        for k in 0..f.max_steps {
            let t = (k as f32 + ray.o) * f.h;
            if t >= ray.len {
                reached_end = true;
                break;
            }
            let p = ray.at(t);
            let class = self.brick_class(f, p);
            let occupied = class != 0;
            // A stride's samples are those whose index is its multiple; the others are passed, not leapt over.
            if occupied && !k.is_multiple_of(u64::from(class)) {
                continue;
            }
            // The emission/density march takes the first sample past occupied bricks (its segment), then leaps.
            let exit_sample = absorbing && m.previous_taken && m.previous_occupied;
            if !(occupied || exit_sample) {
                // Leapt over: nothing there can be visible (nor reach the iso value), so the replay goes on.
                m.previous_taken = false;
                continue;
            }
            m.previous_occupied = occupied;
            m.taken += 1;
            let v = self.sample(p);
            // The emission/density march samples the segment's start again where it leapt: the last sample
            // leapt over.
            if !m.previous_taken {
                m.t_prev = self.resumed_at(f, ray, k, class);
                m.previous = self.sample(ray.at(m.t_prev));
                if absorbing {
                    m.taken += 1;
                }
            }
            let (vp, length) = (m.previous, f.step_length * (t - m.t_prev) / f.h);
            let had_previous = m.previous_taken && k > 0;
            (m.previous, m.t_prev, m.previous_taken) = (v, t, true);
            let ended = match f.mode {
                CompositeMode::Mip | CompositeMode::MinIp | CompositeMode::Average => false,
                CompositeMode::Isosurface => m.cross_surfaces(f, k, vp, v, had_previous),
                CompositeMode::Emission | CompositeMode::Density => m.absorb(f, vp, v, length),
            };
            if ended {
                return m.taken;
            }
        }
        // The last segment, to the ray's end, unless the march leapt over what lies before it.
        if absorbing && reached_end && m.previous_taken && m.previous_occupied {
            m.taken += 1;
        }
        m.taken
    }

    /// Where the march resumes after a leap that ends at sample `k` (of a brick of class `class`): the last
    /// sample leapt over, the segment's start (0 at the ray's start).
    fn resumed_at(&self, f: &RayFrame, ray: &PixelRay, k: u64, class: u8) -> f32 {
        let first = ((k + 1).saturating_sub(u64::from(class))..=k)
            .find(|&i| self.brick_class(f, ray.at((i as f32 + ray.o) * f.h)) != 0)
            .unwrap_or(k);
        if first == 0 {
            0.0
        } else {
            (first as f32 - 1.0 + ray.o) * f.h
        }
    }

    /// Counts over the whole image of `s`, rows split across the available cores: its rays (rule 12: one per
    /// `ray_spacing`² pixels where they are spaced), per pixel of the output.
    pub fn count(&self, s: &RenderSettings) -> SampleCount {
        let frame = self.frame(s);
        let (width, height) = s.marched_size();
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .clamp(1, height as usize);
        let totals: Vec<(u64, u64)> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..threads)
                .map(|t| {
                    let frame = &frame;
                    scope.spawn(move || {
                        let mut sum = (0u64, 0u64);
                        for y in (t as u32..height).step_by(threads) {
                            for x in 0..width {
                                let (seg, taken) = self.pixel(frame, x, y);
                                sum.0 += seg;
                                sum.1 += taken;
                            }
                        }
                        sum
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap_or((0, 0))).collect()
        });
        let pixels = (u64::from(s.width) * u64::from(s.height)).max(1) as f64;
        let (seg, taken) = totals.iter().fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        SampleCount {
            segment_per_pixel: seg as f64 / pixels,
            taken_per_pixel: taken as f64 / pixels,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::Camera;
    use crate::volume;

    #[test]
    fn counter_counts_the_segment_of_an_axis_aligned_ray() {
        // A ray straight down the box's axis crosses 64 voxels of a 64³ volume: 64 samples at 1-voxel steps, and the
        // emission march also reads the ray's start and end (its first and last segments' outer ends).
        let v = volume::builtin("box", Some(64)).unwrap();
        let mut s = RenderSettings::new(1, 1, v.extent());
        s.camera = Camera::orbit(0.0, 0.0, 3.0, Vec3::ZERO);
        s.colour.step_alpha = 0.0;
        s.sampling.skip_empty = false;
        let counter = SampleCounter::new(&v);
        let c = counter.count(&s);
        assert_eq!(c.segment_per_pixel, 64.0);
        assert_eq!(c.taken_per_pixel, 66.0, "nothing is opaque, so no ray ends early");
        s.sampling.skip_empty = true;
        let c = counter.count(&s);
        assert_eq!(c.segment_per_pixel, 64.0);
        assert_eq!(
            c.taken_per_pixel, 2.0,
            "nothing is visible: the start and the first sample (its segment), then a leap over every brick"
        );
        s.colour.step_alpha = 1.0;
        s.colour.window = [0.0, 1.0];
        let c = counter.count(&s);
        assert_eq!(c.taken_per_pixel, 2.0, "an opaque first segment ends the ray");
        // A faint constant box at 0.5-voxel steps: 128 samples, every fourth taken where bricks stride 4
        // (extinction 0.0202 × 0.5 × 4 ≤ 0.05, no spread), plus the ray's start and end.
        s.colour.step_alpha = 0.02;
        s.sampling.step_length = 0.5;
        s.sampling.max_stride = 4;
        let c = counter.count(&s);
        assert_eq!((c.segment_per_pixel, c.taken_per_pixel), (128.0, 34.0));
        s.sampling.max_stride = 1;
        assert_eq!(counter.count(&s).taken_per_pixel, 130.0);
    }
}
