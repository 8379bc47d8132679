//! Session files: the viewer's whole state as one JSON file (a [`ViewState`] with its `viewer` part, see
//! `model::session`), written by F12 beside the screenshot, by Ctrl+S or the panel's "Save session", and restored
//! by `volcast view --state FILE`, the panel's "Open session" or by dropping the file on the window. `volcast render
//! --state` renders the same file. Here: reading and writing them, and where their volume comes from.

use super::VolumeSource;
use crate::formats::RawOptions;
use crate::scene::view_state::{ViewState, VolumeRef};
use crate::volume::VoxelType;
use std::path::Path;

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

/// The view state's record of where the shown volume came from (the inverse of [`source_of`]).
pub fn volume_ref(source: Option<&VolumeSource>, spacing: [f32; 3], time: u32) -> VolumeRef {
    let mut r = VolumeRef {
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
        Some(VolumeSource::Memory(_)) | None => {}
    }
    r
}

/// Writes a session file whole or not at all (a temporary file renamed over it).
pub fn write_session(path: &Path, state: &ViewState) -> Result<(), String> {
    let tmp = path.with_extension("json.part");
    std::fs::write(&tmp, state.to_json())
        .and_then(|_| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            format!("writing {}: {e}", path.display())
        })
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let builtin = VolumeSource::Builtin("helix".into(), Some(64));
        match source_of(&volume_ref(Some(&builtin), [1.0; 3], 2)) {
            Some(VolumeSource::Builtin(name, size)) => assert_eq!((name.as_str(), size), ("helix", Some(64))),
            other => panic!("{other:?}"),
        }
    }
}
