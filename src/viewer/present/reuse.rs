//! Whether a frame marches. The view image keeps the last march's pixels; a frame whose settings are those it was
//! marched with, on the same volume, shows them again (the blit alone) instead of marching anew. Most frames of an
//! unchanged view come from the panel: the pointer over its widgets, a tooltip, a text field, a menu, the file
//! dialog, a load's progress bar. On lavapipe each would cost a whole march (0.43 s for the built-in volume at
//! 900×600 on 2 cores); the blit and egui cost some milliseconds.

use crate::scene::settings::RenderSettings;

/// What the view image holds, and what the march reads besides the frame's settings.
#[derive(Default)]
pub(super) struct ViewContent {
    /// Counts changes to what the march reads besides its settings: the volume installed, a step of a series, bricks
    /// uploaded to a streamed pool, the gradient texture, position targets and the view image made anew.
    generation: u64,
    /// The settings and generation of the last march into the view image; `None` before the first, or after a
    /// march that failed to record.
    marched: Option<(RenderSettings, u64)>,
}

impl ViewContent {
    /// What the march reads besides its settings has changed: the next frame marches.
    pub(super) fn changed(&mut self) {
        self.generation += 1;
    }

    /// Whether a frame of `s` must march: the view image does not hold it.
    pub(super) fn stale(&self, s: &RenderSettings) -> bool {
        !matches!(&self.marched, Some((m, g)) if *g == self.generation && m == s)
    }

    /// A march of `s` into the view image was recorded (or `None`: one failed, and the image holds nothing sure).
    pub(super) fn marched(&mut self, s: Option<&RenderSettings>) {
        self.marched = s.map(|s| (s.clone(), self.generation));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn a_frame_marches_unless_its_settings_and_volume_are_those_of_the_last_march() {
        let s = RenderSettings::new(320, 200, Vec3::ONE);
        let mut view = ViewContent::default();
        assert!(view.stale(&s), "nothing marched yet");
        view.marched(Some(&s));
        assert!(!view.stale(&s), "the same settings on the same volume are shown again");
        assert!(!view.stale(&s.clone()), "an equal copy too");

        let mut turned = s.clone();
        turned.camera.eye.x += 1e-3;
        assert!(view.stale(&turned), "a camera moved");
        let mut smaller = s.clone();
        smaller.width -= 1;
        assert!(view.stale(&smaller), "a reduced-detail frame");
        let mut window = s.clone();
        window.colour.window[0] += 0.01;
        assert!(view.stale(&window), "the value window");

        view.changed();
        assert!(view.stale(&s), "the volume changed under the same settings");
        view.marched(Some(&s));
        assert!(!view.stale(&s));

        view.marched(None);
        assert!(view.stale(&s), "a failed march leaves nothing to show again");
    }
}
