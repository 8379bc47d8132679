//! The brick pool and its page table: the one way the march addresses a volume (shaders/volume.glsl `brick_at`).
//!
//! The volume is cut into bricks of `brick` voxels per axis (the last ones along an axis may hang over the edge).
//! Each brick is kept in a slot of the pool, a 3D texture of slots side by side, with a border of [`BORDER`]
//! voxels around it on every side: the voxels around the brick at its level (the edge voxel repeated past the
//! volume's edge, as clamp-to-edge filtering reads it). Trilinear filtering anywhere in a brick, and the six
//! samples one voxel either side of a point in it (gradients), so read only the brick's own slot.
//!
//! The page table (the "directory") has one entry per brick of level 0's grid: the slot that holds the data shown
//! there and the level of that data. A brick of level L covers 2^L level-0 bricks along each axis, so the level-L
//! brick under level-0 brick b is b >> L, and where it lies in its slot follows from that (`addressing`).
//!
//! The march translates the page table once per span of its walk (shaders/walk.glsl): spans end at level-0 brick
//! faces, and a brick's translation is a scale and an offset from a point to its slot's texels.
//!
//! Brick size: a volume that fits the device's 3D limit in one slot is kept as one brick (its page table one
//! entry, its walk's spans those of the skip grid alone); larger ones, or any under `--brick-size`, are tiled.

use super::levels::Cut;
use crate::pyramid::bricks::{covering, grid_at};
use crate::pyramid::geometry::level_dims;

/// Voxels of border on each side of a brick in its slot: a point in the brick, moved one voxel (gradients) and
/// filtered (one more), reads at most two voxels beyond it.
pub const BORDER: u32 = crate::pyramid::budget::BRICK_BORDER;

/// The brick side used when a volume does not fit the device's 3D limit in one slot (docs/large-volumes.md,
/// "Bricks, levels and the page table", states the rule).
pub const TILED_BRICK: u32 = 64;

/// Where bricks lie in the pool and which one each level-0 brick shows.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pool {
    /// Level 0's size in voxels.
    pub dims: [u32; 3],
    /// A brick's size in voxels of its level.
    pub brick: [u32; 3],
    /// Level-0 bricks per axis (the page table's size).
    pub grid: [u32; 3],
    /// Slots per axis.
    pub slots: [u32; 3],
    /// Per slot (x fastest), the brick it holds: its level and index in that level's brick grid.
    pub resident: Vec<Option<Resident>>,
    /// Per level-0 brick (x fastest), the slot whose data is shown there.
    pub directory: Vec<u32>,
    /// Each level's size in voxels, up to the coarsest one shown.
    pub levels: Vec<[u32; 3]>,
}

/// A brick held in a slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Resident {
    pub level: u32,
    pub brick: [u32; 3],
}

/// A slot's side in texels.
pub fn slot_side(brick: u32) -> u32 {
    brick + 2 * BORDER
}

impl Pool {
    /// Every level-0 brick of a volume of `dims` in its own slot. `brick_side` tiles it in bricks of that side
    /// (clamped to the volume); without it, one brick when its slot fits `max_dim`, else [`TILED_BRICK`]. The
    /// slots are arranged so that the pool's sides fit `max_dim`.
    pub fn whole(dims: [u32; 3], brick_side: Option<u32>, max_dim: u32) -> Result<Pool, String> {
        // One texture of at most 2^31 texels: beyond that, 32-bit sizes and offsets in drivers are a risk.
        let texels = dims.iter().map(|&d| u64::from(slot_side(d))).product::<u64>();
        let one = dims.iter().all(|&d| slot_side(d) <= max_dim) && texels <= 1 << 31;
        let brick = match brick_side {
            Some(b) => dims.map(|d| b.max(1).min(d)),
            None if one => dims,
            None => dims.map(|d| TILED_BRICK.min(d)),
        };
        let grid = grid_at(dims, brick, 0);
        // Refused before a page table of that size is made.
        let count = grid.iter().map(|&g| u64::from(g)).product::<u64>();
        if arrange(count, brick.map(slot_side), max_dim).is_none() {
            return Err(too_many(count, brick, max_dim));
        }
        Pool::with_cut(dims, brick, max_dim, &Cut::uniform(grid, 0))
    }

