//! The viewer's own file chooser, for when no desktop file dialog answers (no xdg-desktop-portal, as under Xvfb):
//! a folder's entries, folders first, with the parent folder and a path field. What it lists is read here; the
//! window that shows it is `widgets::panel::chooser`.

use std::path::{Path, PathBuf};

/// One entry of the folder shown.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entry {
    pub name: String,
    pub is_dir: bool,
}

/// The chooser's state: the folder shown, its entries and the path typed or picked.
#[derive(Clone, Debug)]
pub struct FileChooser {
    pub folder: PathBuf,
    pub entries: Vec<Entry>,
    /// The path field: the entry clicked, or what the user typed.
    pub typed: String,
    /// The folder could not be read.
    pub error: Option<String>,
}

impl FileChooser {
    /// A chooser on `folder`.
    pub fn at(folder: &Path) -> FileChooser {
        let mut chooser = FileChooser {
            folder: PathBuf::new(),
            entries: Vec::new(),
            typed: String::new(),
            error: None,
        };
        chooser.enter(folder);
        chooser
    }

    /// A chooser on the folder of `path` (the path field's), else the working folder.
    pub fn near(path: &str) -> FileChooser {
        let path = Path::new(path.trim());
        let folder = if path.is_dir() {
            Some(path.to_path_buf())
        } else {
            path.parent().filter(|p| p.is_dir()).map(Path::to_path_buf)
        };
        let folder = folder
            .filter(|f| !f.as_os_str().is_empty())
            .or_else(|| std::env::current_dir().ok())
            .unwrap_or_else(|| PathBuf::from("/"));
        FileChooser::at(&folder)
    }

    /// Shows `folder`'s entries (folders first, then files, each by name; hidden ones left out).
    pub fn enter(&mut self, folder: &Path) {
        let folder = folder.canonicalize().unwrap_or_else(|_| folder.to_path_buf());
        match std::fs::read_dir(&folder) {
            Ok(read) => {
                let mut entries: Vec<Entry> = read
                    .filter_map(Result::ok)
                    .map(|e| Entry {
                        name: e.file_name().to_string_lossy().into_owned(),
                        is_dir: e.path().is_dir(),
                    })
                    .filter(|e| !e.name.starts_with('.'))
                    .collect();
                entries.sort_by(|a, b| b.is_dir.cmp(&a.is_dir).then_with(|| a.name.cmp(&b.name)));
                self.entries = entries;
                self.error = None;
            }
            Err(e) => {
                self.error = Some(format!("{}: {e}", folder.display()));
                return;
            }
        }
        self.typed = folder.display().to_string();
        self.folder = folder;
    }

    /// Shows the parent folder.
    pub fn up(&mut self) {
        if let Some(parent) = self.folder.parent().map(Path::to_path_buf) {
            self.enter(&parent);
        }
    }

    /// The path of entry `name` of the folder shown.
    pub fn path_of(&self, name: &str) -> PathBuf {
        self.folder.join(name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_folders_first_and_goes_up_and_down() {
        let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
        let mut chooser = FileChooser::at(&data.join("vtk"));
        assert!(chooser.entries.iter().any(|e| e.name == "vti_zlib.vti" && !e.is_dir));
        chooser.up();
        assert_eq!(chooser.folder, data.canonicalize().unwrap());
        let first_file = chooser
            .entries
            .iter()
            .position(|e| !e.is_dir)
            .unwrap_or(chooser.entries.len());
        assert!(chooser.entries[..first_file].iter().all(|e| e.is_dir), "folders first");
        assert!(chooser.entries.iter().any(|e| e.name == "vtk" && e.is_dir));
        chooser.enter(&chooser.path_of("nowhere"));
        assert!(chooser.error.is_some() && chooser.folder == data.canonicalize().unwrap());
    }
}
