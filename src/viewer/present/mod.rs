//! The presenter: everything on the GPU side of the viewer. It owns the device ([`Gpu`]) and all made from it —
//! the window's surface and swapchain ([`screen`]), the frames in flight ([`slots`]), the volume's pass and view
//! image ([`volume_pass`]), egui's renderer — plus the slice views' textures. A frame is [`Presenter::draw`];
//! [`draw::Frame`] says what it holds. It reads no model: the app hands it render settings, egui's shapes and
//! volumes; the slice textures are keyed by what their image shows (`model::slices::SliceImage`).

mod draw;
mod figure;
mod readback;
mod record;
mod reuse;
mod screen;
pub mod slice_textures;
mod slots;
mod volume_pass;

pub use draw::{Drawn, EguiFrame, Frame};
pub use readback::{Pixels, Readback, Wanted};
pub use record::view_pixels;
pub use slots::FRAMES_IN_FLIGHT;

use crate::gpu::swapchain::Surface;
use crate::gpu::{Gpu, GpuError, GpuOptions, ValidationLog, VkContext};
use crate::scene::settings::RenderSettings;
use crate::viewer::ViewerError;
use crate::volume::Volume;
use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use screen::Screen;
use slice_textures::SliceTextures;
use slots::FrameSlots;
use std::sync::Arc;
use volume_pass::VolumePass;
use winit::window::Window;

type EguiRenderer = egui_ash_renderer::Renderer<egui_ash_renderer::allocator::GpuAllocator>;

/// The GPU side of the viewer. `destroy` tears down explicitly (field order is irrelevant), the Gpu last.
pub struct Presenter {
    gpu: Gpu,
    screen: Screen,
    slots: FrameSlots,
    pass: VolumePass,
    egui: Option<EguiRenderer>,
    /// The slice views' images (egui textures).
    pub slice_textures: SliceTextures,
}

impl Presenter {
    /// Opens the device with what `window` needs to present, and everything a frame uses.
    pub fn new(window: &Window, opts: &GpuOptions, vsync: bool) -> Result<Presenter, ViewerError> {
        let display = window
            .display_handle()
            .map_err(|e| ViewerError::NoDisplay(e.to_string()))?
            .as_raw();
        let handle = window
            .window_handle()
            .map_err(|e| ViewerError::NoDisplay(e.to_string()))?
            .as_raw();
        let required = ash_window::enumerate_required_extensions(display).ctx("surface extensions")?;
        let mut gpu_opts = opts.clone();
        // SAFETY: ash-window returns pointers to static, NUL-terminated extension names.
        gpu_opts.instance_extensions = required
            .iter()
            .map(|&p| unsafe { std::ffi::CStr::from_ptr(p) })
            .collect();
        gpu_opts.swapchain = true;
        let gpu = Gpu::new(&gpu_opts)?;
        // SAFETY: the window outlives the surface: the app destroys the presenter before it drops the window.
        let surface = unsafe { Surface::new(&gpu, display, handle) }?;
        let mut presenter = Presenter {
            gpu,
            screen: Screen::new(surface),
            slots: FrameSlots::default(),
            pass: VolumePass::default(),
            egui: None,
            slice_textures: SliceTextures::default(),
        };
        // On error what was made is torn down properly before the error is returned.
        let size = window.inner_size();
        match presenter.init(size.width, size.height, vsync) {
            Ok(()) => Ok(presenter),
            Err(e) => {
                presenter.destroy();
                Err(e)
            }
        }
    }

    fn init(&mut self, width: u32, height: u32, vsync: bool) -> Result<(), ViewerError> {
        self.pass = VolumePass::new(&self.gpu, FRAMES_IN_FLIGHT)?;
        self.slots = FrameSlots::new(&self.gpu)?;
        self.screen.recreate(&self.gpu, width, height, vsync)?;
        let allocator = self.gpu.allocator.clone().ok_or(GpuError::Lost("allocator"))?;
        let format = self.screen.swapchain()?.format;
        let egui = egui_ash_renderer::Renderer::with_gpu_allocator(
            allocator,
            self.gpu.device.clone(),
            egui_ash_renderer::RenderMode::DynamicRendering(egui_ash_renderer::DynamicRendering {
                color_attachment_format: format,
                depth_attachment_format: None,
                stencil_attachment_format: None,
            }),
            egui_ash_renderer::Options {
                in_flight_frames: FRAMES_IN_FLIGHT,
                enable_depth_test: false,
                enable_depth_write: false,
                srgb_framebuffer: false,
            },
        )
        .map_err(|e| ViewerError::Other(format!("egui renderer: {e}")))?;
        self.egui = Some(egui);
        Ok(())
    }

