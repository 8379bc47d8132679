//! Window surface and swapchain, recreated (with `oldSwapchain`) on resize, SUBOPTIMAL and OUT_OF_DATE.

use super::{Gpu, GpuError, VkContext};
use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

pub struct Surface {
    pub raw: vk::SurfaceKHR,
    pub loader: ash::khr::surface::Instance,
}

impl Surface {
    /// # Safety
    /// The handles must belong to a live window that outlives the surface.
    pub unsafe fn new(gpu: &Gpu, display: RawDisplayHandle, window: RawWindowHandle) -> Result<Surface, GpuError> {
        // SAFETY: the caller guarantees the handles are valid; the instance was created with the extensions that
        // ash-window asked for.
        let raw = unsafe { ash_window::create_surface(&gpu.entry, &gpu.instance, display, window, None) }
            .ctx("vkCreate*SurfaceKHR")?;
        let loader = ash::khr::surface::Instance::new(&gpu.entry, &gpu.instance);
        // SAFETY: the surface was just created on this instance.
        let supported =
            unsafe { loader.get_physical_device_surface_support(gpu.physical, gpu.queue_family, raw) }.unwrap_or(false);
        if !supported {
            // SAFETY: nothing uses the surface yet.
            unsafe { loader.destroy_surface(raw, None) };
            return Err(GpuError::NoDevice(format!(
                "{} cannot present to this window",
                gpu.device_name
            )));
        }
        Ok(Surface { raw, loader })
    }

    pub fn destroy(self) {
        // SAFETY: the swapchain using the surface was destroyed first (Viewer teardown order).
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}

/// What the viewer asks of a swapchain.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SwapchainDesc {
    pub width: u32,
    pub height: u32,
    pub vsync: bool,
}

pub struct Swapchain {
    pub raw: vk::SwapchainKHR,
    pub loader: ash::khr::swapchain::Device,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub images: Vec<vk::Image>,
    pub views: Vec<vk::ImageView>,
    pub desc: SwapchainDesc,
    /// The images can be copied from (the viewer's "as shown" screenshots read the presented pixels).
    pub readable: bool,
}

/// UNORM first: volcast writes display-encoded 8-bit values and egui-ash-renderer encodes to sRGB itself for a
/// non-sRGB target, so an SRGB swapchain would encode a second time (too bright).
fn choose_format(formats: &[vk::SurfaceFormatKHR]) -> Option<vk::SurfaceFormatKHR> {
    let preferred = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM];
    preferred.iter().find_map(|f| {
        formats
            .iter()
            .find(|s| s.format == *f && s.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
            .copied()
    })
}

/// What the surface supports on this device.
struct SurfaceSupport {
    caps: vk::SurfaceCapabilitiesKHR,
    formats: Vec<vk::SurfaceFormatKHR>,
    modes: Vec<vk::PresentModeKHR>,
}

impl SurfaceSupport {
    fn query(gpu: &Gpu, surface: &Surface) -> Result<SurfaceSupport, GpuError> {
        let loader = &surface.loader;
        // SAFETY: queries on a live surface and device.
        unsafe {
            Ok(SurfaceSupport {
                caps: loader
                    .get_physical_device_surface_capabilities(gpu.physical, surface.raw)
                    .ctx("surface caps")?,
                formats: loader
                    .get_physical_device_surface_formats(gpu.physical, surface.raw)
                    .ctx("surface formats")?,
                modes: loader
                    .get_physical_device_surface_present_modes(gpu.physical, surface.raw)
                    .ctx("present modes")?,
            })
        }
    }
}

/// The surface's own extent when it fixes one, else the asked size clamped to what it allows.
fn choose_extent(caps: &vk::SurfaceCapabilitiesKHR, desc: &SwapchainDesc) -> vk::Extent2D {
    if caps.current_extent.width != u32::MAX {
        return caps.current_extent;
    }
    vk::Extent2D {
        width: desc
            .width
            .clamp(caps.min_image_extent.width, caps.max_image_extent.width),
        height: desc
            .height
            .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
    }
}

/// FIFO with vsync; otherwise MAILBOX or IMMEDIATE where offered (FIFO is always there).
fn choose_present_mode(modes: &[vk::PresentModeKHR], vsync: bool) -> vk::PresentModeKHR {
    if vsync {
        return vk::PresentModeKHR::FIFO;
    }
    [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
        .into_iter()
        .find(|m| modes.contains(m))
        .unwrap_or(vk::PresentModeKHR::FIFO)
}

impl Swapchain {
    /// Creates a swapchain for `surface`, retiring `old` if given (its images may still be presenting).
    pub fn new(
        gpu: &Gpu,
        surface: &Surface,
        desc: SwapchainDesc,
        old: Option<&Swapchain>,
    ) -> Result<Swapchain, GpuError> {
        let support = SurfaceSupport::query(gpu, surface)?;
        let caps = support.caps;
        let format = choose_format(&support.formats).ok_or_else(|| {
            GpuError::NoDevice(format!(
                "the window offers no 8-bit UNORM surface format (it offers {:?})",
                support.formats
            ))
        })?;
        let needed = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if !caps.supported_usage_flags.contains(needed) {
            return Err(GpuError::NoDevice(
                "the swapchain cannot be a blit target and colour attachment".into(),
            ));
        }
        // Readable where the surface allows it: a screenshot as shown copies the image after egui drew on it.
        let readable = caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let usage = if readable {
            needed | vk::ImageUsageFlags::TRANSFER_SRC
        } else {
            needed
        };
        let extent = choose_extent(&caps, &desc);
        let mode = choose_present_mode(&support.modes, desc.vsync);
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let loader = ash::khr::swapchain::Device::new(&gpu.instance, &gpu.device);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(mode)
            .clipped(true)
            .old_swapchain(old.map(|o| o.raw).unwrap_or_default());
        // SAFETY: `info` describes a valid swapchain for this surface; `old` is retired by this call.
        let raw = unsafe { loader.create_swapchain(&info, None) }.ctx("vkCreateSwapchainKHR")?;
        // SAFETY: `raw` was just created.
        let images = match unsafe { loader.get_swapchain_images(raw) } {
            Ok(i) => i,
            Err(e) => {
                // SAFETY: nothing uses the new swapchain yet.
                unsafe { loader.destroy_swapchain(raw, None) };
                return Err(GpuError::vk("vkGetSwapchainImagesKHR", e));
            }
        };
        let mut chain = Swapchain {
            raw,
            loader,
            format: format.format,
            extent,
            images,
            views: Vec::new(),
            desc,
            readable,
        };
        if let Err(e) = chain.create_views(gpu) {
            chain.destroy(gpu);
            return Err(e);
        }
        Ok(chain)
    }

    /// One colour view per swapchain image, pushed onto `views` as made (so a
    /// failure leaves only views that `destroy` frees).
    fn create_views(&mut self, gpu: &Gpu) -> Result<(), GpuError> {
        for &image in &self.images {
            let view_info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(self.format)
                .subresource_range(super::sync::COLOR_RANGE);
            // SAFETY: the image belongs to the swapchain and the view matches its format.
            let view = unsafe { gpu.device.create_image_view(&view_info, None) }.ctx("vkCreateImageView")?;
            self.views.push(view);
        }
        Ok(())
    }

    /// Callers wait for the device to be idle (or at least for every frame using these images) first.
    pub fn destroy(self, gpu: &Gpu) {
        // SAFETY: no pending work uses the views or the swapchain (caller's contract).
        unsafe {
            for v in &self.views {
                gpu.device.destroy_image_view(*v, None);
            }
            self.loader.destroy_swapchain(self.raw, None);
        }
    }
}
