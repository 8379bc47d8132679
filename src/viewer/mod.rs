//! The desktop viewer: a winit window, a swapchain, the same `Renderer` as `volcast render` drawing into an
//! offscreen view image that is blitted to the swapchain, and an egui panel on top (egui-ash-renderer records
//! into our command buffer; we own submission and lifetimes).
//!
//! Frame: wait for the slot's fence → egui → (re)create what changed → acquire → record [march into the view
//! image → blit to the swapchain image → egui over it] → submit → present. Redraws happen only when something
//! changed, so an idle viewer sleeps in the event loop.

mod app;
mod frame;
mod loading;
pub mod model;
mod present;
pub mod recording;
mod screenshot;
mod script;
pub mod session;
pub mod widgets;

pub use script::{parse_script, ScriptStep};

use crate::gpu::resources::Image;
use crate::gpu::swapchain::{Surface, Swapchain, SwapchainDesc};
use crate::gpu::{Gpu, GpuError, GpuOptions, ValidationLog, VkContext};
use crate::render::headless::OUTPUT_FORMAT;
use crate::render::{PreparedVolume, Renderer};
use crate::volume::{RawOptions, Volume};
use ash::vk;
use loading::{open_source, value_histogram, Loading};
use model::actions::UiAction;
use model::Model;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use script::Script;
use std::path::PathBuf;
use std::sync::mpsc::Receiver;
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

/// Frames the CPU may record ahead of the GPU.
const FRAMES_IN_FLIGHT: usize = 2;

#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    #[error("no display to open a window on ({0}); use `volcast render` to render to a PNG without one")]
    NoDisplay(String),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("{0}")]
    Other(String),
}

/// Where the first volume comes from.
#[derive(Clone, Debug)]
pub enum VolumeSource {
    Builtin(String, Option<u32>),
    File(PathBuf, RawOptions),
}

pub struct ViewerOptions {
    pub source: VolumeSource,
    pub gpu: GpuOptions,
    pub size: (u32, u32),
    pub script: Vec<ScriptStep>,
    /// The step of a time series to show first (`--time`).
    pub time: Option<u32>,
    /// Sampling quality of still frames (`--quality`; the panel and Q change it).
    pub quality: crate::scene::quality::Quality,
    /// Start in the four-up layout with the slice views (`--slices`; L toggles it).
    pub slices: bool,
    /// A session to restore once its volume (`source`) is shown (`--state`).
    pub restore: Option<crate::scene::view_state::ViewState>,
    /// A transfer function to open with, locked (`--preset`, `--tf`); None: the one chosen by modality.
    pub transfer_function: Option<crate::transfer::function::TransferFunction>,
}

/// Opens the viewer and runs until the window closes. Returns the validation log for the caller to report.
pub fn run(opts: ViewerOptions) -> Result<Arc<ValidationLog>, ViewerError> {
    let unset = |v: &str| std::env::var_os(v).is_none_or(|x| x.is_empty());
    if cfg!(all(unix, not(target_os = "macos")))
        && unset("DISPLAY")
        && unset("WAYLAND_DISPLAY")
        && unset("WAYLAND_SOCKET")
    {
        return Err(ViewerError::NoDisplay(
            "neither DISPLAY nor WAYLAND_DISPLAY is set".into(),
        ));
    }
    let event_loop = EventLoop::new().map_err(|e| ViewerError::NoDisplay(e.to_string()))?;
    let mut app = App {
        opts,
        running: None,
        error: None,
        log: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewerError::Other(format!("event loop: {e}")))?;
    if let Some(r) = app.running.take() {
        r.destroy();
    }
    match app.error {
        Some(e) => Err(e),
        None => app
            .log
            .ok_or_else(|| ViewerError::Other("the window never opened".into())),
    }
}

