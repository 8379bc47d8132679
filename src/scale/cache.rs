//! The pyramid cache: a level that a file read in place was shown at, kept on disk as an OME-Zarr store (written by
//! `volcast convert`'s writer: zstd, 64³ chunks, with its own coarser levels), so the next open of the same file at
//! that level reads the store instead of the file. The store is a standard OME-Zarr 0.5 one.
//!
//! An entry is `<cache>/pyramids/<key>.ome.zarr`, its stamp `<key>.json` and, for a level whose finer levels are
//! read by box, level 0's value range per cell `<key>.cells` (`volume::cells`, made by the pass that read the level:
//! which finer bricks can show anything is known before they are read). A decoded file (compressed, or a DICOM
//! series) held at a coarser level also keeps its level 0 there as raw bytes, `<key>.level0` (`scale::level0`: its
//! finer bricks are read from it). The key hashes what makes the level (the data file's canonical path, where its
//! voxels start, their layout, the level); the stamp records what says the file is unchanged (its length and
//! modification time), the cache's version and whether level 0 was kept, and is written last, so an entry without
//! one is unfinished. A stale, corrupt or other-version entry is rebuilt with a note; a cache folder that cannot be
//! written is a note, never an error: the volume is shown all the same.

use super::level0::{self, Level0};
use crate::convert::layout::OmeVersion;
use crate::convert::source::Source;
use crate::convert::{convert, Compression, ConvertOptions};
use crate::formats;
use crate::formats::in_place::InPlace;
use crate::formats::OpenOptions;
use crate::pyramid::reduce::Reduce;
use crate::volume::cells::CellRanges;
use crate::volume::Volume;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::UNIX_EPOCH;

/// Changes whenever what a cached level holds would change (the pyramid's rule, the store's layout, what is kept
/// beside it: level 0's ranges per cell since version 3).
pub const CACHE_VERSION: u32 = 3;

/// Where the cache lives: `--cache-dir`, else `$XDG_CACHE_HOME/volcast`, else `~/.cache/volcast`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PyramidCache {
    pub root: PathBuf,
}

/// What a stamp says of the file its entry was made from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Stamp {
    version: u32,
    file: String,
    len: u64,
    modified_ns: u128,
    level: u32,
    dims: [u32; 3],
    /// Level 0's stored value range (the level normalises by it); not part of the file's identity.
    #[serde(default)]
    stored_range: Option<[f64; 2]>,
    /// For a decoded file (`level0::applies`): whether its level 0 was kept beside the entry; `None` in an entry
    /// made before level 0 was kept. Not part of the file's identity.
    #[serde(default)]
    level0: Option<bool>,
}

/// What looking a level up found.
pub enum Lookup {
    /// The level, read from the store.
    Hit(Box<Volume>),
    /// No usable entry; `note` says why an entry that was there was not used.
    Miss { note: Option<String> },
}

impl PyramidCache {
    /// The default folder (see the type's description).
    pub fn default_root() -> PathBuf {
        let base = std::env::var_os("XDG_CACHE_HOME")
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
            .unwrap_or_else(std::env::temp_dir);
        base.join("volcast")
    }

    pub fn new(root: Option<PathBuf>) -> PyramidCache {
        PyramidCache {
            root: root.unwrap_or_else(PyramidCache::default_root),
        }
    }

    fn folder(&self) -> PathBuf {
        self.root.join("pyramids")
    }

    /// The entry's store and stamp for level `level` of `place`.
    fn entry(&self, place: &InPlace, level: u32) -> (PathBuf, PathBuf) {
        let path = std::fs::canonicalize(&place.data_file).unwrap_or_else(|_| place.data_file.clone());
        // A folder of several DICOM series keeps an entry per series.
        let series = place.slices.as_ref().map_or("", |s| s.uid());
        let what = format!(
            "{}{series}|{}|{:?}|{:?}|{:?}|{}|{level}|{CACHE_VERSION}",
            path.display(),
            place.offset,
            place.dims,
            place.voxel_type,
            place.endian,
            place.timesteps
        );
        let key = format!("{:016x}", fnv1a(what.as_bytes()));
        let dir = self.folder();
        (dir.join(format!("{key}.ome.zarr")), dir.join(format!("{key}.json")))
    }

