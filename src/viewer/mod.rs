//! The desktop viewer: a winit window, a swapchain, the same `Renderer` as `volcast render` drawing into an
//! offscreen view image that is blitted to the swapchain, and an egui panel on top (egui-ash-renderer records
//! into our command buffer; we own submission and lifetimes).
//!
//! Frame: wait for the slot's fence → egui → (re)create what changed → acquire → record [march into the view
//! image → blit to the swapchain image → egui over it] → submit → present. Redraws happen only when something
//! changed, so an idle viewer sleeps in the event loop.

pub mod controls;
pub mod light_gizmo;
pub mod lighting_panel;
pub mod tf_editor;
pub mod time_control;
pub mod ui;

use crate::gpu::resources::{record_readback, Buffer, Image, ImageDesc};
use crate::gpu::swapchain::{Surface, Swapchain, SwapchainDesc};
use crate::gpu::sync::{image_barrier, Access};
use crate::gpu::{Gpu, GpuError, GpuOptions, ValidationLog, VkContext};
use crate::headless::OUTPUT_FORMAT;
use crate::render::{PreparedVolume, Renderer};
use crate::settings::RenderSettings;
use crate::volume::{self, RawOptions, Volume};
use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::sync::Arc;
use std::time::{Duration, Instant};
use ui::{UiAction, ViewerState};
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

/// One step of a scripted session (`--script`, used by the tests to drive a real window under Xvfb).
#[derive(Clone, Debug, PartialEq)]
pub enum ScriptStep {
    /// Render this many frames.
    Frames(u32),
    /// Keep the window open and drawing for this long, so that a test can drive it with real X input meanwhile.
    Wait(Duration),
    /// Rotate the view a little each frame for this many frames, as a drag would, and report the frame times.
    Drag(u32),
    /// Interactive level of detail on or off.
    Lod(bool),
    /// Press "Open…" (the platform file dialog; without a desktop portal it reports that none is available).
    Dialog,
    /// Ask the window system for a new size and wait (a bounded number of frames) until it arrives.
    Resize(u32, u32),
    Minimize,
    Restore,
    /// Behave as if the window system reported a 0×0 size (what minimising does on most platforms).
    ZeroSize,
    /// Press a key (through the same path as the keyboard): r, space, tab or f12.
    Key(String),
    /// Save the current view through the screenshot path (PNG, plus the settings as JSON beside it).
    Screenshot(PathBuf),
    /// Load a file as if it were dropped on the window (the `DroppedFile` handler's path), then wait until the
    /// load ends and say on stderr whether it loaded.
    Drop(PathBuf),
    Exit,
}

/// Parses `frames:3;wait:500;resize:320x240;minimize;restore;zero-size;key:tab;screenshot:PATH;drop:PATH;exit` (wait in
/// milliseconds).
pub fn parse_script(s: &str) -> Result<Vec<ScriptStep>, String> {
    s.split(';')
        .filter(|p| !p.trim().is_empty())
        .map(|part| {
            let part = part.trim();
            let (cmd, arg) = part.split_once(':').unwrap_or((part, ""));
            let bad = || format!("bad script step '{part}'");
            Ok(match cmd {
                "frames" => ScriptStep::Frames(arg.parse().map_err(|_| bad())?),
                "wait" => ScriptStep::Wait(Duration::from_millis(arg.parse().map_err(|_| bad())?)),
                "drag" => ScriptStep::Drag(arg.parse().map_err(|_| bad())?),
                "lod" if arg == "on" || arg == "off" => ScriptStep::Lod(arg == "on"),
                "dialog" => ScriptStep::Dialog,
                "resize" => {
                    let (w, h) = arg.split_once('x').ok_or_else(bad)?;
                    ScriptStep::Resize(w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?)
                }
                "minimize" => ScriptStep::Minimize,
                "restore" => ScriptStep::Restore,
                "zero-size" => ScriptStep::ZeroSize,
                "key" => ScriptStep::Key(arg.to_lowercase()),
                "screenshot" if !arg.is_empty() => ScriptStep::Screenshot(PathBuf::from(arg)),
                "drop" if !arg.is_empty() => ScriptStep::Drop(PathBuf::from(arg)),
                "exit" => ScriptStep::Exit,
                _ => return Err(bad()),
            })
        })
        .collect()
}

