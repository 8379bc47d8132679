//! The panel's file fields (a volume's path and the raw format's dims, type and scale; the session file) and what
//! a path given to the viewer — typed, dropped or picked — asks it to do.

use super::actions::UiAction;
use super::chooser::FileChooser;
use crate::formats::{parse_scivis_name, RawOptions};
use crate::volume::VoxelType;
use std::path::{Path, PathBuf};

/// The paths and raw-format fields the panel edits.
#[derive(Clone, Debug)]
pub struct FileFields {
    pub load_path: String,
    pub raw_dims: [u32; 3],
    pub raw_type: VoxelType,
    pub raw_spacing: [f32; 3],
    /// The path typed names a file that would be read as raw: the panel shows the raw fields (for any other
    /// format they would only show the last raw file's values, which the load ignores). Kept up to date by
    /// [`FileFields::path_edited`].
    pub path_is_raw: bool,
    /// Where Ctrl+S and "Save session" write, and "Open session" reads.
    pub session_path: String,
    /// The viewer's own file chooser, while open (when no desktop file dialog answered *Open…*).
    pub chooser: Option<FileChooser>,
    /// What *Open…* has to say (the dialog was closed without a file), shown beside it.
    pub open_note: Option<String>,
}

impl Default for FileFields {
    fn default() -> FileFields {
        FileFields {
            load_path: String::new(),
            raw_dims: [256, 256, 256],
            raw_type: VoxelType::U8,
            raw_spacing: [1.0; 3],
            path_is_raw: false,
            session_path: "volcast-session.json".into(),
            chooser: None,
            open_note: None,
        }
    }
}

impl FileFields {
    /// The raw fields (dims, type, scale) describe the volume shown, so a raw reload starts from them.
    pub fn describe_raw(&mut self, dims: [u32; 3], voxel_type: VoxelType, spacing: [f32; 3]) {
        self.raw_dims = dims;
        self.raw_type = voxel_type;
        self.raw_spacing = spacing;
    }

    /// Fills dims and type from an open-scivis file name, if it matches.
    pub fn take_dims_from_name(&mut self) {
        if let Some((_, dims, ty)) = parse_scivis_name(&self.load_path) {
            self.raw_dims = dims;
            self.raw_type = ty;
        }
    }

    /// The path field changed (typed, dropped, picked): dims and type from a scivis name, and whether the raw
    /// fields apply. Not done per frame: deciding may read the file's first bytes.
    pub fn path_edited(&mut self) {
        self.take_dims_from_name();
        self.path_is_raw = read_as_raw(Path::new(self.load_path.trim()));
    }

    pub fn raw_options(&self) -> RawOptions {
        RawOptions {
            dims: Some(self.raw_dims),
            voxel_type: Some(self.raw_type),
            spacing: Some(self.raw_spacing),
        }
    }

    /// A load of `path` with dims/type from its name when it matches, else from the panel's fields; a session
    /// file is opened as one.
    pub fn load_action(&mut self, path: PathBuf) -> UiAction {
        if is_session_file(&path) {
            return UiAction::OpenSession(path);
        }
        self.load_path = path.display().to_string();
        let named = parse_scivis_name(&self.load_path).is_some();
        self.path_edited();
        let mut opts = self.raw_options();
        if named {
            opts.dims = None;
            opts.voxel_type = None;
        }
        UiAction::LoadFile(path.clone(), raw_only(&path, opts))
    }

    /// The "Load volume" button: the path field with the raw fields as they stand (filled from a scivis name,
    /// they may have been edited since).
    pub fn load_field_action(&self) -> UiAction {
        let path = PathBuf::from(self.load_path.trim());
        UiAction::LoadFile(path.clone(), raw_only(&path, self.raw_options()))
    }
}

