//! Recording a frame: the entry and exit passes, the march (fragment or compute), their barriers and
//! timestamps, and reading the timestamps back.

use super::{mirrors, FrameUniforms, PassTimings, Renderer, QUERIES};
use crate::gpu::sync::{image_barriers, Access, ImageTransition};
use crate::gpu::{Gpu, GpuError, VkContext};
use crate::scene::settings::{PositionFormat, RaySetup, RenderSettings};
use ash::vk;

impl Renderer {
    /// Records one frame into `output` (a `width`×`height` colour image of `output_format`, last used as `from`;
    /// its old contents are discarded). `output` ends in `Access::ColorAttachmentWrite`.
    /// Call [`Renderer::prepare`] with the same settings first. `slot` (< frames in flight) must not be used by a
    /// frame that is still pending on the GPU: its uniforms are written now, by the host.
    pub fn record(
        &mut self,
        gpu: &Gpu,
        cb: vk::CommandBuffer,
        slot: usize,
        output: (vk::Image, vk::ImageView),
        from: Access,
        s: &RenderSettings,
    ) -> Result<(), GpuError> {
        let vol = self.volume.as_ref().ok_or(GpuError::Lost("no volume loaded"))?;
        let uniforms = FrameUniforms::new(s, &vol.info);
        let key = self.march_key(s);
        let slot = self
            .slots
            .get_mut(slot)
            .ok_or(GpuError::Lost("frame slot out of range"))?;
        slot.uniforms.write(bytemuck::bytes_of(&uniforms))?;
        slot.recorded = Some(s.ray_setup);
        let (frame_set, query_pool, storage_set) = (slot.set, slot.query_pool, slot.storage_set);
        let march_pipeline = self.march_pipelines[key.index()];
        if march_pipeline == vk::Pipeline::null() {
            return Err(GpuError::Lost("prepare() was not called for these settings"));
        }
        let dev = &gpu.device;
        let extent = vk::Extent2D {
            width: s.width,
            height: s.height,
        };
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: s.width as f32,
            height: s.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let scissor = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent,
        };
        let ts = |cb, i| {
            // SAFETY: the query was reset at the start of this command buffer.
            unsafe { dev.cmd_write_timestamp2(cb, vk::PipelineStageFlags2::ALL_COMMANDS, query_pool, i) }
        };
        // SAFETY: `cb` is recording, outside any rendering scope.
        unsafe { dev.cmd_reset_query_pool(cb, query_pool, 0, QUERIES) };
        ts(cb, 0);
        let begin = |view: vk::ImageView, load: vk::AttachmentLoadOp| {
            let attachment = [vk::RenderingAttachmentInfo::default()
                .image_view(view)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(load)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue {
                    color: vk::ClearColorValue { float32: [0.0; 4] },
                })];
            let info = vk::RenderingInfo::default()
                .render_area(scissor)
                .layer_count(1)
                .color_attachments(&attachment);
            // SAFETY: `view`'s image is in COLOR_ATTACHMENT_OPTIMAL (barriers above) and matches `extent`.
            unsafe {
                dev.cmd_begin_rendering(cb, &info);
                dev.cmd_set_viewport(cb, 0, &[viewport]);
                dev.cmd_set_scissor(cb, 0, &[scissor]);
            }
        };
        let output_to_attachment = ImageTransition {
            image: output.0,
            from,
            to: Access::ColorAttachmentWrite,
            discard: true,
        };
        match s.ray_setup {
            RaySetup::Faces => {
                let p = self
                    .positions
                    .as_ref()
                    .ok_or(GpuError::Lost("prepare() was not called"))?;
                let pi = match p.format {
                    PositionFormat::Rgba32f => 0,
                    PositionFormat::Rgba16f => 1,
                };
                // Last frame's march read both targets; wait for that before overwriting them.
                let discard = |image| ImageTransition {
                    image,
                    from: Access::FragmentSampled,
                    to: Access::ColorAttachmentWrite,
                    discard: true,
                };
                image_barriers(
                    dev,
                    cb,
                    &[discard(p.entry.raw), discard(p.exit.raw), output_to_attachment],
                );
                // Pipeline 0 culls back faces, 1 front faces; a mirroring placement swaps which is which.
                let flip = usize::from(self.volume.as_ref().is_some_and(|v| mirrors(v.info.tex_to_world(s))));
                for (j, target) in [&p.entry, &p.exit].into_iter().enumerate() {
                    begin(target.view, vk::AttachmentLoadOp::CLEAR);
                    // SAFETY: rendering has begun; the pipeline and set match the faces layout.
                    unsafe {
                        dev.cmd_bind_pipeline(
                            cb,
                            vk::PipelineBindPoint::GRAPHICS,
                            self.position_pipelines[pi][j ^ flip],
                        );
                        dev.cmd_bind_descriptor_sets(
                            cb,
                            vk::PipelineBindPoint::GRAPHICS,
                            self.faces_layout,
                            0,
                            &[frame_set],
                            &[],
                        );
                        dev.cmd_draw(cb, 36, 1, 0, 0);
                        dev.cmd_end_rendering(cb);
                    }
                    ts(cb, 1 + j as u32);
                }
                let to_sampled = |image| ImageTransition {
                    image,
                    from: Access::ColorAttachmentWrite,
                    to: Access::FragmentSampled,
                    discard: false,
                };
                image_barriers(dev, cb, &[to_sampled(p.entry.raw), to_sampled(p.exit.raw)]);
                // The march writes every pixel, so the old contents need not be loaded.
                begin(output.1, vk::AttachmentLoadOp::DONT_CARE);
                // SAFETY: rendering has begun; the sets match the march-faces layout and hold live resources.
                unsafe {
                    dev.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, march_pipeline);
                    dev.cmd_bind_descriptor_sets(
                        cb,
                        vk::PipelineBindPoint::GRAPHICS,
                        self.march_faces_layout,
                        0,
                        &[frame_set, self.volume_set, self.positions_set],
                        &[],
                    );
                    dev.cmd_draw(cb, 3, 1, 0, 0);
                    dev.cmd_end_rendering(cb);
                }
                ts(cb, 3);
            }
            RaySetup::Analytic if s.compute => {
                let image_info = [vk::DescriptorImageInfo::default()
                    .image_view(output.1)
                    .image_layout(vk::ImageLayout::GENERAL)];
                let write = vk::WriteDescriptorSet::default()
                    .dst_set(storage_set)
                    .dst_binding(0)
                    .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                    .image_info(&image_info);
                // SAFETY: the slot's last frame has completed (record's contract), so nothing uses the set.
                unsafe { dev.update_descriptor_sets(&[write], &[]) };
                image_barriers(
                    dev,
                    cb,
                    &[ImageTransition {
                        to: Access::ComputeWrite,
                        ..output_to_attachment
                    }],
                );
                // SAFETY: the sets match the march-compute layout and hold live resources; `output` is in GENERAL.
                unsafe {
                    dev.cmd_bind_pipeline(cb, vk::PipelineBindPoint::COMPUTE, march_pipeline);
                    dev.cmd_bind_descriptor_sets(
                        cb,
                        vk::PipelineBindPoint::COMPUTE,
                        self.march_compute_layout,
                        0,
                        &[frame_set, self.volume_set, storage_set],
                        &[],
                    );
                    dev.cmd_dispatch(cb, s.width.div_ceil(8), s.height.div_ceil(8), 1);
                }
                ts(cb, 1);
                // record's contract: the output ends as a colour attachment, whichever pass wrote it.
                image_barriers(
                    dev,
                    cb,
                    &[ImageTransition {
                        image: output.0,
                        from: Access::ComputeWrite,
                        to: Access::ColorAttachmentWrite,
                        discard: false,
                    }],
                );
            }
            RaySetup::Analytic => {
                image_barriers(dev, cb, &[output_to_attachment]);
                begin(output.1, vk::AttachmentLoadOp::DONT_CARE);
                // SAFETY: rendering has begun; the sets match the march-analytic layout and hold live resources.
                unsafe {
                    dev.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, march_pipeline);
                    dev.cmd_bind_descriptor_sets(
                        cb,
                        vk::PipelineBindPoint::GRAPHICS,
                        self.march_analytic_layout,
                        0,
                        &[frame_set, self.volume_set],
                        &[],
                    );
                    dev.cmd_draw(cb, 3, 1, 0, 0);
                    dev.cmd_end_rendering(cb);
                }
                ts(cb, 1);
            }
        }
        Ok(())
    }

    /// GPU times of the last frame recorded in `slot`; call after its submission has completed.
    pub fn timings(&self, gpu: &Gpu, slot: usize) -> Result<Option<PassTimings>, GpuError> {
        let Some(slot) = self.slots.get(slot) else {
            return Ok(None);
        };
        let Some(setup) = slot.recorded else { return Ok(None) };
        let count = match setup {
            RaySetup::Faces => 4,
            RaySetup::Analytic => 2,
        };
        let mut ticks = [0u64; QUERIES as usize];
        // SAFETY: the queries were written by a completed submission; WAIT is not needed but harmless.
        unsafe {
            gpu.device.get_query_pool_results(
                slot.query_pool,
                0,
                &mut ticks[..count],
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .ctx("vkGetQueryPoolResults")?;
        let ms = |a: usize, b: usize| ticks[b].saturating_sub(ticks[a]) as f64 * self.timestamp_period_ns * 1e-6;
        Ok(Some(match setup {
            RaySetup::Faces => PassTimings {
                entry_ms: Some(ms(0, 1)),
                exit_ms: Some(ms(1, 2)),
                march_ms: ms(2, 3),
                total_ms: ms(0, 3),
            },
            RaySetup::Analytic => PassTimings {
                entry_ms: None,
                exit_ms: None,
                march_ms: ms(0, 1),
                total_ms: ms(0, 1),
            },
        }))
    }
}
