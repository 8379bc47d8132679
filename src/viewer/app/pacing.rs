//! When the viewer draws. The one place that decides whether another frame is needed without new input
//! ([`Activity`]): a load or a file dialog under way, the camera moving by itself, a series playing, a script
//! running, a reduced-detail frame to refine, input held back for the next frame. Besides these, input that egui
//! says changed something, a resize and a dropped file each ask for one frame, and egui may ask for one later
//! (a tooltip's delay).
//!
//! Without activity the viewer sleeps until input, egui's wish or a script's wait ending: an untouched viewer
//! costs no CPU. While only a load is under way it draws at the pace of [`LOADING_INTERVAL`], whatever egui wishes
//! (and when the load delivers, or on input): the cores are the load's.

use std::time::{Duration, Instant};

/// While only a load is under way, a frame at most this often after the last one ended, and never sooner than twice
/// that frame's time: enough for its progress, and a frame of the preview shown meanwhile (the whole march, on
/// lavapipe's cores: 0.43 s at 900x600 on 2 idle cores, some 2 s beside a load) takes at most a third of the time
/// from the load. (A frame whose view has not changed does not march, `present::reuse`: a still preview's paced frames
/// cost the blit and egui; the pace bounds those that march, the preview's first and the volume's.)
pub(super) const LOADING_INTERVAL: Duration = Duration::from_millis(250);

/// Everything that asks for frames to follow each other.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Activity {
    pub(super) loading: bool,
    pub(super) dialog: bool,
    /// A fly-to or auto-rotation.
    pub(super) camera_moving: bool,
    pub(super) playing: bool,
    pub(super) script: bool,
    /// The last frame was a reduced-detail one: draw again at full quality once the view is still.
    pub(super) refining: bool,
    /// Input a slow frame held back for the next one (see `input::drag_cut`).
    pub(super) held_input: bool,
}

impl Activity {
    /// Whether frames follow each other as fast as they are drawn: any activity but a load alone.
    pub(super) fn continuous(&self) -> bool {
        Activity {
            loading: false,
            ..*self
        }
        .any()
    }

    pub(super) fn any(&self) -> bool {
        let Activity {
            loading,
            dialog,
            camera_moving,
            playing,
            script,
            refining,
            held_input,
        } = *self;
        loading || dialog || camera_moving || playing || script || refining || held_input
    }
}

/// What the event loop does once it has handled its events.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Wake {
    /// Draw now and keep polling.
    Continuous,
    /// Sleep until `at` (egui's repaint); `due`: it has come, draw now.
    At { at: Instant, due: bool },
    /// Sleep until an event comes.
    Sleep,
}

/// One frame's clock.
#[derive(Clone, Copy, Debug)]
pub(super) struct Tick {
    pub(super) now: Instant,
    /// Seconds since the last frame.
    pub(super) interval_s: f64,
    /// The animation step: the interval, capped (a slow frame must not throw the view).
    pub(super) dt: f32,
    /// Frames were following each other (so the interval is a frame time, not an idle pause).
    pub(super) follows: bool,
}

pub(super) struct Pacing {
    last_frame: Instant,
    /// When egui asked to be drawn again.
    repaint_at: Option<Instant>,
    /// The last frame was a reduced-detail one.
    pub(super) refine_pending: bool,
    /// When the last frame ended, and how long it took.
    frame_end: Instant,
    frame_took: Duration,
}

impl Pacing {
    pub(super) fn new() -> Pacing {
        Pacing {
            last_frame: Instant::now(),
            repaint_at: None,
            refine_pending: false,
            frame_end: Instant::now(),
            frame_took: Duration::ZERO,
        }
    }

    /// Starts a frame; `busy`: whether frames were following each other ([`Activity::continuous`]).
    pub(super) fn tick(&mut self, busy: bool) -> Tick {
        let now = Instant::now();
        let interval_s = now.duration_since(self.last_frame).as_secs_f64();
        self.last_frame = now;
        Tick {
            now,
            interval_s,
            dt: (interval_s as f32).min(0.1),
            follows: busy,
        }
    }

