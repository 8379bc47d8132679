//! Which bricks refining can change (docs/large-volumes.md, "Only what can be seen is refined"). Pure code.
//!
//! The rule: a brick of level L ≥ 1 is refined only if the range of the level-0 voxels within 2^L voxels of its
//! box, rounded out to the cells of [`CellRanges`], can be visible for the frame by the skip rule's test
//! ([`BrickGrid::classify`], on that one range). Otherwise every voxel there, and every mean of them at any level
//! (a mean lies within their range), draws nothing: the brick and all below it show nothing, and its children
//! would change no pixel, so they take no slot in the pool and are never read. 2^L voxels cover the apron that a
//! trilinear sample of the brick, or of any brick below it, reads.

use super::skip::BrickGrid;
use crate::pyramid::bricks::{grid_at, to_level0};
use crate::scene::settings::RenderSettings;
use crate::volume::cells::CellRanges;
use crate::volume::Volume;
use rayon::prelude::*;

/// Per level L ≥ 1 of a pool's pyramid, the range each brick's children can reach (normalised as the volume's
/// elements are).
#[derive(Clone, Debug)]
pub struct Refinable {
    levels: Vec<BrickGrid>,
}

/// Which bricks may be refined for one frame.
#[derive(Clone, Debug)]
pub struct Classes {
    /// Per level from 1: its grid's size in bricks, and each brick's class.
    levels: Vec<([u32; 3], Vec<u8>)>,
}

impl Refinable {
    /// The ranges of every brick of levels 1..=`top` over a level 0 of `cells.dims` in bricks of `brick` voxels,
    /// from `cells` (elements of `volume`, which normalises them).
    pub fn new(cells: &CellRanges, volume: &Volume, brick: [u32; 3], top: u32) -> Refinable {
        let dims = cells.dims;
        let levels = (1..=top)
            .map(|l| {
                let grid = grid_at(dims, brick, l);
                let [gx, gy, gz] = grid.map(|g| g as usize);
                let side = brick.map(|b| to_level0(b, l));
                let apron = to_level0(1, l);
                let ranges: Vec<(f32, f32)> = (0..gx * gy * gz)
                    .into_par_iter()
                    .map(|k| {
                        let b = [k % gx, k / gx % gy, k / (gx * gy)].map(|v| v as u32);
                        let lo = [0, 1, 2].map(|a| (b[a] * side[a]).saturating_sub(apron));
                        let hi = [0, 1, 2].map(|a| (b[a] + 1) * side[a] + apron);
                        volume.normalize_range(cells.over(lo, hi))
                    })
                    .collect();
                let (min, max) = ranges.into_iter().unzip();
                BrickGrid { bricks: grid, min, max }
            })
            .collect();
        Refinable { levels }
    }

    /// Which bricks frame `s` (whose baked table is `lut`) may refine.
    pub fn classes(&self, lut: &[[f32; 4]], s: &RenderSettings) -> Classes {
        Classes {
            levels: self.levels.iter().map(|g| (g.bricks, g.classify(lut, s))).collect(),
        }
    }
}

impl Classes {
    /// Whether brick `b` of level `l` may be refined (level 0 never is; a level beyond the ranges always may).
    pub fn may_refine(&self, l: u32, b: [u32; 3]) -> bool {
        let Some(([gx, gy, _], class)) = l.checked_sub(1).and_then(|i| self.levels.get(i as usize)) else {
            return l > 0;
        };
        class
            .get((b[0] + gx * (b[1] + gy * b[2])) as usize)
            .is_none_or(|&c| c > 0)
    }

    /// How many bricks of levels 1.. may not be refined.
    pub fn closed(&self) -> usize {
        self.levels
            .iter()
            .map(|(_, c)| c.iter().filter(|&&c| c == 0).count())
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{VoxelData, VoxelType};

    /// A 64³ uint8 volume, 0 everywhere but a 4³ block of 200 at (40..44, 8..12, 8..12).
    fn block() -> Volume {
        let n = 64usize;
        let mut data = vec![0u8; n * n * n];
        for z in 8..12 {
            for y in 8..12 {
                for x in 40..44 {
                    data[x + n * (y + n * z)] = 200;
                }
            }
        }
        Volume::new("block", [64; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap()
    }

    #[test]
    fn only_bricks_near_something_visible_may_be_refined() {
        let v = block();
        let cells = CellRanges::of(&v);
        let r = Refinable::new(&cells, &v, [16; 3], 2);
        let mut s = RenderSettings::for_volume(8, 8, &v);
        s.colour.window = [0.5, 1.0];
        let lut = crate::transfer::function::bake(&s.classification(), s.colour.window, v.range);
        let c = r.classes(&lut, &s);
        // Level 1 (32³ bricks): the block lies in brick (1, 0, 0), in cells (5, 1, 1) that no other brick's region
        // (its box and 2 voxels, rounded out to cells of 8) reaches.
        let open: Vec<[u32; 3]> = (0..8)
            .map(|k| [k % 2, k / 2 % 2, k / 4])
            .filter(|&b| c.may_refine(1, b))
            .collect();
        assert_eq!(open, vec![[1, 0, 0]]);
        assert!(c.may_refine(2, [0, 0, 0]));
        assert!(!c.may_refine(0, [0, 0, 0]));
        assert_eq!(c.closed(), 7);
        // Without skipping, nothing counts as empty: every brick may be refined.
        s.sampling.skip_empty = false;
        assert_eq!(r.classes(&lut, &s).closed(), 0);
    }
}