    pub fn validation_log(&self) -> Arc<ValidationLog> {
        self.gpu.log.clone()
    }

    /// The largest 2D texture side (egui's limit).
    pub fn max_texture_side(&self) -> usize {
        self.gpu.properties.limits.max_image_dimension2_d as usize
    }

    /// The budgets a volume is shown within on this presenter's device ([`Gpu::budgets`]).
    pub fn budgets(&self, host: Option<u64>, device: Option<u64>) -> crate::pyramid::budget::Budgets {
        self.gpu.budgets(host, device)
    }

    /// Makes the swapchain fit a window of `width`×`height` (or take a new vsync) if it no longer does; returns
    /// its extent.
    pub fn fit_window(&mut self, width: u32, height: u32, vsync: bool) -> Result<vk::Extent2D, ViewerError> {
        if self.screen.needs_recreate(width, height) {
            self.screen.recreate(&self.gpu, width, height, vsync)?;
        }
        Ok(self.screen.swapchain()?.extent)
    }

    /// The swapchain is made again before the next frame (vsync changed).
    pub fn invalidate_swapchain(&mut self) {
        self.screen.stale = true;
    }

    /// Shows `volume` (a new one, or a series): whole, or streamed where one step is over `budgets`' GPU budget
    /// whole ([`refine`](Self::refine) fills the pool).
    pub fn set_volume(
        &mut self,
        volume: &Volume,
        budgets: &crate::pyramid::budget::Budgets,
    ) -> Result<crate::render::placement::Placed, GpuError> {
        self.pass.set_volume(&self.gpu, volume, budgets)
    }

    /// Shows `layers` with the volume, in place of those before.
    pub fn set_layers(&mut self, layers: &crate::scene::layer_set::Layers) -> Result<(), GpuError> {
        self.pass.set_layers(&self.gpu, layers)
    }

    /// One step of a streamed volume (`kept`, the one shown) towards the cut the still view `s` wants, one level
    /// coarser while `moving`: its progress, and whether it reached that cut just now. `None`: shown whole.
    pub fn refine(
        &mut self,
        s: &RenderSettings,
        moving: bool,
        kept: Option<&Volume>,
    ) -> Result<Option<(crate::render::placement::Progress, bool)>, GpuError> {
        match kept {
            Some(volume) => self.pass.refine(&self.gpu, s, moving, volume),
            None => Ok(None),
        }
    }

    /// Shows step `step` of `series`, whose voxels are that step's now.
    pub fn show_step(&mut self, series: &Volume, step: u32) -> Result<(), GpuError> {
        self.pass.show_step(&self.gpu, series, step)
    }

    /// Whether step `step` of the series was uploaded ahead.
    pub fn holds_ahead(&self, step: u32) -> bool {
        self.pass.holds_ahead(step)
    }

    /// Forgets the step uploaded ahead, if any.
    pub fn drop_ahead(&mut self) {
        self.pass.drop_ahead(&self.gpu);
    }

    /// Uploads `volume` (showing step `step` of a series) ahead of display. Called after a frame is submitted: the
    /// conversion and brick grid are made on the CPU while the device renders that frame.
    pub fn upload_ahead(&mut self, step: u32, volume: &Volume) -> Result<(), GpuError> {
        self.pass.upload_ahead(&self.gpu, step, volume)
    }

    /// Creates what `settings` needs beyond the frame (the gradient texture from `kept`, the view image...) only
    /// when something changed.
    pub fn prepare(&mut self, settings: &RenderSettings, kept: Option<&Volume>) -> Result<(), GpuError> {
        self.pass.prepare(&self.gpu, settings, kept)
    }

    /// Waits for the device, then takes a frame's read-back pixels (RGBA8).
    pub fn pixels(&self, readback: Readback) -> Pixels {
        readback.pixels(&self.gpu)
    }

    fn wait_idle(&self) -> Result<(), GpuError> {
        // SAFETY: plain wait on a live device.
        unsafe { self.gpu.device.device_wait_idle() }.ctx("vkDeviceWaitIdle")
    }

    /// Tears everything down after the device is idle; the Gpu drops last.
    pub fn destroy(mut self) {
        let _ = self.wait_idle();
        // egui's renderer holds a clone of the allocator: drop it before the Gpu drops the allocator.
        drop(self.egui.take());
        self.pass.destroy(&self.gpu);
        self.slots.destroy(&self.gpu);
        self.screen.destroy(&self.gpu);
        // The Gpu drops here, after everything made from it.
    }
}
