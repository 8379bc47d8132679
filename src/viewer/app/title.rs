//! The window's title: what it shows, then the program (`head.nrrd — volcast`, `helix — volcast`), so that a
//! window list or task bar tells several viewers apart.

use crate::viewer::VolumeSource;

/// `<file name> — volcast` (a built-in's name in place of the file's), or `volcast` before anything is shown.
pub(super) fn window_title(source: Option<&VolumeSource>) -> String {
    let shown = match source {
        Some(VolumeSource::Builtin(name, _)) => Some(name.clone()),
        Some(VolumeSource::Memory(v)) => Some(v.name.clone()),
        Some(VolumeSource::File(path, _)) => path
            .file_name()
            .or(Some(path.as_os_str()))
            .map(|n| n.to_string_lossy().into_owned()),
        None => None,
    };
    match shown {
        Some(name) if !name.is_empty() => format!("{name} — volcast"),
        _ => "volcast".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn the_title_names_the_volume() {
        assert_eq!(window_title(None), "volcast");
        let helix = VolumeSource::Builtin("helix".into(), Some(64));
        assert_eq!(window_title(Some(&helix)), "helix — volcast");
        let file = VolumeSource::File(PathBuf::from("/data/ct/head.nrrd"), Default::default());
        assert_eq!(window_title(Some(&file)), "head.nrrd — volcast");
    }
}
