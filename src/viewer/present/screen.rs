//! The window's surface and swapchain: made again when the window's size or vsync changes or presentation says
//! it is out of date; one "rendering finished" semaphore per swapchain image (present waits on it).

use crate::gpu::swapchain::{Surface, Swapchain, SwapchainDesc};
use crate::gpu::{Gpu, GpuError, VkContext};
use crate::viewer::ViewerError;
use ash::vk;

pub(super) struct Screen {
    surface: Option<Surface>,
    swapchain: Option<Swapchain>,
    /// Signalled when an image's frame is rendered, waited on by its present; one per swapchain image.
    render_finished: Vec<vk::Semaphore>,
    /// The swapchain no longer fits (out of date, suboptimal, vsync changed): made again before the next frame.
    pub(super) stale: bool,
}

/// A swapchain image acquired for this frame.
#[derive(Clone, Copy)]
pub(super) struct Acquired {
    pub(super) index: usize,
    pub(super) image: vk::Image,
    pub(super) view: vk::ImageView,
    pub(super) render_finished: vk::Semaphore,
}

impl Screen {
    pub(super) fn new(surface: Surface) -> Screen {
        Screen {
            surface: Some(surface),
            swapchain: None,
            render_finished: Vec::new(),
            stale: true,
        }
    }

    pub(super) fn swapchain(&self) -> Result<&Swapchain, GpuError> {
        self.swapchain.as_ref().ok_or(GpuError::Lost("swapchain"))
    }

    /// Whether the swapchain must be made again before drawing into a window of `width`×`height`.
    pub(super) fn needs_recreate(&self, width: u32, height: u32) -> bool {
        self.stale
            || self
                .swapchain
                .as_ref()
                .is_some_and(|s| (s.extent.width, s.extent.height) != (width, height))
    }

    /// Makes the swapchain for a window of `width`×`height` (at least 1×1), with its semaphores. Waits for the
    /// device first: the old swapchain and semaphores may still be in use.
    pub(super) fn recreate(&mut self, gpu: &Gpu, width: u32, height: u32, vsync: bool) -> Result<(), ViewerError> {
        // SAFETY: plain wait on a live device.
        unsafe { gpu.device.device_wait_idle() }.ctx("vkDeviceWaitIdle")?;
        let desc = SwapchainDesc {
            width: width.max(1),
            height: height.max(1),
            vsync,
        };
        let surface = self.surface.as_ref().ok_or(GpuError::Lost("surface"))?;
        let new = Swapchain::new(gpu, surface, desc, self.swapchain.as_ref())?;
        if let Some(old) = self.swapchain.replace(new) {
            old.destroy(gpu);
        }
        for s in self.render_finished.drain(..) {
            // SAFETY: the device is idle, so no submission waits on or signals these semaphores.
            unsafe { gpu.device.destroy_semaphore(s, None) };
        }
        let count = self.swapchain.as_ref().map(|s| s.images.len()).unwrap_or(0);
        for _ in 0..count {
            // SAFETY: valid create info on a live device.
            let s = unsafe { gpu.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                .ctx("vkCreateSemaphore")?;
            self.render_finished.push(s);
        }
        self.stale = false;
        Ok(())
    }

    /// The next image, signalling `image_available` when it is free; None when the swapchain is out of date (it
    /// is then marked stale).
    pub(super) fn acquire(&mut self, image_available: vk::Semaphore) -> Result<Option<Acquired>, GpuError> {
        let swapchain = self.swapchain()?;
        // SAFETY: the semaphore is unsignalled (its last wait completed with the slot's fence).
        let acquired = unsafe {
            swapchain
                .loader
                .acquire_next_image(swapchain.raw, u64::MAX, image_available, vk::Fence::null())
        };
        let index = match acquired {
            Ok((i, suboptimal)) => {
                self.stale |= suboptimal;
                i as usize
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                return Ok(None);
            }
            Err(e) => return Err(GpuError::vk("vkAcquireNextImageKHR", e)),
        };
        let swapchain = self.swapchain()?;
        Ok(Some(Acquired {
            index,
            image: swapchain.images[index],
            view: swapchain.views[index],
            render_finished: self.render_finished[index],
        }))
    }

    /// Presents `image` once its rendering has finished.
    pub(super) fn present(&mut self, gpu: &Gpu, image: &Acquired) -> Result<(), GpuError> {
        let swapchain = self.swapchain()?;
        let wait = [image.render_finished];
        let chains = [swapchain.raw];
        let indices = [image.index as u32];
        let present = vk::PresentInfoKHR::default()
            .wait_semaphores(&wait)
            .swapchains(&chains)
            .image_indices(&indices);
        // SAFETY: the image was acquired and its rendering is submitted with this semaphore signalled.
        match unsafe { swapchain.loader.queue_present(gpu.queue, &present) } {
            Ok(suboptimal) => self.stale |= suboptimal,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.stale = true,
            Err(e) => return Err(GpuError::vk("vkQueuePresentKHR", e)),
        }
        Ok(())
    }

    /// Destroys the semaphores, the swapchain, then the surface. The device must be idle.
    pub(super) fn destroy(mut self, gpu: &Gpu) {
        for s in self.render_finished.drain(..) {
            // SAFETY: the device is idle; no submission uses the semaphore.
            unsafe { gpu.device.destroy_semaphore(s, None) };
        }
        if let Some(s) = self.swapchain.take() {
            s.destroy(gpu);
        }
        if let Some(s) = self.surface.take() {
            s.destroy();
        }
    }
}
