//! Filling single slots of a streamed pool (stream.rs): each brick's texels and border gathered from its level on
//! every core into one staging buffer, then copied into its slot, one copy region per brick. A brick of a level
//! finer than the one the host holds is read from the volume's file first, as one box (`scale::finer`), the
//! batch's boxes on every core. Uploads are bounded per step by the caller, and batched here within
//! [`STAGING_CHUNK`] bytes of staging.

use super::gpu_volume::VolumeLayout;
use super::pool::{slot_side, Pool, PoolRows, Resident, BORDER};
use super::texels::{write_texels, Levels, Run, TexelKind, TexelRows};
use crate::gpu::resources::{Buffer, Image};
use crate::gpu::sync::{Access, COLOR_LAYERS};
use crate::gpu::upload::{copy_to_image, STAGING_CHUNK};
use crate::gpu::{Gpu, GpuError};
use crate::volume::{FinerLevels as Finer, VoxelData};
use ash::vk;
use gpu_allocator::MemoryLocation;
use rayon::prelude::*;

/// One slot's texels, rows of its slot-local (y, z), x fastest: from the pool's levels, or from `within`, a box
/// of the brick's level read for it.
struct SlotRows<'a> {
    pool: &'a Pool,
    brick: Resident,
    within: Option<&'a Boxed>,
}

/// The voxels a slot of a brick below the held level reads: its level's voxels `lo..lo + size`.
struct Boxed {
    data: VoxelData,
    lo: [u32; 3],
    size: [u32; 3],
}

impl SlotRows<'_> {
    /// Where the slot's rows start in x within the data they are read from (the level, or the box), where every
    /// row is contiguous there: the slot's x span (brick and border) lies inside the level. `None` at its x edges
    /// (the border clamps).
    fn first_x(&self) -> Option<usize> {
        let dims = self.pool.levels[self.brick.level as usize];
        let side = slot_side(self.pool.brick[0]);
        let x0 = (self.brick.brick[0] * self.pool.brick[0]).checked_sub(BORDER)?;
        let lo = self.within.map_or(0, |b| b.lo[0]);
        (x0 + side <= dims[0]).then_some((x0 - lo) as usize)
    }

    /// Slot-local texel `l` along axis `a` as a coordinate of the data the slot reads: clamped into its level (the
    /// border past the level's edge repeats it), less the box's corner where the slot reads a box.
    fn at(&self, a: usize, l: u32) -> usize {
        let dims = self.pool.levels[self.brick.level as usize];
        let lo = self.within.map_or(0, |b| b.lo[a]);
        let v = i64::from(self.brick.brick[a] * self.pool.brick[a]) + i64::from(l) - i64::from(BORDER);
        (v.clamp(0, i64::from(dims[a]) - 1) as u32 - lo) as usize
    }

    /// The level (as `Levels` index it) and element of x = 0 of row (`ly`, `lz`)'s data: the row [`row`](Self::row)
    /// reads, less its x offset.
    fn row_start(&self, ly: u32, lz: u32) -> (u32, usize) {
        let (level, [w, h, _]) = match self.within {
            Some(b) => (0, b.size),
            None => (self.brick.level, self.pool.levels[self.brick.level as usize]),
        };
        (level, w as usize * (self.at(1, ly) + h as usize * self.at(2, lz)))
    }

    /// Row (`ly`, `lz`) of the slot: from the levels, or (level 0 of the box's own [`Levels`]) from the box.
    fn row(&self, ly: u32, lz: u32, out: &mut Vec<Option<super::pool::Source>>) {
        if self.within.is_none() {
            return self.pool.slot_row(self.brick, ly, lz, out);
        }
        let (_, first) = self.row_start(ly, lz);
        out.extend((0..slot_side(self.pool.brick[0])).map(|lx| Some((0, first + self.at(0, lx)))));
    }
}