    /// Where level 0's ranges per cell are kept beside an entry's stamp.
    fn cells_path(stamp: &Path) -> PathBuf {
        stamp.with_extension("cells")
    }

    /// Where a decoded file's level 0 is kept beside an entry's stamp (`scale::level0`).
    fn level0_path(stamp: &Path) -> PathBuf {
        stamp.with_extension("level0")
    }

    /// Starts keeping level 0 of `place`, decoded into level `level`, beside that level's entry (whose stamp is
    /// removed first: the entry is being made again); else why not.
    pub fn begin_level0(&self, place: &InPlace, level: u32) -> Result<Level0, String> {
        std::fs::create_dir_all(self.folder())
            .map_err(|e| format!("cannot make the folder {}: {e}", self.folder().display()))?;
        let stamp = self.entry(place, level).1;
        let _ = std::fs::remove_file(&stamp);
        // An older entry's level 0 is never left to pass for this one's.
        let _ = std::fs::remove_file(PyramidCache::level0_path(&stamp));
        Level0::begin(PyramidCache::level0_path(&stamp), level0::kept_bytes(place))
    }

    /// The level 0 of `place` kept beside its level `level`'s entry, if it is there whole (its length is the step's).
    pub fn kept_level0(&self, place: &InPlace, level: u32) -> Option<PathBuf> {
        let path = PyramidCache::level0_path(&self.entry(place, level).1);
        let len = std::fs::metadata(&path).ok()?.len();
        (len == level0::kept_bytes(place)).then_some(path)
    }

    /// Level 0's ranges per cell kept beside the entry whose stamp is `stamp`, as `read::read_level` made them for
    /// level `level` of `place` (cells of 8 voxels of that level); `None` if absent or not what they must be.
    fn cells(stamp: &Path, place: &InPlace, level: u32) -> Option<CellRanges> {
        let path = PyramidCache::cells_path(stamp);
        let cell = crate::pyramid::bricks::to_level0(CellRanges::SIDE, level);
        // The length is known before anything is read: a foreign or truncated file allocates nothing.
        if std::fs::metadata(&path).ok()?.len() != CellRanges::byte_len(place.dims, cell) {
            return None;
        }
        CellRanges::from_bytes(&std::fs::read(&path).ok()?, place.dims).filter(|c| c.cell == cell)
    }

    /// What the stamp of level `level` of `place` must say now.
    fn stamp(place: &InPlace, level: u32) -> Option<Stamp> {
        let (len, modified_ns) = match &place.slices {
            // A DICOM series: its files together.
            Some(series) => series.identity()?,
            None => {
                let meta = std::fs::metadata(&place.data_file).ok()?;
                (
                    meta.len(),
                    meta.modified().ok()?.duration_since(UNIX_EPOCH).ok()?.as_nanos(),
                )
            }
        };
        Some(Stamp {
            version: CACHE_VERSION,
            file: place.data_file.display().to_string(),
            len,
            modified_ns,
            level,
            dims: crate::pyramid::geometry::level_dims(place.dims, level),
            stored_range: None,
            level0: None,
        })
    }

    /// The store of level `level` of `place` and the level's size, if its entry's stamp says it was made from the file
    /// as it is now; else why not (`None`: there is no entry).
    fn valid(&self, place: &InPlace, level: u32) -> Result<(PathBuf, Stamp), Option<String>> {
        let (store, stamp_path) = self.entry(place, level);
        let text = std::fs::read_to_string(&stamp_path).map_err(|_| None)?;
        let found: Option<Stamp> = serde_json::from_str(&text).ok();
        let now = PyramidCache::stamp(place, level).map(|n| Stamp {
            stored_range: found.as_ref().and_then(|f| f.stored_range),
            level0: found.as_ref().and_then(|f| f.level0),
            ..n
        });
        let why = match (&found, &now) {
            (None, _) => "its stamp is unreadable",
            (Some(f), _) if f.version != CACHE_VERSION => "it was written by another version of volcast",
            (Some(f), Some(n)) if f != n => "the file changed since it was made",
            (Some(f), Some(_)) => return Ok((store, f.clone())),
            (_, None) => "the file's size and time cannot be read",
        };
        Err(Some(format!(
            "the pyramid cache's entry {} was not used ({why}): rebuilt",
            store.display()
        )))
    }

