//! Creating the renderer: descriptor set and pipeline layouts, samplers, pipelines for every variant, the
//! table buffer and the frame slots.

use super::{FrameSlot, FrameUniforms, PositionTargets, Renderer, LUT_ROWS, QUERIES};
use crate::gpu::pipeline::{graphics_pipeline, shader, GraphicsDesc};
use crate::gpu::resources::Buffer;
use crate::gpu::{Gpu, GpuError, VkContext};
use crate::scene::settings::{PositionFormat, RenderSettings};
use crate::transfer::function::LUT_SIZE;
use ash::vk;
use gpu_allocator::MemoryLocation;

/// The pre-integration table's size: [`LUT_SIZE`] vec4 of f32, 64 KiB.
const INTEGRALS_BYTES: u64 = (LUT_SIZE * std::mem::size_of::<[f32; 4]>()) as u64;

fn set_layout(
    gpu: &Gpu,
    bindings: &[(vk::DescriptorType, vk::ShaderStageFlags)],
) -> Result<vk::DescriptorSetLayout, GpuError> {
    let b: Vec<vk::DescriptorSetLayoutBinding> = bindings
        .iter()
        .enumerate()
        .map(|(i, &(ty, stages))| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(i as u32)
                .descriptor_type(ty)
                .descriptor_count(1)
                .stage_flags(stages)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&b);
    // SAFETY: valid create info on a live device.
    unsafe { gpu.device.create_descriptor_set_layout(&info, None) }.ctx("vkCreateDescriptorSetLayout")
}

fn pipeline_layout(gpu: &Gpu, sets: &[vk::DescriptorSetLayout]) -> Result<vk::PipelineLayout, GpuError> {
    let info = vk::PipelineLayoutCreateInfo::default().set_layouts(sets);
    // SAFETY: the set layouts are live.
    unsafe { gpu.device.create_pipeline_layout(&info, None) }.ctx("vkCreatePipelineLayout")
}

fn sampler(gpu: &Gpu, filter: vk::Filter) -> Result<vk::Sampler, GpuError> {
    let info = vk::SamplerCreateInfo::default()
        .mag_filter(filter)
        .min_filter(filter)
        .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
        .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .max_lod(0.0);
    // SAFETY: valid create info on a live device.
    unsafe { gpu.device.create_sampler(&info, None) }.ctx("vkCreateSampler")
}