    /// The bricks `cut` shows, each in a slot (in the order of [`Cut::shown`]), and the page table pointing every
    /// level-0 brick at the slot of the brick over it.
    pub fn with_cut(dims: [u32; 3], brick: [u32; 3], max_dim: u32, cut: &Cut) -> Result<Pool, String> {
        let shown = cut.shown();
        let count = shown.len() as u64;
        let slots = arrange(count, brick.map(slot_side), max_dim).ok_or_else(|| too_many(count, brick, max_dim))?;
        let n_slots = slots.iter().map(|&s| s as usize).product::<usize>();
        let mut resident = vec![None; n_slots];
        for (slot, &(level, brick)) in shown.iter().enumerate() {
            resident[slot] = Some(Resident { level, brick });
        }
        let directory = (0..cut.level.len())
            .map(|i| {
                let l = cut.level[i];
                let key = (l, covering(cut.brick_of(i), l));
                shown.binary_search(&key).map_or(0, |slot| slot as u32)
            })
            .collect();
        let top = cut.level.iter().copied().max().unwrap_or(0);
        let levels = (0..=top).map(|l| level_dims(dims, l)).collect();
        Ok(Pool {
            dims,
            brick,
            grid: cut.grid,
            slots,
            resident,
            directory,
            levels,
        })
    }

    /// An empty pool of at least `capacity` slots (as many as its arrangement holds) for streaming levels
    /// 0..=`top`: nothing resident, every page-table entry at slot 0 until a stream writes it (stream.rs).
    pub fn with_capacity(
        dims: [u32; 3],
        brick: [u32; 3],
        max_dim: u32,
        capacity: usize,
        top: u32,
    ) -> Result<Pool, String> {
        let count = capacity.max(1) as u64;
        let slots = arrange(count, brick.map(slot_side), max_dim).ok_or_else(|| too_many(count, brick, max_dim))?;
        let grid = grid_at(dims, brick, 0);
        Ok(Pool {
            dims,
            brick,
            grid,
            slots,
            resident: vec![None; slots.iter().map(|&s| s as usize).product()],
            directory: vec![0; grid.iter().map(|&g| g as usize).product()],
            levels: (0..=top).map(|l| level_dims(dims, l)).collect(),
        })
    }

    /// Slots in the pool.
    pub fn capacity(&self) -> usize {
        self.resident.len()
    }

    /// Its shape as the uniforms carry it.
    pub fn info(&self) -> super::PoolInfo {
        super::PoolInfo {
            brick: self.brick,
            texels: self.texels(),
        }
    }

    /// The pool texture's size in texels.
    pub fn texels(&self) -> [u32; 3] {
        [0, 1, 2].map(|a| self.slots[a] * slot_side(self.brick[a]))
    }

    /// Texels in the pool.
    pub fn texel_count(&self) -> u64 {
        self.texels().iter().map(|&t| u64::from(t)).product()
    }

    /// Slot `index`'s position in the slot grid.
    pub fn slot_at(&self, index: u32) -> [u32; 3] {
        let [sx, sy, _] = self.slots;
        [index % sx, index / sx % sy, index / (sx * sy)]
    }

    /// The page table as the shaders read it (RG32_UINT per level-0 brick): the slot's position packed 10:10:10
    /// bits (x lowest) and the level of the data in it.
    pub fn table(&self) -> Vec<[u32; 2]> {
        self.directory
            .iter()
            .map(|&slot| {
                let [x, y, z] = self.slot_at(slot);
                let level = self.resident[slot as usize].map_or(0, |r| r.level);
                [x | y << 10 | z << 20, level]
            })
            .collect()
    }

    /// For each texel of pool row (`y`, `z`), the voxel it holds: its level and index in that level (x fastest),
    /// or None in an empty slot. The border repeats the level's edge voxel past its edge.
    pub fn row_sources(&self, y: u32, z: u32, out: &mut Vec<Option<Source>>) {
        out.clear();
        let side = self.brick.map(slot_side);
        let [sy, sz] = [y / side[1], z / side[2]];
        for sx in 0..self.slots[0] {
            let index = sx + self.slots[0] * (sy + self.slots[1] * sz);
            match self.resident.get(index as usize).copied().flatten() {
                Some(r) => self.slot_row(r, y % side[1], z % side[2], out),
                None => out.extend((0..side[0]).map(|_| None)),
            }
        }
    }

