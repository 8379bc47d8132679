//! The entry/exit method's two position targets (passes 1 and 2 write them, the march reads them), at the size
//! the march works at (`RenderSettings::marched_size`, rule 12).

use crate::gpu::resources::{Image, ImageDesc};
use crate::gpu::{Gpu, GpuError};
use crate::scene::settings::{PositionFormat, RenderSettings};
use ash::vk;

/// Bytes per pixel that the entry/exit method needs beyond the output image (both position targets).
pub fn position_bytes_per_pixel(format: PositionFormat) -> u64 {
    match format {
        PositionFormat::Rgba32f => 32,
        PositionFormat::Rgba16f => 16,
    }
}

pub(super) struct PositionTargets {
    pub entry: Image,
    pub exit: Image,
    pub format: PositionFormat,
}

impl PositionTargets {
    pub fn vk_format(format: PositionFormat) -> vk::Format {
        match format {
            PositionFormat::Rgba32f => vk::Format::R32G32B32A32_SFLOAT,
            PositionFormat::Rgba16f => vk::Format::R16G16B16A16_SFLOAT,
        }
    }

    /// Both targets for `s`, written into `set` (the march's positions set) with the point `sampler`. No
    /// submitted work may use the set (`Renderer::prepare`'s contract).
    pub fn new(
        gpu: &Gpu,
        s: &RenderSettings,
        sampler: vk::Sampler,
        set: vk::DescriptorSet,
    ) -> Result<PositionTargets, GpuError> {
        let format = PositionTargets::vk_format(s.pipeline.position_format);
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        let (width, height) = s.marched_size();
        let entry = Image::new(gpu, ImageDesc::d2(format, width, height, usage), "entry positions")?;
        let exit = match Image::new(gpu, ImageDesc::d2(format, width, height, usage), "exit positions") {
            Ok(i) => i,
            Err(e) => {
                entry.destroy(gpu);
                return Err(e);
            }
        };
        let targets = PositionTargets {
            entry,
            exit,
            format: s.pipeline.position_format,
        };
        targets.write_set(gpu, sampler, set);
        Ok(targets)
    }

    fn write_set(&self, gpu: &Gpu, sampler: vk::Sampler, set: vk::DescriptorSet) {
        let infos = [self.entry.view, self.exit.view].map(|v| {
            [vk::DescriptorImageInfo::default()
                .image_view(v)
                .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)]
        });
        let sampler_info = [vk::DescriptorImageInfo::default().sampler(sampler)];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&infos[0]),
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&infos[1]),
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(2)
                .descriptor_type(vk::DescriptorType::SAMPLER)
                .image_info(&sampler_info),
        ];
        // SAFETY: no submitted work uses the set (`new`'s contract).
        unsafe { gpu.device.update_descriptor_sets(&writes, &[]) };
    }

    /// Whether these are the targets `s` needs.
    pub fn fit(&self, s: &RenderSettings) -> bool {
        self.format == s.pipeline.position_format
            && (self.entry.desc.extent.width, self.entry.desc.extent.height) == s.marched_size()
    }

    pub fn destroy(self, gpu: &Gpu) {
        self.exit.destroy(gpu);
        self.entry.destroy(gpu);
    }
}