impl Renderer {
    /// Creates pipelines and fixed resources. `output_format` is the colour target's format (RGBA8 headless);
    /// `frames_in_flight` slots let that many recorded frames be pending at once (see [`Renderer::record`]).
    /// On error everything created so far is destroyed again.
    pub fn new(gpu: &Gpu, output_format: vk::Format, frames_in_flight: usize) -> Result<Renderer, GpuError> {
        let all = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT | vk::ShaderStageFlags::COMPUTE;
        let frag = vk::ShaderStageFlags::FRAGMENT | vk::ShaderStageFlags::COMPUTE;
        let uniform_range = gpu.properties.limits.max_uniform_buffer_range;
        if u64::from(uniform_range) < INTEGRALS_BYTES {
            return Err(GpuError::NoDevice(format!(
                "the device's uniform buffers hold {uniform_range} bytes; the march needs {INTEGRALS_BYTES}"
            )));
        }
        let lut = Buffer::new(
            gpu,
            (LUT_ROWS * LUT_SIZE * std::mem::size_of::<[f32; 4]>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
            "transfer function table",
        )?;
        let integrals = match Buffer::new(
            gpu,
            INTEGRALS_BYTES,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            MemoryLocation::CpuToGpu,
            "pre-integration table",
        ) {
            Ok(b) => b,
            Err(e) => {
                lut.destroy(gpu);
                return Err(e);
            }
        };
        let mut r = Renderer {
            output_format,
            layouts: Default::default(),
            pipelines: Default::default(),
            descriptors: Default::default(),
            samplers: Default::default(),
            slots: Vec::new(),
            table: super::parts::Table {
                lut,
                integrals,
                baked: None,
                entries: Vec::new(),
            },
            targets: Default::default(),
            volume: None,
            layers: None,
            texel_policy: gpu.texel_policy,
            brick_side: gpu.brick_side,
            light_ms: None,
            timestamp_period_ns: gpu.properties.limits.timestamp_period as f64,
        };
        match r.init(gpu, all, frag, frames_in_flight.max(1)) {
            Ok(()) => Ok(r),
            Err(e) => {
                r.destroy(gpu);
                Err(e)
            }
        }
    }

    fn init(
        &mut self,
        gpu: &Gpu,
        all: vk::ShaderStageFlags,
        frag: vk::ShaderStageFlags,
        slots: usize,
    ) -> Result<(), GpuError> {
        self.create_layouts(gpu, all, frag)?;
        let light_pass = super::light_volume::LightPass::new(gpu, self.layouts.frame_set, self.layouts.volume_set)?;
        self.pipelines.light = Some(light_pass);
        self.samplers.linear = sampler(gpu, vk::Filter::LINEAR)?;
        self.samplers.point = sampler(gpu, vk::Filter::NEAREST)?;
        self.create_position_pipelines(gpu)?;
        let sets = self.allocate_sets(gpu, slots)?;
        (self.descriptors.volume_set, self.descriptors.positions_set) = (sets[0], sets[1]);
        if let Some(pass) = &mut self.pipelines.light {
            pass.set = sets[2];
        }
        for (&set, &storage_set) in sets[3..3 + slots].iter().zip(&sets[3 + slots..]) {
            let slot = frame_slot(gpu, set, storage_set)?;
            self.slots.push(slot);
        }
        self.layers = Some(super::layers::GpuLayers::new(gpu, &[])?);
        self.write_layer_set(gpu);
        let initial = RenderSettings::default();
        self.upload_lut(&initial, [0.0, 1.0])?;
        Ok(())
    }

    /// The descriptor-set layouts (frame, volume, positions, storage) and the
    /// pipeline layouts built from them.
    fn create_layouts(
        &mut self,
        gpu: &Gpu,
        all: vk::ShaderStageFlags,
        frag: vk::ShaderStageFlags,
    ) -> Result<(), GpuError> {
        use vk::DescriptorType as D;
        self.layouts.frame_set = set_layout(gpu, &[(D::UNIFORM_BUFFER, all)])?;
        self.layouts.volume_set = set_layout(
            gpu,
            &[
                (D::SAMPLED_IMAGE, frag),
                (D::SAMPLER, frag),
                (D::STORAGE_BUFFER, frag),
                (D::SAMPLED_IMAGE, frag),
                (D::SAMPLED_IMAGE, frag),
                (D::SAMPLED_IMAGE, frag),
                (D::UNIFORM_BUFFER, frag),
                (D::SAMPLED_IMAGE, frag),
                // The brick pool's page table (render/pool.rs).
                (D::SAMPLED_IMAGE, frag),
                // Rule 13's layers (render/layers.rs): overlay values, label ids, their table (uniform) and colours.
                (D::SAMPLED_IMAGE, frag),
                (D::SAMPLED_IMAGE, frag),
                (D::UNIFORM_BUFFER, frag),
                (D::SAMPLED_IMAGE, frag),
            ],
        )?;
        self.layouts.positions_set = set_layout(
            gpu,
            &[(D::SAMPLED_IMAGE, frag), (D::SAMPLED_IMAGE, frag), (D::SAMPLER, frag)],
        )?;
        self.layouts.faces = pipeline_layout(gpu, &[self.layouts.frame_set])?;
        self.layouts.march_faces = pipeline_layout(
            gpu,
            &[
                self.layouts.frame_set,
                self.layouts.volume_set,
                self.layouts.positions_set,
            ],
        )?;
        self.layouts.march_analytic = pipeline_layout(gpu, &[self.layouts.frame_set, self.layouts.volume_set])?;
        self.layouts.storage_set = set_layout(gpu, &[(D::STORAGE_IMAGE, vk::ShaderStageFlags::COMPUTE)])?;
        self.layouts.march_compute = pipeline_layout(
            gpu,
            &[
                self.layouts.frame_set,
                self.layouts.volume_set,
                self.layouts.storage_set,
            ],
        )?;
        Ok(())
    }

    /// The box-face pipelines: one per position format, front and back culling.
    fn create_position_pipelines(&mut self, gpu: &Gpu) -> Result<(), GpuError> {
        let faces_vert = shader!("faces.vert");
        let faces_frag = shader!("faces.frag");
        for (i, format) in [PositionFormat::Rgba32f, PositionFormat::Rgba16f]
            .into_iter()
            .enumerate()
        {
            for (j, cull) in [vk::CullModeFlags::BACK, vk::CullModeFlags::FRONT]
                .into_iter()
                .enumerate()
            {
                self.pipelines.position[i][j] = graphics_pipeline(
                    gpu,
                    &GraphicsDesc {
                        vertex: &faces_vert,
                        fragment: &faces_frag,
                        layout: self.layouts.faces,
                        color_format: PositionTargets::vk_format(format),
                        cull,
                    },
                )?;
            }
        }
        Ok(())
    }

    /// The descriptor pool and its sets, in this order: volume, positions,
    /// light, then `slots` frame sets and `slots` storage sets.
    fn allocate_sets(&mut self, gpu: &Gpu, slots: usize) -> Result<Vec<vk::DescriptorSet>, GpuError> {
        use vk::DescriptorType as D;
        let n = slots as u32;
        let size = |ty, descriptor_count| vk::DescriptorPoolSize { ty, descriptor_count };
        let sizes = [
            size(D::UNIFORM_BUFFER, n + 2),
            size(D::SAMPLED_IMAGE, 12),
            size(D::SAMPLER, 2),
            size(D::STORAGE_IMAGE, n + 1),
            size(D::STORAGE_BUFFER, 2),
        ];
        let pool_info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(3 + 2 * n)
            .pool_sizes(&sizes);
        // SAFETY: valid create info on a live device.
        self.descriptors.pool =
            unsafe { gpu.device.create_descriptor_pool(&pool_info, None) }.ctx("vkCreateDescriptorPool")?;
        let light_set_layout = self
            .pipelines
            .light
            .as_ref()
            .map(|p| p.set_layout())
            .unwrap_or_default();
        let mut layouts = vec![self.layouts.volume_set, self.layouts.positions_set, light_set_layout];
        layouts.extend(std::iter::repeat_n(self.layouts.frame_set, slots));
        layouts.extend(std::iter::repeat_n(self.layouts.storage_set, slots));
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.descriptors.pool)
            .set_layouts(&layouts);
        // SAFETY: the pool has room for exactly these sets.
        unsafe { gpu.device.allocate_descriptor_sets(&alloc) }.ctx("vkAllocateDescriptorSets")
    }
}

