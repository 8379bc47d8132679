//! Rule 12's spaced rays (`RenderSettings::ray_spacing`): the march writes an image of
//! `RenderSettings::marched_size` into a target of its own, and a linear blit stretches it over the output. On
//! lavapipe a frame costs about what its rays do, so `draft`'s one ray per 2×2 pixels takes a quarter of the time
//! (docs/performance.md, Quality levels); VTK's `ImageSampleDistance` does the same while the user interacts.

use crate::gpu::resources::{Image, ImageDesc};
use crate::gpu::sync::{image_barriers, Access, ImageTransition, COLOR_LAYERS};
use crate::gpu::{Gpu, GpuError};
use crate::scene::settings::RenderSettings;
use ash::vk;

/// The march's target where rays are spaced: the output's format at the marched size.
pub struct SpacedTarget {
    pub image: Image,
}

impl SpacedTarget {
    /// A target for `s`'s marched size in `format`, which must take a linear blit (as RGBA8 must on every Vulkan
    /// device; a float share's may not: the caller is told so).
    pub fn new(gpu: &Gpu, format: vk::Format, s: &RenderSettings) -> Result<SpacedTarget, GpuError> {
        // SAFETY: `physical` is the device's own physical device, alive as long as the instance.
        let features = unsafe { gpu.instance.get_physical_device_format_properties(gpu.physical, format) };
        let needed = vk::FormatFeatureFlags::BLIT_SRC
            | vk::FormatFeatureFlags::BLIT_DST
            | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR;
        if !features.optimal_tiling_features.contains(needed) {
            return Err(GpuError::InvalidSettings(format!(
                "ray spacing {} needs a linear blit of the output format {format:?}, which this device lacks",
                s.spacing()
            )));
        }
        let (width, height) = s.marched_size();
        // STORAGE for the compute march, TRANSFER_SRC for the blit.
        let usage =
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let image = Image::new(gpu, ImageDesc::d2(format, width, height, usage), "spaced rays")?;
        Ok(SpacedTarget { image })
    }

    /// Whether this target is the size `s` marches at.
    pub fn fits(&self, s: &RenderSettings) -> bool {
        let e = self.image.desc.extent;
        (e.width, e.height) == s.marched_size()
    }

    pub fn destroy(self, gpu: &Gpu) {
        self.image.destroy(gpu);
    }
}

/// Where a spaced frame's march goes and what it is stretched into.
#[derive(Clone, Copy)]
pub struct Stretch {
    /// The march's target, a colour attachment written by the march when this is recorded.
    pub from: (vk::Image, vk::Extent2D),
    /// The output, last used as `last`, and its size.
    pub output: vk::Image,
    pub last: Access,
    pub extent: vk::Extent2D,
}

impl Stretch {
    /// Records the blit that stretches the march's image over the output (rule 12's bilinear filter): the output
    /// ends in `Access::ColorAttachmentWrite`, as `Renderer::record` promises.
    pub fn record(&self, dev: &ash::Device, cb: vk::CommandBuffer) {
        image_barriers(
            dev,
            cb,
            &[
                ImageTransition {
                    image: self.from.0,
                    from: Access::ColorAttachmentWrite,
                    to: Access::TransferRead,
                    discard: false,
                },
                ImageTransition {
                    image: self.output,
                    from: self.last,
                    to: Access::TransferWrite,
                    discard: true,
                },
            ],
        );
        let corner = |e: vk::Extent2D| {
            [
                vk::Offset3D::default(),
                vk::Offset3D {
                    x: e.width as i32,
                    y: e.height as i32,
                    z: 1,
                },
            ]
        };
        let layers = COLOR_LAYERS;
        let region = vk::ImageBlit::default()
            .src_subresource(layers)
            .src_offsets(corner(self.from.1))
            .dst_subresource(layers)
            .dst_offsets(corner(self.extent));
        // SAFETY: both images are in the layouts the barrier above gave them; the format takes a linear blit
        // (checked when the target was made); `cb` is recording outside any rendering scope.
        unsafe {
            dev.cmd_blit_image(
                cb,
                self.from.0,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.output,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
                vk::Filter::LINEAR,
            )
        };
        image_barriers(
            dev,
            cb,
            &[ImageTransition {
                image: self.output,
                from: Access::TransferWrite,
                to: Access::ColorAttachmentWrite,
                discard: false,
            }],
        );
    }
}

/// Makes `target` what `s` needs: a target of its marched size where its rays are spaced, else none (its memory
/// freed). No submitted frame may use the old one (`Renderer::prepare`'s contract).
pub fn prepare(
    gpu: &Gpu,
    target: &mut Option<SpacedTarget>,
    format: vk::Format,
    s: &RenderSettings,
) -> Result<(), GpuError> {
    if fits(target, s) {
        return Ok(());
    }
    if let Some(old) = target.take() {
        old.destroy(gpu);
    }
    if s.spacing() > 1 {
        *target = Some(SpacedTarget::new(gpu, format, s)?);
    }
    Ok(())
}

/// Whether `target` is what `s` needs ([`prepare`] has nothing to do).
pub fn fits(target: &Option<SpacedTarget>, s: &RenderSettings) -> bool {
    match target {
        Some(t) => s.spacing() > 1 && t.fits(s),
        None => s.spacing() == 1,
    }
}
