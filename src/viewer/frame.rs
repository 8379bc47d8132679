//! One frame: the UI pass, then the march into the view image, its blit into the swapchain image and egui over
//! it, submitted and presented; and what a frame must create first (`prepare`).

use super::app::input::{drag_cut, take_tab_presses};
use super::screenshot::{save_screenshot, write_session};
use super::widgets::layout::frame_ui;
use super::{Flow, Running, ViewerError, FRAMES_IN_FLIGHT};
use crate::gpu::resources::{record_readback, Buffer, Image, ImageDesc};
use crate::gpu::sync::{image_barrier, Access};
use crate::gpu::{GpuError, VkContext};
use crate::render::headless::OUTPUT_FORMAT;
use crate::scene::settings::RenderSettings;
use crate::volume::Volume;
use ash::vk;
use std::sync::mpsc::TryRecvError;
use std::time::{Duration, Instant};

impl Running {
    pub(super) fn redraw(&mut self) -> Result<Flow, ViewerError> {
        let now = Instant::now();
        let frame_s = now.duration_since(self.last_frame).as_secs_f64();
        // Animation steps are capped (a slow frame must not throw the view); the frame time shown is not.
        let dt = (frame_s as f32).min(0.1);
        self.last_frame = now;
        // The interval since the last frame is the frame time while frames follow each other; after an idle
        // pause it is the pause, so the last frame's GPU time stands in.
        let follows = self.wants_continuous_redraw() || self.refine_pending;
        self.poll_loading()?;
        if let Some(rx) = &self.dialog {
            match rx.try_recv() {
                Ok(Some(path)) => {
                    self.dialog = None;
                    let action = self.state.files.load_action(path);
                    self.apply(vec![action]);
                }
                Ok(None) | Err(TryRecvError::Disconnected) => {
                    self.dialog = None;
                    self.state.messages.status = Some("no file chosen (or no file dialog here: type a path)".into());
                }
                Err(TryRecvError::Empty) => {}
            }
        }
        self.state.animate(dt);
        self.state.time.advance(dt);

        let size = self.window.inner_size();
        if self.zero_size || size.width == 0 || size.height == 0 || self.window.is_minimized() == Some(true) {
            // Minimised: nothing to draw into. Keep the event loop (and a running script) going.
            return self.step_script();
        }

        // The UI runs first: it may change what this frame shows.
        let mut raw_input = self.egui_state.take_egui_input(&self.window);
        // Events a slow frame held back for a drag (`drag_cut`) come first; again some may wait.
        raw_input.events.splice(0..0, std::mem::take(&mut self.deferred_events));
        let held = self
            .egui_ctx
            .input(|i| i.pointer.press_origin().filter(|_| i.pointer.any_down()));
        let click_dist = self.egui_ctx.options(|o| o.input_options.max_click_dist);
        if let Some(cut) = drag_cut(&raw_input.events, held, click_dist) {
            self.deferred_events = raw_input.events.split_off(cut);
        }
        // Tab belongs to the panel, not to egui's focus traversal: egui would move the focus into a text field,
        // which then swallowed every shortcut (Tab included) once the panel was hidden.
        let tabs = take_tab_presses(&mut raw_input);
        let state = &mut self.state;
        // What the slice views resample: the shown step of a series, or the kept volume.
        let volume = self.series.as_ref().or(self.kept.as_ref());
        let textures = &mut self.slice_textures;
        let mut images = |ctx: &egui::Context, image: &_, volume: Option<&_>| textures.texture(ctx, image, volume);
        let mut actions = Vec::new();
        let full = self.egui_ctx.run_ui(raw_input, |ui| {
            actions = frame_ui(ui, state, tabs, volume, &mut images);
        });
        self.apply(actions);
        self.show_wanted_step()?;
        // FullOutput implements Drop, so its parts are taken rather than moved out.
        let mut full = full;
        let platform_output = std::mem::take(&mut full.platform_output);
        let textures_delta = std::mem::take(&mut full.textures_delta);
        let shapes = std::mem::take(&mut full.shapes);
        let pixels_per_point = full.pixels_per_point;
        let viewport_output = std::mem::take(&mut full.viewport_output);
        self.egui_state.handle_platform_output(&self.window, platform_output);
        self.repaint_at = viewport_output
            .get(&egui::ViewportId::ROOT)
            .filter(|v| v.repaint_delay < Duration::from_secs(3600))
            .map(|v| now + v.repaint_delay);
        let primitives = self.egui_ctx.tessellate(shapes, pixels_per_point);

        if self.recreate_swapchain
            || self
                .swapchain
                .as_ref()
                .is_some_and(|s| (s.extent.width, s.extent.height) != (size.width, size.height))
        {
            self.recreate_swapchain()?;
        }
        let extent = self.swapchain.as_ref().ok_or(GpuError::Lost("swapchain"))?.extent;
        let (view_offset, view_size) = view_pixels(self.state.interaction.view_rect, pixels_per_point, extent);
        // Interacting, animating or auto-rotating: a cheaper frame; once still, one at full quality.
        let dragging = self.script.as_ref().is_some_and(|s| s.drag_left > 0);
        if dragging {
            self.drag_frames.push(frame_s * 1e3);
        }
        // Screenshots and recorded frames are full frames.
        let moving = (self.state.interaction.interacting || self.state.camera_moving() || dragging)
            && self.pending_screenshot.is_none()
            && self.recorder.is_none();
        let settings = self.state.frame_settings(view_size.width, view_size.height, moving);
        self.refine_pending = moving && self.state.sampling.lod;
        if let Some(path) = self.pending_session.take() {
            // The session holds the still frame's settings, whether or not this frame is a reduced one.
            let still = self.state.render_settings(view_size.width, view_size.height);
            match write_session(&path, &self.session_state(&still)) {
                Ok(()) => {
                    eprintln!("saved session {}", path.display());
                    self.state.messages.status = Some(format!("saved session {}", path.display()));
                }
                Err(e) => self.state.messages.error = Some(e),
            }
        }
        self.prepare(&settings)?;

        let slot = self.frame_index % FRAMES_IN_FLIGHT;
        let sync = &self.frames[slot];
        // SAFETY: the fence belongs to this device; waiting makes the slot's resources reusable.
        unsafe { self.gpu.device.wait_for_fences(&[sync.fence], true, u64::MAX) }.ctx("vkWaitForFences")?;
        let renderer = self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))?;
        if self.frame_index >= FRAMES_IN_FLIGHT {
            self.state.stats.gpu = renderer.timings(&self.gpu, slot)?;
            if !self.slot_reduced[slot] {
                self.state.stats.full_frame_ms = self.state.stats.gpu.map(|t| t.total_ms);
            }
        }
        self.slot_reduced[slot] = settings.width < view_size.width;
        self.state.stats.frame_ms = frame_time_ms(frame_s, follows, self.state.stats.gpu.map(|t| t.total_ms));

        let swapchain = self.swapchain.as_ref().ok_or(GpuError::Lost("swapchain"))?;
        // SAFETY: the semaphore is unsignalled (its last wait completed with the slot's fence).
        let acquired = unsafe {
            swapchain
                .loader
                .acquire_next_image(swapchain.raw, u64::MAX, sync.image_available, vk::Fence::null())
        };
        let image_index = match acquired {
            Ok((i, suboptimal)) => {
                self.recreate_swapchain |= suboptimal;
                i as usize
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.recreate_swapchain = true;
                self.window.request_redraw();
                return Ok(Flow::Continue);
            }
            Err(e) => return Err(GpuError::vk("vkAcquireNextImageKHR", e).into()),
        };

        let egui_renderer = self.egui_renderer.as_mut().ok_or(GpuError::Lost("egui renderer"))?;
        for (id, deltas) in &textures_delta.set {
            for delta in deltas {
                egui_renderer
                    .set_texture(self.gpu.queue, self.gpu.command_pool, *id, delta)
                    .map_err(|e| ViewerError::Other(format!("egui texture: {e}")))?;
            }
        }

        let view = self.view_image.as_ref().ok_or(GpuError::Lost("view image"))?;
        let dev = &self.gpu.device;
        let cb = sync.cb;
        // SAFETY: the slot's previous submission finished (fence waited), so its command buffer can be reset.
        unsafe {
            dev.reset_fences(&[sync.fence]).ctx("vkResetFences")?;
            dev.reset_command_buffer(cb, vk::CommandBufferResetFlags::empty())
                .ctx("vkResetCommandBuffer")?;
            dev.begin_command_buffer(
                cb,
                &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
            .ctx("vkBeginCommandBuffer")?;
        }
        renderer.record(
            &self.gpu,
            cb,
            slot,
            (view.raw, view.view),
            Access::TransferRead,
            &settings,
        )?;
        image_barrier(dev, cb, view.raw, Access::ColorAttachmentWrite, Access::TransferRead);
        let target = swapchain.images[image_index];
        image_barrier(dev, cb, target, Access::SwapchainAcquired, Access::TransferWrite);
        // Cleared first: the panel covers the rest, but not while it is hidden or being laid out.
        let black = vk::ClearColorValue {
            float32: [0.0, 0.0, 0.0, 1.0],
        };
        // SAFETY: the image is in TRANSFER_DST layout.
        unsafe {
            dev.cmd_clear_color_image(
                cb,
                target,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &black,
                &[crate::gpu::sync::COLOR_RANGE],
            )
        };
        crate::gpu::sync::memory_barrier(dev, cb, Access::TransferWrite, Access::TransferWrite);
        let corner = vk::Offset3D {
            x: settings.width as i32,
            y: settings.height as i32,
            z: 1,
        };
        let dst_corner = vk::Offset3D {
            x: view_offset.x + view_size.width as i32,
            y: view_offset.y + view_size.height as i32,
            z: 1,
        };
        let dst_origin = vk::Offset3D {
            x: view_offset.x,
            y: view_offset.y,
            z: 0,
        };
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let blit = vk::ImageBlit::default()
            .src_subresource(layers)
            .src_offsets([vk::Offset3D::default(), corner])
            .dst_subresource(layers)
            .dst_offsets([dst_origin, dst_corner]);
        // SAFETY: both images are in the layouts named and the regions lie inside them. At full detail the sizes
        // match and the blit only swizzles RGBA to BGRA; at reduced detail it also upscales (linear).
        unsafe {
            dev.cmd_blit_image(
                cb,
                view.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                target,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[blit],
                if settings.width == view_size.width {
                    vk::Filter::NEAREST
                } else {
                    vk::Filter::LINEAR
                },
            )
        };
        image_barrier(dev, cb, target, Access::TransferWrite, Access::ColorAttachmentWrite);
        let attachment = [vk::RenderingAttachmentInfo::default()
            .image_view(swapchain.views[image_index])
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let rendering = vk::RenderingInfo::default()
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent,
            })
            .layer_count(1)
            .color_attachments(&attachment);
        // SAFETY: the swapchain image is a colour attachment now.
        unsafe { dev.cmd_begin_rendering(cb, &rendering) };
        egui_renderer
            .cmd_draw(cb, extent, pixels_per_point, &primitives)
            .map_err(|e| ViewerError::Other(format!("egui draw: {e}")))?;
        // SAFETY: rendering was begun above.
        unsafe { dev.cmd_end_rendering(cb) };
        image_barrier(dev, cb, target, Access::ColorAttachmentWrite, Access::Present);
        // The view image is read back once for whoever wants this frame: F12 and the recording.
        let screenshot = self.pending_screenshot.take();
        let readback = if screenshot.is_some() || self.recorder.is_some() {
            let buffer = Buffer::new(
                &self.gpu,
                view_size.width as u64 * view_size.height as u64 * 4,
                vk::BufferUsageFlags::TRANSFER_DST,
                gpu_allocator::MemoryLocation::GpuToCpu,
                "view readback",
            )?;
            record_readback(&self.gpu, cb, view, Access::TransferRead, &buffer);
            Some(buffer)
        } else {
            None
        };
        // SAFETY: `cb` is recording.
        unsafe { dev.end_command_buffer(cb) }.ctx("vkEndCommandBuffer")?;

        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(sync.image_available)
            .stage_mask(vk::PipelineStageFlags2::TRANSFER)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(self.render_finished[image_index])
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cbs = [vk::CommandBufferSubmitInfo::default().command_buffer(cb)];
        let submit = [vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cbs)
            .signal_semaphore_infos(&signals)];
        // SAFETY: every resource the command buffer uses is alive until its fence signals.
        unsafe { dev.queue_submit2(self.gpu.queue, &submit, sync.fence) }.ctx("vkQueueSubmit2")?;
        let wait = [self.render_finished[image_index]];
        let chains = [swapchain.raw];
        let indices = [image_index as u32];
        let present = vk::PresentInfoKHR::default()
            .wait_semaphores(&wait)
            .swapchains(&chains)
            .image_indices(&indices);
        // SAFETY: the image was acquired and its rendering is submitted with this semaphore signalled.
        match unsafe { swapchain.loader.queue_present(self.gpu.queue, &present) } {
            Ok(suboptimal) => self.recreate_swapchain |= suboptimal,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.recreate_swapchain = true,
            Err(e) => return Err(GpuError::vk("vkQueuePresentKHR", e).into()),
        }
        self.frame_index += 1;
        self.upload_ahead()?;

        if let Some(buffer) = readback {
            let pixels = self.wait_idle().map_err(|e| e.to_string()).and_then(|_| {
                buffer
                    .mapped()
                    .map(<[u8]>::to_vec)
                    .ok_or_else(|| "the view's readback buffer is not mapped".to_string())
            });
            buffer.destroy(&self.gpu);
            // F12 is rare and takes a copy; the recording takes the pixels.
            if let Some(path) = screenshot {
                let step = self.series.as_ref().map(Volume::shown_step);
                let saved = pixels
                    .clone()
                    .map_err(ViewerError::Other)
                    .and_then(|p| save_screenshot(&path, p, &self.session_state(&settings), step));
                match saved {
                    Ok(()) => self.state.messages.status = Some(format!("saved {}", path.display())),
                    Err(e) => self.state.messages.error = Some(format!("screenshot: {e}")),
                }
            }
            if self.recorder.is_some() {
                let pushed = pixels.and_then(|p| {
                    let r = self.recorder.as_mut().ok_or("no recording")?;
                    r.push(view_size.width, view_size.height, p, now)
                });
                if let Err(e) = pushed {
                    self.state.messages.error = Some(format!("recording: {e}"));
                    if let Some(r) = self.recorder.take() {
                        self.stop_recording(r);
                    }
                }
            }
        }
        if !textures_delta.free.is_empty() {
            self.wait_idle()?;
            let egui_renderer = self.egui_renderer.as_mut().ok_or(GpuError::Lost("egui renderer"))?;
            for id in &textures_delta.free {
                egui_renderer
                    .free_texture(*id)
                    .map_err(|e| ViewerError::Other(format!("egui: {e}")))?;
            }
        }
        self.step_script()
    }

    /// Creates what `settings` needs beyond the frame (position targets, colormap, the view image) after
    /// waiting for in-flight frames, only when something changed.
    pub(super) fn prepare(&mut self, settings: &RenderSettings) -> Result<(), ViewerError> {
        let view_fits = self
            .view_image
            .as_ref()
            .is_some_and(|v| (v.desc.extent.width, v.desc.extent.height) == (settings.width, settings.height));
        // The gradient texture on the first frame that reads gradients (the volume was kept for it).
        if settings.gradient_texture && self.renderer.as_ref().is_some_and(|r| !r.has_gradient_texture()) {
            let volume = self
                .kept
                .as_ref()
                .ok_or(GpuError::Lost("no volume kept for gradients"))?;
            self.wait_idle()?;
            let renderer = self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))?;
            renderer.enable_gradient_texture(&self.gpu, volume)?;
        }
        let renderer = self.renderer.as_ref().ok_or(GpuError::Lost("renderer"))?;
        if view_fits && !renderer.needs_prepare(settings) {
            return Ok(());
        }
        self.wait_idle()?;
        if !view_fits {
            if let Some(old) = self.view_image.take() {
                old.destroy(&self.gpu);
            }
            let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
            self.view_image = Some(Image::new(
                &self.gpu,
                ImageDesc::d2(OUTPUT_FORMAT, settings.width, settings.height, usage),
                "view",
            )?);
        }
        let renderer = self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))?;
        renderer.prepare(&self.gpu, settings)?;
        Ok(())
    }
}

