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

/// Voxels of border on each side of a brick in its slot: a point in the brick, moved one voxel (gradients) and
/// filtered (one more), reads at most two voxels beyond it.
pub const BORDER: u32 = 2;

/// The brick side used when a volume does not fit the device's 3D limit in one slot (docs/large-volumes.md has
/// the measurements).
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
        let one = dims.iter().all(|&d| slot_side(d) <= max_dim);
        let brick = match brick_side {
            Some(b) => dims.map(|d| b.max(1).min(d)),
            None if one => dims,
            None => dims.map(|d| TILED_BRICK.min(d)),
        };
        let grid = [0, 1, 2].map(|a| dims[a].div_ceil(brick[a]));
        let count = grid.iter().map(|&g| u64::from(g)).product::<u64>();
        let slots = arrange(count, brick.map(slot_side), max_dim).ok_or_else(|| {
            format!(
                "{count} bricks of {}x{}x{} do not fit a pool of 3D textures of at most {max_dim} per side",
                brick[0], brick[1], brick[2]
            )
        })?;
        let n_slots = slots.iter().map(|&s| s as usize).product::<usize>();
        let mut resident = vec![None; n_slots];
        let mut directory = Vec::with_capacity(count as usize);
        for z in 0..grid[2] {
            for y in 0..grid[1] {
                for x in 0..grid[0] {
                    let slot = directory.len();
                    resident[slot] = Some(Resident {
                        level: 0,
                        brick: [x, y, z],
                    });
                    directory.push(slot as u32);
                }
            }
        }
        Ok(Pool {
            dims,
            brick,
            grid,
            slots,
            resident,
            directory,
        })
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

    /// For each texel of pool row (`y`, `z`), the level-0 voxel (x, y, z index into `dims`) it holds, or None in
    /// an empty slot. Slots hold level-0 bricks only here; the border repeats the edge past the volume.
    pub fn row_sources(&self, y: u32, z: u32, out: &mut Vec<Option<usize>>) {
        out.clear();
        let side = self.brick.map(slot_side);
        let [sy, sz] = [y / side[1], z / side[2]];
        let (ly, lz) = (y % side[1], z % side[2]);
        let clamp = |a: usize, b: u32, l: u32| -> usize {
            let v = i64::from(b * self.brick[a]) + i64::from(l) - i64::from(BORDER);
            v.clamp(0, i64::from(self.dims[a]) - 1) as usize
        };
        for sx in 0..self.slots[0] {
            let index = sx + self.slots[0] * (sy + self.slots[1] * sz);
            match self.resident.get(index as usize).copied().flatten() {
                Some(r) => {
                    let row = self.dims[0] as usize
                        * (clamp(1, r.brick[1], ly) + self.dims[1] as usize * clamp(2, r.brick[2], lz));
                    out.extend((0..side[0]).map(|lx| Some(row + clamp(0, r.brick[0], lx))));
                }
                None => out.extend((0..side[0]).map(|_| None)),
            }
        }
    }

    /// Fills `dst`, the pool's texels from texel `first` on (whole rows; past the last slice they wrap to the
    /// first, as a depth-1 pool's second copy does), with `texel(row sources, x)`, rows on every core.
    pub fn fill<T: Send>(&self, first: usize, dst: &mut [T], texel: impl Fn(&PoolRows, usize) -> T + Sync) {
        use rayon::prelude::*;
        let [tx, ty, tz] = self.texels().map(|t| t as usize);
        let first_row = first / tx;
        dst.par_chunks_mut(tx).enumerate().for_each_init(
            || (Vec::new(), Vec::new()),
            |(this, next), (r, row)| {
                let at = (first_row + r) % (ty * tz);
                let (y, z) = ((at % ty) as u32, (at / ty) as u32);
                self.row_sources(y, z, this);
                self.row_sources((y + 1).min(ty as u32 - 1), z, next);
                let rows = PoolRows { this, next };
                for (x, d) in row.iter_mut().enumerate() {
                    *d = texel(&rows, x);
                }
            },
        );
    }
}

/// A pool row's sources and those of the row after it (the corner layout reads both).
pub struct PoolRows<'a> {
    pub this: &'a [Option<usize>],
    pub next: &'a [Option<usize>],
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
                        v[0] + 37 * (v[1] + 20 * v[2])
                    });
                    assert_eq!(row[x as usize], want, "texel {x} {y} {z}");
                }
            }
        }
        // The table names each level-0 brick's slot.
        let table = p.table();
        assert_eq!(table.len(), 3 * 2 * 1);
        for (i, e) in table.iter().enumerate() {
            let [x, y, z] = p.slot_at(i as u32);
            assert_eq!(*e, [x | y << 10 | z << 20, 0]);
        }
    }
}
