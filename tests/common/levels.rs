//! The resolution pyramid and the level shown per brick, from their definitions (docs/large-volumes.md, "Bricks,
//! levels and the page table"), for the reference: what a GPU frame over a pool of mixed levels must show.
//!
//! - Level L + 1 halves every axis of level L (rounding up); each voxel is the mean of the up-to-2×2×2 voxels of
//!   level L it covers, rounded half away from zero for integer data. Level L's voxel i covers level-0 voxels
//!   [i·2^L, (i + 1)·2^L) along each axis, so a point at level-0 texture coordinate p lies at p·dims0/2^L in level L's
//!   voxels.
//! - Bricks are `brick` voxels of their level per side; a level-L brick covers 2^L level-0 bricks per axis.
//! - A cut gives every level-0 brick the level shown there; a point's value is the trilinear sample of that level's
//!   grid (clamped to its edge) at the point, and a gradient's six samples are taken in the level of their centre.
//! - The screen rule: a brick of level L ≥ 1 is replaced by its children while its voxel is larger than `factor`
//!   pixels at its distance; without a bound on the bricks that gives one cut, which [`screen_cut`] computes.
//! - Only what can be seen is refined: a brick of level L ≥ 1 is replaced by its children only if the range of
//!   level 0's values within 2^L voxels of its box, rounded out to cells of `cell` voxels, can be visible
//!   ([`may_refine`]).

use super::placement::Placement;
use glam::DVec3;
use volcast::scene::settings::RenderSettings;
use volcast::volume::{Volume, VoxelData};

/// One level of the pyramid: its size and its normalised values (x fastest).
#[derive(Clone, Debug)]
pub struct Level {
    pub dims: [usize; 3],
    pub values: Vec<f64>,
}

/// Levels 0..=`top` of `volume`, normalised as the reference normalises level 0 (the element's value by the
/// volume's scaling, then by its range).
pub fn pyramid(volume: &Volume, top: u32) -> Vec<Level> {
    let integer = !matches!(volume.data, VoxelData::F32(_));
    let mut dims = volume.dims.map(|d| d as usize);
    let mut elements: Vec<f64> = match &volume.data {
        VoxelData::U8(v) => v.iter().map(|&e| f64::from(e)).collect(),
        VoxelData::U16(v) => v.iter().map(|&e| f64::from(e)).collect(),
        VoxelData::F32(v) => v.iter().map(|&e| f64::from(e)).collect(),
    };
    let normalise = |e: &[f64]| e.iter().map(|&e| volume.normalize_element(e)).collect::<Vec<f64>>();
    let mut out = vec![Level {
        dims,
        values: normalise(&elements),
    }];
    for _ in 0..top {
        let coarse = dims.map(|d| d.div_ceil(2));
        let mut next = Vec::with_capacity(coarse.iter().product());
        for z in 0..coarse[2] {
            for y in 0..coarse[1] {
                for x in 0..coarse[0] {
                    let (mut sum, mut n) = (0.0, 0.0);
                    for (dx, dy, dz) in (0..8).map(|i| (i & 1, (i >> 1) & 1, i >> 2)) {
                        let (fx, fy, fz) = (2 * x + dx, 2 * y + dy, 2 * z + dz);
                        if fx < dims[0] && fy < dims[1] && fz < dims[2] {
                            sum += elements[fx + dims[0] * (fy + dims[1] * fz)];
                            n += 1.0;
                        }
                    }
                    let mean = sum / n;
                    // Round half away from zero (the elements are non-negative); float data as f32.
                    next.push(if integer {
                        (mean + 0.5).floor()
                    } else {
                        f64::from(mean as f32)
                    });
                }
            }
        }
        dims = coarse;
        elements = next;
        out.push(Level {
            dims,
            values: normalise(&elements),
        });
    }
    out
}

impl Level {
    fn at(&self, x: usize, y: usize, z: usize) -> f64 {
        self.values[x + self.dims[0] * (y + self.dims[1] * z)]
    }

    /// Trilinear at level-L voxel coordinate `u` (centres at i + 0.5), clamped to the edge.
    pub fn sample(&self, u: DVec3) -> f64 {
        let mut i = [[0usize; 2]; 3];
        let mut w = [0.0; 3];
        for a in 0..3 {
            let q = u[a] - 0.5;
            let f = q.floor();
            w[a] = q - f;
            let top = (self.dims[a] - 1) as f64;
            i[a] = [f.clamp(0.0, top) as usize, (f + 1.0).clamp(0.0, top) as usize];
        }
        let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
        let [[x0, x1], [y0, y1], [z0, z1]] = i;
        let c00 = lerp(self.at(x0, y0, z0), self.at(x1, y0, z0), w[0]);
        let c10 = lerp(self.at(x0, y1, z0), self.at(x1, y1, z0), w[0]);
        let c01 = lerp(self.at(x0, y0, z1), self.at(x1, y0, z1), w[0]);
        let c11 = lerp(self.at(x0, y1, z1), self.at(x1, y1, z1), w[0]);
        lerp(lerp(c00, c10, w[1]), lerp(c01, c11, w[1]), w[2])
    }
}

