//! One frame on the GPU: wait for its slot, acquire a swapchain image, record [march into the view image (unless it
//! holds this frame already) → blit into the swapchain image → egui over it (→ read the view image and/or the view
//! as shown back)], submit, present.

use super::readback::{Place, Readback, Wanted};
use super::record::{record_blit, record_egui, Blit};
use super::screen::Acquired;
use super::Presenter;
use crate::gpu::sync::Access;
use crate::gpu::{GpuError, VkContext};
use crate::render::PassTimings;
use crate::scene::settings::RenderSettings;
use crate::viewer::ViewerError;
use ash::vk;

/// What egui painted this frame.
pub struct EguiFrame {
    pub primitives: Vec<egui::ClippedPrimitive>,
    pub textures: egui::TexturesDelta,
    pub pixels_per_point: f32,
}

/// What a frame draws.
pub struct Frame<'a> {
    /// The march's settings: the view's size, or less for a reduced-detail frame (then upscaled).
    pub settings: &'a RenderSettings,
    /// Where the view goes in the swapchain image (pixels).
    pub view_offset: vk::Offset2D,
    pub view_size: vk::Extent2D,
    pub egui: &'a EguiFrame,
    /// The pixels to read back (for a screenshot or the recording).
    pub readback: Wanted,
}

/// What the GPU measured of the frame a slot last held.
pub struct SlotTimings {
    pub gpu: Option<PassTimings>,
    /// That frame was a reduced-detail one.
    pub was_reduced: bool,
}

/// How a frame ended.
pub enum Drawn {
    /// The swapchain was out of date: nothing was drawn; it is made again for the next frame.
    OutOfDate,
    /// Presented, with the view image's pixels when asked for; `marched`: the view was marched anew (else the
    /// last march's image was shown again).
    Presented {
        readback: Option<Box<Readback>>,
        marched: bool,
    },
}

impl Presenter {
    /// Waits until the next frame's slot is free. Returns the GPU times of the frame it held (once every slot has
    /// been used), and records whether the frame about to be drawn there is `reduced`.
    pub fn begin_frame(&mut self, reduced: bool) -> Result<Option<SlotTimings>, ViewerError> {
        let (slot, sync) = self.slots.current();
        sync.wait(&self.gpu)?;
        let measured = if self.slots.all_used() {
            Some(self.pass.timings(&self.gpu, slot)?)
        } else {
            None
        };
        let was_reduced = self.slots.swap_reduced(reduced);
        Ok(measured.map(|gpu| SlotTimings { gpu, was_reduced }))
    }

    /// Acquires a swapchain image, records the frame into the current slot, submits it and presents.
    pub fn draw(&mut self, frame: &Frame<'_>) -> Result<Drawn, ViewerError> {
        let (slot, sync) = self.slots.current();
        let (cb, fence, image_available) = (sync.cb, sync.fence, sync.image_available);
        let extent = self.screen.swapchain()?.extent;
        let Some(target) = self.screen.acquire(image_available)? else {
            return Ok(Drawn::OutOfDate);
        };
        self.upload_textures(&frame.egui.textures)?;
        self.begin_commands(cb, fence)?;
        let view_access = self.pass.record(&self.gpu, cb, slot, frame.settings)?;
        let dev = &self.gpu.device;
        let view = self.pass.view()?;
        let blit = Blit {
            rendered: vk::Extent2D {
                width: frame.settings.width,
                height: frame.settings.height,
            },
            offset: frame.view_offset,
            size: frame.view_size,
        };
        record_blit(dev, cb, (view, view_access), target.image, blit);
        let egui = self.egui.as_mut().ok_or(GpuError::Lost("egui renderer"))?;
        record_egui(
            dev,
            cb,
            egui,
            &target,
            extent,
            frame.egui.pixels_per_point,
            &frame.egui.primitives,
        )?;
        // Each kind is read back once for whoever wants this frame: the screenshots and the recording.
        let mut readback = Readback::record_clean(&self.gpu, cb, view, frame.readback)?;
        let swapchain = self.screen.swapchain()?;
        let place = Place {
            wanted: frame.readback.shown,
            readable: swapchain.readable,
            format: swapchain.format,
            offset: frame.view_offset,
            size: frame.view_size,
        };
        readback.record_shown(&self.gpu, cb, target.image, place)?;
        let readback = frame.readback.any().then(|| Box::new(readback));
        self.submit(cb, fence, image_available, &target)?;
        self.screen.present(&self.gpu, &target)?;
        self.slots.advance();
        Ok(Drawn::Presented {
            readback,
            marched: view_access != Access::TransferRead,
        })
    }

    /// Frees the textures egui no longer uses (after the device is done with them).
    pub fn free_textures(&mut self, textures: &egui::TexturesDelta) -> Result<(), ViewerError> {
        if textures.free.is_empty() {
            return Ok(());
        }
        self.wait_idle()?;
        let egui = self.egui.as_mut().ok_or(GpuError::Lost("egui renderer"))?;
        for id in &textures.free {
            egui.free_texture(*id)
                .map_err(|e| ViewerError::Other(format!("egui: {e}")))?;
        }
        Ok(())
    }

    /// New or changed egui textures (the font atlas, the slice views' images), uploaded before they are drawn.
    fn upload_textures(&mut self, textures: &egui::TexturesDelta) -> Result<(), ViewerError> {
        let egui = self.egui.as_mut().ok_or(GpuError::Lost("egui renderer"))?;
        for (id, deltas) in &textures.set {
            for delta in deltas {
                egui.set_texture(self.gpu.queue, self.gpu.command_pool, *id, delta)
                    .map_err(|e| ViewerError::Other(format!("egui texture: {e}")))?;
            }
        }
        Ok(())
    }

    fn begin_commands(&self, cb: vk::CommandBuffer, fence: vk::Fence) -> Result<(), GpuError> {
        let dev = &self.gpu.device;
        // SAFETY: the slot's previous submission finished (fence waited), so its command buffer can be reset.
        unsafe {
            dev.reset_fences(&[fence]).ctx("vkResetFences")?;
            dev.reset_command_buffer(cb, vk::CommandBufferResetFlags::empty())
                .ctx("vkResetCommandBuffer")?;
            dev.begin_command_buffer(
                cb,
                &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
            .ctx("vkBeginCommandBuffer")
        }
    }

    /// Ends `cb` and submits it: it waits for the image to be acquired, signals the image's "rendering finished"
    /// and the slot's fence.
    fn submit(
        &self,
        cb: vk::CommandBuffer,
        fence: vk::Fence,
        image_available: vk::Semaphore,
        target: &Acquired,
    ) -> Result<(), GpuError> {
        let dev = &self.gpu.device;
        // SAFETY: `cb` is recording.
        unsafe { dev.end_command_buffer(cb) }.ctx("vkEndCommandBuffer")?;
        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(image_available)
            .stage_mask(vk::PipelineStageFlags2::TRANSFER)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(target.render_finished)
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cbs = [vk::CommandBufferSubmitInfo::default().command_buffer(cb)];
        let submit = [vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cbs)
            .signal_semaphore_infos(&signals)];
        // SAFETY: every resource the command buffer uses is alive until its fence signals.
        unsafe { dev.queue_submit2(self.gpu.queue, &submit, fence) }.ctx("vkQueueSubmit2")
    }
}
