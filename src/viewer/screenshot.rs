//! What the viewer writes: the F12 screenshot (the view image's pixels) and, beside it, the view state that
//! `volcast render --state` renders again.

use super::{ViewerError, VolumeSource};
use crate::scene::view_state::ViewState;

/// The view state's record of where the shown volume came from.
pub(super) fn volume_ref(
    source: Option<&VolumeSource>,
    spacing: [f32; 3],
    time: u32,
) -> crate::scene::view_state::VolumeRef {
    let mut r = crate::scene::view_state::VolumeRef {
        spacing,
        time,
        ..Default::default()
    };
    match source {
        Some(VolumeSource::Builtin(name, size)) => (r.builtin, r.builtin_size) = (Some(name.clone()), *size),
        Some(VolumeSource::File(path, raw)) => {
            r.path = Some(std::fs::canonicalize(path).unwrap_or_else(|_| path.clone()));
            r.raw_dims = raw.dims;
            r.raw_type = raw.voxel_type.map(|t| t.name().to_string());
            r.raw_spacing = raw.spacing;
        }
        None => {}
    }
    r
}

/// Writes the view image's pixels (RGBA8, exactly what the view shows without the panel) and the settings; a
/// series' shown step is logged after the file name.
pub(super) fn save_screenshot(
    path: &std::path::Path,
    pixels: Vec<u8>,
    state: &ViewState,
    step: Option<u32>,
) -> Result<(), ViewerError> {
    let settings = &state.settings;
    let img = image::RgbaImage::from_raw(settings.width, settings.height, pixels)
        .ok_or_else(|| ViewerError::Other("screenshot size mismatch".into()))?;
    crate::render::png::save(&img, path).map_err(ViewerError::Other)?;
    // The view state: the settings (still readable as plain `RenderSettings`), the volume's origin and the
    // viewer's own state, so that `volcast render --state` renders this view again and `view --state` restores it.
    write_session(&path.with_extension("json"), state).map_err(ViewerError::Other)?;
    match step {
        Some(t) => eprintln!("saved screenshot {} (time step {t})", path.display()),
        None => eprintln!("saved screenshot {}", path.display()),
    }
    Ok(())
}

/// Writes a session file whole or not at all (a temporary file renamed over it).
pub(super) fn write_session(path: &std::path::Path, state: &ViewState) -> Result<(), String> {
    let tmp = path.with_extension("json.part");
    std::fs::write(&tmp, state.to_json())
        .and_then(|_| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            format!("writing {}: {e}", path.display())
        })
}