    /// Ends the frame started at the last [`tick`](Self::tick).
    pub(super) fn drawn(&mut self, now: Instant) {
        self.frame_took = now.saturating_duration_since(self.last_frame);
        self.frame_end = now;
    }

    /// egui's wish for the next frame after the one started at `now` (`None`: only on input).
    pub(super) fn repaint_after(&mut self, now: Instant, delay: Option<Duration>) {
        self.repaint_at = delay.filter(|d| *d < Duration::from_secs(3600)).map(|d| now + d);
    }

    /// Draws a frame at `at` at the latest (a script's wait ending), without drawing before it.
    pub(super) fn wake_by(&mut self, at: Instant) {
        self.repaint_at = Some(self.repaint_at.map_or(at, |r| r.min(at)));
    }

    /// What the event loop does next, given the viewer's `activity`.
    pub(super) fn wake(&mut self, activity: Activity, now: Instant) -> Wake {
        if activity.continuous() {
            return Wake::Continuous;
        }
        if activity.loading {
            // egui's wishes too (a progress bar asks for every frame): the paced frame meets them.
            let at = self.frame_end + LOADING_INTERVAL.max(2 * self.frame_took);
            self.repaint_at = None;
            return Wake::At { at, due: now >= at };
        }
        let Some(at) = self.repaint_at else {
            return Wake::Sleep;
        };
        let due = now >= at;
        if due {
            self.repaint_at = None;
        }
        Wake::At { at, due }
    }
}

/// The frame time shown: the interval since the last frame when it followed directly (never capped: a 256 ms
/// frame shows 256), else the frame's GPU time (the interval would be the idle pause before it).
pub(super) fn frame_time_ms(interval_s: f64, follows: bool, gpu_ms: Option<f64>) -> f64 {
    match (follows, gpu_ms) {
        (false, Some(gpu)) => gpu,
        _ => interval_s * 1e3,
    }
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
    fn activity_polls_and_quiet_waits_for_egui_or_input() {
        let mut pacing = Pacing::new();
        let now = Instant::now();
        let playing = Activity {
            playing: true,
            ..Activity::default()
        };
        assert_eq!(pacing.wake(playing, now), Wake::Continuous);
        assert_eq!(pacing.wake(Activity::default(), now), Wake::Sleep);
        pacing.repaint_after(now, Some(Duration::from_millis(500)));
        let at = now + Duration::from_millis(500);
        assert_eq!(pacing.wake(Activity::default(), now), Wake::At { at, due: false });
        assert_eq!(pacing.wake(Activity::default(), at), Wake::At { at, due: true });
        assert_eq!(
            pacing.wake(Activity::default(), at),
            Wake::Sleep,
            "a repaint is drawn once"
        );
        pacing.repaint_after(now, Some(Duration::from_secs(7200)));
        assert_eq!(
            pacing.wake(Activity::default(), now),
            Wake::Sleep,
            "egui's 'never' is no wish"
        );
    }

    #[test]
    fn a_load_alone_is_paced_and_anything_else_is_continuous() {
        let mut pacing = Pacing::new();
        let started = pacing.tick(true).now;
        let ended = started + Duration::from_millis(10);
        pacing.drawn(ended);
        let loading = Activity {
            loading: true,
            ..Activity::default()
        };
        let next = ended + LOADING_INTERVAL;
        assert_eq!(pacing.wake(loading, ended), Wake::At { at: next, due: false });
        assert_eq!(pacing.wake(loading, next), Wake::At { at: next, due: true });
        pacing.repaint_after(ended, Some(Duration::ZERO));
        assert_eq!(
            pacing.wake(loading, ended),
            Wake::At { at: next, due: false },
            "egui's wish for every frame waits for the paced one"
        );
        // A slow frame (a preview beside the load) is followed by twice its time without one.
        let slow = pacing.tick(true).now;
        pacing.drawn(slow + Duration::from_secs(2));
        let after = slow + Duration::from_secs(6);
        assert_eq!(pacing.wake(loading, slow), Wake::At { at: after, due: false });
        let dragging_while_loading = Activity {
            held_input: true,
            ..loading
        };
        assert_eq!(pacing.wake(dragging_while_loading, started), Wake::Continuous);
    }
}
