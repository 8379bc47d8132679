//! Which level of the resolution pyramid each brick shows (docs/large-volumes.md, "Bricks, levels and the page
//! table"). Pure code: the renderer's pool (pool.rs) holds the bricks a [`Cut`] names.
//!
//! - The pyramid (`crate::pyramid`): its geometry, its bricks across levels (`pyramid::bricks`: level-L bricks nest
//!   over 2^L level-0 bricks per axis) and its levels of a volume held in memory (`pyramid::in_memory`).
//! - The screen rule: starting from the top level (one brick), a brick of level L ≥ 1 is replaced by its children
//!   while its voxel (2^L level-0 voxels, smallest side) is larger than `factor` pixels at its distance: the distance
//!   from the eye to its centre less half its diagonal (world units), a pixel there being 2·d·tan(fov/2)/height
//!   (orthographic: the view's height / height).
//! - Within a bound on the bricks (the pool's slots), refinement goes by need (voxel / pixel, largest first; ties to
//!   the coarser brick, then the lower index), and a brick whose children do not fit stays as it is.

use crate::pyramid::bricks::{children, covering, grid_at, level0_bricks};
use glam::{DMat4, DVec3};
use std::collections::BinaryHeap;

/// The level shown in each brick of level 0's grid (x fastest).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Cut {
    pub grid: [u32; 3],
    pub level: Vec<u32>,
}

/// How levels are chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LevelChoice {
    /// Level 0 everywhere.
    Finest,
    /// One level everywhere (`--level`).
    Forced(u32),
    /// The screen rule with this factor, within this many bricks.
    Screen { factor: f64, bricks: usize },
}

/// What the screen rule needs of the view: the texture-to-world placement, the camera and the image height.
#[derive(Clone, Copy, Debug)]
pub struct View {
    pub tex_to_world: DMat4,
    pub eye: DVec3,
    pub tan_half_fov: f64,
    /// Orthographic: the world height of a pixel, everywhere.
    pub ortho_pixel: Option<f64>,
    pub height: f64,
}

impl View {
    /// The view of `s` over a volume placed as `info` says.
    pub fn of(info: &super::VolumeInfo, s: &crate::scene::settings::RenderSettings) -> View {
        let c = &s.camera;
        let eye = c.eye.as_dvec3();
        let tan_half_fov = (f64::from(c.fov_y_deg).to_radians() / 2.0).tan();
        let height = f64::from(s.height);
        View {
            tex_to_world: info.tex_to_world(s),
            eye,
            tan_half_fov,
            ortho_pixel: c
                .ortho
                .then(|| 2.0 * (c.target.as_dvec3() - eye).length() * tan_half_fov / height),
            height,
        }
    }
}

impl Cut {
    pub fn uniform(grid: [u32; 3], level: u32) -> Cut {
        Cut {
            grid,
            level: vec![level; grid.iter().map(|&g| g as usize).product()],
        }
    }

