//! Rendering to an offscreen image and reading it back: what `render`, `compare` and the tests use.

use crate::gpu::resources::{record_readback, Buffer, Image, ImageDesc};
use crate::gpu::sync::Access;
use crate::gpu::{Gpu, GpuError};
use crate::render::{PassTimings, Renderer};
use crate::scene::settings::RenderSettings;
use crate::volume::Volume;
use ash::vk;
use gpu_allocator::MemoryLocation;

/// The format of offscreen images: 8-bit linear RGBA, written to PNG as is.
pub const OUTPUT_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
/// The format of a rank's share (rule 11's partial output, `src/distributed`): 32-bit float RGBA, composited before
/// anything is rounded.
pub const SHARE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

struct Offscreen {
    image: Image,
    readback: Buffer,
}

/// One rendered frame.
pub struct Frame {
    pub image: image::RgbaImage,
    pub timings: Option<PassTimings>,
}

/// A renderer with its offscreen target and readback buffer.
pub struct Headless {
    pub renderer: Renderer,
    target: Option<Offscreen>,
    format: vk::Format,
}

impl Headless {
    pub fn new(gpu: &Gpu) -> Result<Headless, GpuError> {
        Headless::with_format(gpu, OUTPUT_FORMAT)
    }

    /// Offscreen images of `format`: [`OUTPUT_FORMAT`], or [`SHARE_FORMAT`] for a rank's share.
    pub fn with_format(gpu: &Gpu, format: vk::Format) -> Result<Headless, GpuError> {
        Ok(Headless {
            renderer: Renderer::new(gpu, format, 1)?,
            target: None,
            format,
        })
    }

    fn bytes_per_pixel(&self) -> u64 {
        if self.format == SHARE_FORMAT {
            16
        } else {
            4
        }
    }

    pub fn set_volume(&mut self, gpu: &Gpu, volume: &Volume) -> Result<(), GpuError> {
        self.renderer.set_volume(gpu, volume)
    }

    fn ensure_target(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<(), GpuError> {
        if let Some(t) = &self.target {
            if t.image.desc.extent.width == width && t.image.desc.extent.height == height {
                return Ok(());
            }
        }
        if let Some(old) = self.target.take() {
            old.readback.destroy(gpu);
            old.image.destroy(gpu);
        }
        // STORAGE for the compute march (RGBA8 storage images are required of every Vulkan device), TRANSFER_DST
        // for the blit of spaced rays (rule 12).
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::TRANSFER_DST;
        let image = Image::new(
            gpu,
            ImageDesc::d2(self.format, width, height, usage),
            "offscreen colour",
        )?;
        let bytes = width as u64 * height as u64 * self.bytes_per_pixel();
        match Buffer::new(
            gpu,
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
            "readback",
        ) {
            Ok(readback) => {
                self.target = Some(Offscreen { image, readback });
                Ok(())
            }
            Err(e) => {
                image.destroy(gpu);
                Err(e)
            }
        }
    }

    /// Renders one frame with `s` and reads it back. Blocks until the GPU is done.
    pub fn render(&mut self, gpu: &Gpu, s: &RenderSettings) -> Result<Frame, GpuError> {
        if self.format != OUTPUT_FORMAT {
            return Err(GpuError::InvalidSettings(
                "render() reads 8-bit images; use render_share()".into(),
            ));
        }
        let pixels = self.draw(gpu, s)?;
        let image = image::RgbaImage::from_raw(s.width, s.height, pixels).ok_or(GpuError::Lost("readback size"))?;
        Ok(Frame {
            image,
            timings: self.renderer.timings(gpu, 0)?,
        })
    }

    /// Renders a rank's share with `s` (a [`SHARE_FORMAT`] target): RGBA f32 per pixel, rows top down.
    pub fn render_share(&mut self, gpu: &Gpu, s: &RenderSettings) -> Result<Vec<f32>, GpuError> {
        if self.format != SHARE_FORMAT {
            return Err(GpuError::InvalidSettings("render_share() needs a float target".into()));
        }
        // One ray per pixel: a share's partial colours are composited before anything could stretch them.
        let mut one_ray = s.clone();
        one_ray.sampling.ray_spacing = 1;
        let s = &one_ray;
        let bytes = self.draw(gpu, s)?;
        Ok(bytes
            .chunks_exact(4)
            .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
            .collect())
    }

    /// Draws `s` and returns the target's bytes.
    fn draw(&mut self, gpu: &Gpu, s: &RenderSettings) -> Result<Vec<u8>, GpuError> {
        s.validate().map_err(GpuError::InvalidSettings)?;
        self.renderer.prepare(gpu, s)?;
        self.ensure_target(gpu, s.width, s.height)?;
        let target = self.target.as_ref().ok_or(GpuError::Lost("offscreen target"))?;
        let renderer = &mut self.renderer;
        let mut recorded = Ok(());
        gpu.submit_and_wait(|cb| {
            recorded = renderer.record(
                gpu,
                cb,
                0,
                (target.image.raw, target.image.view),
                Access::TransferRead,
                s,
            );
            if recorded.is_ok() {
                record_readback(gpu, cb, &target.image, Access::ColorAttachmentWrite, &target.readback);
            }
        })?;
        recorded?;
        Ok(target
            .readback
            .mapped()
            .ok_or(GpuError::Lost("readback buffer is not mapped"))?
            .to_vec())
    }

    pub fn destroy(mut self, gpu: &Gpu) {
        if let Some(t) = self.target.take() {
            // SAFETY: render() waits for its submission, so nothing is in flight.
            t.readback.destroy(gpu);
            t.image.destroy(gpu);
        }
        self.renderer.destroy(gpu);
    }
}
