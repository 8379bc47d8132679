//! The time egui gives each frame. egui times clicks by their frame's time, and the event loop reads the window's
//! input only between frames, so a frame's time is when its input arrived rather than when it is drawn.

use std::time::{Duration, Instant};

/// Input that arrives this soon after a frame was drawn had waited while it was drawn: the event loop reads the
/// window's events only between frames.
pub const QUEUED: Duration = Duration::from_millis(50);

/// egui's clock, fed with the instants of input, of a frame's start and of its drawing.
pub struct FrameClock {
    /// What the clock counts from.
    start: Instant,
    /// The last time given, which no later time goes below.
    last_time: f64,
    /// When the last frame began (took its input) and when it was drawn.
    began_at: Option<Instant>,
    drawn_at: Option<Instant>,
    /// When the first input since the last frame arrived, and whether it had waited while that frame was drawn.
    first_input: Option<(Instant, bool)>,
}

impl FrameClock {
    pub fn new(start: Instant) -> FrameClock {
        FrameClock {
            start,
            last_time: 0.0,
            began_at: None,
            drawn_at: None,
            first_input: None,
        }
    }

    /// Input arrived at `now`. Only the first since the last frame counts.
    pub fn input(&mut self, now: Instant) {
        if self.first_input.is_none() {
            let queued = self.drawn_at.is_some_and(|d| now.saturating_duration_since(d) < QUEUED);
            self.first_input = Some((now, queued));
        }
    }

    /// The last frame was drawn at `now`: input from then on waited for it only if it comes within [`QUEUED`].
    pub fn drawn(&mut self, now: Instant) {
        self.drawn_at = Some(now);
    }

    /// The time, in seconds, of the frame that begins at `now`: when its first input arrived; for input that
    /// waited while the last frame was drawn (its real time is unknown, somewhere in that frame), just after that
    /// frame began; else `now`. With the time of drawing, the two clicks of a double click that a slow frame split
    /// (the first drawn at once, the second waiting while it was) were a frame's length apart: no double click once
    /// a frame took 0.3 s, which lavapipe's frames of a large volume, or a loaded machine's, do. The clock lags by
    /// at most a frame, so animations (a scroll gliding) keep their pace, and it never runs backwards.
    pub fn frame_time(&mut self, now: Instant) -> f64 {
        let since = |at: Instant| at.saturating_duration_since(self.start).as_secs_f64();
        let time = match (self.first_input.take(), self.began_at) {
            (Some((_, true)), Some(began)) => since(began) + 1e-3,
            (Some((at, _)), _) => since(at),
            (None, _) => since(now),
        };
        self.began_at = Some(now);
        self.last_time = time.max(self.last_time);
        self.last_time
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    fn close(a: f64, b: f64) {
        assert!((a - b).abs() < 1e-9, "{a} against {b}");
    }

    #[test]
    fn a_frame_without_input_is_timed_when_it_begins() {
        let t0 = Instant::now();
        let mut clock = FrameClock::new(t0);
        close(clock.frame_time(t0 + ms(100)), 0.1);
        close(clock.frame_time(t0 + ms(250)), 0.25);
    }

    #[test]
    fn input_between_frames_takes_its_arrival() {
        let t0 = Instant::now();
        let mut clock = FrameClock::new(t0);
        clock.frame_time(t0);
        clock.drawn(t0 + ms(20));
        clock.input(t0 + ms(500));
        clock.input(t0 + ms(520));
        close(clock.frame_time(t0 + ms(530)), 0.5);
    }

    /// The double click a slow frame split: the first click's frame begins at once and takes 400 ms to draw; the
    /// second click arrived while it was drawn and is read just after. Its time is just after the first's, so
    /// the two stay within egui's 0.3 s.
    #[test]
    fn input_that_waited_for_a_slow_frame_takes_that_frame_s_start() {
        let t0 = Instant::now();
        let mut clock = FrameClock::new(t0);
        clock.input(t0 + ms(1000));
        let first = clock.frame_time(t0 + ms(1001));
        close(first, 1.0);
        clock.drawn(t0 + ms(1400));
        clock.input(t0 + ms(1410));
        let second = clock.frame_time(t0 + ms(1411));
        close(second, 1.002);
        assert!(second - first < 0.3);
    }

    /// Under steady input each frame's time lags its start by at most a frame, so a scroll glides at its pace.
    #[test]
    fn steady_input_through_slow_frames_lags_by_a_frame_at_most() {
        let t0 = Instant::now();
        let mut clock = FrameClock::new(t0);
        let mut begin = t0;
        for _ in 0..20 {
            clock.input(begin + ms(1));
            let time = clock.frame_time(begin + ms(2));
            let drawn = begin + ms(300);
            clock.drawn(drawn);
            let behind = (begin + ms(2)).duration_since(t0).as_secs_f64() - time;
            assert!((0.0..=0.31).contains(&behind), "{behind} s behind");
            begin = drawn + ms(5);
        }
    }

    /// An instant reported late (input stamped before the last frame began) does not take the clock back.
    #[test]
    fn the_clock_never_runs_backwards() {
        let t0 = Instant::now();
        let mut clock = FrameClock::new(t0);
        close(clock.frame_time(t0 + ms(300)), 0.3);
        clock.input(t0 + ms(100));
        close(clock.frame_time(t0 + ms(400)), 0.3);
        close(clock.frame_time(t0 + ms(700)), 0.7);
    }
}
