//! What a view is, as one JSON file: the render settings (at the top level, so the file still reads as plain
//! `RenderSettings`) and where the volume came from. The viewer's F12 writes it beside the screenshot, and
//! `volcast render --state FILE.json` renders that view again.

use crate::scene::settings::RenderSettings;
use std::path::PathBuf;

/// Where the shown volume came from: a file (with the raw options it was opened with) or a built-in.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct VolumeRef {
    /// The file, absolute (None for a built-in).
    pub path: Option<PathBuf>,
    pub builtin: Option<String>,
    pub builtin_size: Option<u32>,
    /// A raw file's layout as the viewer opened it (None: from the file's name or header).
    pub raw_dims: Option<[u32; 3]>,
    pub raw_type: Option<String>,
    pub raw_spacing: Option<[f32; 3]>,
    /// The voxel spacing shown (mm; from the header, or the raw options).
    pub spacing: [f32; 3],
    /// The time step shown (0 for a single volume).
    pub time: u32,
    /// The channel of an OME-Zarr image (`--channel`); absent for other volumes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub channel: Option<u32>,
}

/// What the viewer shows beyond the rendered view, for a session to restore it (`render` ignores it).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct ViewerSession {
    /// The four-up layout with the slice views.
    pub slice_views: bool,
    /// The slice views' crosshair, in continuous voxel index coordinates.
    pub crosshair: [f64; 3],
    /// The slice views' window and level in data units.
    pub window_level: Option<crate::scene::slice::WindowLevel>,
    /// The quality level (None: the settings' own step length).
    pub quality: Option<crate::scene::quality::Quality>,
    /// Lower detail while moving.
    pub lod: bool,
    /// Keep the transfer function when another volume loads.
    pub tf_locked: bool,
    pub panel_visible: bool,
}

impl Default for ViewerSession {
    fn default() -> ViewerSession {
        ViewerSession {
            slice_views: false,
            crosshair: [0.0; 3],
            window_level: None,
            quality: Some(crate::scene::quality::Quality::Normal),
            lod: true,
            tf_locked: false,
            panel_visible: true,
        }
    }
}

/// One view: the volume and the settings (flattened: the file is also a valid `RenderSettings` JSON), and the
/// viewer's own state when the viewer wrote it (a session).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ViewState {
    #[serde(default)]
    pub volume: VolumeRef,
    #[serde(flatten)]
    pub settings: RenderSettings,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub viewer: Option<ViewerSession>,
}

impl ViewState {
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Reads a view from `text`; the error names `file`.
    pub fn from_json(text: &str, file: &str) -> Result<ViewState, String> {
        serde_json::from_str(text).map_err(|e| format!("{file}: not a volcast view state: {e}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_state_round_trips_and_still_reads_as_settings() {
        let mut settings = RenderSettings::new(320, 200, glam::Vec3::ONE);
        settings.compositing.iso_value = 0.3;
        let state = ViewState {
            volume: VolumeRef {
                path: Some("/data/ct.nrrd".into()),
                spacing: [0.5, 0.5, 1.5],
                time: 2,
                ..VolumeRef::default()
            },
            settings: settings.clone(),
            viewer: Some(ViewerSession {
                slice_views: true,
                crosshair: [1.5, 2.0, 3.25],
                ..ViewerSession::default()
            }),
        };
        let json = state.to_json();
        assert_eq!(ViewState::from_json(&json, "x.json").unwrap(), state);
        let plain: RenderSettings = serde_json::from_str(&json).unwrap();
        assert_eq!(plain, settings);
        assert!(ViewState::from_json("{", "bad.json").unwrap_err().contains("bad.json"));
    }
}
