//! One frame, as its steps: poll (loads, the dialog, animations, playback), the UI pass, the frame's settings
//! (size, level of detail, what must exist first), the presenter's record → blit → present, then what follows a
//! presented frame (the next step uploaded ahead, captures, freed textures) and the script.

use super::capture;
use super::gui::GuiPass;
use super::pacing::{frame_time_ms, Tick};
use super::running::Running;
use super::script::{Command, Next, Seen};
use super::Flow;
use crate::scene::settings::RenderSettings;
use crate::viewer::model::actions::UiAction;
use crate::viewer::model::slices::{SliceData, SliceSource};
use crate::viewer::present::{view_pixels, Drawn, Frame, Readback};
use crate::viewer::ViewerError;
use ash::vk;

/// What a frame renders, and where it goes in the window.
struct Planned {
    settings: RenderSettings,
    view_offset: vk::Offset2D,
    view_size: vk::Extent2D,
}

impl Running {
    pub(super) fn redraw(&mut self) -> Result<Flow, ViewerError> {
        let tick = self.pacing.tick(self.activity().continuous());
        self.poll(&tick)?;
        if self.window_hidden() {
            // Nothing to draw into. Keep the event loop (and a running script) going.
            return self.step_script();
        }
        let ui = self.ui(&tick)?;
        let planned = self.settings(&ui, &tick)?;
        let drawn = self.present(&planned, &ui)?;
        self.gui.drawn();
        let readback = match drawn {
            Drawn::Presented { readback, marched } => {
                self.model.stats.drawn += 1;
                self.model.stats.marched += u64::from(marched);
                readback
            }
            Drawn::OutOfDate => {
                self.window.request_redraw();
                return Ok(Flow::Continue);
            }
        };
        self.after_present(readback, &planned, &tick)?;
        self.presenter.free_textures(&ui.painted.textures)?;
        self.step_script()
    }

    /// What happened since the last frame: a load finished (or progressed), the file dialog answered, animations
    /// advanced by the tick's capped step, playback by the real time passed (its rate is measured on it).
    fn poll(&mut self, tick: &Tick) -> Result<(), ViewerError> {
        if let Some(arrived) = self.loader.poll(&mut self.model) {
            self.install_arrived(arrived)?;
        }
        if let Some(path) = self.loader.poll_dialog(&mut self.model) {
            self.drop_file(path);
        }
        self.model.animate(tick.dt);
        // Paused since the last frame: say the rate playback reached (advance forgets it).
        if let (false, Some(r)) = (self.model.time.playing, self.model.time.reached) {
            eprintln!(
                "playback: paused; reached {r:.1} steps/s of the {:.1} asked",
                self.model.time.fps
            );
        }
        self.model.time.advance(tick.interval_s as f32);
        Ok(())
    }

    /// Minimised, or 0×0: there is nothing to draw into.
    fn window_hidden(&self) -> bool {
        let size = self.window.inner_size();
        self.script.as_ref().is_some_and(|s| s.zero_size)
            || size.width == 0
            || size.height == 0
            || self.window.is_minimized() == Some(true)
    }

    /// The UI pass (it may change what this frame shows), then what it asked for.
    fn ui(&mut self, tick: &Tick) -> Result<GuiPass, ViewerError> {
        let textures = &mut self.presenter.slice_textures;
        let mut images =
            |ctx: &egui::Context, image: &_, source: Option<SliceSource<'_>>| textures.texture(ctx, image, source);
        let data = SliceData {
            volume: self.shown.for_slices(),
            layers: &self.shown.layers,
        };
        let mut pass = self.gui.run(&self.window, &mut self.model, data, &mut images);
        self.pacing.repaint_after(tick.now, pass.repaint_delay);
        self.apply(std::mem::take(&mut pass.actions));
        self.shown.show_wanted_step(&mut self.presenter, &mut self.model)?;
        Ok(pass)
    }