pub struct ViewerOptions {
    pub source: VolumeSource,
    pub gpu: GpuOptions,
    pub size: (u32, u32),
    pub script: Vec<ScriptStep>,
    /// The step of a time series to show first (`--time`).
    pub time: Option<u32>,
    /// Sampling quality of still frames (`--quality`; the panel and Q change it).
    pub quality: crate::quality::Quality,
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
                let action = r.state.load_action(path);
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

struct Loading {
    label: String,
    /// What is loading (recorded for the view state once shown).
    source: VolumeSource,
    progress: Arc<AtomicU32>,
    rx: Receiver<Result<(Volume, Vec<u64>), String>>,
}

struct Script {
    steps: VecDeque<ScriptStep>,
    frames_left: u32,
    drag_left: u32,
    waiting_for_size: Option<(u32, u32, u32)>,
    wait_until: Option<Instant>,
    started: Instant,
    /// A `drop:` step's load is under way.
    waiting_for_load: bool,
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
    state: ViewerState,
    loading: Option<Loading>,
    pending_screenshot: Option<PathBuf>,
    zero_size: bool,
    recreate_swapchain: bool,
    last_frame: Instant,
    repaint_at: Option<Instant>,
    script: Option<Script>,
    has_volume: bool,
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
    /// (`ViewerState::gradient_texture`); `None` for a series or a volume whose texture would exceed
    /// `quality::GRADIENT_LIMIT`.
    kept: Option<Volume>,
    /// The step after the shown one while playing, uploaded ahead of display (see `upload_ahead`).
    ahead: Option<(u32, PreparedVolume)>,
}

/// The editor's histogram: 256 bins of normalised values.
fn value_histogram(v: &Volume) -> Vec<u64> {
    let [w, h, d] = v.dims;
    let values = (0..d).flat_map(move |z| (0..h).flat_map(move |y| (0..w).map(move |x| (x, y, z))));
    tf_editor::histogram(values.map(|(x, y, z)| v.normalized(x, y, z)), 256)
}

/// Loads any format `volume::open` reads (raw with the given options); a volume larger than `max_dim` (the
/// device's 3D texture limit) is downsampled with a warning rather than refused.
fn open_source(source: &VolumeSource, max_dim: u32, progress: &mut dyn FnMut(f32)) -> Result<Volume, String> {
    match source {
        VolumeSource::Builtin(name, size) => volume::builtin(name, *size).map_err(|e| e.to_string()),
        VolumeSource::File(path, raw) => {
            let opts = volume::OpenOptions {
                raw: raw.clone(),
                max_dim: Some(max_dim),
                ..Default::default()
            };
            volume::open_with_progress(path, &opts, progress).map_err(|e| e.to_string())
        }
    }
}

fn load_in_background(source: VolumeSource, max_dim: u32) -> Loading {
    let label = match &source {
        VolumeSource::Builtin(name, _) => name.clone(),
        VolumeSource::File(path, _) => path.display().to_string(),
    };
    let progress = Arc::new(AtomicU32::new(0));
    let (tx, rx) = std::sync::mpsc::channel();
    let p = progress.clone();
    let recorded = source.clone();
    std::thread::spawn(move || {
        // Reading is 90% of the bar, the histogram the rest.
        let result = open_source(&source, max_dim, &mut |f| {
            p.store((0.9 * f).to_bits(), Ordering::Relaxed)
        });
        p.store(0.9f32.to_bits(), Ordering::Relaxed);
        let analysed: Result<(Volume, Vec<u64>), String> = result.map(|v| {
            let h = value_histogram(&v);
            (v, h)
        });
        p.store(1.0f32.to_bits(), Ordering::Relaxed);
        let _ = tx.send(analysed);
    });
    Loading {
        label,
        source: recorded,
        progress,
        rx,
    }
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
            state: ViewerState {
                quality: Some(opts.quality),
                ..ViewerState::new(glam::Vec3::ONE, "loading…".into())
            },
            loading: None,
            pending_screenshot: None,
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
            self.install_volume(placeholder, Vec::new())?;
            self.state.volume_label = "loading…".into();
            self.start_load(opts.source.clone());
            self.initial_load = Some(opts.time);
            if let Some(script) = &mut self.script {
                script.waiting_for_load = true;
            }
            return Ok(());
        }
        let first = open_source(&opts.source, max_dim, &mut |_| {}).map_err(ViewerError::Other)?;
        let histogram = value_histogram(&first);
        self.install_volume(first, histogram)?;
        self.shown_source = Some(opts.source.clone());
        self.apply_time(opts.time)
    }

    /// `--time`: the step to show first; an error where the volume has no such step.
    fn apply_time(&mut self, time: Option<u32>) -> Result<(), ViewerError> {
        if let Some(t) = time {
            let steps = self.state.time.steps;
            if t >= steps {
                return Err(ViewerError::Other(format!(
                    "time step {t} does not exist: the volume has {steps} (0 to {})",
                    steps - 1
                )));
            }
            self.state.time.wanted = t;
        }
        Ok(())
    }

    fn install_volume(&mut self, v: Volume, histogram: Vec<u64>) -> Result<(), GpuError> {
        // SAFETY: plain wait on a live device; set_volume rewrites descriptors that in-flight frames use.
        unsafe { self.gpu.device.device_wait_idle() }.ctx("vkDeviceWaitIdle")?;
        if let Some((_, old)) = self.ahead.take() {
            old.destroy(&self.gpu);
        }
        let renderer = self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))?;
        renderer.set_volume(&self.gpu, &v)?;
        let spacing = v.spacing();
        let label = format!(
            "{} — {}×{}×{} {}, spacing {}×{}×{}",
            v.name, v.dims[0], v.dims[1], v.dims[2], v.source_type, spacing[0], spacing[1], spacing[2]
        );
        self.state.set_volume(v.extent(), v.geometry, v.dims, label);
        self.state.describe_raw(v.dims, v.source_type, spacing);
        self.state.histogram = histogram;
        self.state.range = v.range;
        self.state.time = time_control::TimeControl::new(v.timesteps(), v.shown_step());
        let keep = v.timesteps() == 1 && crate::quality::Gradients::texture_fits(v.voxel_count() as u64);
        self.state.gradient_texture = keep;
        (self.series, self.kept) = if v.timesteps() > 1 {
            (Some(v), None)
        } else {
            (None, keep.then_some(v))
        };
        self.has_volume = true;
        Ok(())
    }

    /// Uploads the step the time controls ask for, if it is not the one on the GPU.
    fn show_wanted_step(&mut self) -> Result<(), GpuError> {
        let wanted = self.state.time.wanted;
        let Some(series) = self.series.as_mut().filter(|s| s.shown_step() != wanted) else {
            return Ok(());
        };
        if series.show_step(wanted).is_err() {
            return Ok(());
        }
        // SAFETY: plain wait on a live device; the volume replaced is one that in-flight frames use.
        unsafe { self.gpu.device.device_wait_idle() }.ctx("vkDeviceWaitIdle")?;
        let renderer = self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))?;
        match self.ahead.take() {
            // Uploaded ahead: showing it is a descriptor update.
            Some((step, prepared)) if step == wanted => {
                renderer.install_volume(&self.gpu, prepared);
                Ok(())
            }
            other => {
                if let Some((_, stale)) = other {
                    stale.destroy(&self.gpu);
                }
                renderer.set_volume(&self.gpu, series)
            }
        }
    }

    /// While a series plays, uploads the step after the shown one, so that when its time comes it is shown without
    /// waiting for an upload. Called after a frame is submitted: the volume's conversion and brick grid are made on
    /// the CPU while the device renders that frame (on a GPU in parallel; on lavapipe the two share the cores).
    fn upload_ahead(&mut self) -> Result<(), GpuError> {
        let time = &self.state.time;
        let Some(series) = self.series.as_mut().filter(|_| time.playing && time.steps > 1) else {
            return Ok(());
        };
        let next = (time.wanted + 1) % time.steps;
        if self.ahead.as_ref().is_some_and(|(step, _)| *step == next) {
            return Ok(());
        }
        if let Some((_, stale)) = self.ahead.take() {
            stale.destroy(&self.gpu);
        }
        let shown = series.shown_step();
        if series.show_step(next).is_err() {
            return Ok(());
        }
        let renderer = self.renderer.as_ref().ok_or(GpuError::Lost("renderer"))?;
        let prepared = renderer.prepare_volume(&self.gpu, series);
        // Moving the step's voxels back costs nothing: show_step swaps vectors.
        let _ = series.show_step(shown);
        // A step that cannot be uploaded now (memory for two volumes) is uploaded when it is due instead, where
        // a failure is reported.
        self.ahead = prepared.ok().map(|p| (next, p));
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
            vsync: self.state.vsync,
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
            || self.state.auto_rotate
            || self.state.animation.is_some()
            || self.script.is_some()
            || self.refine_pending
            || self.state.time.playing
    }

    fn apply(&mut self, actions: Vec<UiAction>) {
        for action in actions {
            match action {
                UiAction::LoadFile(path, opts) => self.start_load(VolumeSource::File(path, opts)),
                UiAction::LoadBuiltin(name) => self.start_load(VolumeSource::Builtin(name, None)),
                UiAction::Screenshot => {
                    let stamp = std::time::SystemTime::now()
                        .duration_since(std::time::UNIX_EPOCH)
                        .map(|d| d.as_secs())
                        .unwrap_or(0);
                    self.pending_screenshot = Some(PathBuf::from(format!("volcast-{stamp}.png")));
                }
                UiAction::VsyncChanged => self.recreate_swapchain = true,
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

    /// Prints the frame times of scripted drags (the first frame of each drag includes the switch of detail).
    fn report_drag(&mut self) {
        if self.drag_frames.len() < 3 {
            return;
        }
        let mut t: Vec<f64> = self.drag_frames.drain(..).skip(2).collect();
        t.sort_by(|a, b| a.total_cmp(b));
        let median = t[t.len() / 2];
        eprintln!(
            "drag: median frame {median:.1} ms ({:.1} fps) over {} frames, level of detail {}",
            1e3 / median,
            t.len(),
            if self.state.lod { "on" } else { "off" }
        );
    }

    fn start_load(&mut self, source: VolumeSource) {
        if self.loading.is_some() {
            self.state.status = Some("a volume is already loading".into());
            return;
        }
        self.state.error = None;
        self.loading = Some(load_in_background(
            source,
            self.gpu.properties.limits.max_image_dimension3_d,
        ));
    }

    /// Takes a finished background load, keeping the old volume on error.
    fn poll_loading(&mut self) -> Result<(), ViewerError> {
        let Some(loading) = &self.loading else { return Ok(()) };
        match loading.rx.try_recv() {
            Ok(Ok((volume, histogram))) => {
                let label = loading.label.clone();
                let source = loading.source.clone();
                self.loading = None;
                self.state.loading = None;
                // Logged too: a load from the panel or a drop has no other trace outside the window.
                if let Err(e) = self.install_volume(volume, histogram) {
                    eprintln!("could not show {label}: {e}");
                    self.state.error = Some(format!("{label}: {e}"));
                    if self.initial_load.take().is_some() {
                        return Err(e.into());
                    }
                } else {
                    eprintln!("loaded {label}");
                    self.state.status = Some(format!("loaded {label}"));
                    self.shown_source = Some(source);
                    if let Some(time) = self.initial_load.take() {
                        self.apply_time(time)?;
                    }
                }
            }
            Ok(Err(e)) => {
                if self.initial_load.take().is_some() {
                    // The command line's volume: nothing else to show, so the session ends with its error.
                    return Err(ViewerError::Other(e));
                }
                eprintln!("could not load {}: {e}", loading.label);
                self.state.error = Some(format!("{}: {e}", loading.label));
                self.loading = None;
                self.state.loading = None;
            }
            Err(TryRecvError::Empty) => {
                let p = f32::from_bits(loading.progress.load(Ordering::Relaxed));
                self.state.loading = Some((loading.label.clone(), p));
            }
            Err(TryRecvError::Disconnected) => {
                self.state.error = Some(format!("{}: the loader stopped unexpectedly", loading.label));
                self.loading = None;
                self.state.loading = None;
            }
        }
        Ok(())
    }

    /// Advances the script after a frame; returns Exit when it ends the session.
    fn step_script(&mut self) -> Result<Flow, ViewerError> {
        let Some(script) = &mut self.script else {
            return Ok(Flow::Continue);
        };
        if script.started.elapsed() > Duration::from_secs(300) {
            return Err(ViewerError::Other(format!(
                "script timed out with steps left: {:?}",
                script.steps
            )));
        }
        if script.frames_left > 0 {
            script.frames_left -= 1;
            return Ok(Flow::Continue);
        }
        if script.wait_until.is_some_and(|t| Instant::now() < t) {
            return Ok(Flow::Continue);
        }
        script.wait_until = None;
        if script.drag_left > 0 {
            script.drag_left -= 1;
            self.state.orbit.turn(0.03);
            return Ok(Flow::Continue);
        }
        if let Some((w, h, tries)) = script.waiting_for_size {
            let size = self.window.inner_size();
            if (size.width, size.height) == (w, h) {
                script.waiting_for_size = None;
            } else if tries == 0 {
                return Err(ViewerError::Other(format!(
                    "window did not resize to {w}x{h} (it is {size:?})"
                )));
            } else {
                script.waiting_for_size = Some((w, h, tries - 1));
                return Ok(Flow::Continue);
            }
        }
        if script.waiting_for_load {
            if self.loading.is_some() {
                return Ok(Flow::Continue);
            }
            script.waiting_for_load = false;
            match &self.state.error {
                Some(e) => eprintln!("script: load failed: {e}"),
                None => eprintln!("script: loaded {}", self.state.volume_label),
            }
        }
        let Some(step) = script.steps.pop_front() else {
            self.report_drag();
            return Ok(Flow::Exit);
        };
        eprintln!("script: {step:?}");
        match step {
            ScriptStep::Frames(n) => script.frames_left = n,
            ScriptStep::Wait(d) => script.wait_until = Some(Instant::now() + d),
            ScriptStep::Drag(n) => script.drag_left = n,
            ScriptStep::Dialog => self.apply(vec![UiAction::OpenDialog]),
            ScriptStep::Drop(path) => {
                script.waiting_for_load = true;
                let action = self.state.load_action(path);
                self.apply(vec![action]);
            }
            ScriptStep::Lod(on) => {
                self.report_drag();
                self.state.lod = on;
            }
            ScriptStep::Resize(w, h) => {
                let _ = self.window.request_inner_size(winit::dpi::PhysicalSize::new(w, h));
                script.waiting_for_size = Some((w, h, 200));
            }
            ScriptStep::Minimize => self.window.set_minimized(true),
            ScriptStep::Restore => {
                self.window.set_minimized(false);
                self.zero_size = false;
            }
            ScriptStep::ZeroSize => self.zero_size = true,
            ScriptStep::Key(k) => {
                let key = match k.as_str() {
                    "r" => egui::Key::R,
                    "space" => egui::Key::Space,
                    "tab" => egui::Key::Tab,
                    "f12" => egui::Key::F12,
                    _ => return Err(ViewerError::Other(format!("script: unknown key {k}"))),
                };
                self.egui_ctx.input_mut(|i| {
                    i.events.push(egui::Event::Key {
                        key,
                        physical_key: None,
                        pressed: true,
                        repeat: false,
                        modifiers: Default::default(),
                    });
                    i.keys_down.insert(key);
                });
                let actions = ui::shortcuts(&self.egui_ctx, &mut self.state);
                self.egui_ctx.input_mut(|i| {
                    i.keys_down.remove(&key);
                    i.events.clear();
                });
                self.apply(actions);
            }
            ScriptStep::Screenshot(path) => self.pending_screenshot = Some(path),
            ScriptStep::Exit => {
                self.report_drag();
                return Ok(Flow::Exit);
            }
        }
        Ok(Flow::Continue)
    }

    fn redraw(&mut self) -> Result<Flow, ViewerError> {
        let now = Instant::now();
        let frame_s = now.duration_since(self.last_frame).as_secs_f64();
        // Animation steps are capped (a slow frame must not throw the view); the frame time shown is not.
        let dt = (frame_s as f32).min(0.1);
        self.last_frame = now;
        // The interval since the last frame is the frame time while frames follow each other; after an idle
        // pause it is the pause, so the last frame's GPU time stands in.
        let follows = self.wants_continuous_redraw() || self.refine_pending;
        self.poll_loading()?;
        if let Some(rx) = &self.dialog {
            match rx.try_recv() {
                Ok(Some(path)) => {
                    self.dialog = None;
                    let action = self.state.load_action(path);
                    self.apply(vec![action]);
                }
                Ok(None) | Err(TryRecvError::Disconnected) => {
                    self.dialog = None;
                    self.state.status = Some("no file chosen (or no file dialog here: type a path)".into());
                }
                Err(TryRecvError::Empty) => {}
            }
        }
        self.state.animate(dt);
        self.state.time.advance(dt);

        let size = self.window.inner_size();
        if self.zero_size || size.width == 0 || size.height == 0 || self.window.is_minimized() == Some(true) {
            // Minimised: nothing to draw into. Keep the event loop (and a running script) going.
            return self.step_script();
        }

        // The UI runs first: it may change what this frame shows.
        let mut raw_input = self.egui_state.take_egui_input(&self.window);
        // Tab belongs to the panel, not to egui's focus traversal: egui would move the focus into a text field,
        // which then swallowed every shortcut (Tab included) once the panel was hidden.
        let tabs = ui::take_tab_presses(&mut raw_input);
        let state = &mut self.state;
        let mut actions = Vec::new();
        let full = self.egui_ctx.run_ui(raw_input, |ui| {
            if tabs % 2 == 1 {
                state.panel_visible = !state.panel_visible;
            }
            if !state.panel_visible {
                // Nothing hidden may keep the keyboard.
                ui.ctx().memory_mut(|m| m.stop_text_input());
            }
            actions.extend(ui::shortcuts(ui.ctx(), state));
            if state.panel_visible {
                egui::Panel::left("settings")
                    .resizable(false)
                    .default_size(270.0)
                    .show(ui, |ui| {
                        egui::ScrollArea::vertical().show(ui, |ui| actions.extend(ui::settings_panel(ui, state)));
                    });
            }
            egui::CentralPanel::no_frame().show(ui, |ui| ui::view_overlay(ui, state));
        });
        self.apply(actions);
        self.show_wanted_step()?;
        // FullOutput implements Drop, so its parts are taken rather than moved out.
        let mut full = full;
        let platform_output = std::mem::take(&mut full.platform_output);
        let textures_delta = std::mem::take(&mut full.textures_delta);
        let shapes = std::mem::take(&mut full.shapes);
        let pixels_per_point = full.pixels_per_point;
        let viewport_output = std::mem::take(&mut full.viewport_output);
        self.egui_state.handle_platform_output(&self.window, platform_output);
        self.repaint_at = viewport_output
            .get(&egui::ViewportId::ROOT)
            .filter(|v| v.repaint_delay < Duration::from_secs(3600))
            .map(|v| now + v.repaint_delay);
        let primitives = self.egui_ctx.tessellate(shapes, pixels_per_point);

        if self.recreate_swapchain
            || self
                .swapchain
                .as_ref()
                .is_some_and(|s| (s.extent.width, s.extent.height) != (size.width, size.height))
        {
            self.recreate_swapchain()?;
        }
        let extent = self.swapchain.as_ref().ok_or(GpuError::Lost("swapchain"))?.extent;
        let (view_offset, view_size) = view_pixels(self.state.view_rect, pixels_per_point, extent);
        // Interacting, animating or auto-rotating: a cheaper frame; once still, one at full quality.
        let dragging = self.script.as_ref().is_some_and(|s| s.drag_left > 0);
        if dragging {
            self.drag_frames.push(frame_s * 1e3);
        }
        let moving = (self.state.interacting || self.state.animation.is_some() || self.state.auto_rotate || dragging)
            && self.pending_screenshot.is_none();
        let settings = self.state.frame_settings(view_size.width, view_size.height, moving);
        self.refine_pending = moving && self.state.lod;
        self.prepare(&settings)?;

        let slot = self.frame_index % FRAMES_IN_FLIGHT;
        let sync = &self.frames[slot];
        // SAFETY: the fence belongs to this device; waiting makes the slot's resources reusable.
        unsafe { self.gpu.device.wait_for_fences(&[sync.fence], true, u64::MAX) }.ctx("vkWaitForFences")?;
        let renderer = self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))?;
        if self.frame_index >= FRAMES_IN_FLIGHT {
            self.state.gpu = renderer.timings(&self.gpu, slot)?;
            if !self.slot_reduced[slot] {
                self.state.full_frame_ms = self.state.gpu.map(|t| t.total_ms);
            }
        }
        self.slot_reduced[slot] = settings.width < view_size.width;
        self.state.frame_ms = frame_time_ms(frame_s, follows, self.state.gpu.map(|t| t.total_ms));

        let swapchain = self.swapchain.as_ref().ok_or(GpuError::Lost("swapchain"))?;
        // SAFETY: the semaphore is unsignalled (its last wait completed with the slot's fence).
        let acquired = unsafe {
            swapchain
                .loader
                .acquire_next_image(swapchain.raw, u64::MAX, sync.image_available, vk::Fence::null())
        };
        let image_index = match acquired {
            Ok((i, suboptimal)) => {
                self.recreate_swapchain |= suboptimal;
                i as usize
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.recreate_swapchain = true;
                self.window.request_redraw();
                return Ok(Flow::Continue);
            }
            Err(e) => return Err(GpuError::vk("vkAcquireNextImageKHR", e).into()),
        };

        let egui_renderer = self.egui_renderer.as_mut().ok_or(GpuError::Lost("egui renderer"))?;
        for (id, deltas) in &textures_delta.set {
            for delta in deltas {
                egui_renderer
                    .set_texture(self.gpu.queue, self.gpu.command_pool, *id, delta)
                    .map_err(|e| ViewerError::Other(format!("egui texture: {e}")))?;
            }
        }

        let view = self.view_image.as_ref().ok_or(GpuError::Lost("view image"))?;
        let dev = &self.gpu.device;
        let cb = sync.cb;
        // SAFETY: the slot's previous submission finished (fence waited), so its command buffer can be reset.
        unsafe {
            dev.reset_fences(&[sync.fence]).ctx("vkResetFences")?;
            dev.reset_command_buffer(cb, vk::CommandBufferResetFlags::empty())
                .ctx("vkResetCommandBuffer")?;
            dev.begin_command_buffer(
                cb,
                &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
            .ctx("vkBeginCommandBuffer")?;
        }
        renderer.record(
            &self.gpu,
            cb,
            slot,
            (view.raw, view.view),
            Access::TransferRead,
            &settings,
        )?;
        image_barrier(dev, cb, view.raw, Access::ColorAttachmentWrite, Access::TransferRead);
        let target = swapchain.images[image_index];
        image_barrier(dev, cb, target, Access::SwapchainAcquired, Access::TransferWrite);
        // Cleared first: the panel covers the rest, but not while it is hidden or being laid out.
        let black = vk::ClearColorValue {
            float32: [0.0, 0.0, 0.0, 1.0],
        };
        // SAFETY: the image is in TRANSFER_DST layout.
        unsafe {
            dev.cmd_clear_color_image(
                cb,
                target,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &black,
                &[crate::gpu::sync::COLOR_RANGE],
            )
        };
        crate::gpu::sync::memory_barrier(dev, cb, Access::TransferWrite, Access::TransferWrite);
        let corner = vk::Offset3D {
            x: settings.width as i32,
            y: settings.height as i32,
            z: 1,
        };
        let dst_corner = vk::Offset3D {
            x: view_offset.x + view_size.width as i32,
            y: view_offset.y + view_size.height as i32,
            z: 1,
        };
        let dst_origin = vk::Offset3D {
            x: view_offset.x,
            y: view_offset.y,
            z: 0,
        };
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let blit = vk::ImageBlit::default()
            .src_subresource(layers)
            .src_offsets([vk::Offset3D::default(), corner])
            .dst_subresource(layers)
            .dst_offsets([dst_origin, dst_corner]);
        // SAFETY: both images are in the layouts named and the regions lie inside them. At full detail the sizes
        // match and the blit only swizzles RGBA to BGRA; at reduced detail it also upscales (linear).
        unsafe {
            dev.cmd_blit_image(
                cb,
                view.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                target,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[blit],
                if settings.width == view_size.width {
                    vk::Filter::NEAREST
                } else {
                    vk::Filter::LINEAR
                },
            )
        };
        image_barrier(dev, cb, target, Access::TransferWrite, Access::ColorAttachmentWrite);
        let attachment = [vk::RenderingAttachmentInfo::default()
            .image_view(swapchain.views[image_index])
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let rendering = vk::RenderingInfo::default()
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent,
            })
            .layer_count(1)
            .color_attachments(&attachment);
        // SAFETY: the swapchain image is a colour attachment now.
        unsafe { dev.cmd_begin_rendering(cb, &rendering) };
        egui_renderer
            .cmd_draw(cb, extent, pixels_per_point, &primitives)
            .map_err(|e| ViewerError::Other(format!("egui draw: {e}")))?;
        // SAFETY: rendering was begun above.
        unsafe { dev.cmd_end_rendering(cb) };
        image_barrier(dev, cb, target, Access::ColorAttachmentWrite, Access::Present);
        let screenshot = match self.pending_screenshot.take() {
            Some(path) => {
                let buffer = Buffer::new(
                    &self.gpu,
                    view_size.width as u64 * view_size.height as u64 * 4,
                    vk::BufferUsageFlags::TRANSFER_DST,
                    gpu_allocator::MemoryLocation::GpuToCpu,
                    "screenshot",
                )?;
                record_readback(&self.gpu, cb, view, Access::TransferRead, &buffer);
                Some((path, buffer))
            }
            None => None,
        };
        // SAFETY: `cb` is recording.
        unsafe { dev.end_command_buffer(cb) }.ctx("vkEndCommandBuffer")?;

        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(sync.image_available)
            .stage_mask(vk::PipelineStageFlags2::TRANSFER)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(self.render_finished[image_index])
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cbs = [vk::CommandBufferSubmitInfo::default().command_buffer(cb)];
        let submit = [vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cbs)
            .signal_semaphore_infos(&signals)];
        // SAFETY: every resource the command buffer uses is alive until its fence signals.
        unsafe { dev.queue_submit2(self.gpu.queue, &submit, sync.fence) }.ctx("vkQueueSubmit2")?;
        let wait = [self.render_finished[image_index]];
        let chains = [swapchain.raw];
        let indices = [image_index as u32];
        let present = vk::PresentInfoKHR::default()
            .wait_semaphores(&wait)
            .swapchains(&chains)
            .image_indices(&indices);
        // SAFETY: the image was acquired and its rendering is submitted with this semaphore signalled.
        match unsafe { swapchain.loader.queue_present(self.gpu.queue, &present) } {
            Ok(suboptimal) => self.recreate_swapchain |= suboptimal,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.recreate_swapchain = true,
            Err(e) => return Err(GpuError::vk("vkQueuePresentKHR", e).into()),
        }
        self.frame_index += 1;
        self.upload_ahead()?;

        if let Some((path, buffer)) = screenshot {
            let saved = self.wait_idle().map_err(ViewerError::from).and_then(|_| {
                let step = self.series.as_ref().map(Volume::shown_step);
                let volume = volume_ref(self.shown_source.as_ref(), self.state.raw_spacing, step.unwrap_or(0));
                save_screenshot(&path, &buffer, &settings, volume, step)
            });
            buffer.destroy(&self.gpu);
            match saved {
                Ok(()) => self.state.status = Some(format!("saved {}", path.display())),
                Err(e) => self.state.error = Some(format!("screenshot: {e}")),
            }
        }
        if !textures_delta.free.is_empty() {
            self.wait_idle()?;
            let egui_renderer = self.egui_renderer.as_mut().ok_or(GpuError::Lost("egui renderer"))?;
            for id in &textures_delta.free {
                egui_renderer
                    .free_texture(*id)
                    .map_err(|e| ViewerError::Other(format!("egui: {e}")))?;
            }
        }
        self.step_script()
    }

    /// Creates what `settings` needs beyond the frame (position targets, colormap, the view image) after
    /// waiting for in-flight frames, only when something changed.
    fn prepare(&mut self, settings: &RenderSettings) -> Result<(), ViewerError> {
        let view_fits = self
            .view_image
            .as_ref()
            .is_some_and(|v| (v.desc.extent.width, v.desc.extent.height) == (settings.width, settings.height));
        // The gradient texture on the first frame that reads gradients (the volume was kept for it).
        if settings.gradient_texture && self.renderer.as_ref().is_some_and(|r| !r.has_gradient_texture()) {
            let volume = self
                .kept
                .as_ref()
                .ok_or(GpuError::Lost("no volume kept for gradients"))?;
            self.wait_idle()?;
            let renderer = self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))?;
            renderer.enable_gradient_texture(&self.gpu, volume)?;
        }
        let renderer = self.renderer.as_ref().ok_or(GpuError::Lost("renderer"))?;
        if view_fits && !renderer.needs_prepare(settings) {
            return Ok(());
        }
        self.wait_idle()?;
        if !view_fits {
            if let Some(old) = self.view_image.take() {
                old.destroy(&self.gpu);
            }
            let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
            self.view_image = Some(Image::new(
                &self.gpu,
                ImageDesc::d2(OUTPUT_FORMAT, settings.width, settings.height, usage),
                "view",
            )?);
        }
        let renderer = self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))?;
        renderer.prepare(&self.gpu, settings)?;
        Ok(())
    }

    fn destroy(mut self) {
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

/// The volume view's place in the swapchain image, in pixels: the central area egui left free (the whole
/// window before the first layout), clamped to the image.
fn view_pixels(rect: Option<egui::Rect>, pixels_per_point: f32, extent: vk::Extent2D) -> (vk::Offset2D, vk::Extent2D) {
    let (w, h) = (extent.width as f32, extent.height as f32);
    let r = rect
        .map(|r| {
            let ppp = pixels_per_point.max(0.1);
            egui::Rect::from_min_max(
                egui::pos2(
                    (r.min.x * ppp).round().clamp(0.0, w - 1.0),
                    (r.min.y * ppp).round().clamp(0.0, h - 1.0),
                ),
                egui::pos2(
                    (r.max.x * ppp).round().clamp(1.0, w),
                    (r.max.y * ppp).round().clamp(1.0, h),
                ),
            )
        })
        .unwrap_or(egui::Rect::from_min_max(egui::Pos2::ZERO, egui::pos2(w, h)));
    let width = (r.width() as u32).max(1);
    let height = (r.height() as u32).max(1);
    (
        vk::Offset2D {
            x: r.min.x as i32,
            y: r.min.y as i32,
        },
        vk::Extent2D { width, height },
    )
}

/// The view state's record of where the shown volume came from.
fn volume_ref(source: Option<&VolumeSource>, spacing: [f32; 3], time: u32) -> crate::view_state::VolumeRef {
    let mut r = crate::view_state::VolumeRef {
        spacing,
        time,
        ..Default::default()
    };
    match source {
        Some(VolumeSource::Builtin(name, size)) => (r.builtin, r.builtin_size) = (Some(name.clone()), *size),
        Some(VolumeSource::File(path, raw)) => {
            r.path = Some(std::fs::canonicalize(path).unwrap_or_else(|_| path.clone()));
            r.raw_dims = raw.dims;
            r.raw_type = raw.voxel_type.map(|t| t.name().to_string());
            r.raw_spacing = raw.spacing;
        }
        None => {}
    }
    r
}

/// The frame time shown: the interval since the last frame when it followed directly (never capped: a 256 ms
/// frame shows 256), else the frame's GPU time (the interval would be the idle pause before it).
fn frame_time_ms(interval_s: f64, follows: bool, gpu_ms: Option<f64>) -> f64 {
    match (follows, gpu_ms) {
        (false, Some(gpu)) => gpu,
        _ => interval_s * 1e3,
    }
}

/// Writes the view image's pixels (RGBA8, exactly what the view shows without the panel) and the settings; a
/// series' shown step is logged after the file name.
fn save_screenshot(
    path: &std::path::Path,
    buffer: &Buffer,
    settings: &RenderSettings,
    volume: crate::view_state::VolumeRef,
    step: Option<u32>,
) -> Result<(), ViewerError> {
    let pixels = buffer
        .mapped()
        .ok_or(GpuError::Lost("screenshot buffer is not mapped"))?
        .to_vec();
    let img = image::RgbaImage::from_raw(settings.width, settings.height, pixels)
        .ok_or_else(|| ViewerError::Other("screenshot size mismatch".into()))?;
    crate::image_out::save(&img, path).map_err(ViewerError::Other)?;
    // The view state: the settings (still readable as plain `RenderSettings`) and the volume's origin, so that
    // `volcast render --state` renders this view again.
    let json = crate::view_state::ViewState {
        volume,
        settings: settings.clone(),
    }
    .to_json();
    std::fs::write(path.with_extension("json"), json)
        .map_err(|e| ViewerError::Other(format!("writing {}: {e}", path.with_extension("json").display())))?;
    match step {
        Some(t) => eprintln!("saved screenshot {} (time step {t})", path.display()),
        None => eprintln!("saved screenshot {}", path.display()),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frame_time_is_not_capped_and_ignores_idle_pauses() {
        // A 256 ms frame following another shows 256 ms (it was capped at 100).
        assert_eq!(frame_time_ms(0.256, true, Some(250.0)), 256.0);
        // After a 7 s idle pause the GPU time stands in.
        assert_eq!(frame_time_ms(7.0, false, Some(250.0)), 250.0);
        assert_eq!(frame_time_ms(0.03, false, None), 30.0);
    }

    #[test]
    fn scripts_parse_and_reject_nonsense() {
        let steps =
            parse_script("frames:3; resize:320x240;minimize;restore;zero-size;key:Tab;screenshot:/tmp/a.png;exit")
                .expect("valid");
        assert_eq!(
            steps,
            vec![
                ScriptStep::Frames(3),
                ScriptStep::Resize(320, 240),
                ScriptStep::Minimize,
                ScriptStep::Restore,
                ScriptStep::ZeroSize,
                ScriptStep::Key("tab".into()),
                ScriptStep::Screenshot(PathBuf::from("/tmp/a.png")),
                ScriptStep::Exit
            ]
        );
        assert_eq!(
            parse_script("drag:5;lod:off;wait:1500").unwrap(),
            vec![
                ScriptStep::Drag(5),
                ScriptStep::Lod(false),
                ScriptStep::Wait(Duration::from_millis(1500))
            ]
        );
        for bad in [
            "frames:x",
            "resize:10",
            "dance",
            "screenshot:",
            "lod:maybe",
            "drag:",
            "wait:",
            "wait:-1",
            "wait:2s",
        ] {
            assert!(parse_script(bad).is_err(), "{bad}");
        }
    }
}
