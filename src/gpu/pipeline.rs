//! The SPIR-V that build.rs made, and one graphics-pipeline builder for dynamic rendering.

use super::{Gpu, GpuError, VkContext};
use ash::vk;

/// A compiled shader stage from `OUT_DIR`.
pub struct ShaderCode {
    pub name: &'static str,
    pub bytes: &'static [u8],
}

macro_rules! shader {
    ($name:literal) => {
        $crate::gpu::pipeline::ShaderCode {
            name: $name,
            bytes: include_bytes!(concat!(env!("OUT_DIR"), "/", $name, ".spv")),
        }
    };
}
pub(crate) use shader;

fn module(gpu: &Gpu, code: &ShaderCode) -> Result<vk::ShaderModule, GpuError> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(code.bytes))
        .map_err(|_| GpuError::Lost("SPIR-V from build.rs is malformed"))?;
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    // SAFETY: `words` is SPIR-V that naga validated at build time.
    unsafe { gpu.device.create_shader_module(&info, None) }.ctx("vkCreateShaderModule")
}

/// What differs between volcast's graphics pipelines.
pub struct GraphicsDesc<'a> {
    pub vertex: &'a ShaderCode,
    pub fragment: &'a ShaderCode,
    pub layout: vk::PipelineLayout,
    pub color_format: vk::Format,
    pub cull: vk::CullModeFlags,
}

/// A pipeline with dynamic viewport and scissor, no depth, no blending, no vertex input.
pub fn graphics_pipeline(gpu: &Gpu, desc: &GraphicsDesc) -> Result<vk::Pipeline, GpuError> {
    let vs = module(gpu, desc.vertex)?;
    let fs = match module(gpu, desc.fragment) {
        Ok(m) => m,
        Err(e) => {
            // SAFETY: the module is not used by any pipeline.
            unsafe { gpu.device.destroy_shader_module(vs, None) };
            return Err(e);
        }
    };
    let stages = [
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(vs)
            .name(c"main"),
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::FRAGMENT)
            .module(fs)
            .name(c"main"),
    ];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
    let input_assembly =
        vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    // Outward faces are counter-clockwise on screen with camera.rs's y-down projection.
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(desc.cull)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let multisample =
        vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let attachments =
        [vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA)];
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let formats = [desc.color_format];
    let mut rendering = vk::PipelineRenderingCreateInfo::default().color_attachment_formats(&formats);
    let info = vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&input_assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(desc.layout)
        .push_next(&mut rendering);
    // SAFETY: all referenced state lives until the call returns; the modules are valid.
    let result = unsafe {
        gpu.device
            .create_graphics_pipelines(vk::PipelineCache::null(), &[info], None)
    };
    // SAFETY: pipelines keep no reference to their shader modules once created.
    unsafe {
        gpu.device.destroy_shader_module(vs, None);
        gpu.device.destroy_shader_module(fs, None);
    }
    match result {
        Ok(p) => Ok(p[0]),
        Err((_, e)) => Err(GpuError::vk("vkCreateGraphicsPipelines", e)),
    }
}

/// A compute pipeline running `code`'s `main`.
pub fn compute_pipeline(gpu: &Gpu, code: &ShaderCode, layout: vk::PipelineLayout) -> Result<vk::Pipeline, GpuError> {
    let cs = module(gpu, code)?;
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::COMPUTE)
        .module(cs)
        .name(c"main");
    let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout);
    // SAFETY: the module and layout are live; the info lives until the call returns.
    let result = unsafe {
        gpu.device
            .create_compute_pipelines(vk::PipelineCache::null(), &[info], None)
    };
    // SAFETY: pipelines keep no reference to their shader modules once created.
    unsafe { gpu.device.destroy_shader_module(cs, None) };
    match result {
        Ok(p) => Ok(p[0]),
        Err((_, e)) => Err(GpuError::vk("vkCreateComputePipelines", e)),
    }
}