    /// Appends the sources of row (`ly`, `lz`) of a slot holding `r` (slot-local texels).
    pub fn slot_row(&self, r: Resident, ly: u32, lz: u32, out: &mut Vec<Option<Source>>) {
        let dims = self.levels[r.level as usize];
        let clamp = |a: usize, l: u32| -> usize {
            let v = i64::from(r.brick[a] * self.brick[a]) + i64::from(l) - i64::from(BORDER);
            v.clamp(0, i64::from(dims[a]) - 1) as usize
        };
        let row = dims[0] as usize * (clamp(1, ly) + dims[1] as usize * clamp(2, lz));
        out.extend((0..slot_side(self.brick[0])).map(|lx| Some((r.level, row + clamp(0, lx)))));
    }

    /// Per level, the first and last slice (z) of that level the pool's texels `first..first + count` (whole rows,
    /// wrapping as in [`fill`](Self::fill)) hold voxels of; None where they hold none.
    pub fn source_slices(&self, first: usize, count: usize) -> Vec<Option<(usize, usize)>> {
        let [tx, ty, tz] = self.texels().map(|t| t as usize);
        let mut spans: Vec<Option<(usize, usize)>> = vec![None; self.levels.len()];
        let mut row = Vec::new();
        for r in first / tx..(first + count).div_ceil(tx) {
            let at = r % (ty * tz);
            self.row_sources((at % ty) as u32, (at / ty) as u32, &mut row);
            for &(l, i) in row.iter().flatten() {
                let [dx, dy, _] = self.levels[l as usize];
                let z = i / (dx as usize * dy as usize);
                let span = &mut spans[l as usize];
                *span = Some(span.map_or((z, z), |(a, b)| (a.min(z), b.max(z))));
            }
        }
        spans
    }

    /// Fills `dst`, the pool's texels from texel `first` on (whole rows; past the last slice they wrap to the
    /// first, as a depth-1 pool's second copy does), with `texel(row sources, x)`, rows on every core.
    pub fn fill<T: Send>(
        &self,
        first: usize,
        dst: &mut [T],
        pairs: bool,
        texel: impl Fn(&PoolRows, usize) -> T + Sync,
    ) {
        use rayon::prelude::*;
        let [tx, ty, tz] = self.texels().map(|t| t as usize);
        let first_row = first / tx;
        dst.par_chunks_mut(tx).enumerate().for_each_init(
            || (Vec::new(), Vec::new()),
            |(this, next), (r, row)| {
                let at = (first_row + r) % (ty * tz);
                let (y, z) = ((at % ty) as u32, (at / ty) as u32);
                self.row_sources(y, z, this);
                if pairs {
                    self.row_sources((y + 1).min(ty as u32 - 1), z, next);
                }
                let rows = PoolRows { this, next };
                for (x, d) in row.iter_mut().enumerate() {
                    *d = texel(&rows, x);
                }
            },
        );
    }
}

/// Where a pool texel's value comes from: a level and the voxel's index in it.
pub type Source = (u32, usize);

fn too_many(count: u64, brick: [u32; 3], max_dim: u32) -> String {
    format!(
        "{count} bricks of {}x{}x{} do not fit a pool of 3D textures of at most {max_dim} per side",
        brick[0], brick[1], brick[2]
    )
}

/// A pool row's sources and those of the row after it (the corner layout reads both).
pub struct PoolRows<'a> {
    pub this: &'a [Option<Source>],
    pub next: &'a [Option<Source>],
}

/// The most slots a pool of bricks of `brick` holds within `max_slots` slots and `max_dim` per side (its
/// arrangement rounds a count up to whole rows and layers, so it is searched from `max_slots` down).
pub fn slots_within(max_slots: u64, brick: [u32; 3], max_dim: u32) -> u64 {
    let side = brick.map(slot_side);
    let held = |c: u64| arrange(c, side, max_dim).map(|s| s.iter().map(|&v| u64::from(v)).product::<u64>());
    (1..=max_slots)
        .rev()
        .find_map(|c| held(c).filter(|&n| n <= max_slots))
        .unwrap_or(0)
}

