//! Playback of a series (4-D NIfTI, NRRD, MetaImage, DICOM with temporal positions): the step asked for,
//! play/pause, steps per second and looping (the panel's time controls edit it). The app uploads the step asked for
//! ([`TimeControl::wanted`]); the transfer function and value range stay the series'.

/// The real time the rate reached is measured over.
const RATE_WINDOW_S: f32 = 2.0;

/// Where playback is.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeControl {
    /// Steps in the series; 1 hides the controls.
    pub steps: u32,
    /// The step the user (or playback) asks for.
    pub wanted: u32,
    pub playing: bool,
    /// Playback speed in steps per second.
    pub fps: f32,
    /// Time since the last step while playing.
    since_step: f32,
    /// Real time since the step before, while playing (what the reached rate is measured over).
    since_shown: f32,
    /// The rate playback reaches (steps per second, smoothed), once it has taken a step; None when paused.
    pub reached: Option<f32>,
    /// The times between the last steps, covering about the last two seconds: `reached` is their count over
    /// their sum (a smoothed mean of rates instead overstated the rate when frames were uneven, since a short
    /// interval weighs more as a rate than a long one).
    intervals: std::collections::VecDeque<f32>,
}

/// Fastest playback offered: beyond it frames would be dropped on most machines anyway.
pub const MAX_FPS: f32 = 60.0;

impl TimeControl {
    pub fn new(steps: u32, shown: u32) -> TimeControl {
        TimeControl {
            steps: steps.max(1),
            wanted: shown.min(steps.saturating_sub(1)),
            playing: false,
            fps: 10.0,
            since_step: 0.0,
            since_shown: 0.0,
            reached: None,
            intervals: Default::default(),
        }
    }

    /// Advances playback by `dt` seconds of real time: at most one step per frame (a slow frame does not skip
    /// steps, so every step is seen), looping at the end. Returns whether the wanted step changed.
    pub fn advance(&mut self, dt: f32) -> bool {
        if !self.playing || self.steps < 2 {
            self.since_step = 0.0;
            self.since_shown = 0.0;
            self.reached = None;
            self.intervals.clear();
            return false;
        }
        self.since_step += dt;
        self.since_shown += dt;
        let period = 1.0 / self.fps.clamp(0.1, MAX_FPS);
        if self.since_step < period {
            return false;
        }
        self.since_step = (self.since_step - period).min(period);
        self.wanted = (self.wanted + 1) % self.steps;
        self.intervals.push_back(self.since_shown);
        let mut sum: f32 = self.intervals.iter().sum();
        while self.intervals.len() > 1 && sum - self.intervals[0] >= RATE_WINDOW_S {
            sum -= self.intervals.pop_front().unwrap_or_default();
        }
        self.reached = Some(self.intervals.len() as f32 / sum.max(1e-3));
        self.since_shown = 0.0;
        true
    }

    /// Playing slower than asked (the frames cannot keep up): the rate reached, to show beside the one asked.
    pub fn falling_behind(&self) -> Option<f32> {
        self.reached.filter(|r| self.playing && *r < 0.95 * self.fps)
    }

    /// Asks for step `t` (`--time`); an error where the series has no such step.
    pub fn start_at(&mut self, t: u32) -> Result<(), String> {
        if t >= self.steps {
            return Err(format!(
                "time step {t} does not exist: the volume has {} (0 to {})",
                self.steps,
                self.steps - 1
            ));
        }
        self.wanted = t;
        Ok(())
    }

    pub fn toggle_play(&mut self) {
        if self.steps > 1 {
            self.playing = !self.playing;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rate_reached_is_measured_over_real_time() {
        let mut t = TimeControl::new(5, 0);
        t.toggle_play();
        t.fps = 10.0;
        // Frames of 0.25 s: one step each (never skipped), so 4 steps/s where 10 were asked.
        for _ in 0..20 {
            assert!(t.advance(0.25));
        }
        let reached = t.falling_behind().expect("behind");
        assert!((reached - 4.0).abs() < 0.01, "{reached}");
        // Frames of 0.02 s keep up: 10 steps/s.
        for _ in 0..200 {
            t.advance(0.02);
        }
        assert!((t.reached.unwrap() - 10.0).abs() < 0.6, "{:?}", t.reached);
        assert_eq!(t.falling_behind(), None);
        t.toggle_play();
        t.advance(0.1);
        assert_eq!(t.reached, None, "paused: no rate");
    }

    #[test]
    fn uneven_frames_do_not_inflate_the_rate_reached() {
        // Frames of 0.06 and 0.09 s at 10 steps/s asked: some steps come after one frame, some after two, and
        // in the long run exactly 10 a second (no step skipped, the remainder carried). A mean of the
        // reciprocal intervals made that look faster than asked.
        let mut t = TimeControl::new(5, 0);
        t.toggle_play();
        t.fps = 10.0;
        let (mut steps, mut time) = (0, 0.0);
        for k in 0..600 {
            let dt = if k % 2 == 0 { 0.06 } else { 0.09 };
            time += dt;
            steps += t.advance(dt) as u32;
        }
        let true_rate = steps as f32 / time;
        let reached = t.reached.unwrap();
        assert!((reached - true_rate).abs() < 0.3, "reached {reached}, true {true_rate}");
    }

    #[test]
    fn playback_steps_at_the_set_rate_and_loops() {
        let mut t = TimeControl::new(3, 0);
        assert!(!t.advance(1.0), "paused");
        t.toggle_play();
        t.fps = 4.0;
        assert!(!t.advance(0.2));
        assert!(t.advance(0.1));
        assert_eq!(t.wanted, 1);
        // A long frame moves one step, not several.
        assert!(t.advance(5.0));
        assert_eq!(t.wanted, 2);
        assert!(t.advance(0.25));
        assert_eq!(t.wanted, 0, "loops");
        let mut one = TimeControl::new(1, 0);
        one.toggle_play();
        assert!(!one.playing && !one.advance(1.0));
        assert_eq!(TimeControl::new(4, 9).wanted, 3);
        let mut four = TimeControl::new(4, 0);
        assert!(four.start_at(3).is_ok() && four.wanted == 3);
        assert_eq!(
            four.start_at(4).unwrap_err(),
            "time step 4 does not exist: the volume has 4 (0 to 3)"
        );
    }
}
