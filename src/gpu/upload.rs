//! Filling sampled images: through a staging buffer in slabs (device images), or written in place (images made
//! by `Image::new_host_written`, on lavapipe). Either way the image ends ready for sampling in shaders.

use super::resources::{Buffer, Filling, Image};
use super::sync::{image_barrier, Access, COLOR_LAYERS};
use super::{Gpu, GpuError};
use ash::vk;
use gpu_allocator::MemoryLocation;
use rayon::prelude::*;

/// Most bytes staged at once. Larger images are uploaded in slabs of whole slices through one staging buffer of
/// this size, so an upload never needs a second copy of a large volume in memory (on lavapipe a 1 GiB volume
/// took 1 GiB of staging that the kernel had to zero first).
pub const STAGING_CHUNK: u64 = 64 << 20;

/// Fills `image` with `bytes` (tightly packed texels) and leaves it ready for sampling in fragment shaders.
pub fn upload_image(gpu: &Gpu, image: &mut Image, bytes: &[u8]) -> Result<(), GpuError> {
    upload_image_with(gpu, image, bytes.len() as u64, |range, dst| {
        // In blocks on every core: on lavapipe this copy is into fresh pages, and the kernel's zeroing of them
        // runs on the copying thread.
        dst.par_chunks_mut(1 << 20)
            .zip(bytes[range].par_chunks(1 << 20))
            .for_each(|(d, s)| d.copy_from_slice(s));
    })
}

/// Like [`upload_image`], but `fill(range, dst)` writes bytes `range` of the `len` bytes of tightly packed texels
/// straight into the staging buffer, or into a host-written image itself where it packs its rows and slices as
/// tightly (else through a scratch slab); conversions need no second copy of the data. It is called once per slab
/// of whole slices, in order, with `dst` aligned for any texel type.
pub fn upload_image_with(
    gpu: &Gpu,
    image: &mut Image,
    len: u64,
    mut fill: impl FnMut(std::ops::Range<usize>, &mut [u8]),
) -> Result<(), GpuError> {
    let extent = image.desc.extent;
    let depth = u64::from(extent.depth.max(1));
    let slice = len / depth;
    if slice == 0 || slice * depth != len {
        return Err(GpuError::Lost("upload size is not a whole number of slices"));
    }
    match image.filling {
        Filling::Transfer => {}
        Filling::HostPending(layout) => {
            let row = slice / u64::from(extent.height.max(1));
            return write_in_place(gpu, image, layout, [row, slice, len], fill);
        }
        Filling::HostWritten => return Err(GpuError::Lost("a host-written image is filled once")),
    }
    let per_chunk = (STAGING_CHUNK / slice).clamp(1, depth);
    let mut staging = Buffer::new(
        gpu,
        per_chunk * slice,
        vk::BufferUsageFlags::TRANSFER_SRC,
        MemoryLocation::CpuToGpu,
        "staging upload",
    )?;
    let mut result = Ok(());
    let mut z = 0;
    while z < depth && result.is_ok() {
        let n = per_chunk.min(depth - z);
        let bytes = (n * slice) as usize;
        let start = (z * slice) as usize;
        result = match staging.mapped_mut() {
            Some(dst) => {
                fill(start..start + bytes, &mut dst[..bytes]);
                Ok(())
            }
            None => Err(GpuError::Lost("staging buffer is not host-visible")),
        };
        let (first, last) = (z == 0, z + n == depth);
        result = result.and_then(|_| {
            let from = if first {
                Access::Undefined
            } else {
                Access::TransferWrite
            };
            let to = if last {
                Access::FragmentSampled
            } else {
                Access::TransferWrite
            };
            let region = vk::BufferImageCopy::default()
                .image_subresource(COLOR_LAYERS)
                .image_offset(vk::Offset3D {
                    x: 0,
                    y: 0,
                    z: z as i32,
                })
                .image_extent(vk::Extent3D {
                    depth: n as u32,
                    ..extent
                });
            copy_to_image(gpu, &staging, image.raw, &[region], from, to)
        });
        z += n;
    }
    staging.destroy(gpu);
    result
}