/// The slots of the pool arranged for `count` bricks (at least `count`: whole rows and layers), if they fit `max_dim`
/// per side: a pool that holds every brick of a pyramid holds them all, not the most a smaller count arranges.
pub fn slots_holding(count: u64, brick: [u32; 3], max_dim: u32) -> Option<u64> {
    arrange(count, brick.map(slot_side), max_dim).map(|s| s.iter().map(|&v| u64::from(v)).product())
}

/// Slots per axis for `count` slots of `side` texels within `max_dim` per pool side: close to a cube of slots
/// (neighbouring bricks stay near in the pool), else as few rows and layers as fit. None when they cannot fit.
fn arrange(count: u64, side: [u32; 3], max_dim: u32) -> Option<[u32; 3]> {
    let per = side.map(|s| u64::from(max_dim / s));
    if per.contains(&0) || count == 0 {
        return None;
    }
    let cube = (count as f64).cbrt().ceil() as u64;
    let sx = cube.min(per[0]).min(count);
    let sy = count.div_ceil(sx).isqrt().max(1).min(per[1]);
    let sy = if sx * sy * per[2] < count {
        count.div_ceil(sx).min(per[1])
    } else {
        sy
    };
    let sz = count.div_ceil(sx * sy);
    (sz <= per[2]).then_some([sx as u32, sy as u32, sz as u32])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_brick_when_it_fits_else_tiles() {
        let p = Pool::whole([100, 50, 20], None, 2048).unwrap();
        assert_eq!((p.brick, p.grid, p.slots), ([100, 50, 20], [1, 1, 1], [1, 1, 1]));
        assert_eq!(p.texels(), [104, 54, 24]);
        let p = Pool::whole([4000, 64, 64], None, 2048).unwrap();
        assert_eq!((p.brick, p.grid), ([64, 64, 64], [63, 1, 1]));
        // 63 slots of 68 texels: a cube of 4 x 4 x 4.
        assert_eq!(p.slots, [4, 4, 4]);
        assert!(p.texels().iter().all(|&t| t <= 2048));
        let p = Pool::whole([40, 40, 40], Some(16), 2048).unwrap();
        assert_eq!((p.brick, p.grid), ([16, 16, 16], [3, 3, 3]));
        assert!(Pool::whole([1 << 20, 1 << 20, 1 << 20], None, 2048).is_err());
        // Within a small limit (5 slots of 20 texels per side).
        let p = Pool::whole([400, 16, 16], Some(16), 100).unwrap();
        assert_eq!(p.slots, [3, 3, 3]);
        assert!(Pool::whole([256, 256, 256], Some(16), 200).is_err());
    }

    #[test]
    fn a_pool_for_a_whole_pyramid_rounds_up_to_its_arrangement() {
        // 15 bricks of 64³ (a 160x96x80 pyramid) arrange as 3x2x3 slots; within 15 the most are 12 (3x2x2).
        assert_eq!(slots_holding(15, [64; 3], 2048), Some(18));
        assert_eq!(slots_within(15, [64; 3], 2048), 12);
        assert_eq!(
            slots_holding(15, [64; 3], 64),
            None,
            "a slot (a brick and its border) is wider than 64"
        );
    }

    #[test]
    fn slots_within_a_budget_count_the_whole_arrangement() {
        for max in [1, 2, 13, 18, 40, 1000] {
            let n = slots_within(max, [64; 3], 2048);
            let p = Pool::with_capacity([4096; 3], [64; 3], 2048, n as usize, 0).unwrap();
            assert!(p.capacity() as u64 <= max && p.capacity() as u64 == n, "{max}: {n}");
        }
        assert!(slots_within(13, [64; 3], 2048) >= 12);
        // 5 slots of 20 texels per side at most.
        assert_eq!(slots_within(1000, [16; 3], 100), 125);
    }

    /// Every texel of every slot holds the voxel at its place around the brick, clamped to the volume.
    #[test]
    fn slots_hold_their_brick_and_its_border() {
        let dims = [37, 20, 9];
        let p = Pool::whole(dims, Some(16), 200).unwrap();
        let [tx, ty, tz] = p.texels();
        let side = p.brick.map(slot_side);
        let mut row = Vec::new();
        for z in 0..tz {
            for y in 0..ty {
                p.row_sources(y, z, &mut row);
                assert_eq!(row.len(), tx as usize);
                for x in 0..tx {
                    let slot = [x / side[0], y / side[1], z / side[2]];
                    let index = slot[0] + p.slots[0] * (slot[1] + p.slots[1] * slot[2]);
                    let local = [x % side[0], y % side[1], z % side[2]];
                    let want = p.resident[index as usize].map(|r| {
                        let v = [0, 1, 2].map(|a| {
                            (i64::from(r.brick[a] * p.brick[a] + local[a]) - 2).clamp(0, i64::from(dims[a]) - 1)
                                as usize
                        });
                        (0, v[0] + 37 * (v[1] + 20 * v[2]))
                    });
                    assert_eq!(row[x as usize], want, "texel {x} {y} {z}");
                }
            }
        }
        // The table names each level-0 brick's slot.
        let table = p.table();
        assert_eq!(table.len(), 6);
        let cut = Cut::uniform(p.grid, 0);
        for (i, e) in table.iter().enumerate() {
            let slot = p.directory[i];
            let [x, y, z] = p.slot_at(slot);
            assert_eq!(*e, [x | y << 10 | z << 20, 0]);
            let brick = cut.brick_of(i);
            assert_eq!(p.resident[slot as usize], Some(Resident { level: 0, brick }));
        }
    }

    /// A cut of mixed levels: one slot per brick shown, each level-0 brick pointed at the brick over it, and the
    /// slot's texels taken from that brick's level (clamped to the level's edge).
    #[test]
    fn a_cut_of_levels_fills_slots_from_its_levels() {
        let dims = [40, 24, 16];
        // Bricks of 8: a level-0 grid of 5 x 3 x 2; level 1 is 20 x 12 x 8, level 2 10 x 6 x 4.
        let mut cut = Cut::uniform([5, 3, 2], 0);
        let flat = cut.clone();
        for (i, l) in cut.level.iter_mut().enumerate() {
            let b = flat.brick_of(i);
            *l = if b[0] >= 2 { 2 } else { u32::from(b[1] >= 2) };
        }
        let p = Pool::with_cut(dims, [8; 3], 2048, &cut).unwrap();
        assert_eq!(p.levels, vec![[40, 24, 16], [20, 12, 8], [10, 6, 4]]);
        for (i, &slot) in p.directory.iter().enumerate() {
            let l = cut.level[i];
            let r = p.resident[slot as usize].unwrap();
            assert_eq!(
                (r.level, r.brick),
                (l, crate::pyramid::bricks::covering(cut.brick_of(i), l)),
                "level-0 brick {i}"
            );
        }
        // Level 2 bricks: x >= 2 at level 0 is brick 0 of level 2 (it covers level-0 bricks 0..4 per axis).
        let shown = cut.shown();
        assert!(shown.contains(&(2, [0, 0, 0])) && shown.contains(&(2, [1, 0, 0])));
        assert_eq!(p.resident.iter().flatten().count(), shown.len());
        let mut row = Vec::new();
        let side = 12;
        for (slot, r) in p.resident.iter().enumerate() {
            let Some(r) = r else { continue };
            let [sx, sy, sz] = p.slot_at(slot as u32);
            let ld = p.levels[r.level as usize];
            for (ly, lz) in [(0, 0), (5, 7), (11, 11)] {
                p.row_sources(sy * side + ly, sz * side + lz, &mut row);
                for lx in 0..side {
                    let at =
                        |a: usize, l: u32| (i64::from(r.brick[a] * 8 + l) - 2).clamp(0, i64::from(ld[a]) - 1) as usize;
                    let want = at(0, lx) + ld[0] as usize * (at(1, ly) + ld[1] as usize * at(2, lz));
                    assert_eq!(row[(sx * side + lx) as usize], Some((r.level, want)));
                }
            }
        }
    }
}
