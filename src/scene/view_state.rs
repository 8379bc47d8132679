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

/// The files of the layers a view shows (rule 13), as `render` names them; their looks are the settings' `layers`,
/// in the order they load: the overlays, the channels, the label maps.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct LayerFiles {
    /// Absolute, as the volume's path.
    pub overlays: Vec<PathBuf>,
    pub labels: Vec<PathBuf>,
    pub label_table: Option<PathBuf>,
    pub label_ids: Vec<u32>,
    /// `--channels`: `all` or numbers.
    pub channels: Vec<String>,
}

impl LayerFiles {
    pub fn is_empty(&self) -> bool {
        self.overlays.is_empty() && self.labels.is_empty() && self.channels.is_empty()
    }
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
    /// The layers' files (none: the volume alone); `settings.layers` holds their looks.
    #[serde(default, skip_serializing_if = "LayerFiles::is_empty")]
    pub layer_files: LayerFiles,
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
            layer_files: LayerFiles {
                overlays: vec!["/data/zmap.nii.gz".into()],
                ..LayerFiles::default()
            },
        };
        let json = state.to_json();
        assert_eq!(ViewState::from_json(&json, "x.json").unwrap(), state);
        let plain: RenderSettings = serde_json::from_str(&json).unwrap();
        assert_eq!(plain, settings);
        assert!(ViewState::from_json("{", "bad.json").unwrap_err().contains("bad.json"));
    }

    /// `RenderSettings`'s fields before they were grouped (602609e): a state file's keys, which must not change.
    const KEYS_BEFORE_THE_GROUPS: [&str; 37] = [
        "width",
        "height",
        "camera",
        "colormap",
        "window",
        "step_alpha",
        "step_length",
        "multiplied_alpha",
        "transfer_function",
        "mode",
        "iso_value",
        "iso_color",
        "iso_opacity",
        "extra_isosurfaces",
        "light",
        "shadows",
        "ambient_occlusion",
        "density",
        "shading",
        "gradient_opacity",
        "shading_fade",
        "jitter",
        "early_termination",
        "background",
        "slab_lo",
        "slab_hi",
        "ray_setup",
        "position_format",
        "skip_empty",
        "max_stride",
        "stride_tolerance",
        "gradient_texture",
        "compute",
        "ray_spacing",
        "voxel_axes",
        "clip_plane",
        "count_samples",
    ];

    #[test]
    fn a_state_keeps_the_flat_keys_it_had_before_the_settings_were_grouped() {
        let json = serde_json::to_value(RenderSettings::default()).unwrap();
        let mut keys: Vec<&str> = json.as_object().unwrap().keys().map(String::as_str).collect();
        let mut before = KEYS_BEFORE_THE_GROUPS.to_vec();
        keys.sort_unstable();
        before.sort_unstable();
        assert_eq!(keys, before);
    }

    #[test]
    fn a_state_written_before_the_groups_reads_into_them() {
        // Part of a state as 602609e wrote it: one value of each part, the others left to their defaults.
        let old = r#"{"volume": {"builtin": "helix"}, "width": 64, "height": 48, "colormap": "plasma",
            "window": [0.25, 0.75], "mode": "isosurface", "iso_value": 0.4, "shadows": true, "shading_fade": 0.5,
            "step_length": 0.5, "max_stride": 4, "slab_lo": [0.0, 0.1, 0.0], "ray_setup": "analytic",
            "compute": true, "voxel_axes": true, "background": [1.0, 1.0, 1.0]}"#;
        let s = ViewState::from_json(old, "old.json").unwrap().settings;
        let mut want = RenderSettings::new(64, 48, glam::Vec3::ONE);
        want.camera = s.camera;
        want.colour.colormap = crate::transfer::Colormap::Plasma;
        want.colour.window = [0.25, 0.75];
        want.compositing.mode = crate::scene::settings::CompositeMode::Isosurface;
        want.compositing.iso_value = 0.4;
        want.lighting.shadows = true;
        want.lighting.shading_fade = 0.5;
        want.sampling.step_length = 0.5;
        want.sampling.max_stride = 4;
        want.cut.slab_lo = glam::Vec3::new(0.0, 0.1, 0.0);
        want.pipeline.ray_setup = crate::scene::settings::RaySetup::Analytic;
        want.pipeline.compute = true;
        want.voxel_axes = true;
        want.background = glam::Vec3::ONE;
        assert_eq!(s, want);
    }
}
