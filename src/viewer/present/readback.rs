//! A frame's pixels read back for the captures (F12, F9 and their Shift forms): the view image (the clean render,
//! what `volcast render --state` renders again) and the view's place in the swapchain image after egui drew over
//! it (the view as shown: box and clip outlines, labels, gizmos).

use crate::gpu::resources::{record_readback, Buffer, Image};
use crate::gpu::sync::{image_barrier, memory_barrier, Access, COLOR_LAYERS};
use crate::gpu::{Gpu, GpuError, VkContext};
use ash::vk;

/// Which pixels of a frame its captures want.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Wanted {
    /// The view image: the render alone.
    pub clean: bool,
    /// The view's rectangle of the presented image, overlays included.
    pub shown: bool,
}

impl Wanted {
    pub fn any(self) -> bool {
        self.clean || self.shown
    }
}

/// A frame's pixels (RGBA8, the view's size), each kind when wanted.
#[derive(Default)]
pub struct Pixels {
    pub clean: Option<Result<Vec<u8>, String>>,
    pub shown: Option<Result<Vec<u8>, String>>,
}

/// The copies a frame recorded into host-visible buffers: read them once the frame is done.
pub struct Readback {
    clean: Option<Buffer>,
    /// The swapchain's copy, and whether it holds BGRA (swapped to RGBA when read).
    shown: Option<(Buffer, bool)>,
    /// Why the shown copy could not be made (a swapchain the surface does not let be read).
    shown_error: Option<String>,
}

impl Readback {
    /// Records the copy of `view` (after the blit read it), if wanted.
    pub(super) fn record_clean(
        gpu: &Gpu,
        cb: vk::CommandBuffer,
        view: &Image,
        wanted: Wanted,
    ) -> Result<Readback, GpuError> {
        let clean = if wanted.clean {
            let extent = view.desc.extent;
            let buffer = host_buffer(gpu, extent.width, extent.height, "view readback")?;
            record_readback(gpu, cb, view, Access::TransferRead, &buffer);
            Some(buffer)
        } else {
            None
        };
        Ok(Readback {
            clean,
            shown: None,
            shown_error: None,
        })
    }

    /// After egui drew on `target` (a colour attachment): copies the view's rectangle of it when wanted, and
    /// makes `target` ready to present either way.
    pub(super) fn record_shown(
        &mut self,
        gpu: &Gpu,
        cb: vk::CommandBuffer,
        target: vk::Image,
        place: Place,
    ) -> Result<(), GpuError> {
        let dev = &gpu.device;
        if !place.wanted {
            image_barrier(dev, cb, target, Access::ColorAttachmentWrite, Access::Present);
            return Ok(());
        }
        if !place.readable {
            self.shown_error = Some("this window's swapchain cannot be read back (no TRANSFER_SRC)".into());
            image_barrier(dev, cb, target, Access::ColorAttachmentWrite, Access::Present);
            return Ok(());
        }
        let buffer = host_buffer(gpu, place.size.width, place.size.height, "shown readback")?;
        image_barrier(dev, cb, target, Access::ColorAttachmentWrite, Access::TransferRead);
        let region = vk::BufferImageCopy::default()
            .image_subresource(COLOR_LAYERS)
            .image_offset(vk::Offset3D {
                x: place.offset.x,
                y: place.offset.y,
                z: 0,
            })
            .image_extent(vk::Extent3D {
                width: place.size.width,
                height: place.size.height,
                depth: 1,
            });
        // SAFETY: the image is in TRANSFER_SRC layout, the region lies inside it (view_pixels clamps it) and the
        // buffer holds its texels.
        unsafe {
            dev.cmd_copy_image_to_buffer(cb, target, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buffer.raw, &[region])
        };
        memory_barrier(dev, cb, Access::TransferWrite, Access::HostRead);
        image_barrier(dev, cb, target, Access::TransferRead, Access::Present);
        self.shown = Some((buffer, place.format == vk::Format::B8G8R8A8_UNORM));
        Ok(())
    }

    /// Waits for the device, then takes the pixels (RGBA8) and frees the buffers.
    pub(super) fn pixels(self, gpu: &Gpu) -> Pixels {
        // SAFETY: plain wait on a live device.
        let idle = unsafe { gpu.device.device_wait_idle() }
            .ctx("vkDeviceWaitIdle")
            .map_err(|e| e.to_string());
        let read = |buffer: Buffer, bgra: bool| {
            let pixels = idle.clone().and_then(|_| {
                buffer
                    .mapped()
                    .map(<[u8]>::to_vec)
                    .ok_or_else(|| "the readback buffer is not mapped".to_string())
            });
            buffer.destroy(gpu);
            pixels.map(|mut p| {
                for px in p.chunks_exact_mut(4) {
                    if bgra {
                        px.swap(0, 2);
                    }
                    // The swapchain is opaque whatever alpha egui blended into it.
                    px[3] = 255;
                }
                p
            })
        };
        let shown = match (self.shown, self.shown_error) {
            (Some((buffer, bgra)), _) => Some(read(buffer, bgra)),
            (None, Some(e)) => Some(Err(e)),
            (None, None) => None,
        };
        Pixels {
            clean: self.clean.map(|b| read(b, false)),
            shown,
        }
    }
}

/// Where the view is in the swapchain image and what that image is.
pub(super) struct Place {
    pub(super) wanted: bool,
    pub(super) readable: bool,
    pub(super) format: vk::Format,
    pub(super) offset: vk::Offset2D,
    pub(super) size: vk::Extent2D,
}

fn host_buffer(gpu: &Gpu, width: u32, height: u32, name: &str) -> Result<Buffer, GpuError> {
    Buffer::new(
        gpu,
        width as u64 * height as u64 * 4,
        vk::BufferUsageFlags::TRANSFER_DST,
        gpu_allocator::MemoryLocation::GpuToCpu,
        name,
    )
}
