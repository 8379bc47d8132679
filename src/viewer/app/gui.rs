//! egui in the window: its context and winit glue, the window's input prepared for it (`input`), one frame's UI
//! pass over the model (`widgets::layout::frame_ui`) and what it painted, tessellated for the presenter.

use super::clock::FrameClock;
use super::input::{drag_cut, take_tab_presses};
use crate::viewer::model::actions::UiAction;
use crate::viewer::model::slices::SliceData;
use crate::viewer::model::Model;
use crate::viewer::present::EguiFrame;
use crate::viewer::widgets::keys;
use crate::viewer::widgets::layout::frame_ui;
use crate::viewer::widgets::rects;
use crate::viewer::widgets::slice_view::SliceImages;
use std::time::{Duration, Instant};
use winit::event::WindowEvent;
use winit::window::Window;

pub(super) struct Gui {
    ctx: egui::Context,
    winit: egui_winit::State,
    /// Input held back for the next frame so that a quick drag is seen as one (`drag_cut`).
    deferred: Vec<egui::Event>,
    /// The time egui gives each frame: when its input arrived.
    clock: FrameClock,
}

/// What one UI pass produced.
pub(super) struct GuiPass {
    /// What the widgets asked of the app.
    pub(super) actions: Vec<UiAction>,
    /// What to draw over the view.
    pub(super) painted: EguiFrame,
    /// When egui wants to be drawn again without input (`None`: only on input).
    pub(super) repaint_delay: Option<Duration>,
}

impl Gui {
    pub(super) fn new(window: &Window, max_texture_side: usize) -> Gui {
        let ctx = egui::Context::default();
        let winit = egui_winit::State::new(
            ctx.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_texture_side),
        );
        Gui {
            ctx,
            winit,
            deferred: Vec::new(),
            clock: FrameClock::new(Instant::now()),
        }
    }

    /// Hands a window event to egui; true when egui wants a new frame for it.
    pub(super) fn on_window_event(&mut self, window: &Window, event: &WindowEvent) -> bool {
        let input = matches!(
            event,
            WindowEvent::CursorMoved { .. }
                | WindowEvent::MouseInput { .. }
                | WindowEvent::MouseWheel { .. }
                | WindowEvent::KeyboardInput { .. }
                | WindowEvent::Touch(_)
        );
        if input {
            self.clock.input(Instant::now());
        }
        self.winit.on_window_event(window, event).repaint
    }

    /// The frame is drawn: input from now on waited for it only if it comes soon ([`super::clock::QUEUED`]).
    pub(super) fn drawn(&mut self) {
        self.clock.drawn(Instant::now());
    }

    /// Input is waiting for the next frame.
    pub(super) fn holds_input(&self) -> bool {
        !self.deferred.is_empty()
    }

    /// One frame's UI over `model`: the window's input since the last frame (less what a drag needs a new frame
    /// for), the widgets, and what they painted. `data` and `images` are the slice views'.
    pub(super) fn run(
        &mut self,
        window: &Window,
        model: &mut Model,
        data: SliceData,
        images: &mut SliceImages<'_>,
    ) -> GuiPass {
        let mut raw_input = self.winit.take_egui_input(window);
        raw_input.time = Some(self.clock.frame_time(Instant::now()));
        // Events a slow frame held back for a drag come first; again some may wait.
        raw_input.events.splice(0..0, std::mem::take(&mut self.deferred));
        let held = self
            .ctx
            .input(|i| i.pointer.press_origin().filter(|_| i.pointer.any_down()));
        let click_dist = self.ctx.options(|o| o.input_options.max_click_dist);
        if let Some(cut) = drag_cut(&raw_input.events, held, click_dist) {
            self.deferred = raw_input.events.split_off(cut);
        }
        // Tab belongs to the panel, not to egui's focus traversal: egui would move the focus into a text field,
        // which then swallowed every shortcut (Tab included) once the panel was hidden.
        let tabs = take_tab_presses(&mut raw_input);
        let mut actions = Vec::new();
        let mut full = self.ctx.run_ui(raw_input, |ui| {
            actions = frame_ui(ui, model, tabs, data, images);
        });
        // FullOutput implements Drop, so its parts are taken rather than moved out.
        let platform_output = std::mem::take(&mut full.platform_output);
        let textures = std::mem::take(&mut full.textures_delta);
        let shapes = std::mem::take(&mut full.shapes);
        let pixels_per_point = full.pixels_per_point;
        let viewport_output = std::mem::take(&mut full.viewport_output);
        self.winit.handle_platform_output(window, platform_output);
        let repaint_delay = viewport_output.get(&egui::ViewportId::ROOT).map(|v| v.repaint_delay);
        rects::end_frame(repaint_delay.is_none_or(|d| d > rects::STILL));
        let primitives = self.ctx.tessellate(shapes, pixels_per_point);
        GuiPass {
            actions,
            painted: EguiFrame {
                primitives,
                textures,
                pixels_per_point,
            },
            repaint_delay,
        }
    }

    /// A key press outside the window system (a script's): through the shortcuts, as if typed.
    pub(super) fn press_key(&mut self, key: egui::Key, model: &mut Model) -> Vec<UiAction> {
        self.ctx.input_mut(|i| {
            i.events.push(egui::Event::Key {
                key,
                physical_key: None,
                pressed: true,
                repeat: false,
                modifiers: Default::default(),
            });
            i.keys_down.insert(key);
        });
        let actions = keys::shortcuts(&self.ctx, model);
        self.ctx.input_mut(|i| {
            i.keys_down.remove(&key);
            i.events.clear();
        });
        actions
    }
}