/// The panel's dims/type/scale describe raw files; other formats carry their own (and the scale would override
/// their spacing), so they get none.
/// A load's error as the panel shows it: the reason first and the file named once. A reader's error starts with
/// the file's name ("broken.nii: reason"); that prefix gives way to the path loaded, at the end, unless the reason
/// names the file itself.
pub fn load_error_text(label: &str, error: &str) -> String {
    let name = Path::new(label)
        .file_name()
        .map_or_else(|| label.to_string(), |n| n.to_string_lossy().into_owned());
    let reason = error
        .split_once(": ")
        .filter(|(head, _)| !head.contains(' ') && head.ends_with(name.as_str()))
        .map_or(error, |(_, rest)| rest);
    if reason.contains(name.as_str()) {
        reason.to_string()
    } else {
        format!("{reason} ({label})")
    }
}

pub fn raw_only(path: &Path, opts: RawOptions) -> RawOptions {
    match crate::formats::detect_format(path) {
        Ok(crate::formats::Format::Raw) | Err(_) => opts,
        Ok(_) => RawOptions::default(),
    }
}

/// Whether the loader would read `path` as raw, so that the raw fields apply: by its content where it exists (as
/// the loader decides), else by its name while it is being typed (a name without a format's extension is raw).
pub fn read_as_raw(path: &Path) -> bool {
    if path.as_os_str().is_empty() || is_session_file(path) || path.is_dir() {
        return false;
    }
    match crate::formats::detect_format(path) {
        Ok(format) => format == crate::formats::Format::Raw,
        Err(crate::volume::VolumeError::Unsupported { .. }) => false,
        Err(_) => crate::formats::format_by_name(path).is_none(),
    }
}

/// Whether a dropped or typed file is a session rather than a volume.
pub fn is_session_file(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_load_error_gives_its_reason_first_and_names_the_file_once() {
        let label = "/data/scans/broken.nii";
        assert_eq!(
            load_error_text(label, "broken.nii: not a NIfTI header"),
            "not a NIfTI header (/data/scans/broken.nii)"
        );
        assert_eq!(
            load_error_text(label, "/data/scans/broken.nii: too short"),
            "too short (/data/scans/broken.nii)"
        );
        // A reason that names the file itself keeps it, and gets no second mention.
        let own = "cannot read /data/scans/broken.nii: No such file or directory (os error 2)";
        assert_eq!(load_error_text(label, own), own);
    }

    use super::*;

    #[test]
    fn dropped_scivis_file_fills_dims_and_type() {
        let mut files = FileFields::default();
        let action = files.load_action(PathBuf::from("/data/skull_64x32x16_int16.raw"));
        assert_eq!(files.raw_dims, [64, 32, 16]);
        assert_eq!(files.raw_type, VoxelType::I16);
        match action {
            UiAction::LoadFile(p, opts) => {
                assert_eq!(p, PathBuf::from("/data/skull_64x32x16_int16.raw"));
                assert_eq!(opts.dims, None, "the loader reads them from the name");
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            files.load_action(PathBuf::from("a/volcast-1.JSON")),
            UiAction::OpenSession(_)
        ));
        assert!(is_session_file(Path::new("a/volcast-1.JSON")) && !is_session_file(Path::new("a.nii")));
    }

    #[test]
    fn only_a_path_read_as_raw_takes_the_raw_fields() {
        let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
        for (path, raw) in [
            ("", false),
            ("/nowhere/head.nii.gz", false),
            ("/nowhere/head.NRRD", false),
            ("/nowhere/ct.dcm", false),
            ("/nowhere/session.json", false),
            ("/nowhere/skull_64x32x16_int16.raw", true),
            ("/nowhere/volume.bin", true),
            ("/nowhere/volume", true),
        ] {
            assert_eq!(read_as_raw(Path::new(path)), raw, "{path:?}");
        }
        // Existing files are decided by content, as the loader decides: a DICOM folder and a DICOM file
        // without an extension are not raw.
        assert!(!read_as_raw(&data.join("dicom/u16_j2k")));
        let mut files = FileFields {
            load_path: "/nowhere/x.bin".into(),
            ..Default::default()
        };
        files.path_edited();
        assert!(files.path_is_raw);
        files.load_path = "/nowhere/x.nii.gz".into();
        files.path_edited();
        assert!(!files.path_is_raw);
    }
}
