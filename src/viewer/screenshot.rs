//! What the viewer writes: the F12 screenshot (the view image's pixels) and, beside it, the view state that
//! `volcast render --state` renders again.

use super::{ViewerError, VolumeSource};
use crate::gpu::resources::Buffer;
use crate::gpu::GpuError;
use crate::settings::RenderSettings;

/// The view state's record of where the shown volume came from.
pub(super) fn volume_ref(source: Option<&VolumeSource>, spacing: [f32; 3], time: u32) -> crate::view_state::VolumeRef {
    let mut r = crate::view_state::VolumeRef {
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
    buffer: &Buffer,
    settings: &RenderSettings,
    volume: crate::view_state::VolumeRef,
    step: Option<u32>,
) -> Result<(), ViewerError> {
    let pixels = buffer
        .mapped()
        .ok_or(GpuError::Lost("screenshot buffer is not mapped"))?
        .to_vec();
    let img = image::RgbaImage::from_raw(settings.width, settings.height, pixels)
        .ok_or_else(|| ViewerError::Other("screenshot size mismatch".into()))?;
    crate::image_out::save(&img, path).map_err(ViewerError::Other)?;
    // The view state: the settings (still readable as plain `RenderSettings`) and the volume's origin, so that
    // `volcast render --state` renders this view again.
    let json = crate::view_state::ViewState {
        volume,
        settings: settings.clone(),
    }
    .to_json();
    std::fs::write(path.with_extension("json"), json)
        .map_err(|e| ViewerError::Other(format!("writing {}: {e}", path.with_extension("json").display())))?;
    match step {
        Some(t) => eprintln!("saved screenshot {} (time step {t})", path.display()),
        None => eprintln!("saved screenshot {}", path.display()),
    }
    Ok(())
}
