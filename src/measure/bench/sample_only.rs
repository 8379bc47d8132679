//! The sample-only micro-benchmark: the device's raw trilinear 3D-texture sampling rate per texel format.

use super::Stats;
use crate::gpu::pipeline::{graphics_pipeline, shader, GraphicsDesc};
use crate::gpu::resources::{Buffer, Image, ImageDesc};
use crate::gpu::sync::{image_barriers, Access, ImageTransition};
use crate::gpu::upload::upload_image;
use crate::gpu::{Gpu, GpuError, VkContext};
use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;
use std::time::Instant;

/// The GPU formats volcast stores volumes in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum TexelFormat {
    #[serde(rename = "R8_UNORM")]
    R8Unorm,
    #[serde(rename = "R16_UNORM")]
    R16Unorm,
    #[serde(rename = "R32_SFLOAT")]
    R32Sfloat,
}

impl TexelFormat {
    pub const ALL: [TexelFormat; 3] = [TexelFormat::R8Unorm, TexelFormat::R16Unorm, TexelFormat::R32Sfloat];

    pub fn name(self) -> &'static str {
        match self {
            TexelFormat::R8Unorm => "R8_UNORM",
            TexelFormat::R16Unorm => "R16_UNORM",
            TexelFormat::R32Sfloat => "R32_SFLOAT",
        }
    }

    fn vk(self) -> vk::Format {
        match self {
            TexelFormat::R8Unorm => vk::Format::R8_UNORM,
            TexelFormat::R16Unorm => vk::Format::R16_UNORM,
            TexelFormat::R32Sfloat => vk::Format::R32_SFLOAT,
        }
    }

    /// `n`³ texels of a pattern with texel-to-texel variation, so a filter cannot shortcut equal neighbours.
    fn test_texels(self, n: u32) -> Vec<u8> {
        let level = |x: u32, y: u32, z: u32| ((x * 7) ^ (y * 13) ^ (z * 29)) & 255;
        let mut out = Vec::with_capacity((n as usize).pow(3) * 4);
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let l = level(x, y, z);
                    match self {
                        TexelFormat::R8Unorm => out.push(l as u8),
                        TexelFormat::R16Unorm => out.extend_from_slice(&((l * 257) as u16).to_ne_bytes()),
                        TexelFormat::R32Sfloat => out.extend_from_slice(&(l as f32 / 255.0).to_ne_bytes()),
                    }
                }
            }
        }
        out
    }
}

/// One result of the sample-only micro-benchmark.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SampleRate {
    pub format: TexelFormat,
    /// Edge of the cubic test texture.
    pub texture: u32,
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    pub frames: u32,
    pub gpu_ms: Stats,
    pub wall_ms: Stats,
    /// Trilinear samples per second from the median GPU time, in 10⁹.
    pub gsamples_per_s: f64,
}

// ---------------------------------------------------------------------------------------------------------------
// The sample-only micro-benchmark.

/// The uniform block `Params` in shaders/sample_only.frag.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct SampleParams {
    start: [f32; 4],
    step: [f32; 4],
    viewport: [f32; 4],
}

/// Size of one sample-only run.
#[derive(Clone, Copy, Debug)]
pub struct SampleOnlyConfig {
    pub texture: u32,
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    pub frames: u32,
    pub warmup: u32,
}

impl SampleOnlyConfig {
    /// 256³ textures, 512² pixels × 256 samples (67 M samples, ~0.3 s a frame on lavapipe).
    pub fn full(frames: u32) -> SampleOnlyConfig {
        SampleOnlyConfig {
            texture: 256,
            width: 512,
            height: 512,
            samples_per_pixel: 256,
            frames: frames.clamp(1, 5),
            warmup: 1,
        }
    }

    pub fn quick() -> SampleOnlyConfig {
        SampleOnlyConfig {
            texture: 64,
            width: 64,
            height: 64,
            samples_per_pixel: 64,
            frames: 2,
            warmup: 1,
        }
    }
}

const SAMPLE_TARGET_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