/// The box of its level a slot of `r` reads (the brick and its border, clamped into the level).
fn slot_box(pool: &Pool, r: Resident) -> ([u32; 3], [u32; 3]) {
    let dims = pool.levels[r.level as usize];
    let lo = [0, 1, 2].map(|a| (r.brick[a] * pool.brick[a]).saturating_sub(BORDER));
    let hi = [0, 1, 2].map(|a| (r.brick[a] * pool.brick[a] + pool.brick[a] + BORDER).min(dims[a]));
    (lo, [0, 1, 2].map(|a| hi[a] - lo[a]))
}

impl TexelRows for SlotRows<'_> {
    fn fill<T: Send>(&self, dst: &mut [T], pairs: bool, texel: impl Fn(&PoolRows, usize) -> T + Sync, run: Run<T>) {
        let side = self.pool.brick.map(slot_side);
        let first_x = self.first_x();
        dst.par_chunks_mut(side[0] as usize).enumerate().for_each_init(
            || (Vec::new(), Vec::new()),
            |(this, next), (r, row)| {
                let (ly, lz) = (r as u32 % side[1], r as u32 / side[1]);
                if let (Some(run), Some(x0), false) = (run, first_x, pairs) {
                    let (level, first) = self.row_start(ly, lz);
                    return run(level, first + x0, row);
                }
                this.clear();
                next.clear();
                self.row(ly, lz, this);
                if pairs {
                    self.row((ly + 1).min(side[1] - 1), lz, next);
                }
                let rows = PoolRows { this, next };
                for (x, d) in row.iter_mut().enumerate() {
                    *d = texel(&rows, x);
                }
            },
        );
    }

    fn last_x(&self) -> usize {
        slot_side(self.pool.brick[0]) as usize - 1
    }
}

/// What the skip grid needs of a brick read from the file: the element range of each skip cell it covers
/// (finer_cells.rs).
pub(super) type BoxRange = (Resident, super::finer_cells::BoxCells<Option<(f64, f64)>>);

/// Uploads the bricks `pool.resident` names in `slots` into `image` (the pool's texture or corner texture in
/// `layout`). `fresh`: the image has never been written (its old contents are discarded on the first copy).
/// Returns the element ranges of the bricks read from `finer`'s file.
pub(super) fn upload_bricks(
    gpu: &Gpu,
    image: &Image,
    layout: VolumeLayout,
    (levels, finer): (&Levels, Option<&dyn Finer>),
    pool: &Pool,
    slots: &[u32],
    fresh: bool,
) -> Result<Vec<BoxRange>, GpuError> {
    let kind = layout.texel_kind(levels);
    let side = pool.brick.map(slot_side);
    let slot_bytes = side.iter().map(|&s| s as usize).product::<usize>() * kind.bytes(levels);
    let per_batch = (STAGING_CHUNK as usize / slot_bytes).clamp(1, slots.len().max(1));
    let mut staging = Buffer::new(
        gpu,
        (per_batch * slot_bytes) as u64,
        vk::BufferUsageFlags::TRANSFER_SRC,
        MemoryLocation::CpuToGpu,
        "staging bricks",
    )?;
    let (mut ranges, mut result) = (Vec::new(), Ok(()));
    for (n, batch) in slots.chunks(per_batch).enumerate() {
        result = fill_batch(&mut staging, (pool, levels, finer), kind, batch, slot_bytes).and_then(|mut r| {
            copy_batch(gpu, &staging, image, pool, batch, slot_bytes, fresh && n == 0)?;
            ranges.append(&mut r);
            Ok(())
        });
        if result.is_err() {
            break;
        }
    }
    staging.destroy(gpu);
    result.map(|()| ranges)
}

