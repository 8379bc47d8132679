//! The handful of resource states volcast uses, and synchronization2 barriers between them. A barrier reads as
//! `image_barrier(.., Access::ColorAttachmentWrite, Access::FragmentSampled)`; stages, access masks and layouts
//! are derived from the names (after kajiya's `AccessType`).

use ash::vk;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Contents are discarded.
    Undefined,
    /// A swapchain image just acquired: contents discarded, and the barrier must wait at the stage where the
    /// submission waits for the acquire semaphore (TRANSFER), so the layout transition happens after it.
    SwapchainAcquired,
    TransferWrite,
    TransferRead,
    ColorAttachmentWrite,
    /// Sampled or fetched by a fragment shader.
    FragmentSampled,
    /// Written by a compute shader as a storage image (GENERAL layout).
    ComputeWrite,
    /// Read and written by a compute shader as a storage image (GENERAL layout): a pass reading an earlier one's.
    ComputeReadWrite,
    Present,
    HostRead,
    /// Written by the host before submission (a host-written image, PREINITIALIZED).
    HostWrite,
}

impl Access {
    fn stage(self) -> vk::PipelineStageFlags2 {
        match self {
            Access::Undefined => vk::PipelineStageFlags2::NONE,
            Access::SwapchainAcquired => vk::PipelineStageFlags2::TRANSFER,
            Access::TransferWrite | Access::TransferRead => vk::PipelineStageFlags2::TRANSFER,
            Access::ColorAttachmentWrite => vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            Access::FragmentSampled => vk::PipelineStageFlags2::FRAGMENT_SHADER,
            Access::ComputeWrite | Access::ComputeReadWrite => vk::PipelineStageFlags2::COMPUTE_SHADER,
            // Presentation is ordered by semaphores; the barrier needs no later stage.
            Access::Present => vk::PipelineStageFlags2::NONE,
            Access::HostRead | Access::HostWrite => vk::PipelineStageFlags2::HOST,
        }
    }

    fn access(self) -> vk::AccessFlags2 {
        match self {
            Access::Undefined | Access::SwapchainAcquired | Access::Present => vk::AccessFlags2::NONE,
            Access::TransferWrite => vk::AccessFlags2::TRANSFER_WRITE,
            Access::TransferRead => vk::AccessFlags2::TRANSFER_READ,
            Access::ColorAttachmentWrite => vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
            // SHADER_READ rather than SHADER_SAMPLED_READ: the 1.3.239 layer's best-practices check flags the
            // latter with SHADER_READ_ONLY_OPTIMAL (a false positive), and SHADER_READ covers it.
            Access::FragmentSampled => vk::AccessFlags2::SHADER_READ,
            Access::ComputeWrite => vk::AccessFlags2::SHADER_STORAGE_WRITE,
            Access::ComputeReadWrite => vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
            Access::HostRead => vk::AccessFlags2::HOST_READ,
            Access::HostWrite => vk::AccessFlags2::HOST_WRITE,
        }
    }

    fn layout(self) -> vk::ImageLayout {
        match self {
            Access::Undefined | Access::SwapchainAcquired => vk::ImageLayout::UNDEFINED,
            Access::TransferWrite => vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            Access::TransferRead => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            Access::ColorAttachmentWrite => vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            Access::FragmentSampled => vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            Access::Present => vk::ImageLayout::PRESENT_SRC_KHR,
            Access::HostRead | Access::ComputeWrite | Access::ComputeReadWrite => vk::ImageLayout::GENERAL,
            Access::HostWrite => vk::ImageLayout::PREINITIALIZED,
        }
    }
}

/// One image transition; colour aspect, whole image.
#[derive(Clone, Copy, Debug)]
pub struct ImageTransition {
    pub image: vk::Image,
    pub from: Access,
    pub to: Access,
    /// Old contents are not needed: the layout goes from UNDEFINED, but the barrier still waits for `from`'s
    /// stage (a write-after-read on a target reused every frame).
    pub discard: bool,
}

/// Records all `transitions` as one `vkCmdPipelineBarrier2`.
pub fn image_barriers(device: &ash::Device, cb: vk::CommandBuffer, transitions: &[ImageTransition]) {
    let barriers: Vec<vk::ImageMemoryBarrier2> = transitions
        .iter()
        .map(|t| {
            vk::ImageMemoryBarrier2::default()
                .src_stage_mask(t.from.stage())
                .src_access_mask(t.from.access())
                .dst_stage_mask(t.to.stage())
                .dst_access_mask(t.to.access())
                .old_layout(if t.discard {
                    vk::ImageLayout::UNDEFINED
                } else {
                    t.from.layout()
                })
                .new_layout(t.to.layout())
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(t.image)
                .subresource_range(COLOR_RANGE)
        })
        .collect();
    let dep = vk::DependencyInfo::default().image_memory_barriers(&barriers);
    // SAFETY: `cb` is recording and every image belongs to `device`.
    unsafe { device.cmd_pipeline_barrier2(cb, &dep) };
}

pub fn image_barrier(device: &ash::Device, cb: vk::CommandBuffer, image: vk::Image, from: Access, to: Access) {
    image_barriers(
        device,
        cb,
        &[ImageTransition {
            image,
            from,
            to,
            discard: false,
        }],
    );
}

/// A global memory barrier (buffers need no layout, and volcast never shares a buffer's ranges).
pub fn memory_barrier(device: &ash::Device, cb: vk::CommandBuffer, from: Access, to: Access) {
    let barrier = [vk::MemoryBarrier2::default()
        .src_stage_mask(from.stage())
        .src_access_mask(from.access())
        .dst_stage_mask(to.stage())
        .dst_access_mask(to.access())];
    let dep = vk::DependencyInfo::default().memory_barriers(&barrier);
    // SAFETY: `cb` is recording on `device`.
    unsafe { device.cmd_pipeline_barrier2(cb, &dep) };
}

pub const COLOR_RANGE: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

/// The colour aspect's one mip level and layer, for buffer/image copies and blits.
pub const COLOR_LAYERS: vk::ImageSubresourceLayers = vk::ImageSubresourceLayers {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    mip_level: 0,
    base_array_layer: 0,
    layer_count: 1,
};