/// The level shown in each level-0 brick (x fastest).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Cut {
    pub brick: [usize; 3],
    pub grid: [usize; 3],
    pub level: Vec<u32>,
    /// The level the host holds (a file's finer levels are read by brick below it; 0 otherwise).
    pub held: u32,
}

impl Cut {
    pub fn uniform(dims: [usize; 3], brick: [usize; 3], level: u32) -> Cut {
        let grid = [0, 1, 2].map(|a| dims[a].div_ceil(brick[a]));
        Cut {
            brick,
            grid,
            level: vec![level; grid.iter().product()],
            held: 0,
        }
    }

    /// The level shown at level-0 texture coordinate `tex` of a volume of `dims`.
    pub fn level_at(&self, tex: DVec3, dims: [usize; 3]) -> u32 {
        let b = [0, 1, 2].map(|a| {
            let i = (tex[a] * dims[a] as f64 / self.brick[a] as f64).floor();
            i.clamp(0.0, (self.grid[a] - 1) as f64) as usize
        });
        self.level[b[0] + self.grid[0] * (b[1] + self.grid[1] * b[2])]
    }
}

/// The screen rule's cut without a bound on the bricks (see the module's docs): level-0 brick b shows the
/// coarsest level L (≤ `top`) such that no brick on its chain from `top` down to L + 1 needs refining... i.e. the
/// finest level reached by refining from the top while the brick holding b needs it.
pub fn screen_cut(
    dims: [usize; 3],
    brick: [usize; 3],
    top: u32,
    placement: &Placement,
    s: &RenderSettings,
    factor: f64,
) -> Cut {
    screen_cut_where(dims, brick, top, (placement, s, factor), &|_, _| true)
}

/// [`screen_cut`] where only bricks (level, index in its level's grid) that `refine` allows are refined.
pub fn screen_cut_where(
    dims: [usize; 3],
    brick: [usize; 3],
    top: u32,
    (placement, s, factor): (&Placement, &RenderSettings, f64),
    refine: &dyn Fn(u32, [usize; 3]) -> bool,
) -> Cut {
    let mut cut = Cut::uniform(dims, brick, top);
    let voxel = placement.voxel_sides().min_element();
    let c = &s.camera;
    let eye = c.eye.as_dvec3();
    let tan = (f64::from(c.fov_y_deg).to_radians() / 2.0).tan();
    let ortho_pixel = 2.0 * (c.target.as_dvec3() - eye).length() * tan / f64::from(s.height);
    for (i, level) in cut.level.iter_mut().enumerate() {
        let b = [
            i % cut.grid[0],
            i / cut.grid[0] % cut.grid[1],
            i / (cut.grid[0] * cut.grid[1]),
        ];
        let mut l = top;
        while l > 0 {
            // The level-l brick over b: its box in level-0 texture coordinates.
            let side = [0, 1, 2].map(|a| (brick[a] << l) as f64);
            let lo = DVec3::from_array([0, 1, 2].map(|a| ((b[a] >> l) as f64 * side[a]) / dims[a] as f64));
            let hi =
                DVec3::from_array([0, 1, 2].map(|a| (((b[a] >> l) + 1) as f64 * side[a] / dims[a] as f64).min(1.0)));
            let (wl, wh) = (placement.to_world(lo), placement.to_world(hi));
            let centre = (wl + wh) / 2.0;
            let radius = (wh - wl).length() / 2.0;
            let pixel = if c.ortho {
                ortho_pixel
            } else {
                2.0 * ((centre - eye).length() - radius).max(0.0) * tan / f64::from(s.height)
            };
            if f64::from(1u32 << l) * voxel <= factor * pixel || !refine(l, b.map(|v| v >> l)) {
                break;
            }
            l -= 1;
        }
        *level = l;
    }
    cut
}

/// The rule that only what can be seen is refined, for brick `b` of level `l` in bricks of `brick` voxels over
/// `level0` (its normalised values): the smallest and largest value (NaN ignored) over level 0's voxels within
/// 2^l voxels of the brick's box, that box rounded out to whole cells of `cell` voxels (cells from the volume's
/// corner), can be visible by `visible`. A region of only NaN cannot.
pub fn may_refine(
    level0: &Level,
    (brick, cell): ([usize; 3], usize),
    l: u32,
    b: [usize; 3],
    visible: &dyn Fn(f64, f64) -> bool,
) -> bool {
    let dims = level0.dims;
    let reach = 1usize << l;
    let lo = [0, 1, 2].map(|a| (((b[a] * brick[a]) << l).saturating_sub(reach) / cell) * cell);
    let hi = [0, 1, 2].map(|a| ((((b[a] + 1) * brick[a]) << l) + reach).div_ceil(cell) * cell);
    let mut range: Option<(f64, f64)> = None;
    for z in lo[2]..hi[2].min(dims[2]) {
        for y in lo[1]..hi[1].min(dims[1]) {
            for x in lo[0]..hi[0].min(dims[0]) {
                let v = level0.at(x, y, z);
                if !v.is_nan() {
                    range = Some(range.map_or((v, v), |(a, c)| (a.min(v), c.max(v))));
                }
            }
        }
    }
    range.is_some_and(|(a, c)| visible(a, c))
}