/// Pipeline, descriptor set, target and queries of the sample-only pass. Null handles are skipped on destroy, so a
/// half-built one can be destroyed.
struct SamplePass {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    sampler: vk::Sampler,
    query_pool: vk::QueryPool,
    uniforms: Option<Buffer>,
    target: Option<Image>,
}

impl SamplePass {
    fn new(gpu: &Gpu, width: u32, height: u32) -> Result<SamplePass, GpuError> {
        let mut p = SamplePass {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            sampler: vk::Sampler::null(),
            query_pool: vk::QueryPool::null(),
            uniforms: None,
            target: None,
        };
        match p.init(gpu, width, height) {
            Ok(()) => Ok(p),
            Err(e) => {
                p.destroy(gpu);
                Err(e)
            }
        }
    }

    fn init(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<(), GpuError> {
        self.init_pipeline(gpu)?;
        self.init_set(gpu)?;
        self.init_resources(gpu, width, height)
    }

    /// The set layout (uniforms, the texture, its sampler), the pipeline layout and the pipeline.
    fn init_pipeline(&mut self, gpu: &Gpu) -> Result<(), GpuError> {
        use vk::DescriptorType as D;
        let dev = &gpu.device;
        let frag = vk::ShaderStageFlags::FRAGMENT;
        let bindings: Vec<vk::DescriptorSetLayoutBinding> = [D::UNIFORM_BUFFER, D::SAMPLED_IMAGE, D::SAMPLER]
            .into_iter()
            .enumerate()
            .map(|(i, ty)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(frag)
            })
            .collect();
        // SAFETY: valid create info on a live device.
        self.set_layout = unsafe {
            dev.create_descriptor_set_layout(&vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings), None)
        }
        .ctx("vkCreateDescriptorSetLayout")?;
        // SAFETY: the set layout is live.
        self.layout = unsafe {
            dev.create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default().set_layouts(&[self.set_layout]),
                None,
            )
        }
        .ctx("vkCreatePipelineLayout")?;
        self.pipeline = graphics_pipeline(
            gpu,
            &GraphicsDesc {
                vertex: &shader!("fullscreen.vert"),
                fragment: &shader!("sample_only.frag"),
                layout: self.layout,
                color_format: SAMPLE_TARGET_FORMAT,
                cull: vk::CullModeFlags::NONE,
            },
        )?;
        Ok(())
    }

    /// The descriptor pool and its one set.
    fn init_set(&mut self, gpu: &Gpu) -> Result<(), GpuError> {
        use vk::DescriptorType as D;
        let dev = &gpu.device;
        let sizes = [D::UNIFORM_BUFFER, D::SAMPLED_IMAGE, D::SAMPLER].map(|ty| vk::DescriptorPoolSize {
            ty,
            descriptor_count: 1,
        });
        // SAFETY: valid create info on a live device.
        self.pool = unsafe {
            dev.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes),
                None,
            )
        }
        .ctx("vkCreateDescriptorPool")?;
        // SAFETY: the pool has room for this one set.
        self.set = unsafe {
            dev.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(self.pool)
                    .set_layouts(&[self.set_layout]),
            )
        }
        .ctx("vkAllocateDescriptorSets")?[0];
        Ok(())
    }

    /// The sampler, the timestamp queries, the uniform buffer and the `width`×`height` target.
    fn init_resources(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<(), GpuError> {
        let dev = &gpu.device;
        let sampler_info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0);
        // SAFETY: valid create info on a live device.
        self.sampler = unsafe { dev.create_sampler(&sampler_info, None) }.ctx("vkCreateSampler")?;
        let query_info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(2);
        // SAFETY: valid create info on a live device.
        self.query_pool = unsafe { dev.create_query_pool(&query_info, None) }.ctx("vkCreateQueryPool")?;
        self.uniforms = Some(Buffer::new(
            gpu,
            std::mem::size_of::<SampleParams>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            MemoryLocation::CpuToGpu,
            "sample-only uniforms",
        )?);
        self.target = Some(Image::new(
            gpu,
            ImageDesc::d2(
                SAMPLE_TARGET_FORMAT,
                width,
                height,
                vk::ImageUsageFlags::COLOR_ATTACHMENT,
            ),
            "sample-only target",
        )?);
        Ok(())
    }

    /// Points the descriptor set at `texture`. No submitted work may be using the set.
    fn bind(&self, gpu: &Gpu, texture: &Image) -> Result<(), GpuError> {
        let uniforms = self.uniforms.as_ref().ok_or(GpuError::Lost("sample-only uniforms"))?;
        let buffer_info = [vk::DescriptorBufferInfo::default()
            .buffer(uniforms.raw)
            .offset(0)
            .range(vk::WHOLE_SIZE)];
        let image_info = [vk::DescriptorImageInfo::default()
            .image_view(texture.view)
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        let sampler_info = [vk::DescriptorImageInfo::default().sampler(self.sampler)];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .buffer_info(&buffer_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&image_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(2)
                .descriptor_type(vk::DescriptorType::SAMPLER)
                .image_info(&sampler_info),
        ];
        // SAFETY: every frame is waited for (submit_and_wait), so nothing uses the set now.
        unsafe { gpu.device.update_descriptor_sets(&writes, &[]) };
        Ok(())
    }

    /// Draws one frame and returns (GPU ms from timestamps, wall ms). `first`: the target's old state is undefined.
    fn frame(&self, gpu: &Gpu, first: bool) -> Result<(f64, f64), GpuError> {
        let target = self.target.as_ref().ok_or(GpuError::Lost("sample-only target"))?;
        let dev = &gpu.device;
        let extent = vk::Extent2D {
            width: target.desc.extent.width,
            height: target.desc.extent.height,
        };
        let t = Instant::now();
        gpu.submit_and_wait(|cb| {
            // SAFETY: `cb` is recording, outside any rendering scope.
            unsafe { dev.cmd_reset_query_pool(cb, self.query_pool, 0, 2) };
            image_barriers(
                dev,
                cb,
                &[ImageTransition {
                    image: target.raw,
                    from: if first {
                        Access::Undefined
                    } else {
                        Access::ColorAttachmentWrite
                    },
                    to: Access::ColorAttachmentWrite,
                    discard: true,
                }],
            );
            let scissor = vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent,
            };
            let viewport = vk::Viewport {
                x: 0.0,
                y: 0.0,
                width: extent.width as f32,
                height: extent.height as f32,
                min_depth: 0.0,
                max_depth: 1.0,
            };
            let attachment = [vk::RenderingAttachmentInfo::default()
                .image_view(target.view)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::DONT_CARE)
                .store_op(vk::AttachmentStoreOp::STORE)];
            let info = vk::RenderingInfo::default()
                .render_area(scissor)
                .layer_count(1)
                .color_attachments(&attachment);
            // SAFETY: the target is in COLOR_ATTACHMENT_OPTIMAL (barrier above); pipeline, layout and set match and
            // hold live resources; the queries were reset above.
            unsafe {
                dev.cmd_write_timestamp2(cb, vk::PipelineStageFlags2::ALL_COMMANDS, self.query_pool, 0);
                dev.cmd_begin_rendering(cb, &info);
                dev.cmd_set_viewport(cb, 0, &[viewport]);
                dev.cmd_set_scissor(cb, 0, &[scissor]);
                dev.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, self.pipeline);
                dev.cmd_bind_descriptor_sets(cb, vk::PipelineBindPoint::GRAPHICS, self.layout, 0, &[self.set], &[]);
                dev.cmd_draw(cb, 3, 1, 0, 0);
                dev.cmd_end_rendering(cb);
                dev.cmd_write_timestamp2(cb, vk::PipelineStageFlags2::ALL_COMMANDS, self.query_pool, 1);
            }
        })?;
        let wall = t.elapsed().as_secs_f64() * 1e3;
        let mut ticks = [0u64; 2];
        // SAFETY: both queries were written by the submission that just completed.
        unsafe {
            dev.get_query_pool_results(
                self.query_pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .ctx("vkGetQueryPoolResults")?;
        let period_ns = f64::from(gpu.properties.limits.timestamp_period);
        Ok((ticks[1].saturating_sub(ticks[0]) as f64 * period_ns * 1e-6, wall))
    }

    fn destroy(mut self, gpu: &Gpu) {
        if let Some(t) = self.target.take() {
            t.destroy(gpu);
        }
        if let Some(u) = self.uniforms.take() {
            u.destroy(gpu);
        }
        // SAFETY: every frame was waited for; Vulkan ignores null handles.
        unsafe {
            let d = &gpu.device;
            d.destroy_query_pool(self.query_pool, None);
            d.destroy_sampler(self.sampler, None);
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_pipeline(self.pipeline, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// Measures trilinear 3D-texture samples per second for each of `formats`: a full-screen pass whose fragments
/// only take `samples_per_pixel` samples along a fixed direction (shaders/sample_only.frag).
pub fn sample_only(
    gpu: &Gpu,
    formats: &[TexelFormat],
    cfg: SampleOnlyConfig,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<SampleRate>, GpuError> {
    let mut pass = SamplePass::new(gpu, cfg.width, cfg.height)?;
    let result = (|| {
        let k = cfg.samples_per_pixel.max(1);
        // Rays cross 0.8 of the texture along a skew direction, starting in a 0.4-wide square: they stay inside
        // the texture (no clamped samples) and take steps of 0.8·n/k texels.
        let dir = Vec3::new(1.0, 2.0, 3.0).normalize() * (0.8 / k as f32);
        let params = SampleParams {
            start: [0.05, 0.05, 0.1, 0.4],
            step: [dir.x, dir.y, dir.z, k as f32],
            viewport: [cfg.width as f32, cfg.height as f32, 0.0, 0.0],
        };
        pass.uniforms
            .as_mut()
            .ok_or(GpuError::Lost("sample-only uniforms"))?
            .write(bytemuck::bytes_of(&params))?;
        let pass = &pass;
        let mut out = Vec::new();
        let mut first = true;
        for &format in formats {
            log(&format!(
                "sample-only {}: uploading a {}^3 texture",
                format.name(),
                cfg.texture
            ));
            let n = cfg.texture;
            let desc = ImageDesc {
                format: format.vk(),
                extent: vk::Extent3D {
                    width: n,
                    height: n,
                    depth: n,
                },
                usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            };
            let mut texture = Image::new(gpu, desc, "sample-only texture")?;
            let measured = (|| -> Result<SampleRate, GpuError> {
                upload_image(gpu, &mut texture, &format.test_texels(n))?;
                pass.bind(gpu, &texture)?;
                let (mut gpu_ms, mut wall_ms) = (Vec::new(), Vec::new());
                for i in 0..cfg.warmup + cfg.frames.max(1) {
                    let (g, w) = pass.frame(gpu, first)?;
                    first = false;
                    if i >= cfg.warmup {
                        gpu_ms.push(g);
                        wall_ms.push(w);
                    }
                }
                let gpu_stats = Stats::of(&gpu_ms).ok_or(GpuError::Lost("no frames timed"))?;
                let wall_stats = Stats::of(&wall_ms).ok_or(GpuError::Lost("no frames timed"))?;
                let samples = f64::from(cfg.width) * f64::from(cfg.height) * f64::from(k);
                Ok(SampleRate {
                    format,
                    texture: n,
                    width: cfg.width,
                    height: cfg.height,
                    samples_per_pixel: k,
                    frames: gpu_ms.len() as u32,
                    gpu_ms: gpu_stats,
                    wall_ms: wall_stats,
                    gsamples_per_s: samples / (gpu_stats.median.max(1e-6) * 1e-3) / 1e9,
                })
            })();
            texture.destroy(gpu);
            let rate = measured?;
            log(&format!(
                "sample-only {}: {:.3} G samples/s",
                format.name(),
                rate.gsamples_per_s
            ));
            out.push(rate);
        }
        Ok(out)
    })();
    pass.destroy(gpu);
    result
}