/// Writes each slot's texels into its part of the staging buffer: the boxes of bricks below the held level read
/// from the file first, on every core.
fn fill_batch(
    staging: &mut Buffer,
    (pool, levels, finer): (&Pool, &Levels, Option<&dyn Finer>),
    kind: TexelKind,
    batch: &[u32],
    slot_bytes: usize,
) -> Result<Vec<BoxRange>, GpuError> {
    let bricks = batch
        .iter()
        .map(|&slot| pool.resident.get(slot as usize).copied().flatten())
        .collect::<Option<Vec<Resident>>>()
        .ok_or(GpuError::Lost("an upload into a slot that holds no brick"))?;
    let boxes = bricks
        .par_iter()
        .map(|&r| match finer {
            Some(f) if r.level < f.held() => {
                let (lo, size) = slot_box(pool, r);
                let data = f.read(r.level, lo, size).map_err(|e| GpuError::Source(e.to_string()))?;
                Ok(Some(Boxed { data, lo, size }))
            }
            _ => Ok(None),
        })
        .collect::<Result<Vec<Option<Boxed>>, GpuError>>()?;
    let dst = staging
        .mapped_mut()
        .ok_or(GpuError::Lost("staging buffer is not host-visible"))?;
    for (i, (&brick, boxed)) in bricks.iter().zip(&boxes).enumerate() {
        let part = &mut dst[i * slot_bytes..(i + 1) * slot_bytes];
        let rows = SlotRows {
            pool,
            brick,
            within: boxed.as_ref(),
        };
        match boxed {
            Some(b) => write_texels(&rows, &Levels::single(&b.data), kind, part),
            None => write_texels(&rows, levels, kind, part),
        }
    }
    let Some(held) = finer.map(|f| f.held()) else {
        return Ok(Vec::new());
    };
    let cell = super::skip::BRICK << held;
    Ok(bricks
        .par_iter()
        .zip(&boxes)
        .filter_map(|(&r, b)| {
            let b = b.as_ref()?;
            let dims = pool.levels[r.level as usize];
            let ilo = [0, 1, 2].map(|a| r.brick[a] * pool.brick[a]);
            let ihi = [0, 1, 2].map(|a| (ilo[a] + pool.brick[a]).min(dims[a]));
            let cells = super::finer_cells::box_cells(&b.data, (b.lo, b.size), (ilo, ihi), r.level, cell);
            Some((r, cells))
        })
        .collect())
}

