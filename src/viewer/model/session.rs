//! The model in a session file: its part of a [`ViewState`] (the `viewer` part: layout, crosshair,
//! window/level, quality) and how a saved view state is restored into it.

use super::framing;
use super::orbit::OrbitView;
use super::Model;
use crate::scene::view_state::{ViewState, ViewerSession};
use glam::DVec3;

impl Model {
    /// The viewer's part of a session.
    pub fn session(&self) -> ViewerSession {
        ViewerSession {
            slice_views: self.slices.shown,
            crosshair: self.slices.crosshair.to_array(),
            window_level: self.slices.wl,
            quality: self.sampling.quality,
            lod: self.sampling.lod,
            tf_locked: self.tf_editor.locked,
            panel_visible: self.display.panel_visible,
        }
    }

    /// Shows a saved view of the volume now shown: its settings (transfer function, mode, lighting, slabs, clip
    /// plane…), camera and, when the viewer wrote it, the viewer's own state.
    pub fn restore(&mut self, state: &ViewState) {
        let s = &state.settings;
        let (width, height) = (self.look.width, self.look.height);
        self.look = s.clone();
        (self.look.width, self.look.height) = (width, height);
        self.camera.orbit = OrbitView::from_camera(&s.camera);
        self.camera.ortho = s.camera.ortho;
        // The saved camera stood back by the view's fit factor; the orbit holds the distance before it.
        let fov = self.camera.orbit.fov_y_deg;
        self.camera.orbit.distance /= framing::fit_factor(s.width as f32, s.height as f32, true, fov, s.camera.ortho);
        self.camera.animation = None;
        self.camera.auto_rotate = false;
        for axis in 0..3 {
            let (lo, hi) = (s.cut.slab_lo[axis], s.cut.slab_hi[axis]);
            self.slabs[axis] = ((lo + hi) / 2.0, hi - lo);
        }
        match &state.viewer {
            Some(v) => {
                self.slices.shown = v.slice_views;
                self.slices.crosshair = DVec3::from_array(v.crosshair);
                if v.window_level.is_some() {
                    self.slices.wl = v.window_level;
                }
                self.sampling.quality = v.quality;
                self.sampling.lod = v.lod;
                self.tf_editor.locked = v.tf_locked;
                self.display.panel_visible = v.panel_visible;
            }
            // A plain view state (no viewer part): its own step length, as `render --state` uses it.
            None => self.sampling.quality = None,
        }
        self.time.wanted = state.volume.time.min(self.time.steps.saturating_sub(1));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::settings::RenderSettings;
    use crate::scene::view_state::VolumeRef;

    #[test]
    fn a_session_restores_what_it_saved() {
        let mut a = Model::new(glam::Vec3::ONE, "a".into());
        a.slabs[1] = (0.3, 0.4);
        a.slices.shown = true;
        a.slices.crosshair = DVec3::new(3.0, 4.5, 6.0);
        a.sampling.quality = Some(crate::scene::quality::Quality::Fast);
        a.camera.orbit.turn(0.7);
        a.look.compositing.mode = crate::scene::settings::CompositeMode::Mip;
        let settings = a.render_settings(200, 100);
        let saved = ViewState {
            volume: VolumeRef::default(),
            settings: settings.clone(),
            viewer: Some(a.session()),
            layer_files: Default::default(),
        };
        let json = saved.to_json();
        let mut b = Model::new(glam::Vec3::ONE, "b".into());
        b.restore(&ViewState::from_json(&json, "s.json").unwrap());
        // The camera goes through the orbit's rotation and the slabs through (position, width): equal to float
        // rounding; everything else exactly.
        let mut restored = b.render_settings(200, 100);
        assert!(restored.camera.eye.distance(settings.camera.eye) < 1e-5);
        assert!(restored.camera.up.distance(settings.camera.up) < 1e-5);
        assert!(
            restored.cut.slab_lo.distance(settings.cut.slab_lo) < 1e-6
                && restored.cut.slab_hi.distance(settings.cut.slab_hi) < 1e-6
        );
        (restored.camera, restored.cut.slab_lo, restored.cut.slab_hi) =
            (settings.camera, settings.cut.slab_lo, settings.cut.slab_hi);
        assert_eq!(restored, settings);
        assert_eq!(b.session(), a.session());
        // A plain view state keeps its own step.
        let mut plain: RenderSettings = settings;
        plain.sampling.step_length = 0.37;
        b.restore(&ViewState {
            volume: VolumeRef::default(),
            settings: plain,
            viewer: None,
            layer_files: Default::default(),
        });
        assert_eq!(b.render_settings(200, 100).sampling.step_length, 0.37);
    }
}
