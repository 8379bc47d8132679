//! Reading a keyframed path's view states (the viewer's F12 JSON, [`ViewState`]) and checking that they make one
//! movie: the same volume and the same image size in every file.

use super::MovieError;
use crate::scene::view_state::{ViewState, VolumeRef};
use std::path::{Path, PathBuf};

/// Reads every state in `paths` (at least two); the first error names its file, a mismatch both files.
pub fn read_keyframes(paths: &[PathBuf]) -> Result<Vec<ViewState>, MovieError> {
    if paths.len() < 2 {
        return Err(MovieError::Usage(
            "--keyframes needs at least two view states (FIRST.json LAST.json ...)".into(),
        ));
    }
    let states = paths.iter().map(|p| read_state(p)).collect::<Result<Vec<_>, _>>()?;
    let (first, first_path) = (&states[0], &paths[0]);
    for (state, path) in states.iter().zip(paths).skip(1) {
        if state.volume != first.volume {
            return Err(MovieError::Input(format!(
                "{} and {} show different volumes ({} and {}): every keyframe of a path must show the same one",
                first_path.display(),
                path.display(),
                describe(&first.volume),
                describe(&state.volume)
            )));
        }
        let (a, b) = (&first.settings, &state.settings);
        if (a.width, a.height) != (b.width, b.height) {
            return Err(MovieError::Input(format!(
                "{} is {}x{} but {} is {}x{}: every keyframe of a path must have the same image size",
                first_path.display(),
                a.width,
                a.height,
                path.display(),
                b.width,
                b.height
            )));
        }
    }
    Ok(states)
}

fn read_state(path: &Path) -> Result<ViewState, MovieError> {
    let text =
        std::fs::read_to_string(path).map_err(|e| MovieError::Input(format!("reading {}: {e}", path.display())))?;
    ViewState::from_json(&text, &path.display().to_string()).map_err(MovieError::Input)
}

/// A volume reference in a few words, for messages.
pub fn describe(v: &VolumeRef) -> String {
    let mut text = match (&v.builtin, &v.path) {
        (Some(name), _) => match v.builtin_size {
            Some(size) => format!("built-in {name} at {size}³"),
            None => format!("built-in {name}"),
        },
        (None, Some(path)) => path.display().to_string(),
        (None, None) => "no volume".into(),
    };
    if let Some(d) = v.raw_dims {
        text += &format!(" as {}x{}x{}", d[0], d[1], d[2]);
    }
    if let Some(t) = &v.raw_type {
        text += &format!(" {t}");
    }
    if let Some(s) = v.raw_spacing {
        text += &format!(" spacing {}x{}x{}", s[0], s[1], s[2]);
    }
    if v.time > 0 {
        text += &format!(", time step {}", v.time);
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::settings::RenderSettings;

    fn write(dir: &Path, name: &str, builtin: &str, size: (u32, u32)) -> PathBuf {
        let state = ViewState {
            volume: VolumeRef {
                builtin: Some(builtin.into()),
                builtin_size: Some(16),
                ..VolumeRef::default()
            },
            settings: RenderSettings::new(size.0, size.1, glam::Vec3::ONE),
            viewer: None,
            layer_files: Default::default(),
        };
        let path = dir.join(name);
        std::fs::write(&path, state.to_json()).unwrap();
        path
    }

    #[test]
    fn states_must_exist_parse_and_agree() {
        let dir = std::env::temp_dir().join(format!("volcast-keyframes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let a = write(&dir, "a.json", "helix", (32, 24));
        let b = write(&dir, "b.json", "helix", (32, 24));
        let c = write(&dir, "c.json", "box", (32, 24));
        let d = write(&dir, "d.json", "helix", (48, 24));
        assert_eq!(read_keyframes(&[a.clone(), b.clone()]).unwrap().len(), 2);
        let e = read_keyframes(&[a.clone(), b.clone(), c.clone()])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("a.json") && e.contains("c.json") && e.contains("built-in box"),
            "{e}"
        );
        let e = read_keyframes(&[a.clone(), d]).unwrap_err().to_string();
        assert!(e.contains("32x24") && e.contains("48x24"), "{e}");
        let e = read_keyframes(&[a.clone(), dir.join("missing.json")])
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing.json"), "{e}");
        std::fs::write(dir.join("bad.json"), "{").unwrap();
        let e = read_keyframes(&[a.clone(), dir.join("bad.json")])
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.json") && e.contains("view state"), "{e}");
        assert!(read_keyframes(&[a]).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