    /// Level `level` of `place` from the cache, if an entry for the file as it is now is there and reads back.
    pub fn lookup(&self, place: &InPlace, level: u32) -> Lookup {
        let (store, stamp) = match self.valid(place, level) {
            Ok(found) => found,
            Err(note) => return Lookup::Miss { note },
        };
        let store_label = store.display();
        // A level whose finer levels stay in the file needs level 0's ranges (which of their bricks can show
        // anything); an entry without them is read again, once.
        let cells = PyramidCache::cells(&self.entry(place, level).1, place, level).map(std::sync::Arc::new);
        let decoded = level0::applies(place, level);
        if (place.by_box() && level > 0 || decoded) && cells.is_none() {
            return Lookup::Miss {
                note: Some(format!(
                    "the pyramid cache's entry {store_label} has no readable level-0 ranges beside it: rebuilt"
                )),
            };
        }
        let why_not = match stamp.level0 {
            None if decoded => Some("it was made before volcast kept a decoded file's level 0"),
            Some(true) if self.kept_level0(place, level).is_none() => Some("its level 0 is missing or cut short"),
            _ => None,
        };
        if let Some(why) = why_not {
            return Lookup::Miss {
                note: Some(format!(
                    "the pyramid cache's entry {store_label} was not used ({why}): rebuilt"
                )),
            };
        }
        match formats::open(&store, &OpenOptions::default()) {
            Ok(v) if v.dims == stamp.dims => {
                let mut v = match stamp.stored_range {
                    Some(r) => v.with_stored_range(r),
                    None => v,
                };
                v.name = place.name.clone();
                v.format = place.format.to_string();
                v.notes = vec![format!("read from the pyramid cache ({store_label})")];
                v.cells = cells;
                Lookup::Hit(Box::new(v))
            }
            Ok(v) => Lookup::Miss {
                note: Some(format!(
                    "the pyramid cache's entry {store_label} holds {:?}, not the level's size: rebuilt",
                    v.dims
                )),
            },
            Err(e) => Lookup::Miss {
                note: Some(format!(
                    "the pyramid cache's entry {store_label} is corrupt ({e}): rebuilt"
                )),
            },
        }
    }

    /// A preview of level `level` of `place` from its cache entry's own coarser levels: the finest of them with at
    /// most `side` voxels per axis, if the entry is valid and reads.
    pub fn preview(&self, place: &InPlace, level: u32, side: u32) -> Option<Volume> {
        let (store, _) = self.valid(place, level).ok()?;
        let opts = OpenOptions {
            max_dim: Some(side),
            ..Default::default()
        };
        let mut v = formats::open(&store, &opts).ok()?;
        let [x, y, z] = v.dims;
        v.name = place.name.clone();
        v.format = place.format.to_string();
        v.notes = vec![format!(
            "a preview from the pyramid cache ({x}x{y}x{z}) while the level is read"
        )];
        Some(v.stand_in_for(&place.geometry, 1.0))
    }