struct App {
    opts: ViewerOptions,
    running: Option<Running>,
    error: Option<ViewerError>,
    log: Option<Arc<ValidationLog>>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_some() {
            return;
        }
        match Running::new(event_loop, &self.opts) {
            Ok(r) => {
                self.log = Some(r.gpu.log.clone());
                r.window.request_redraw();
                self.running = Some(r);
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(r) = &mut self.running else { return };
        let response = r.egui_state.on_window_event(&r.window, &event);
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(_) => r.window.request_redraw(),
            WindowEvent::DroppedFile(path) => {
                let action = r.state.files.load_action(path);
                r.apply(vec![action]);
                r.window.request_redraw();
            }
            WindowEvent::RedrawRequested => match r.redraw() {
                Ok(Flow::Continue) => {}
                Ok(Flow::Exit) => event_loop.exit(),
                Err(e) => {
                    self.error = Some(e);
                    event_loop.exit();
                }
            },
            _ => {}
        }
        if response.repaint {
            r.window.request_redraw();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(r) = &mut self.running else { return };
        if r.wants_continuous_redraw() {
            r.window.request_redraw();
            event_loop.set_control_flow(ControlFlow::Poll);
        } else if let Some(at) = r.repaint_at {
            event_loop.set_control_flow(ControlFlow::WaitUntil(at));
            if Instant::now() >= at {
                r.repaint_at = None;
                r.window.request_redraw();
            }
        } else {
            event_loop.set_control_flow(ControlFlow::Wait);
        }
    }
}

enum Flow {
    Continue,
    Exit,
}

struct FrameSync {
    cb: vk::CommandBuffer,
    fence: vk::Fence,
    image_available: vk::Semaphore,
}

/// The live viewer. Field order is irrelevant: `destroy` tears down explicitly, the Gpu last.
struct Running {
    window: Arc<Window>,
    gpu: Gpu,
    surface: Option<Surface>,
    swapchain: Option<Swapchain>,
    render_finished: Vec<vk::Semaphore>,
    frames: Vec<FrameSync>,
    frame_index: usize,
    renderer: Option<Renderer>,
    view_image: Option<Image>,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: Option<egui_ash_renderer::Renderer<egui_ash_renderer::allocator::GpuAllocator>>,
    state: Model,
    /// The slice views' textures.
    slice_textures: present::slice_textures::SliceTextures,
    loading: Option<Loading>,
    pending_screenshot: Option<PathBuf>,
    /// Input held back for the next frame so that a quick drag is seen as one (`app::input::drag_cut`).
    deferred_events: Vec<egui::Event>,
    /// The GIF being recorded (F9).
    recorder: Option<recording::Recorder>,
    zero_size: bool,
    recreate_swapchain: bool,
    last_frame: Instant,
    repaint_at: Option<Instant>,
    script: Option<Script>,
    has_volume: bool,
    /// A session to restore once its volume is shown.
    pending_restore: Option<crate::scene::view_state::ViewState>,
    /// Save the session to this file with the next frame's settings.
    pending_session: Option<PathBuf>,
    /// The volume named on the command line is loading in the background: its failure ends the session (there is
    /// nothing else to show), and `--time` applies once it is there.
    initial_load: Option<Option<u32>>,
    /// Where the shown volume came from (for F12's view state).
    shown_source: Option<VolumeSource>,
    /// The last frame was a reduced-detail one: draw again at full quality once the view is still.
    refine_pending: bool,
    /// Frame times (ms) of scripted drags, reported when the script ends.
    drag_frames: Vec<f64>,
    /// Whether the frame last recorded in each slot was a reduced-detail one.
    slot_reduced: [bool; FRAMES_IN_FLIGHT],
    /// An open file dialog's answer (None inside: cancelled, or no dialog available, e.g. no desktop portal).
    dialog: Option<Receiver<Option<PathBuf>>>,
    /// A time series' every step, kept to upload the one the time controls ask for; `None` for a 3-D volume.
    series: Option<Volume>,
    /// A 3-D volume kept for its gradient texture, made on the first frame that reads gradients
    /// (`Sampling::gradient_texture`); `None` for a series or a volume whose texture would exceed
    /// `quality::GRADIENT_LIMIT`.
    kept: Option<Volume>,
    /// The step after the shown one while playing, uploaded ahead of display (see `upload_ahead`).
    ahead: Option<(u32, PreparedVolume)>,
}

impl Running {
    fn new(event_loop: &ActiveEventLoop, opts: &ViewerOptions) -> Result<Running, ViewerError> {
        let attributes = Window::default_attributes()
            .with_title("volcast")
            .with_inner_size(winit::dpi::PhysicalSize::new(opts.size.0, opts.size.1));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| ViewerError::NoDisplay(format!("creating a window: {e}")))?,
        );
        let display = window
            .display_handle()
            .map_err(|e| ViewerError::NoDisplay(e.to_string()))?
            .as_raw();
        let handle = window
            .window_handle()
            .map_err(|e| ViewerError::NoDisplay(e.to_string()))?
            .as_raw();
        let required = ash_window::enumerate_required_extensions(display).ctx("surface extensions")?;
        let mut gpu_opts = opts.gpu.clone();
        // SAFETY: ash-window returns pointers to static, NUL-terminated extension names.
        gpu_opts.instance_extensions = required
            .iter()
            .map(|&p| unsafe { std::ffi::CStr::from_ptr(p) })
            .collect();
        gpu_opts.swapchain = true;
        let gpu = Gpu::new(&gpu_opts)?;
        // SAFETY: the window outlives the surface: Running::destroy drops the surface before the window.
        let surface = unsafe { Surface::new(&gpu, display, handle) }?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.properties.limits.max_image_dimension2_d as usize),
        );
        let mut r = Running {
            window: window.clone(),
            gpu,
            surface: Some(surface),
            swapchain: None,
            render_finished: Vec::new(),
            frames: Vec::new(),
            frame_index: 0,
            renderer: None,
            view_image: None,
            egui_ctx,
            egui_state,
            egui_renderer: None,
            state: Model::new(glam::Vec3::ONE, "loading…".into()),
            slice_textures: Default::default(),
            loading: None,
            pending_screenshot: None,
            deferred_events: Vec::new(),
            recorder: None,
            zero_size: false,
            recreate_swapchain: true,
            last_frame: Instant::now(),
            repaint_at: None,
            script: (!opts.script.is_empty()).then(|| Script {
                steps: opts.script.iter().cloned().collect(),
                frames_left: 0,
                drag_left: 0,
                waiting_for_size: None,
                waiting_for_load: false,
                wait_until: None,
                started: Instant::now(),
            }),
            has_volume: false,
            pending_restore: opts.restore.clone(),
            pending_session: None,
            initial_load: None,
            shown_source: None,
            refine_pending: false,
            drag_frames: Vec::new(),
            slot_reduced: [false; FRAMES_IN_FLIGHT],
            series: None,
            kept: None,
            ahead: None,
            dialog: None,
        };
        r.state.sampling.quality = Some(opts.quality);
        r.state.slices.shown = opts.slices;
        if let Some(tf) = &opts.transfer_function {
            // Locked, so that loading the volume does not replace it with the automatic one.
            r.state.look.transfer_function = Some(tf.clone());
            r.state.look.window = [0.0, 1.0];
            r.state.tf_editor.locked = true;
        }
        // On error `r` is torn down properly before the error is returned.
        match r.init(opts) {
            Ok(()) => Ok(r),
            Err(e) => {
                r.destroy();
                Err(e)
            }
        }
    }

    fn init(&mut self, opts: &ViewerOptions) -> Result<(), ViewerError> {
        let gpu = &self.gpu;
        self.renderer = Some(Renderer::new(gpu, OUTPUT_FORMAT, FRAMES_IN_FLIGHT)?);
        for _ in 0..FRAMES_IN_FLIGHT {
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(gpu.command_pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            // SAFETY: valid allocate/create infos on a live device; each object is destroyed in `destroy`.
            let sync = unsafe {
                FrameSync {
                    cb: gpu
                        .device
                        .allocate_command_buffers(&alloc)
                        .ctx("vkAllocateCommandBuffers")?[0],
                    fence: gpu
                        .device
                        .create_fence(
                            &vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED),
                            None,
                        )
                        .ctx("vkCreateFence")?,
                    image_available: gpu
                        .device
                        .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
                        .ctx("vkCreateSemaphore")?,
                }
            };
            self.frames.push(sync);
        }
        self.recreate_swapchain()?;
        let allocator = self.gpu.allocator.clone().ok_or(GpuError::Lost("allocator"))?;
        let format = self
            .swapchain
            .as_ref()
            .map(|s| s.format)
            .ok_or(GpuError::Lost("swapchain"))?;
        let egui_renderer = egui_ash_renderer::Renderer::with_gpu_allocator(
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
        self.egui_renderer = Some(egui_renderer);
        let max_dim = self.gpu.properties.limits.max_image_dimension3_d;
        if let VolumeSource::File(..) = &opts.source {
            // A file loads in the background, so the window shows its progress at once (a 1 GiB volume took 20 s
            // with no window at all). Until it is there an empty placeholder (all below the value window) stands
            // in, and a script waits for it.
            let placeholder = Volume::new(
                "loading",
                [2; 3],
                [1.0; 3],
                crate::volume::VoxelType::U8,
                crate::volume::VoxelData::U8(vec![0; 8]),
            )
            .map_err(|e| ViewerError::Other(e.to_string()))?;
            self.install_volume(placeholder, Vec::new(), false)?;
            self.state.volume.label = "loading…".into();
            self.start_load(opts.source.clone());
            self.initial_load = Some(opts.time);
            if let Some(script) = &mut self.script {
                script.waiting_for_load = true;
            }
            return Ok(());
        }
        let first = open_source(&opts.source, max_dim, &mut |_| {}).map_err(ViewerError::Other)?;
        let histogram = value_histogram(&first);
        let from_file = matches!(opts.source, VolumeSource::File(..));
        self.install_volume(first, histogram, from_file)?;
        self.shown_source = Some(opts.source.clone());
        self.apply_time(opts.time)?;
        if let Some(session) = self.pending_restore.take() {
            self.state.restore(&session);
        }
        Ok(())
    }

    fn wait_idle(&self) -> Result<(), GpuError> {
        // SAFETY: plain wait on a live device.
        unsafe { self.gpu.device.device_wait_idle() }.ctx("vkDeviceWaitIdle")
    }

    fn recreate_swapchain(&mut self) -> Result<(), ViewerError> {
        self.wait_idle()?;
        let size = self.window.inner_size();
        let desc = SwapchainDesc {
            width: size.width.max(1),
            height: size.height.max(1),
            vsync: self.state.display.vsync,
        };
        let surface = self.surface.as_ref().ok_or(GpuError::Lost("surface"))?;
        let new = Swapchain::new(&self.gpu, surface, desc, self.swapchain.as_ref())?;
        if let Some(old) = self.swapchain.replace(new) {
            old.destroy(&self.gpu);
        }
        for s in self.render_finished.drain(..) {
            // SAFETY: the device is idle, so no submission waits on or signals these semaphores.
            unsafe { self.gpu.device.destroy_semaphore(s, None) };
        }
        let count = self.swapchain.as_ref().map(|s| s.images.len()).unwrap_or(0);
        for _ in 0..count {
            // SAFETY: valid create info on a live device.
            let s = unsafe {
                self.gpu
                    .device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
            }
            .ctx("vkCreateSemaphore")?;
            self.render_finished.push(s);
        }
        self.recreate_swapchain = false;
        Ok(())
    }

    fn wants_continuous_redraw(&self) -> bool {
        self.loading.is_some()
            || self.dialog.is_some()
            || self.state.camera.auto_rotate
            || self.state.camera.animation.is_some()
            || self.script.is_some()
            || self.refine_pending
            || self.state.time.playing
            || !self.deferred_events.is_empty()
    }

    fn apply(&mut self, actions: Vec<UiAction>) {
        for action in actions {
            match action {
                UiAction::LoadFile(path, opts) => self.start_load(VolumeSource::File(path, opts)),
                UiAction::LoadBuiltin(name) => self.start_load(VolumeSource::Builtin(name, None)),
                UiAction::Screenshot => {
                    self.pending_screenshot = Some(PathBuf::from(format!("volcast-{}.png", time_stamp())));
                }
                UiAction::ToggleRecording => match self.recorder.take() {
                    Some(r) => self.stop_recording(r),
                    None => {
                        let path = PathBuf::from(format!("volcast-{}.gif", time_stamp()));
                        eprintln!("recording {}", path.display());
                        self.state.messages.recording = Some(path.display().to_string());
                        self.recorder = Some(recording::Recorder::new(path));
                    }
                },
                UiAction::VsyncChanged => self.recreate_swapchain = true,
                UiAction::SaveSession => {
                    self.pending_session = Some(PathBuf::from(self.state.files.session_path.trim()))
                }
                UiAction::OpenSession(path) => self.open_session(&path),
                UiAction::OpenDialog if self.dialog.is_none() => {
                    // The dialog blocks until the user answers, so it runs on its own thread.
                    let (tx, rx) = std::sync::mpsc::channel();
                    std::thread::spawn(move || {
                        let _ = tx.send(rfd::FileDialog::new().set_title("Load volume").pick_file());
                    });
                    self.dialog = Some(rx);
                }
                UiAction::OpenDialog => {}
            }
        }
    }

    /// Ends a recording: writes its GIF (or says why not).
    fn stop_recording(&mut self, r: recording::Recorder) {
        let path = r.path().display().to_string();
        self.state.messages.recording = None;
        match r.finish(Instant::now()) {
            Ok(frames) => {
                eprintln!("saved recording {path} ({frames} frames)");
                self.state.messages.status = Some(format!("saved {path} ({frames} frames)"));
            }
            Err(e) => {
                eprintln!("recording: {e}");
                self.state.messages.error = Some(format!("recording: {e}"));
            }
        }
    }

    fn destroy(mut self) {
        // A recording still running is written, as if stopped.
        if let Some(r) = self.recorder.take() {
            self.stop_recording(r);
        }
        let _ = self.wait_idle();
        // egui's renderer holds a clone of the allocator: drop it before the Gpu drops the allocator.
        drop(self.egui_renderer.take());
        if let Some((_, v)) = self.ahead.take() {
            v.destroy(&self.gpu);
        }
        if let Some(r) = self.renderer.take() {
            r.destroy(&self.gpu);
        }
        if let Some(v) = self.view_image.take() {
            v.destroy(&self.gpu);
        }
        // SAFETY: the device is idle; these objects are no longer used.
        unsafe {
            for f in self.frames.drain(..) {
                self.gpu.device.destroy_fence(f.fence, None);
                self.gpu.device.destroy_semaphore(f.image_available, None);
                self.gpu.device.free_command_buffers(self.gpu.command_pool, &[f.cb]);
            }
            for s in self.render_finished.drain(..) {
                self.gpu.device.destroy_semaphore(s, None);
            }
        }
        if let Some(s) = self.swapchain.take() {
            s.destroy(&self.gpu);
        }
        if let Some(s) = self.surface.take() {
            s.destroy();
        }
        // The Gpu drops here, after everything made from it.
    }
}

/// Seconds since 1970, for the names of screenshots and recordings.
fn time_stamp() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0)
}
