//! Rule 9's light grid for the reference, written from the rule (`RenderSettings` docs) in f64: the shadow sweep
//! away from the light and the 14-ray ambient occlusion, over a grid of cells that sample the volume by rule 3.

use super::classify::Classifier;
use super::placement::Placement;
use super::reference::Reference;
use glam::DVec3;
use volcast::scene::settings::{CompositeMode, RenderSettings};

/// The grid: per cell T and O, and where to read T from a lit point.
pub struct LightGridRef {
    n: [usize; 3],
    t: Vec<f64>,
    o: Vec<f64>,
    /// 1.5 steps towards the light, texture space.
    read_offset: DVec3,
}

/// Rule 9's extinction of value v.
fn extinction(s: &RenderSettings, classifier: &Classifier, wall: f64, v: f64) -> f64 {
    if v.is_nan() {
        return 0.0;
    }
    match s.compositing.mode {
        CompositeMode::Isosurface => {
            if v >= wall {
                32.0
            } else {
                0.0
            }
        }
        CompositeMode::Density => (classifier.at(v).1 * f64::from(s.compositing.density)).min(32.0),
        _ => (-(1.0 - classifier.at(v).1.clamp(0.0, 1.0)).ln()).min(32.0),
    }
}

/// The key light (rule 9) for `s`'s camera, written from its definition: towards the eye, 0.6 up and 0.6 left.
fn key_light(s: &RenderSettings) -> DVec3 {
    let c = &s.camera;
    let view = (c.eye - c.target).as_dvec3().normalize();
    let forward = -view;
    let right = forward.cross(c.up.as_dvec3()).normalize();
    let up = right.cross(forward);
    (view + 0.6 * (up - right)).normalize()
}

/// Rule 5's light direction as rule 9 resolves it (None: a headlight).
pub fn light_direction(s: &RenderSettings) -> Option<DVec3> {
    match s.lighting.light.direction {
        Some(d) => Some(d.as_dvec3().normalize()),
        None if s.lighting.shadows && applies(s) => Some(key_light(s)),
        None => None,
    }
}

