//! Sessions: the viewer's whole state as one JSON file (a [`ViewState`] with its `viewer` part), written by F12
//! beside the screenshot, by Ctrl+S or the panel's "Save session", and restored by `volcast view --state FILE`,
//! the panel's "Open session" or by dropping the file on the window. `volcast render --state` renders the same
//! file (the `viewer` part is the viewer's own: layout, crosshair, window/level, quality).

use super::controls::OrbitView;
use super::ui::ViewerState;
use super::{Running, VolumeSource};
use crate::scene::view_state::{ViewState, ViewerSession, VolumeRef};
use crate::volume::{RawOptions, VoxelType};
use glam::DVec3;
use std::path::Path;

impl ViewerState {
    /// The viewer's part of a session.
    pub fn session(&self) -> ViewerSession {
        ViewerSession {
            slice_views: self.slices.shown,
            crosshair: self.slices.crosshair.to_array(),
            window_level: self.slices.wl,
            quality: self.quality,
            lod: self.lod,
            tf_locked: self.tf_locked,
            panel_visible: self.panel_visible,
        }
    }

    /// Shows a saved view of the volume now shown: its settings (transfer function, mode, lighting, slabs, clip
    /// plane…), camera and, when the viewer wrote it, the viewer's own state.
    pub fn restore(&mut self, state: &ViewState) {
        let s = &state.settings;
        let (width, height) = (self.look.width, self.look.height);
        self.look = s.clone();
        (self.look.width, self.look.height) = (width, height);
        self.orbit = OrbitView::from_camera(&s.camera);
        self.ortho = s.camera.ortho;
        self.animation = None;
        self.auto_rotate = false;
        for axis in 0..3 {
            let (lo, hi) = (s.slab_lo[axis], s.slab_hi[axis]);
            self.slabs[axis] = ((lo + hi) / 2.0, hi - lo);
        }
        match &state.viewer {
            Some(v) => {
                self.slices.shown = v.slice_views;
                self.slices.crosshair = DVec3::from_array(v.crosshair);
                if v.window_level.is_some() {
                    self.slices.wl = v.window_level;
                }
                self.quality = v.quality;
                self.lod = v.lod;
                self.tf_locked = v.tf_locked;
                self.panel_visible = v.panel_visible;
            }
            // A plain view state (no viewer part): its own step length, as `render --state` uses it.
            None => self.quality = None,
        }
        self.time.wanted = state.volume.time.min(self.time.steps.saturating_sub(1));
    }
}

/// Reads a session (or any view state) file; the error names it.
pub fn read(path: &Path) -> Result<ViewState, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    ViewState::from_json(&text, &path.display().to_string())
}

/// Where a session's volume comes from; None when it names none.
pub fn source_of(r: &VolumeRef) -> Option<VolumeSource> {
    if let Some(name) = &r.builtin {
        return Some(VolumeSource::Builtin(name.clone(), r.builtin_size));
    }
    let path = r.path.clone()?;
    let raw = RawOptions {
        dims: r.raw_dims,
        voxel_type: r.raw_type.as_deref().and_then(VoxelType::parse),
        spacing: r.raw_spacing,
    };
    Some(VolumeSource::File(path, raw))
}

/// Whether a dropped or typed file is a session rather than a volume.
pub fn is_session_file(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

impl Running {
    /// Opens a session: loads its volume unless it is the one shown, then restores the view once it is there.
    pub(super) fn open_session(&mut self, path: &Path) {
        let state = match read(path) {
            Ok(s) => s,
            Err(e) => {
                self.state.error = Some(format!("session {e}"));
                return;
            }
        };
        let Some(source) = source_of(&state.volume) else {
            self.state.error = Some(format!("session {}: it names no volume", path.display()));
            return;
        };
        let shown = self
            .shown_source
            .as_ref()
            .map(|s| super::screenshot::volume_ref(Some(s), self.state.raw_spacing, 0));
        let same = shown.is_some_and(|r| {
            (r.path.as_ref(), r.builtin.as_ref(), r.builtin_size)
                == (
                    state.volume.path.as_ref(),
                    state.volume.builtin.as_ref(),
                    state.volume.builtin_size,
                )
        });
        self.state.status = Some(format!("session {}", path.display()));
        if same && self.loading.is_none() {
            self.state.restore(&state);
        } else {
            self.pending_restore = Some(state);
            self.start_load(source);
        }
    }

    /// The whole state as a view state with the given render settings (those of the frame drawn).
    pub(super) fn session_state(&self, settings: &crate::scene::settings::RenderSettings) -> ViewState {
        let step = self.series.as_ref().map(crate::volume::Volume::shown_step);
        ViewState {
            volume: super::screenshot::volume_ref(
                self.shown_source.as_ref(),
                self.state.raw_spacing,
                step.unwrap_or(0),
            ),
            settings: settings.clone(),
            viewer: Some(self.state.session()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::settings::RenderSettings;

    #[test]
    fn a_session_restores_what_it_saved() {
        let mut a = ViewerState::new(glam::Vec3::ONE, "a".into());
        a.slabs[1] = (0.3, 0.4);
        a.slices.shown = true;
        a.slices.crosshair = DVec3::new(3.0, 4.5, 6.0);
        a.quality = Some(crate::scene::quality::Quality::Fast);
        a.orbit.turn(0.7);
        a.look.mode = crate::scene::settings::CompositeMode::Mip;
        let settings = a.render_settings(200, 100);
        let saved = ViewState {
            volume: VolumeRef::default(),
            settings: settings.clone(),
            viewer: Some(a.session()),
        };
        let json = saved.to_json();
        let mut b = ViewerState::new(glam::Vec3::ONE, "b".into());
        b.restore(&ViewState::from_json(&json, "s.json").unwrap());
        // The camera goes through the orbit's rotation and the slabs through (position, width): equal to float
        // rounding; everything else exactly.
        let mut restored = b.render_settings(200, 100);
        assert!(restored.camera.eye.distance(settings.camera.eye) < 1e-5);
        assert!(restored.camera.up.distance(settings.camera.up) < 1e-5);
        assert!(
            restored.slab_lo.distance(settings.slab_lo) < 1e-6 && restored.slab_hi.distance(settings.slab_hi) < 1e-6
        );
        (restored.camera, restored.slab_lo, restored.slab_hi) = (settings.camera, settings.slab_lo, settings.slab_hi);
        assert_eq!(restored, settings);
        assert_eq!(b.session(), a.session());
        // A plain view state keeps its own step.
        let plain: RenderSettings = RenderSettings {
            step_length: 0.37,
            ..settings
        };
        b.restore(&ViewState {
            volume: VolumeRef::default(),
            settings: plain,
            viewer: None,
        });
        assert_eq!(b.render_settings(200, 100).step_length, 0.37);
    }

    #[test]
    fn sources_come_back_from_the_reference() {
        let r = VolumeRef {
            path: Some("/d/x_8x8x8_uint8.raw".into()),
            raw_dims: Some([8, 8, 8]),
            raw_type: Some("uint8".into()),
            ..VolumeRef::default()
        };
        match source_of(&r) {
            Some(VolumeSource::File(p, raw)) => {
                assert_eq!(p, Path::new("/d/x_8x8x8_uint8.raw"));
                assert_eq!(raw.voxel_type, Some(VoxelType::U8));
            }
            other => panic!("{other:?}"),
        }
        assert!(source_of(&VolumeRef::default()).is_none());
        assert!(is_session_file(Path::new("a/volcast-1.JSON")) && !is_session_file(Path::new("a.nii")));
    }
}