/// The volume view's place in the swapchain image, in pixels: the central area egui left free (the whole
/// window before the first layout), clamped to the image.
pub(super) fn view_pixels(
    rect: Option<egui::Rect>,
    pixels_per_point: f32,
    extent: vk::Extent2D,
) -> (vk::Offset2D, vk::Extent2D) {
    let (w, h) = (extent.width as f32, extent.height as f32);
    let r = rect
        .map(|r| {
            let ppp = pixels_per_point.max(0.1);
            egui::Rect::from_min_max(
                egui::pos2(
                    (r.min.x * ppp).round().clamp(0.0, w - 1.0),
                    (r.min.y * ppp).round().clamp(0.0, h - 1.0),
                ),
                egui::pos2(
                    (r.max.x * ppp).round().clamp(1.0, w),
                    (r.max.y * ppp).round().clamp(1.0, h),
                ),
            )
        })
        .unwrap_or(egui::Rect::from_min_max(egui::Pos2::ZERO, egui::pos2(w, h)));
    let width = (r.width() as u32).max(1);
    let height = (r.height() as u32).max(1);
    (
        vk::Offset2D {
            x: r.min.x as i32,
            y: r.min.y as i32,
        },
        vk::Extent2D { width, height },
    )
}

/// The frame time shown: the interval since the last frame when it followed directly (never capped: a 256 ms
/// frame shows 256), else the frame's GPU time (the interval would be the idle pause before it).
pub(super) fn frame_time_ms(interval_s: f64, follows: bool, gpu_ms: Option<f64>) -> f64 {
    match (follows, gpu_ms) {
        (false, Some(gpu)) => gpu,
        _ => interval_s * 1e3,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frame_time_is_not_capped_and_ignores_idle_pauses() {
        // A 256 ms frame following another shows 256 ms (it was capped at 100).
        assert_eq!(frame_time_ms(0.256, true, Some(250.0)), 256.0);
        // After a 7 s idle pause the GPU time stands in.
        assert_eq!(frame_time_ms(7.0, false, Some(250.0)), 250.0);
        assert_eq!(frame_time_ms(0.03, false, None), 30.0);
    }
}