    /// Keeps `v`, level `level` of `place`, in the cache, and gives it back; the error says why it could not (the
    /// caller notes it). A rescaled file's level is kept as its stored values with the rescale in volcast's metadata
    /// (`ConvertOptions::stored`): read back, it is the level read from the file, in the values its finer bricks are
    /// read in.
    pub fn store(&self, place: &InPlace, level: u32, v: Volume) -> (Volume, Result<(), String>) {
        let (store, stamp_path) = self.entry(place, level);
        let Some(mut stamp) = PyramidCache::stamp(place, level) else {
            return (v, Err("the file's size and time cannot be read".into()));
        };
        let fail = |what: &str, e: &dyn std::fmt::Display| format!("{what} {}: {e}", store.display());
        let made = std::fs::create_dir_all(self.folder())
            .map_err(|e| fail("cannot make the folder of", &e))
            .and_then(|_| {
                let _ = std::fs::remove_file(&stamp_path);
                if store.exists() {
                    std::fs::remove_dir_all(&store).map_err(|e| fail("cannot remove the old entry", &e))?;
                }
                std::fs::create_dir(&store).map_err(|e| fail("cannot write", &e))
            });
        if let Err(e) = made {
            let _ = std::fs::remove_file(PyramidCache::level0_path(&stamp_path));
            return (v, Err(e));
        }
        let opts = ConvertOptions {
            version: OmeVersion::V05,
            chunk: 64,
            shard: None,
            compression: Compression::Zstd,
            reduce: Reduce::Mean,
            step: None,
            stored: true,
        };
        stamp.stored_range = Some(v.stored_range);
        stamp.level0 = level0::applies(place, level).then(|| self.kept_level0(place, level).is_some());
        let level0_path = PyramidCache::level0_path(&stamp_path);
        let cells_path = PyramidCache::cells_path(&stamp_path);
        let _ = std::fs::remove_file(&cells_path);
        let kept_cells = match &v.cells {
            Some(c) => std::fs::write(&cells_path, c.to_bytes()).map_err(|e| fail("cannot write the ranges of", &e)),
            None => Ok(()),
        };
        if let Err(e) = kept_cells {
            let _ = std::fs::remove_file(&level0_path);
            return (v, Err(e));
        }
        let source = Source::Loaded(Box::new(v));
        let written = convert(&source, &store, &opts, &mut |_| {}).map_err(|e| fail("cannot write", &e));
        let Source::Loaded(v) = source else {
            unreachable!("the source was made loaded above")
        };
        let stamped = written.and_then(|_| {
            let text = serde_json::to_string_pretty(&stamp).map_err(|e| fail("cannot stamp", &e))?;
            // The stamp last, through a rename: an entry without one (a full disk, a killed process) is not used.
            let partial = stamp_path.with_extension("json.partial");
            std::fs::write(&partial, text)
                .and_then(|_| std::fs::rename(&partial, &stamp_path))
                .map_err(|e| {
                    let _ = std::fs::remove_file(&partial);
                    fail("cannot stamp", &e)
                })
        });
        if stamped.is_err() {
            let _ = std::fs::remove_dir_all(&store);
            let _ = std::fs::remove_file(&cells_path);
            // A reader that opened it keeps reading it: the file goes when the last handle closes.
            let _ = std::fs::remove_file(&level0_path);
        }
        (*v, stamped)
    }

    /// Empties the cache's pyramids; returns the bytes freed.
    pub fn clear(&self) -> std::io::Result<u64> {
        let dir = self.folder();
        if !dir.exists() {
            return Ok(0);
        }
        let bytes = folder_bytes(&dir);
        std::fs::remove_dir_all(&dir)?;
        Ok(bytes)
    }

    /// The entries (stores) and the bytes they take.
    pub fn usage(&self) -> (usize, u64) {
        let dir = self.folder();
        let entries = std::fs::read_dir(&dir)
            .map(|d| {
                d.flatten()
                    .filter(|e| e.path().extension().is_some_and(|x| x == "zarr"))
                    .count()
            })
            .unwrap_or(0);
        (entries, folder_bytes(&dir))
    }
}

fn folder_bytes(dir: &Path) -> u64 {
    let Ok(entries) = std::fs::read_dir(dir) else { return 0 };
    entries
        .flatten()
        .map(|e| match e.file_type() {
            Ok(t) if t.is_dir() => folder_bytes(&e.path()),
            Ok(_) => e.metadata().map_or(0, |m| m.len()),
            Err(_) => 0,
        })
        .sum()
}