impl LightGridRef {
    pub fn new(volume: &Reference, s: &RenderSettings, classifier: &Classifier, placement: &Placement) -> Self {
        let dims = volume.dims;
        let largest = *dims.iter().max().unwrap();
        let f = largest.div_ceil(128).max(1);
        let n = dims.map(|d| d.div_ceil(f).max(2));
        let nf = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
        let voxel = placement.voxel_sides().min_element();
        // World length (in voxels) of a step of `u` cells.
        let cells_to_voxels =
            |u: DVec3| (placement.to_world(u / nf) - placement.to_world(DVec3::ZERO)).length() / voxel;
        let wall = s
            .isosurfaces()
            .iter()
            .filter(|x| x.opacity >= 1.0)
            .map(|x| f64::from(x.value))
            .fold(f64::INFINITY, f64::min);
        let sigma_at = |c: DVec3| extinction(s, classifier, wall, volume.sample((c + 0.5) / nf));
        let index = |c: [usize; 3]| c[0] + n[0] * (c[1] + n[1] * c[2]);
        let count = n[0] * n[1] * n[2];
        let cells = || (0..n[2]).flat_map(move |z| (0..n[1]).flat_map(move |y| (0..n[0]).map(move |x| [x, y, z])));
        // Occlusion: 14 directions, 4 samples each.
        let mut dirs: Vec<DVec3> = Vec::new();
        for a in 0..3 {
            for sign in [1.0, -1.0] {
                let mut u = DVec3::ZERO;
                u[a] = sign;
                dirs.push(u);
            }
        }
        for x in [1.0, -1.0] {
            for y in [1.0, -1.0] {
                for z in [1.0, -1.0] {
                    dirs.push(DVec3::new(x, y, z) / 3f64.sqrt());
                }
            }
        }
        let mut o = vec![1.0; count];
        if s.lighting.ambient_occlusion {
            for c in cells() {
                let p = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64);
                let mut sum = 0.0;
                for u in &dirs {
                    let ell = cells_to_voxels(*u);
                    let mut tau = 0.0;
                    for k in 1..=4 {
                        let q = p + k as f64 * *u;
                        let inside = q.cmpge(DVec3::splat(-0.5)).all() && q.cmple(nf - 0.5).all();
                        if inside {
                            tau += sigma_at(q) * ell;
                        }
                    }
                    sum += (-tau).exp();
                }
                o[index(c)] = sum / 14.0;
            }
        }
        let mut t = vec![1.0; count];
        let mut read_offset = DVec3::ZERO;
        if let (true, Some(light)) = (s.lighting.shadows, light_direction(s)) {
            // The light in cell units: through texture space (the placement's inverse), scaled by n.
            let d = nf * placement.dir_to_tex(light);
            let a = d.abs();
            let axis = if a.x >= a.y && a.x >= a.z {
                0
            } else if a.y >= a.z {
                1
            } else {
                2
            };
            let delta = d / a[axis];
            read_offset = 1.5 * delta / nf;
            let ell = cells_to_voxels(delta);
            let (o1, o2) = match axis {
                0 => (1, 2),
                1 => (0, 2),
                _ => (0, 1),
            };
            let order: Vec<usize> = if delta[axis] > 0.0 {
                (0..n[axis]).rev().collect()
            } else {
                (0..n[axis]).collect()
            };
            for (step, &slice) in order.iter().enumerate() {
                if step == 0 {
                    continue;
                }
                let previous = t.clone();
                for i in 0..n[o1] {
                    for j in 0..n[o2] {
                        let mut c = [0usize; 3];
                        (c[axis], c[o1], c[o2]) = (slice, i, j);
                        let p = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64);
                        let q = p + delta;
                        let (i0, j0) = (q[o1].floor(), q[o2].floor());
                        let (fx, fy) = (q[o1] - i0, q[o2] - j0);
                        let read = |di: f64, dj: f64| {
                            let (ci, cj) = (i0 + di, j0 + dj);
                            if ci < 0.0 || cj < 0.0 || ci >= n[o1] as f64 || cj >= n[o2] as f64 {
                                return 1.0;
                            }
                            let mut cc = [0usize; 3];
                            (cc[axis], cc[o1], cc[o2]) = (q[axis].round() as usize, ci as usize, cj as usize);
                            previous[index(cc)]
                        };
                        let lerp = |a: f64, b: f64, w: f64| a + w * (b - a);
                        let tq = lerp(
                            lerp(read(0.0, 0.0), read(1.0, 0.0), fx),
                            lerp(read(0.0, 1.0), read(1.0, 1.0), fx),
                            fy,
                        );
                        t[index(c)] = tq * (-sigma_at(p) * ell).exp();
                    }
                }
            }
        }
        LightGridRef { n, t, o, read_offset }
    }

    /// Trilinear interpolation of `field` at texture coordinate `tex` (cell centres at (c + 0.5)/n, clamped).
    fn filter(&self, field: &[f64], tex: DVec3) -> f64 {
        let mut idx = [[0usize; 2]; 3];
        let mut w = [0f64; 3];
        for a in 0..3 {
            let u = tex[a] * self.n[a] as f64 - 0.5;
            let i0 = u.floor();
            w[a] = u - i0;
            let clamp = |i: f64| i.clamp(0.0, (self.n[a] - 1) as f64) as usize;
            idx[a] = [clamp(i0), clamp(i0 + 1.0)];
        }
        let at = |x: usize, y: usize, z: usize| field[x + self.n[0] * (y + self.n[1] * z)];
        let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
        let [[x0, x1], [y0, y1], [z0, z1]] = idx;
        let c0 = lerp(
            lerp(at(x0, y0, z0), at(x1, y0, z0), w[0]),
            lerp(at(x0, y1, z0), at(x1, y1, z0), w[0]),
            w[1],
        );
        let c1 = lerp(
            lerp(at(x0, y0, z1), at(x1, y0, z1), w[0]),
            lerp(at(x0, y1, z1), at(x1, y1, z1), w[0]),
            w[1],
        );
        lerp(c0, c1, w[2])
    }

    /// T of cell `c`.
    pub fn t_cell(&self, c: [usize; 3]) -> f64 {
        self.t[c[0] + self.n[0] * (c[1] + self.n[1] * c[2])]
    }

    /// O of cell `c`.
    pub fn o_cell(&self, c: [usize; 3]) -> f64 {
        self.o[c[0] + self.n[0] * (c[1] + self.n[1] * c[2])]
    }

    /// The grid's size in cells.
    pub fn cells(&self) -> [usize; 3] {
        self.n
    }

    /// T read 1.5 steps towards the light from `tex`.
    pub fn shadow(&self, tex: DVec3) -> f64 {
        self.filter(&self.t, tex + self.read_offset)
    }

    pub fn occlusion(&self, tex: DVec3) -> f64 {
        self.filter(&self.o, tex)
    }
}

/// Whether rule 9 applies to `s` (written from the rule: lit frames with shadows or occlusion).
pub fn applies(s: &RenderSettings) -> bool {
    let lit = match s.compositing.mode {
        CompositeMode::Isosurface => true,
        CompositeMode::Emission | CompositeMode::Density => s.lighting.shading.is_some(),
        _ => false,
    };
    lit && (s.lighting.shadows || s.lighting.ambient_occlusion)
}
