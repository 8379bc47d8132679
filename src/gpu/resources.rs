//! Buffers and images: `raw` handle + `desc` + `allocation`, destroyed explicitly with `destroy(self, gpu)`.

use super::sync::{image_barrier, memory_barrier, Access, COLOR_LAYERS, COLOR_RANGE};
use super::{Gpu, GpuError, VkContext};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

pub struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    allocation: Option<Allocation>,
}

impl Buffer {
    pub fn new(
        gpu: &Gpu,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
        name: &str,
    ) -> Result<Buffer, GpuError> {
        let info = vk::BufferCreateInfo::default().size(size.max(4)).usage(usage);
        // SAFETY: valid create info on a live device.
        let raw = unsafe { gpu.device.create_buffer(&info, None) }.ctx("vkCreateBuffer")?;
        // SAFETY: `raw` was just created on this device.
        let requirements = unsafe { gpu.device.get_buffer_memory_requirements(raw) };
        let allocation = gpu.allocator()?.allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the buffer is unused and unbound.
                unsafe { gpu.device.destroy_buffer(raw, None) };
                return Err(e.into());
            }
        };
        // SAFETY: the allocation satisfies the buffer's requirements and is not bound elsewhere.
        if let Err(e) = unsafe {
            gpu.device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        } {
            // SAFETY: as above, nothing uses the buffer yet.
            unsafe { gpu.device.destroy_buffer(raw, None) };
            let _ = gpu.allocator().map(|mut a| a.free(allocation));
            return Err(GpuError::vk("vkBindBufferMemory", e));
        }
        Ok(Buffer {
            raw,
            size,
            allocation: Some(allocation),
        })
    }

    /// Host-visible contents (CpuToGpu / GpuToCpu buffers).
    pub fn mapped(&self) -> Option<&[u8]> {
        self.allocation
            .as_ref()?
            .mapped_slice()
            .map(|s| &s[..self.size as usize])
    }

    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        let size = self.size as usize;
        self.allocation.as_mut()?.mapped_slice_mut().map(|s| &mut s[..size])
    }

    /// Copies `bytes` to the start of a host-visible buffer.
    pub fn write(&mut self, bytes: &[u8]) -> Result<(), GpuError> {
        let dst = self.mapped_mut().ok_or(GpuError::Lost("buffer is not host-visible"))?;
        if bytes.len() > dst.len() {
            return Err(GpuError::Lost("write larger than the buffer"));
        }
        dst[..bytes.len()].copy_from_slice(bytes);
        Ok(())
    }

    pub fn destroy(mut self, gpu: &Gpu) {
        // SAFETY: callers destroy a buffer only after the GPU finished using it.
        unsafe { gpu.device.destroy_buffer(self.raw, None) };
        if let (Some(a), Ok(mut alloc)) = (self.allocation.take(), gpu.allocator()) {
            let _ = alloc.free(a);
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageDesc {
    pub format: vk::Format,
    pub extent: vk::Extent3D,
    pub usage: vk::ImageUsageFlags,
}

impl ImageDesc {
    pub fn d2(format: vk::Format, width: u32, height: u32, usage: vk::ImageUsageFlags) -> ImageDesc {
        ImageDesc {
            format,
            extent: vk::Extent3D {
                width,
                height,
                depth: 1,
            },
            usage,
        }
    }

    pub fn is_3d(&self) -> bool {
        self.extent.depth > 1
    }

    /// The image and view types its extent calls for.
    fn types(&self) -> (vk::ImageType, vk::ImageViewType) {
        if self.is_3d() {
            (vk::ImageType::TYPE_3D, vk::ImageViewType::TYPE_3D)
        } else {
            (vk::ImageType::TYPE_2D, vk::ImageViewType::TYPE_2D)
        }
    }
}

pub struct Image {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub desc: ImageDesc,
    allocation: Option<Allocation>,
    /// How its texels get there.
    pub filling: Filling,
}

/// How an image's texels are filled (`upload::upload_image_with`).
#[derive(Clone, Copy, Debug)]
pub enum Filling {
    /// By transfers from a staging buffer, as often as needed ([`Image::new`]).
    Transfer,
    /// By the host, in place, once ([`Image::new_host_written`]): not yet written; the texels lie at this layout
    /// in the mapped memory.
    HostPending(vk::SubresourceLayout),
    /// By the host, and written: from here on only the device reads it.
    HostWritten,
}

impl Image {
    /// A device image (optimal tiling, device-local memory), filled by transfers.
    pub fn new(gpu: &Gpu, desc: ImageDesc, name: &str) -> Result<Image, GpuError> {
        Image::create(gpu, desc, name, false)
    }

    /// An image the host writes directly: linear tiling in host-visible memory, created PREINITIALIZED, for
    /// sampling only. `None` where the device cannot sample such an image of this format and size (most GPUs:
    /// there an upload goes through a staging buffer). On lavapipe, where device memory is host memory, this saves
    /// the staging copy and the device's single-threaded copy into the image (`upload::upload_image_with`).
    pub fn new_host_written(gpu: &Gpu, desc: ImageDesc, name: &str) -> Result<Option<Image>, GpuError> {
        let (image_type, _) = desc.types();
        // SAFETY: plain queries on a live physical device.
        let (limits, features) = unsafe {
            (
                gpu.instance.get_physical_device_image_format_properties(
                    gpu.physical,
                    desc.format,
                    image_type,
                    vk::ImageTiling::LINEAR,
                    desc.usage,
                    vk::ImageCreateFlags::empty(),
                ),
                gpu.instance
                    .get_physical_device_format_properties(gpu.physical, desc.format),
            )
        };
        // Sampled, and filtered wherever a device image of the format would be (integer formats never are).
        let filter = vk::FormatFeatureFlags::SAMPLED_IMAGE
            | (features.optimal_tiling_features & vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR);
        let fits = limits.is_ok_and(|l| {
            let e = desc.extent;
            e.width <= l.max_extent.width && e.height <= l.max_extent.height && e.depth <= l.max_extent.depth
        });
        if !fits || !features.linear_tiling_features.contains(filter) {
            return Ok(None);
        }
        let image = Image::create(gpu, desc, name, true)?;
        Ok(Some(image))
    }

    fn create(gpu: &Gpu, desc: ImageDesc, name: &str, host: bool) -> Result<Image, GpuError> {
        let (image_type, view_type) = desc.types();
        let info = vk::ImageCreateInfo::default()
            .image_type(image_type)
            .format(desc.format)
            .extent(desc.extent)
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(if host {
                vk::ImageTiling::LINEAR
            } else {
                vk::ImageTiling::OPTIMAL
            })
            .usage(desc.usage)
            .initial_layout(if host {
                vk::ImageLayout::PREINITIALIZED
            } else {
                vk::ImageLayout::UNDEFINED
            });
        // SAFETY: valid create info on a live device.
        let raw = unsafe { gpu.device.create_image(&info, None) }.ctx("vkCreateImage")?;
        // SAFETY: `raw` was just created on this device.
        let requirements = unsafe { gpu.device.get_image_memory_requirements(raw) };
        let allocation = gpu.allocator().and_then(|mut a| {
            a.allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: if host {
                    MemoryLocation::CpuToGpu
                } else {
                    MemoryLocation::GpuOnly
                },
                linear: host,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(GpuError::from)
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the image is unused and unbound.
                unsafe { gpu.device.destroy_image(raw, None) };
                return Err(e);
            }
        };
        let filling = if host {
            let color = vk::ImageSubresource {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                array_layer: 0,
            };
            // SAFETY: a linear image on this device; the subresource exists.
            Filling::HostPending(unsafe { gpu.device.get_image_subresource_layout(raw, color) })
        } else {
            Filling::Transfer
        };
        let mut image = Image {
            raw,
            view: vk::ImageView::null(),
            desc,
            allocation: Some(allocation),
            filling,
        };
        if host && image.allocation.as_ref().and_then(|a| a.mapped_ptr()).is_none() {
            image.destroy(gpu);
            return Err(GpuError::Lost("host-written image memory is not mapped"));
        }
        let alloc = image.allocation.as_ref().ok_or(GpuError::Lost("image allocation"))?;
        // SAFETY: the allocation satisfies the image's requirements and is not bound elsewhere.
        if let Err(e) = unsafe { gpu.device.bind_image_memory(raw, alloc.memory(), alloc.offset()) } {
            image.destroy(gpu);
            return Err(GpuError::vk("vkBindImageMemory", e));
        }
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(view_type)
            .format(desc.format)
            .subresource_range(COLOR_RANGE);
        // SAFETY: the image is bound and the view matches its type and format.
        match unsafe { gpu.device.create_image_view(&view_info, None) } {
            Ok(v) => image.view = v,
            Err(e) => {
                image.destroy(gpu);
                return Err(GpuError::vk("vkCreateImageView", e));
            }
        }
        Ok(image)
    }

    pub fn destroy(mut self, gpu: &Gpu) {
        // SAFETY: callers destroy an image only after the GPU finished using it.
        unsafe {
            if self.view != vk::ImageView::null() {
                gpu.device.destroy_image_view(self.view, None);
            }
            gpu.device.destroy_image(self.raw, None);
        }
        if let (Some(a), Ok(mut alloc)) = (self.allocation.take(), gpu.allocator()) {
            let _ = alloc.free(a);
        }
    }

    /// The mapped memory of a host-written image not yet written (texels at its `Filling::HostPending` layout).
    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        match self.filling {
            Filling::HostPending(_) => self.allocation.as_mut()?.mapped_slice_mut(),
            _ => None,
        }
    }

    /// Bytes the allocation takes on the device.
    pub fn allocated_bytes(&self) -> u64 {
        self.allocation.as_ref().map(|a| a.size()).unwrap_or(0)
    }
}

/// Records a copy of a 2D colour image (in `from` state) into a host-visible buffer and makes it readable by
/// the host. The image ends in `TransferRead`.
pub fn record_readback(gpu: &Gpu, cb: vk::CommandBuffer, image: &Image, from: Access, buffer: &Buffer) {
    image_barrier(&gpu.device, cb, image.raw, from, Access::TransferRead);
    let region = vk::BufferImageCopy::default()
        .image_subresource(COLOR_LAYERS)
        .image_extent(image.desc.extent);
    // SAFETY: the image is in TRANSFER_SRC layout and the buffer is large enough for its texels.
    unsafe {
        gpu.device.cmd_copy_image_to_buffer(
            cb,
            image.raw,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            buffer.raw,
            &[region],
        )
    };
    memory_barrier(&gpu.device, cb, Access::TransferWrite, Access::HostRead);
}