/// 64-bit FNV-1a: a stable hash (std's is not stable across Rust versions, and the key must be).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::in_place::in_place;

    #[test]
    fn a_kept_level_reads_back_whole_and_as_a_preview() {
        let dims = [40u32, 30, 20];
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let src: Vec<i16> = (0..n).map(|i| ((i * 31) % 997) as i16 - 400).collect();
        let (path, opts) = crate::scale::test_file::int16_raw("cache", dims, &src, Some([0.5, 1.0, 2.0]));
        let folder = path.parent().unwrap().to_path_buf();
        let cache = PyramidCache::new(Some(folder.join("cache")));
        let place = in_place(&path, &opts).unwrap().unwrap();
        let source = Source::in_place(place.clone()).unwrap();
        let level = crate::scale::read::read_level(&source, 1, 1 << 30, Vec::new(), &mut |_| {}).unwrap();
        assert!(matches!(cache.lookup(&place, 1), Lookup::Miss { note: None }));
        let (level, kept) = cache.store(&place, 1, level);
        kept.unwrap();
        let Lookup::Hit(back) = cache.lookup(&place, 1) else {
            panic!("no hit after the store")
        };
        assert_eq!(back.dims, level.dims);
        assert_eq!(back.geometry, level.geometry);
        assert!(level.cells.is_some(), "the read pass made level 0's ranges");
        assert_eq!(back.cells, level.cells, "level 0's ranges are kept beside the entry");
        let [w, h, d] = level.dims;
        for (x, y, z) in [(0, 0, 0), (w - 1, h - 1, d - 1), (7, 3, 5)] {
            assert_eq!(back.value(x, y, z), level.value(x, y, z), "({x}, {y}, {z})");
        }
        // Level 1 is 20x15x10, the store's only level (it is under 64³): a preview of at most 8 per axis is it, halved.
        let preview = cache.preview(&place, 1, 8).expect("a preview");
        assert!(preview.dims.iter().all(|&s| s <= 8), "{:?}", preview.dims);
        assert!(preview.notes[0].starts_with("a preview from the pyramid cache"));
        // Ranges cut short (a full disk, another program): the entry is read again, with a note, never trusted.
        let cells = PyramidCache::cells_path(&cache.entry(&place, 1).1);
        let bytes = std::fs::read(&cells).unwrap();
        std::fs::write(&cells, &bytes[..bytes.len() - 16]).unwrap();
        let Lookup::Miss { note: Some(note) } = cache.lookup(&place, 1) else {
            panic!("a hit without level 0's ranges")
        };
        assert!(note.contains("no readable level-0 ranges"), "{note}");
        std::fs::remove_dir_all(&folder).ok();
    }

    #[test]
    fn a_rescaled_level_is_kept_as_stored_with_its_rescale() {
        // A NIfTI with a negative slope: the store holds the stored int16 values, volcast's metadata the rescale.
        let dims = [36u32, 20, 18];
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let src: Vec<i16> = (0..n).map(|i| ((i * 37) % 1201) as i16 - 600).collect();
        let dir = std::env::temp_dir().join(format!("volcast-cache-rescaled-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("v.nii");
        let header = [3i16, 36, 20, 18, 1, 1, 1, 1];
        let bytes = crate::formats::nifti::tests::nifti_bytes(
            &header,
            4,
            [1.0; 3],
            (-0.5, 100.0),
            false,
            bytemuck::cast_slice(&src),
        );
        std::fs::write(&path, bytes).unwrap();
        let cache = PyramidCache::new(Some(dir.join("cache")));
        let opts = OpenOptions::default();
        let place = in_place(&path, &opts).unwrap().unwrap();
        assert!(place.by_box(), "a rescale does not keep the finer levels in the file");
        let source = Source::in_place(place.clone()).unwrap();
        let level = crate::scale::read::read_level(&source, 1, 1 << 30, Vec::new(), &mut |_| {}).unwrap();
        let (level, kept) = cache.store(&place, 1, level);
        kept.unwrap();
        let Lookup::Hit(back) = cache.lookup(&place, 1) else {
            panic!("a rescaled level is kept")
        };
        assert_eq!((back.scaling, back.range), (level.scaling, level.range));
        assert_eq!((back.source_type, back.data == level.data), (level.source_type, true));
        assert_eq!(level.value(3, 2, 1), -0.5 * level.stored(3, 2, 1) + 100.0);
        let preview = cache.preview(&place, 1, 9).expect("a preview");
        assert_eq!(preview.scaling, level.scaling, "the preview is rescaled too");
        std::fs::remove_dir_all(&dir).ok();
    }
}
