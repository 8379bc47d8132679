//! The viewer application: the winit event loop's glue ([`App`]) around the running viewer
//! ([`running::Running`]), which ties the model, the widgets (through egui, [`gui`]) and the presenter together
//! and keeps what is neither: loads ([`loading`], [`volumes`]), sessions, captures ([`capture`]), the script
//! ([`script`]) and the pacing of frames ([`pacing`]). A frame's steps are in [`frame`].

mod actions;
mod capture;
mod clock;
mod figure;
mod file_names;
mod frame;
mod gui;
pub mod input;
mod layers;
mod loading;
mod pacing;
mod recording;
mod running;
pub mod script;
mod session;
mod title;
mod volumes;

use crate::gpu::ValidationLog;
use crate::viewer::{ViewerError, ViewerOptions};
use pacing::Wake;
use running::Running;
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::window::WindowId;

/// Runs the event loop until the window closes. Returns the validation log for the caller to report.
pub(super) fn run(event_loop: &mut EventLoop<()>, opts: ViewerOptions) -> Result<Arc<ValidationLog>, ViewerError> {
    use winit::platform::run_on_demand::EventLoopExtRunOnDemand;
    let mut app = App {
        waker: event_loop.create_proxy(),
        opts,
        running: None,
        error: None,
        log: None,
    };
    event_loop
        .run_app_on_demand(&mut app)
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

/// What a frame tells the event loop.
enum Flow {
    Continue,
    Exit,
}

struct App {
    opts: ViewerOptions,
    /// For a script's `hold`, whose end arrives on another thread.
    waker: EventLoopProxy<()>,
    running: Option<Running>,
    error: Option<ViewerError>,
    log: Option<Arc<ValidationLog>>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_some() {
            return;
        }
        let layers = std::mem::take(&mut self.opts.layers);
        match Running::new(event_loop, &self.opts, layers, self.waker.clone()) {
            Ok(r) => {
                self.log = Some(r.presenter.validation_log());
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
        let repaint = r.gui.on_window_event(&r.window, &event);
        // egui-winit asks for a repaint on every RedrawRequested; honouring that redrew forever, a full frame
        // after a full frame with nothing changed (a core busy while nobody touched the viewer).
        let repaint = repaint && !matches!(event, WindowEvent::RedrawRequested);
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(_) => r.window.request_redraw(),
            WindowEvent::DroppedFile(path) => {
                r.drop_file(path);
                r.window.request_redraw();
            }
            WindowEvent::RedrawRequested => match r.redraw() {
                Ok(Flow::Continue) => r.pacing.drawn(std::time::Instant::now()),
                Ok(Flow::Exit) => event_loop.exit(),
                Err(e) => {
                    self.error = Some(e);
                    event_loop.exit();
                }
            },
            _ => {}
        }
        if repaint {
            r.window.request_redraw();
        }
    }

    /// Only a script's `hold` sends events: it has ended, and the next frame takes the script's next step.
    fn user_event(&mut self, _event_loop: &ActiveEventLoop, _event: ()) {
        if let Some(r) = &self.running {
            r.window.request_redraw();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(r) = &mut self.running else { return };
        let activity = r.activity();
        if let Some(at) = r.script.as_ref().and_then(|s| s.waiting_until()) {
            r.pacing.wake_by(at);
        }
        match r.pacing.wake(activity, Instant::now()) {
            Wake::Continuous => {
                r.window.request_redraw();
                event_loop.set_control_flow(ControlFlow::Poll);
            }
            Wake::At { at, due } => {
                event_loop.set_control_flow(ControlFlow::WaitUntil(at));
                if due {
                    r.window.request_redraw();
                }
            }
            Wake::Sleep => event_loop.set_control_flow(ControlFlow::Wait),
        }
    }
}
