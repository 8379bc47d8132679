//! Filling single slots of a streamed pool (stream.rs): each brick's texels and border gathered from its level on
//! every core into one staging buffer, then copied into its slot, one copy region per brick. Uploads are bounded
//! per step by the caller, and batched here within [`STAGING_CHUNK`] bytes of staging.

use super::gpu_volume::{write_texels, Levels, TexelKind, TexelRows, VolumeLayout};
use super::pool::{slot_side, Pool, PoolRows, Resident};
use crate::gpu::resources::{Buffer, Image};
use crate::gpu::sync::{Access, COLOR_LAYERS};
use crate::gpu::upload::{copy_to_image, STAGING_CHUNK};
use crate::gpu::{Gpu, GpuError};
use ash::vk;
use gpu_allocator::MemoryLocation;
use rayon::prelude::*;

/// One slot's texels, rows of its slot-local (y, z), x fastest.
struct SlotRows<'a> {
    pool: &'a Pool,
    brick: Resident,
}

impl TexelRows for SlotRows<'_> {
    fn fill<T: Send>(&self, dst: &mut [T], texel: impl Fn(&PoolRows, usize) -> T + Sync) {
        let side = self.pool.brick.map(slot_side);
        dst.par_chunks_mut(side[0] as usize).enumerate().for_each_init(
            || (Vec::new(), Vec::new()),
            |(this, next), (r, row)| {
                let (ly, lz) = (r as u32 % side[1], r as u32 / side[1]);
                this.clear();
                next.clear();
                self.pool.slot_row(self.brick, ly, lz, this);
                self.pool.slot_row(self.brick, (ly + 1).min(side[1] - 1), lz, next);
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

/// Uploads the bricks `pool.resident` names in `slots` into `image` (the pool's texture or corner texture in
/// `layout`). `fresh`: the image has never been written (its old contents are discarded on the first copy).
pub(super) fn upload_bricks(
    gpu: &Gpu,
    image: &Image,
    layout: VolumeLayout,
    levels: &Levels,
    pool: &Pool,
    slots: &[u32],
    fresh: bool,
) -> Result<(), GpuError> {
    let kind = TexelKind::of(layout, levels);
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
    let mut result = Ok(());
    for (n, batch) in slots.chunks(per_batch).enumerate() {
        result = fill_batch(&mut staging, pool, levels, kind, batch, slot_bytes)
            .and_then(|()| copy_batch(gpu, &staging, image, pool, batch, slot_bytes, fresh && n == 0));
        if result.is_err() {
            break;
        }
    }
    staging.destroy(gpu);
    result
}

/// Writes each slot's texels into its part of the staging buffer.
fn fill_batch(
    staging: &mut Buffer,
    pool: &Pool,
    levels: &Levels,
    kind: TexelKind,
    batch: &[u32],
    slot_bytes: usize,
) -> Result<(), GpuError> {
    let dst = staging
        .mapped_mut()
        .ok_or(GpuError::Lost("staging buffer is not host-visible"))?;
    for (i, &slot) in batch.iter().enumerate() {
        let brick = pool
            .resident
            .get(slot as usize)
            .copied()
            .flatten()
            .ok_or(GpuError::Lost("an upload into a slot that holds no brick"))?;
        let part = &mut dst[i * slot_bytes..(i + 1) * slot_bytes];
        write_texels(&SlotRows { pool, brick }, levels, kind, part);
    }
    Ok(())
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
