//! The frames in flight: each slot's command buffer, its fence (signalled when the GPU has finished the frame
//! recorded in it) and the semaphore its swapchain image is acquired with.

use crate::gpu::{Gpu, GpuError, VkContext};
use ash::vk;

/// Frames the CPU may record ahead of the GPU.
pub const FRAMES_IN_FLIGHT: usize = 2;

pub(super) struct FrameSync {
    pub(super) cb: vk::CommandBuffer,
    pub(super) fence: vk::Fence,
    pub(super) image_available: vk::Semaphore,
}

#[derive(Default)]
pub(super) struct FrameSlots {
    slots: Vec<FrameSync>,
    /// Frames submitted so far; the next one records into slot `frame_index % FRAMES_IN_FLIGHT`.
    frame_index: usize,
    /// Whether the frame last recorded in each slot was a reduced-detail one.
    reduced: [bool; FRAMES_IN_FLIGHT],
}

impl FrameSlots {
    pub(super) fn new(gpu: &Gpu) -> Result<FrameSlots, GpuError> {
        let mut slots = FrameSlots {
            slots: Vec::new(),
            frame_index: 0,
            reduced: [false; FRAMES_IN_FLIGHT],
        };
        for _ in 0..FRAMES_IN_FLIGHT {
            match FrameSync::new(gpu) {
                Ok(sync) => slots.slots.push(sync),
                Err(e) => {
                    slots.destroy(gpu);
                    return Err(e);
                }
            }
        }
        Ok(slots)
    }

    /// The slot the next frame records into, and its objects.
    pub(super) fn current(&self) -> (usize, &FrameSync) {
        let slot = self.frame_index % FRAMES_IN_FLIGHT;
        (slot, &self.slots[slot])
    }

    /// Whether every slot has been used once (so that each holds a finished frame's timings).
    pub(super) fn all_used(&self) -> bool {
        self.frame_index >= FRAMES_IN_FLIGHT
    }

    /// Records whether the frame now recorded in the current slot is a reduced one; returns what the slot's last
    /// frame was.
    pub(super) fn swap_reduced(&mut self, reduced: bool) -> bool {
        let slot = self.frame_index % FRAMES_IN_FLIGHT;
        std::mem::replace(&mut self.reduced[slot], reduced)
    }

    /// The current slot's frame was submitted: the next frame takes the next slot.
    pub(super) fn advance(&mut self) {
        self.frame_index += 1;
    }

    /// Destroys every slot's objects. The device must be idle.
    pub(super) fn destroy(&mut self, gpu: &Gpu) {
        for f in self.slots.drain(..) {
            // SAFETY: the device is idle; these objects are no longer used.
            unsafe {
                gpu.device.destroy_fence(f.fence, None);
                gpu.device.destroy_semaphore(f.image_available, None);
                gpu.device.free_command_buffers(gpu.command_pool, &[f.cb]);
            }
        }
    }
}

impl FrameSync {
    fn new(gpu: &Gpu) -> Result<FrameSync, GpuError> {
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(gpu.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: valid allocate/create infos on a live device; each object is destroyed in `destroy` (the ones
        // made before a failure leak only until the device is destroyed, which reports them).
        unsafe {
            Ok(FrameSync {
                cb: gpu
                    .device
                    .allocate_command_buffers(&alloc)
                    .ctx("vkAllocateCommandBuffers")?[0],
                fence: gpu
                    .device
                    .create_fence(
                        &vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED),
                        None,
                    )
                    .ctx("vkCreateFence")?,
                image_available: gpu
                    .device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
                    .ctx("vkCreateSemaphore")?,
            })
        }
    }

    /// Waits until the GPU has finished the frame last recorded here, so that its resources can be reused.
    pub(super) fn wait(&self, gpu: &Gpu) -> Result<(), GpuError> {
        // SAFETY: the fence belongs to this device.
        unsafe { gpu.device.wait_for_fences(&[self.fence], true, u64::MAX) }.ctx("vkWaitForFences")
    }
}
