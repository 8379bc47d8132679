//! The files the viewer opened last: the ten most recent successful loads, newest first, kept in
//! `$XDG_CONFIG_HOME/volcast/recent.json` (else `~/.config/volcast/recent.json`) so a new session offers them.
//! A missing file is kept and offered disabled (a drive may come back); a broken list is ignored with a warning.

use std::path::{Path, PathBuf};

/// How many paths the list keeps.
pub const RECENT_CAP: usize = 10;

/// The list, newest first, without duplicates.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RecentFiles {
    paths: Vec<PathBuf>,
}

/// One entry as the panel offers it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecentEntry {
    pub path: PathBuf,
    /// The file (or folder) is there to open.
    pub exists: bool,
}

#[derive(serde::Serialize, serde::Deserialize)]
struct RecentJson {
    recent: Vec<PathBuf>,
}

impl RecentFiles {
    /// A list of these paths (newest first), deduplicated and capped.
    pub fn from_paths(paths: impl IntoIterator<Item = PathBuf>) -> RecentFiles {
        let mut list = RecentFiles::default();
        let paths: Vec<PathBuf> = paths.into_iter().collect();
        for p in paths.into_iter().rev() {
            list.add(p);
        }
        list
    }

    /// `path` was loaded: it moves to the front (once), the oldest beyond [`RECENT_CAP`] drop off.
    pub fn add(&mut self, path: PathBuf) {
        self.paths.retain(|p| *p != path);
        self.paths.insert(0, path);
        self.paths.truncate(RECENT_CAP);
    }

    pub fn paths(&self) -> &[PathBuf] {
        &self.paths
    }

    /// The entries, newest first, each saying whether its file is there.
    pub fn entries(&self) -> Vec<RecentEntry> {
        self.paths
            .iter()
            .map(|p| RecentEntry {
                path: p.clone(),
                exists: p.exists(),
            })
            .collect()
    }

    /// The list stored at `file`; an empty one if there is none, and a warning with it if it cannot be read.
    pub fn read(file: &Path) -> (RecentFiles, Option<String>) {
        let text = match std::fs::read_to_string(file) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return (RecentFiles::default(), None),
            Err(e) => {
                return (
                    RecentFiles::default(),
                    Some(format!("{}: {e}; recent files start empty", file.display())),
                )
            }
        };
        match serde_json::from_str::<RecentJson>(&text) {
            Ok(json) => (RecentFiles::from_paths(json.recent), None),
            Err(e) => (
                RecentFiles::default(),
                Some(format!(
                    "{} is not a recent-files list ({e}); it is ignored",
                    file.display()
                )),
            ),
        }
    }

    /// Writes the list to `file`, making its folder.
    pub fn write(&self, file: &Path) -> Result<(), String> {
        let json = serde_json::to_string_pretty(&RecentJson {
            recent: self.paths.clone(),
        })
        .map_err(|e| e.to_string())?;
        if let Some(dir) = file.parent() {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        std::fs::write(file, json).map_err(|e| format!("{}: {e}", file.display()))
    }
}

impl RecentFiles {
    /// The list of this user's config (see [`recent_file_from_env`]); a broken one is said on stderr and ignored.
    pub fn from_env() -> RecentFiles {
        let Some(file) = recent_file_from_env() else {
            return RecentFiles::default();
        };
        let (list, warning) = RecentFiles::read(&file);
        if let Some(w) = warning {
            eprintln!("warning: {w}");
        }
        list
    }

    /// `path` loaded: added (as an absolute path, so another working folder opens it too) and the list written
    /// back; a list that cannot be written is said on stderr and kept in memory.
    pub fn remember(&mut self, path: &Path) {
        self.add(std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()));
        if let Some(file) = recent_file_from_env() {
            if let Err(e) = self.write(&file) {
                eprintln!("warning: recent files not saved: {e}");
            }
        }
    }
}

/// Where the list lives, from the values of `XDG_CONFIG_HOME` and `HOME` (an empty or relative XDG_CONFIG_HOME is
/// ignored, as the XDG base directory spec says); `None` without either.
pub fn recent_file(xdg_config_home: Option<&str>, home: Option<&str>) -> Option<PathBuf> {
    let config = match xdg_config_home.map(Path::new).filter(|p| p.is_absolute()) {
        Some(dir) => dir.to_path_buf(),
        None => Path::new(home.filter(|h| !h.is_empty())?).join(".config"),
    };
    Some(config.join("volcast").join("recent.json"))
}

/// [`recent_file`] of this process's environment.
pub fn recent_file_from_env() -> Option<PathBuf> {
    let var = |name| std::env::var(name).ok();
    recent_file(var("XDG_CONFIG_HOME").as_deref(), var("HOME").as_deref())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paths(list: &RecentFiles) -> Vec<&str> {
        list.paths().iter().map(|p| p.to_str().unwrap()).collect()
    }

    #[test]
    fn newest_first_once_each_and_at_most_ten() {
        let mut list = RecentFiles::default();
        for p in ["/a", "/b", "/c", "/a"] {
            list.add(p.into());
        }
        assert_eq!(paths(&list), ["/a", "/c", "/b"]);
        for i in 0..12 {
            list.add(format!("/f{i}").into());
        }
        assert_eq!(list.paths().len(), RECENT_CAP);
        assert_eq!(list.paths()[0], Path::new("/f11"));
        assert_eq!(list.paths()[9], Path::new("/f2"));
        let read = RecentFiles::from_paths(["/x", "/y", "/x", "/z"].map(PathBuf::from));
        assert_eq!(paths(&read), ["/x", "/y", "/z"]);
    }

    #[test]
    fn missing_files_are_kept_and_said_missing() {
        let here = std::env::temp_dir();
        let list = RecentFiles::from_paths([here.clone(), here.join("volcast-no-such-file-8c1f")]);
        let entries = list.entries();
        assert_eq!(entries.len(), 2);
        assert!(entries[0].exists && !entries[1].exists);
    }

    #[test]
    fn a_written_list_reads_back_and_a_broken_one_is_ignored_with_a_warning() {
        let dir = std::env::temp_dir().join(format!("volcast-recent-test-{}", std::process::id()));
        let file = dir.join("volcast/recent.json");
        assert_eq!(RecentFiles::read(&file), (RecentFiles::default(), None));
        let list = RecentFiles::from_paths(["/one", "/two"].map(PathBuf::from));
        list.write(&file).unwrap();
        assert_eq!(RecentFiles::read(&file), (list, None));
        for broken in ["{", "[1, 2]", "{\"recent\": 3}", "\u{0}\u{1}"] {
            std::fs::write(&file, broken).unwrap();
            let (read, warning) = RecentFiles::read(&file);
            assert!(read.paths().is_empty(), "{broken}");
            assert!(warning.is_some_and(|w| w.contains("ignored")), "{broken}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_list_lives_under_xdg_config_home_else_home() {
        let at = |x: Option<&str>, h: Option<&str>| recent_file(x, h).map(|p| p.display().to_string());
        assert_eq!(
            at(Some("/cfg"), Some("/home/u")).as_deref(),
            Some("/cfg/volcast/recent.json")
        );
        assert_eq!(
            at(None, Some("/home/u")).as_deref(),
            Some("/home/u/.config/volcast/recent.json")
        );
        assert_eq!(
            at(Some(""), Some("/home/u")).as_deref(),
            Some("/home/u/.config/volcast/recent.json")
        );
        assert_eq!(
            at(Some("rel"), Some("/home/u")).as_deref(),
            Some("/home/u/.config/volcast/recent.json")
        );
        assert_eq!(at(None, None), None);
    }
}