/// One frame in flight: its uniform buffer (written into `set`), its
/// timestamp queries and its storage-image set.
fn frame_slot(gpu: &Gpu, set: vk::DescriptorSet, storage_set: vk::DescriptorSet) -> Result<FrameSlot, GpuError> {
    let uniforms = Buffer::new(
        gpu,
        std::mem::size_of::<FrameUniforms>() as u64,
        vk::BufferUsageFlags::UNIFORM_BUFFER,
        MemoryLocation::CpuToGpu,
        "frame uniforms",
    )?;
    let query_info = vk::QueryPoolCreateInfo::default()
        .query_type(vk::QueryType::TIMESTAMP)
        .query_count(QUERIES);
    // SAFETY: valid create info on a live device.
    let query_pool = match unsafe { gpu.device.create_query_pool(&query_info, None) } {
        Ok(q) => q,
        Err(e) => {
            uniforms.destroy(gpu);
            return Err(GpuError::vk("vkCreateQueryPool", e));
        }
    };
    let buffer_info = [vk::DescriptorBufferInfo {
        buffer: uniforms.raw,
        offset: 0,
        range: vk::WHOLE_SIZE,
    }];
    let write = vk::WriteDescriptorSet::default()
        .dst_set(set)
        .dst_binding(0)
        .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
        .buffer_info(&buffer_info);
    // SAFETY: the set is not in use by any command buffer.
    unsafe { gpu.device.update_descriptor_sets(&[write], &[]) };
    Ok(FrameSlot {
        uniforms,
        set,
        query_pool,
        storage_set,
        recorded: None,
    })
}
