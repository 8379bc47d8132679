//! Recording a frame: one function per ray setup (faces: the entry pass, the exit pass, the march; analytic: the
//! march; compute: the march's dispatch) over the steps they share, with their barriers and timestamps, and
//! reading the timestamps back.

use super::march_key::Setup;
use super::spacing::Stretch;
use super::{mirrors, FrameUniforms, PassTimings, Renderer, QUERIES};
use crate::gpu::sync::{image_barriers, Access, ImageTransition};
use crate::gpu::{Gpu, GpuError, VkContext};
use crate::scene::settings::{PositionFormat, RaySetup, RenderSettings};
use ash::vk;

/// What the passes of one frame being recorded share.
struct FrameRecording<'a> {
    dev: &'a ash::Device,
    cb: vk::CommandBuffer,
    extent: vk::Extent2D,
    query_pool: vk::QueryPool,
    frame_set: vk::DescriptorSet,
    march_pipeline: vk::Pipeline,
    /// What the march writes: the output, or where rays are spaced (rule 12) the spaced target.
    output: (vk::Image, vk::ImageView),
    /// That image from its last use to a colour attachment, its old contents discarded.
    output_to_attachment: ImageTransition,
    /// Where rays are spaced: the blit from the march's image over the output.
    stretch: Option<Stretch>,
}