/// Copies `regions` of `buffer` into `image` in one submission, waited for: the image goes from `from` to transfer
/// (its contents kept unless `from` is `Undefined`), then to `to` (no second barrier when `to` is a transfer write:
/// the next copy's own barrier orders it).
pub fn copy_to_image(
    gpu: &Gpu,
    buffer: &Buffer,
    image: vk::Image,
    regions: &[vk::BufferImageCopy],
    from: Access,
    to: Access,
) -> Result<(), GpuError> {
    gpu.submit_and_wait(|cb| {
        image_barrier(&gpu.device, cb, image, from, Access::TransferWrite);
        // SAFETY: the caller's regions lie within the buffer and the image, which is in TRANSFER_DST layout.
        unsafe {
            gpu.device
                .cmd_copy_buffer_to_image(cb, buffer.raw, image, vk::ImageLayout::TRANSFER_DST_OPTIMAL, regions)
        };
        if to != Access::TransferWrite {
            image_barrier(&gpu.device, cb, image, Access::TransferWrite, to);
        }
    })
}

/// [`upload_image_with`] for a host-written image at `layout` in its memory, whose tightly packed texels have
/// `[row, slice, len]` bytes: filled where they lie if the device packs them as tightly (one slab), else slab by
/// slab through a scratch buffer and scattered to the device's row and slice pitches on every core (lavapipe pads
/// rows to 64 bytes and slices to 32 rows). Then moved to the layout shaders sample.
fn write_in_place(
    gpu: &Gpu,
    image: &mut Image,
    layout: vk::SubresourceLayout,
    [row, slice, len]: [u64; 3],
    mut fill: impl FnMut(std::ops::Range<usize>, &mut [u8]),
) -> Result<(), GpuError> {
    let raw = image.raw;
    let depth = len / slice;
    let (row_pitch, depth_pitch) = (layout.row_pitch, if depth == 1 { slice } else { layout.depth_pitch });
    let rows = slice / row;
    // The last slice's last row need not be padded.
    let needed = depth_pitch * (depth - 1) + row_pitch * (rows - 1) + row;
    if row_pitch < row || depth_pitch < row_pitch * rows || layout.size < needed {
        return Err(GpuError::Lost("host-written image is smaller than its texels"));
    }
    let memory = image
        .mapped_mut()
        .ok_or(GpuError::Lost("host-written image is not mapped"))?;
    let texels = memory
        .get_mut(layout.offset as usize..(layout.offset + needed) as usize)
        .ok_or(GpuError::Lost("host-written image is outside its memory"))?;
    crate::volume::huge_pages::advise(texels);
    if row_pitch == row && depth_pitch == slice {
        fill(0..len as usize, texels);
    } else {
        let [row, slice, depth, row_pitch, depth_pitch] =
            [row, slice, depth, row_pitch, depth_pitch].map(|v| v as usize);
        let per_slab = (STAGING_CHUNK as usize / slice).clamp(1, depth);
        // u64s, so that `fill` may view the slab as any texel type.
        let mut words = vec![0u64; (per_slab * slice).div_ceil(8)];
        let scratch: &mut [u8] = bytemuck::cast_slice_mut(&mut words);
        for first in (0..depth).step_by(per_slab) {
            let n = per_slab.min(depth - first);
            let src = &mut scratch[..n * slice];
            fill(first * slice..(first + n) * slice, src);
            let start = first * depth_pitch;
            let end = (start + n * depth_pitch).min(texels.len());
            texels[start..end]
                .par_chunks_mut(depth_pitch)
                .zip(src.par_chunks(slice))
                .for_each(|(dst, src)| {
                    for (d, s) in dst.chunks_mut(row_pitch).zip(src.chunks(row)) {
                        d[..row].copy_from_slice(s);
                    }
                });
        }
    }
    // Written once: from here on the device reads the image, so the host must not write it again.
    image.filling = Filling::HostWritten;
    // Host writes before a submission are visible to it; the barrier only changes the layout.
    gpu.submit_and_wait(|cb| image_barrier(&gpu.device, cb, raw, Access::HostWrite, Access::FragmentSampled))
}