    /// The frame's settings: the view's place in the (resized) window, and — while the view moves and no capture
    /// wants this frame — reduced detail; a session asked for is saved with them, and what they need is made.
    fn settings(&mut self, ui: &GuiPass, tick: &Tick) -> Result<Planned, ViewerError> {
        let size = self.window.inner_size();
        let extent = self
            .presenter
            .fit_window(size.width, size.height, self.model.display.vsync)?;
        let view = self.model.interaction.view_rect;
        let (view_offset, view_size) = view_pixels(view, ui.painted.pixels_per_point, extent);
        let dragging = match self.script.as_mut() {
            Some(script) if script.dragging() => {
                script.drag_frame(tick.interval_s * 1e3);
                true
            }
            _ => false,
        };
        // Interacting, animating or auto-rotating: a cheaper frame; once still, one at full quality. Screenshots
        // and recorded frames are full frames.
        // Playback too: each step is seen once, so a reduced frame per step plays at several times the rate.
        let moving =
            (self.model.interaction.interacting || self.model.camera_moving() || dragging || self.model.time.playing)
                && !self.capture.wants_pixels();
        let settings = self.model.frame_settings(view_size.width, view_size.height, moving);
        self.pacing.refine_pending = moving && self.model.sampling.lod;
        if let Some(path) = self.capture.take_session() {
            // The session holds the still frame's settings, whether or not this frame is a reduced one.
            let still = self.model.render_settings(view_size.width, view_size.height);
            capture::save_session(&path, &self.view_state(&still), &mut self.model.messages);
        }
        self.refine(view_size, moving)?;
        self.presenter.prepare(&settings, self.shown.kept())?;
        let reduced = settings.width < view_size.width;
        // A slot whose frame showed the view unchanged measured nothing: the last march's times stand.
        if let Some(slot) = self.presenter.begin_frame(reduced)?.filter(|s| s.gpu.is_some()) {
            let stats = &mut self.model.stats;
            stats.gpu = slot.gpu;
            if !slot.was_reduced {
                stats.full_frame_ms = stats.gpu.map(|t| t.total_ms);
            }
        }
        let gpu_ms = self.model.stats.gpu.map(|t| t.total_ms);
        self.model.stats.frame_ms = frame_time_ms(tick.interval_s, tick.follows, gpu_ms);
        Ok(Planned {
            settings,
            view_offset,
            view_size,
        })
    }

    /// A streamed volume takes a step towards the levels the still view wants (one coarser while `moving`), at
    /// most one bounded upload a frame; reaching them while still is said on stderr.
    fn refine(&mut self, view_size: vk::Extent2D, moving: bool) -> Result<(), ViewerError> {
        if self.model.streaming.is_none() {
            return Ok(());
        }
        let still = self.model.render_settings(view_size.width, view_size.height);
        let Some((progress, reached_now)) = self.presenter.refine(&still, moving, self.shown.kept())? else {
            return Ok(());
        };
        if reached_now && !moving {
            eprintln!(
                "refined: every brick at its level after {} step(s): {} of the level-0 bricks",
                progress.steps,
                progress.levels_shown()
            );
        }
        if let Some(streaming) = &mut self.model.streaming {
            streaming.progress = Some(progress);
        }
        Ok(())
    }

    /// Records the march, blits it into the window with egui over it, and presents (reading the view back when a
    /// capture wants it).
    fn present(&mut self, planned: &Planned, ui: &GuiPass) -> Result<Drawn, ViewerError> {
        self.presenter.draw(&Frame {
            settings: &planned.settings,
            view_offset: planned.view_offset,
            view_size: planned.view_size,
            egui: &ui.painted,
            readback: self.capture.wants(),
        })
    }

    /// After a presented frame: the next step of a playing series uploaded while the GPU draws, then the frame's
    /// pixels to the screenshot and the recording that asked for them.
    fn after_present(
        &mut self,
        readback: Option<Box<Readback>>,
        planned: &Planned,
        tick: &Tick,
    ) -> Result<(), ViewerError> {
        self.shown.upload_ahead(&mut self.presenter, &self.model)?;
        let Some(readback) = readback else { return Ok(()) };
        let pixels = self.presenter.pixels(*readback);
        // F12 is rare and takes a copy; the recording takes the pixels.
        for shot in self.capture.take_screenshots() {
            let state = self.view_state(&planned.settings);
            let step = self.shown.series_step();
            let kind = if shot.as_shown { &pixels.shown } else { &pixels.clean };
            let shot_pixels = kind
                .clone()
                .unwrap_or_else(|| Err("the frame was not read back".into()));
            capture::screenshot(&shot.path, shot_pixels, &state, step, &mut self.model.messages);
        }
        let size = (planned.view_size.width, planned.view_size.height);
        self.capture.record(pixels, size, tick.now, &mut self.model.messages);
        Ok(())
    }

    /// Advances the script after a frame; returns Exit when it ends the session.
    pub(super) fn step_script(&mut self) -> Result<Flow, ViewerError> {
        let Some(script) = &mut self.script else {
            return Ok(Flow::Continue);
        };
        let seen = Seen {
            window_size: self.window.inner_size(),
            loading: self.loader.busy(),
        };
        match script.advance(&mut self.model, seen)? {
            Next::Continue => {}
            Next::Exit => return Ok(Flow::Exit),
            Next::Run(command) => self.run_command(command),
        }
        Ok(Flow::Continue)
    }

    /// Carries out a script's step that needs the window or the app.
    fn run_command(&mut self, command: Command) {
        match command {
            Command::Dialog => self.apply(vec![UiAction::OpenDialog]),
            Command::Drop(path) => self.drop_file(path),
            Command::Resize(w, h) => {
                let _ = self.window.request_inner_size(winit::dpi::PhysicalSize::new(w, h));
            }
            Command::Minimize => self.window.set_minimized(true),
            Command::Restore => self.window.set_minimized(false),
            Command::Key(key) => {
                let actions = self.gui.press_key(key, &mut self.model);
                self.apply(actions);
            }
            Command::Screenshot(path) => self.capture.request_screenshot(path, false),
        }
    }
}