impl FrameRecording<'_> {
    /// Timestamp `query`: 0 before the first pass, then one after each.
    fn timestamp(&self, query: u32) {
        // SAFETY: the query was reset at the start of this command buffer.
        unsafe {
            self.dev
                .cmd_write_timestamp2(self.cb, vk::PipelineStageFlags2::ALL_COMMANDS, self.query_pool, query)
        }
    }

    /// Begins rendering into `view` (whose image is a colour attachment by now) over the whole target.
    fn begin_rendering(&self, view: vk::ImageView, load: vk::AttachmentLoadOp) {
        let area = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: self.extent,
        };
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: self.extent.width as f32,
            height: self.extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let attachment = [vk::RenderingAttachmentInfo::default()
            .image_view(view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                color: vk::ClearColorValue { float32: [0.0; 4] },
            })];
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&attachment);
        // SAFETY: `view`'s image is in COLOR_ATTACHMENT_OPTIMAL (the callers' barriers) and matches `extent`.
        unsafe {
            self.dev.cmd_begin_rendering(self.cb, &info);
            self.dev.cmd_set_viewport(self.cb, 0, &[viewport]);
            self.dev.cmd_set_scissor(self.cb, 0, &[area]);
        }
    }

    /// The fullscreen march into the output (a colour attachment by now), with `sets` bound to `layout`.
    fn draw_march(&self, layout: vk::PipelineLayout, sets: &[vk::DescriptorSet]) {
        // The march writes every pixel, so the old contents need not be loaded.
        self.begin_rendering(self.output.1, vk::AttachmentLoadOp::DONT_CARE);
        // SAFETY: rendering has begun; the callers' sets match `layout` and hold live resources.
        unsafe {
            self.dev
                .cmd_bind_pipeline(self.cb, vk::PipelineBindPoint::GRAPHICS, self.march_pipeline);
            self.dev
                .cmd_bind_descriptor_sets(self.cb, vk::PipelineBindPoint::GRAPHICS, layout, 0, sets, &[]);
            self.dev.cmd_draw(self.cb, 3, 1, 0, 0);
            self.dev.cmd_end_rendering(self.cb);
        }
    }

    /// After the march (its image a colour attachment written): where rays are spaced, the blit over the output.
    fn stretch(&self) {
        if let Some(stretch) = &self.stretch {
            stretch.record(self.dev, self.cb);
        }
    }
}

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
        slot.recorded = Some(s.pipeline.ray_setup);
        let (query_pool, storage_set) = (slot.query_pool, slot.storage_set);
        let (width, height) = s.marched_size();
        let extent = vk::Extent2D { width, height };
        // Spaced rays (rule 12): the march writes its own target, which the last frame's blit read.
        let spaced = match &self.targets.spaced {
            Some(t) if s.spacing() > 1 && t.fits(s) => Some(&t.image),
            _ if s.spacing() > 1 => return Err(GpuError::Lost("prepare() was not called for these settings")),
            _ => None,
        };
        let (marched, marched_from) = spaced.map_or((output, from), |i| ((i.raw, i.view), Access::TransferRead));
        let frame = FrameRecording {
            dev: &gpu.device,
            cb,
            extent,
            query_pool,
            frame_set: slot.set,
            march_pipeline: self.pipelines.march[key.index()],
            output: marched,
            output_to_attachment: ImageTransition {
                image: marched.0,
                from: marched_from,
                to: Access::ColorAttachmentWrite,
                discard: true,
            },
            stretch: spaced.map(|i| Stretch {
                from: (i.raw, extent),
                output: output.0,
                last: from,
                extent: vk::Extent2D {
                    width: s.width,
                    height: s.height,
                },
            }),
        };
        if frame.march_pipeline == vk::Pipeline::null() {
            return Err(GpuError::Lost("prepare() was not called for these settings"));
        }
        // SAFETY: `cb` is recording, outside any rendering scope.
        unsafe { frame.dev.cmd_reset_query_pool(cb, query_pool, 0, QUERIES) };
        frame.timestamp(0);
        match key.setup {
            Setup::Faces => self.record_faces(&frame, s)?,
            Setup::Analytic => self.record_analytic(&frame),
            Setup::Compute => self.record_compute(&frame, storage_set),
        }
        Ok(())
    }

    /// The entry/exit method: the entry pass, the exit pass (timestamps 1 and 2) and the march reading both (3).
    fn record_faces(&self, f: &FrameRecording, s: &RenderSettings) -> Result<(), GpuError> {
        let p = self
            .targets
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
            f.dev,
            f.cb,
            &[discard(p.entry.raw), discard(p.exit.raw), f.output_to_attachment],
        );
        // Pipeline 0 culls back faces, 1 front faces; a mirroring placement swaps which is which.
        let flip = usize::from(self.volume.as_ref().is_some_and(|v| mirrors(v.info.tex_to_world(s))));
        for (j, target) in [&p.entry, &p.exit].into_iter().enumerate() {
            f.begin_rendering(target.view, vk::AttachmentLoadOp::CLEAR);
            // SAFETY: rendering has begun; the pipeline and set match the faces layout.
            unsafe {
                f.dev.cmd_bind_pipeline(
                    f.cb,
                    vk::PipelineBindPoint::GRAPHICS,
                    self.pipelines.position[pi][j ^ flip],
                );
                f.dev.cmd_bind_descriptor_sets(
                    f.cb,
                    vk::PipelineBindPoint::GRAPHICS,
                    self.layouts.faces,
                    0,
                    &[f.frame_set],
                    &[],
                );
                f.dev.cmd_draw(f.cb, 36, 1, 0, 0);
                f.dev.cmd_end_rendering(f.cb);
            }
            f.timestamp(1 + j as u32);
        }
        let to_sampled = |image| ImageTransition {
            image,
            from: Access::ColorAttachmentWrite,
            to: Access::FragmentSampled,
            discard: false,
        };
        image_barriers(f.dev, f.cb, &[to_sampled(p.entry.raw), to_sampled(p.exit.raw)]);
        f.draw_march(
            self.layouts.march_faces,
            &[f.frame_set, self.descriptors.volume_set, self.descriptors.positions_set],
        );
        f.stretch();
        f.timestamp(3);
        Ok(())
    }

    /// The analytic method in a fullscreen fragment pass: the march alone (timestamp 1).
    fn record_analytic(&self, f: &FrameRecording) {
        image_barriers(f.dev, f.cb, &[f.output_to_attachment]);
        f.draw_march(self.layouts.march_analytic, &[f.frame_set, self.descriptors.volume_set]);
        f.stretch();
        f.timestamp(1);
    }

    /// The analytic method as a compute dispatch writing the output as a storage image (`storage_set`, the
    /// slot's; timestamp 1), which then becomes a colour attachment as `record` promises.
    fn record_compute(&self, f: &FrameRecording, storage_set: vk::DescriptorSet) {
        let image_info = [vk::DescriptorImageInfo::default()
            .image_view(f.output.1)
            .image_layout(vk::ImageLayout::GENERAL)];
        let write = vk::WriteDescriptorSet::default()
            .dst_set(storage_set)
            .dst_binding(0)
            .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
            .image_info(&image_info);
        // SAFETY: the slot's last frame has completed (record's contract), so nothing uses the set.
        unsafe { f.dev.update_descriptor_sets(&[write], &[]) };
        image_barriers(
            f.dev,
            f.cb,
            &[ImageTransition {
                to: Access::ComputeWrite,
                ..f.output_to_attachment
            }],
        );
        // SAFETY: the sets match the march-compute layout and hold live resources; `output` is in GENERAL.
        unsafe {
            f.dev
                .cmd_bind_pipeline(f.cb, vk::PipelineBindPoint::COMPUTE, f.march_pipeline);
            f.dev.cmd_bind_descriptor_sets(
                f.cb,
                vk::PipelineBindPoint::COMPUTE,
                self.layouts.march_compute,
                0,
                &[f.frame_set, self.descriptors.volume_set, storage_set],
                &[],
            );
            f.dev
                .cmd_dispatch(f.cb, f.extent.width.div_ceil(8), f.extent.height.div_ceil(8), 1);
        }
        image_barriers(
            f.dev,
            f.cb,
            &[ImageTransition {
                image: f.output.0,
                from: Access::ComputeWrite,
                to: Access::ColorAttachmentWrite,
                discard: false,
            }],
        );
        f.stretch();
        f.timestamp(1);
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