    /// The bricks shown: (level, brick index in its level's grid), each once.
    pub fn shown(&self) -> Vec<(u32, [u32; 3])> {
        let mut out: Vec<(u32, [u32; 3])> = (0..self.level.len())
            .map(|i| {
                let l = self.level[i];
                (l, covering(self.brick_of(i), l))
            })
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Level-0 brick `i`'s position in the grid.
    pub fn brick_of(&self, i: usize) -> [u32; 3] {
        let [gx, gy, _] = self.grid.map(|g| g as usize);
        [i % gx, i / gx % gy, i / (gx * gy)].map(|v| v as u32)
    }
}

/// A brick's need: its voxel over a pixel at its distance (above `factor`: refine).
fn need(view: &View, dims: [u32; 3], brick: [u32; 3], voxel: f64, l: u32, b: [u32; 3]) -> f64 {
    let side = [0, 1, 2].map(|a| f64::from(brick[a]) * f64::from(1u32 << l));
    let lo = DVec3::from_array([0, 1, 2].map(|a| f64::from(b[a]) * side[a] / f64::from(dims[a])));
    let hi = DVec3::from_array([0, 1, 2].map(|a| (f64::from(b[a] + 1) * side[a] / f64::from(dims[a])).min(1.0)));
    let (wl, wh) = (
        view.tex_to_world.transform_point3(lo),
        view.tex_to_world.transform_point3(hi),
    );
    let pixel = view.ortho_pixel.unwrap_or_else(|| {
        let d = ((wl + wh) / 2.0 - view.eye).length() - (wh - wl).length() / 2.0;
        2.0 * d.max(0.0) * view.tan_half_fov / view.height
    });
    f64::from(1u32 << l) * voxel / pixel
}

/// The screen rule's cut for a volume of `dims` in bricks of `brick`, levels up to `top`, within `bricks` bricks
/// (at least the top level's one), refining only bricks that `may_refine` (refinable.rs: those whose children can
/// show anything).
pub fn screen_cut(
    dims: [u32; 3],
    brick: [u32; 3],
    top: u32,
    (view, factor): (&View, f64),
    bricks: usize,
    may_refine: &dyn Fn(u32, [u32; 3]) -> bool,
) -> Cut {
    let grid0 = grid_at(dims, brick, 0);
    // The smallest side of a level-0 voxel in the world.
    let voxel = (0..3)
        .map(|a| view.tex_to_world.col(a).truncate().length() / f64::from(dims[a]))
        .fold(f64::INFINITY, f64::min);
    #[derive(PartialEq)]
    struct Item(f64, u32, [u32; 3]);
    impl Eq for Item {}
    impl PartialOrd for Item {
        fn partial_cmp(&self, o: &Item) -> Option<std::cmp::Ordering> {
            Some(self.cmp(o))
        }
    }
    impl Ord for Item {
        // Largest need first; ties to the coarser brick, then the lower index (z, y, x).
        fn cmp(&self, o: &Item) -> std::cmp::Ordering {
            self.0
                .total_cmp(&o.0)
                .then(self.1.cmp(&o.1))
                .then(o.2[2].cmp(&self.2[2]))
                .then(o.2[1].cmp(&self.2[1]))
                .then(o.2[0].cmp(&self.2[0]))
        }
    }
    let mut shown: std::collections::HashSet<(u32, [u32; 3])> = [(top, [0, 0, 0])].into();
    let mut heap = BinaryHeap::new();
    let consider = |heap: &mut BinaryHeap<Item>, l: u32, b: [u32; 3]| {
        let n = need(view, dims, brick, voxel, l, b);
        if l > 0 && n > factor && may_refine(l, b) {
            heap.push(Item(n, l, b));
        }
    };
    consider(&mut heap, top, [0, 0, 0]);
    let mut count = 1usize;
    while let Some(Item(_, l, b)) = heap.pop() {
        let children = children(dims, brick, l, b);
        if count - 1 + children.len() > bricks {
            continue;
        }
        count += children.len() - 1;
        shown.remove(&(l, b));
        for c in children {
            shown.insert((l - 1, c));
            consider(&mut heap, l - 1, c);
        }
    }
    let mut cut = Cut::uniform(grid0, top);
    for (l, b) in shown {
        // Every level-0 brick under (l, b).
        let (lo, hi) = level0_bricks(b, l, grid0);
        for z in lo[2]..hi[2] {
            for y in lo[1]..hi[1] {
                for x in lo[0]..hi[0] {
                    cut.level[(x + grid0[0] * (y + grid0[1] * z)) as usize] = l;
                }
            }
        }
    }
    cut
}

/// The normalised value range of each skip cell a brick read from the file below the held level covers, by (level,
/// brick) (finer_cells.rs).
pub type FinerRanges = std::collections::HashMap<(u32, [u32; 3]), super::finer_cells::BoxCells<(f32, f32)>>;

/// The skip grid's ranges for `cut` shown in pool bricks of `brick` voxels: each 8³ skip brick takes the ranges of
/// the levels its samples are taken at, those of the pool bricks it overlaps (`grids[L]` is level L's skip grid,
/// whose brick k >> L holds every voxel a level-L sample inside level-0 skip brick k reads). A brick shown at level
/// 2 is thus classified by level 2 alone: level 0's empty bricks under a coarser glow are not leapt over, and a
/// coarse level's glow does not keep level-0 bricks shown elsewhere from being skipped. With `held` > 0 (a file's
/// finer levels read by brick, `VolumeInfo::held`), `grids[0]` is level `held`'s grid, skip bricks are 8 of its
/// voxels, and a brick shown below it takes the range of its own voxels within one voxel of the skip brick, as read
/// (`finer`).
pub fn cut_ranges(
    grids: &[super::skip::BrickGrid],
    cut: &Cut,
    brick: [u32; 3],
    (held, finer): (u32, &FinerRanges),
) -> super::skip::BrickGrid {
    use rayon::prelude::*;
    let base = &grids[0];
    let s = super::skip::BRICK << held;
    let [gx, gy, _] = base.bricks.map(|b| b as usize);
    let (min, max): (Vec<f32>, Vec<f32>) = (0..base.min.len())
        .into_par_iter()
        .map(|k| {
            let at = [k % gx, k / gx % gy, k / (gx * gy)].map(|v| v as u32);
            // The level-0 pool bricks this skip brick overlaps.
            let lo = [0, 1, 2].map(|a| at[a] * s / brick[a]);
            let hi = [0, 1, 2].map(|a| ((at[a] * s + s - 1) / brick[a]).min(cut.grid[a] - 1));
            let mut range = (f32::INFINITY, f32::NEG_INFINITY);
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        let l = cut.level[(x + cut.grid[0] * (y + cut.grid[1] * z)) as usize];
                        let Some(l) = l.checked_sub(held).map(|l| l as usize) else {
                            // A level finer than the one held, read from the file: its brick's own voxels in
                            // and around this skip brick (any value if it was never read).
                            let r = finer
                                .get(&(l, covering([x, y, z], l)))
                                .and_then(|cells| cells.at(at))
                                .unwrap_or((0.0, 1.0));
                            range = (range.0.min(r.0), range.1.max(r.1));
                            continue;
                        };
                        let g = &grids[l.min(grids.len() - 1)];
                        let [cx, cy, cz] = g.bricks.map(|b| b as usize);
                        let [x, y, z] = covering(at, l as u32).map(|v| v as usize);
                        let c = x.min(cx - 1) + cx * (y.min(cy - 1) + cy * z.min(cz - 1));
                        range = (range.0.min(g.min[c]), range.1.max(g.max[c]));
                    }
                }
            }
            range
        })
        .unzip();
    super::skip::BrickGrid {
        bricks: base.bricks,
        min,
        max,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An orthographic view whose pixels are far smaller than a voxel: every brick asks to be refined.
    fn close_view() -> View {
        View {
            tex_to_world: DMat4::IDENTITY,
            eye: DVec3::new(0.5, 0.5, 5.0),
            tan_half_fov: 0.3,
            ortho_pixel: Some(1e-6),
            height: 100.0,
        }
    }

    /// Refining the top brick of a 32³ volume in 16³ bricks replaces one brick by eight: a bound of 8 holds them,
    /// 7 does not (the top brick stays).
    #[test]
    fn the_bound_counts_a_refinement_as_children_minus_one() {
        let view = close_view();
        let cut = screen_cut([32; 3], [16; 3], 1, (&view, 1.0), 8, &|_, _| true);
        assert_eq!(cut.level, vec![0; 8]);
        assert_eq!(cut.shown().len(), 8);
        let cut = screen_cut([32; 3], [16; 3], 1, (&view, 1.0), 7, &|_, _| true);
        assert_eq!(cut.level, vec![1; 8]);
        assert_eq!(cut.shown(), vec![(1, [0, 0, 0])]);
    }

    /// Pixels larger than the top level's voxel: nothing is refined, whatever the bound.
    #[test]
    fn a_far_view_stays_coarse() {
        let view = View {
            ortho_pixel: Some(1.0),
            ..close_view()
        };
        let cut = screen_cut([64; 3], [16; 3], 2, (&view, 1.0), usize::MAX, &|_, _| true);
        assert!(cut.level.iter().all(|&l| l == 2));
    }

    /// Each skip brick takes the ranges of the levels of the pool bricks it overlaps, and only those.
    #[test]
    fn skip_ranges_follow_the_cut() {
        use super::super::skip::BrickGrid;
        use crate::pyramid::in_memory::extend_pyramid;
        use crate::volume::{Volume, VoxelData};
        let n = 32u32;
        let data: Vec<u8> = (0..n * n * n).map(|i| if i % n == 5 { 255 } else { 0 }).collect();
        let v = Volume::new("t", [n; 3], [1.0; 3], crate::volume::VoxelType::U8, VoxelData::U8(data)).unwrap();
        let mut pyramid = Vec::new();
        extend_pyramid(&v, &mut pyramid, 2).unwrap();
        let grids: Vec<BrickGrid> = std::iter::once(&v).chain(&pyramid).map(BrickGrid::new).collect();
        // Pool bricks of 16: level 0 in the lower x half, level 2 in the upper (bricks of 12 straddle skip bricks).
        for side in [16, 12] {
            let g = [0, 1, 2].map(|_| n.div_ceil(side));
            let flat = Cut::uniform(g, 0);
            let mut cut = flat.clone();
            for (i, l) in cut.level.iter_mut().enumerate() {
                *l = if flat.brick_of(i)[0] == 0 { 0 } else { 2 };
            }
            let r = cut_ranges(&grids, &cut, [side; 3], (0, &Default::default()));
            for k in 0..r.min.len() {
                let x = k % 4;
                let (x0, x1) = (x as u32 * 8 / side, (x as u32 * 8 + 7) / side);
                let mut want = (f32::INFINITY, f32::NEG_INFINITY);
                for px in [x0, x1] {
                    let l = if px == 0 { 0 } else { 2 };
                    let g = &grids[l];
                    let c = (x >> l).min(g.bricks[0] as usize - 1)
                        + g.bricks[0] as usize
                            * (((k / 4 % 4) >> l).min(g.bricks[1] as usize - 1)
                                + g.bricks[1] as usize * ((k / 16) >> l).min(g.bricks[2] as usize - 1));
                    want = (want.0.min(g.min[c]), want.1.max(g.max[c]));
                }
                assert_eq!((r.min[k], r.max[k]), want, "pool side {side}, skip brick {k}");
            }
        }
        // Level 0 sees the plane only in its first skip brick along x; level 2's glow reaches further.
        assert!(grids[0].max[1] == 0.0 && grids[2].max[0] > 0.0);
    }
}