/// Copies the batch's staged bricks into their slots: from sampled (or, `fresh`, discarded) to transfer and back.
fn copy_batch(
    gpu: &Gpu,
    staging: &Buffer,
    image: &Image,
    pool: &Pool,
    batch: &[u32],
    slot_bytes: usize,
    fresh: bool,
) -> Result<(), GpuError> {
    let side = pool.brick.map(slot_side);
    let regions: Vec<vk::BufferImageCopy> = batch
        .iter()
        .enumerate()
        .map(|(i, &slot)| {
            let at = pool.slot_at(slot);
            vk::BufferImageCopy::default()
                .buffer_offset((i * slot_bytes) as u64)
                .image_subresource(COLOR_LAYERS)
                .image_offset(vk::Offset3D {
                    x: (at[0] * side[0]) as i32,
                    y: (at[1] * side[1]) as i32,
                    z: (at[2] * side[2]) as i32,
                })
                .image_extent(vk::Extent3D {
                    width: side[0],
                    height: side[1],
                    depth: side[2],
                })
        })
        .collect();
    let from = if fresh {
        Access::Undefined
    } else {
        Access::FragmentSampled
    };
    copy_to_image(gpu, staging, image.raw, &regions, from, Access::FragmentSampled)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The box `lo..lo + size` of `data` (a volume of `dims`).
    fn crop(data: &VoxelData, dims: [u32; 3], lo: [u32; 3], size: [u32; 3]) -> VoxelData {
        fn cut<T: Copy>(v: &[T], dims: [u32; 3], lo: [u32; 3], size: [u32; 3]) -> Vec<T> {
            let at = |x: u32, y: u32, z: u32| (x + dims[0] * (y + dims[1] * z)) as usize;
            (lo[2]..lo[2] + size[2])
                .flat_map(|z| (lo[1]..lo[1] + size[1]).map(move |y| (y, z)))
                .flat_map(|(y, z)| v[at(lo[0], y, z)..at(lo[0] + size[0], y, z)].to_vec())
                .collect()
        }
        match data {
            VoxelData::U8(v) => VoxelData::U8(cut(v, dims, lo, size)),
            VoxelData::U16(v) => VoxelData::U16(cut(v, dims, lo, size)),
            VoxelData::F32(v) => VoxelData::F32(cut(v, dims, lo, size)),
        }
    }

    /// Every slot's texels, written as the stream writes them (rows inside the level copied as runs, the level's x
    /// edges gathered), equal the pool's definition: texel (lx, ly, lz) of brick b is the level's voxel at
    /// b · side + l − BORDER, clamped into the level; for each element type, stored and widened to float.
    #[test]
    fn slot_texels_follow_the_clamped_definition_in_every_kind() {
        let dims = [40u32, 37, 35];
        let pool = Pool::whole(dims, Some(16), 2048).unwrap();
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let u8s: Vec<u8> = (0..n).map(|i| (i * 7919 % 251) as u8).collect();
        let u16s: Vec<u16> = (0..n).map(|i| (i * 7919 % 65521) as u16).collect();
        let f32s: Vec<f32> = (0..n).map(|i| (i * 7919 % 1009) as f32 * 0.5).collect();
        let side = pool.brick.map(slot_side);
        let texels = side.iter().map(|&s| s as usize).product::<usize>();
        let voxel = |r: Resident, l: [u32; 3]| -> usize {
            let at = |a: usize| {
                let v = i64::from(r.brick[a] * pool.brick[a]) + i64::from(l[a]) - i64::from(BORDER);
                v.clamp(0, i64::from(dims[a]) - 1) as usize
            };
            at(0) + dims[0] as usize * (at(1) + dims[1] as usize * at(2))
        };
        let cases: [(VoxelData, TexelKind); 5] = [
            (VoxelData::U8(u8s.clone()), TexelKind::Native),
            (VoxelData::U8(u8s), TexelKind::Widened),
            (VoxelData::U16(u16s.clone()), TexelKind::Native),
            (VoxelData::U16(u16s), TexelKind::Widened),
            (VoxelData::F32(f32s), TexelKind::Native),
        ];
        for (data, kind) in &cases {
            let levels = Levels::single(data);
            for r in pool.resident.iter().flatten() {
                let rows = SlotRows {
                    pool: &pool,
                    brick: *r,
                    within: None,
                };
                let mut dst = vec![0u8; texels * kind.bytes(&levels)];
                write_texels(&rows, &levels, *kind, &mut dst);
                // The same slot from its box (as a brick read from the file is): the same texels.
                let (lo, size) = slot_box(&pool, *r);
                let boxed = Boxed {
                    data: crop(data, dims, lo, size),
                    lo,
                    size,
                };
                let from_box = SlotRows {
                    pool: &pool,
                    brick: *r,
                    within: Some(&boxed),
                };
                let mut again = vec![0u8; dst.len()];
                write_texels(&from_box, &Levels::single(&boxed.data), *kind, &mut again);
                assert!(again == dst, "{kind:?} brick {:?} from its box", r.brick);
                let slot =
                    (0..side[2]).flat_map(|z| (0..side[1]).flat_map(move |y| (0..side[0]).map(move |x| (x, y, z))));
                for (lx, ly, lz) in slot {
                    let i = (lx + side[0] * (ly + side[1] * lz)) as usize;
                    let v = voxel(*r, [lx, ly, lz]);
                    let (got, want) = match (data, kind) {
                        (VoxelData::U8(d), TexelKind::Native) => (f64::from(dst[i]), f64::from(d[v])),
                        (VoxelData::U16(d), TexelKind::Native) => {
                            let got = u16::from_ne_bytes([dst[2 * i], dst[2 * i + 1]]);
                            (f64::from(got), f64::from(d[v]))
                        }
                        (d, _) => {
                            let got = f32::from_ne_bytes(dst[4 * i..4 * i + 4].try_into().unwrap());
                            let want = match d {
                                VoxelData::U8(d) => f32::from(d[v]) / 255.0,
                                VoxelData::U16(d) => f32::from(d[v]) / 65535.0,
                                VoxelData::F32(d) => d[v],
                            };
                            (f64::from(got), f64::from(want))
                        }
                    };
                    assert_eq!(got, want, "{kind:?} brick {:?} texel ({lx}, {ly}, {lz})", r.brick);
                }
            }
        }
    }
}
