//! A decoded file's level 0, kept in the pyramid cache. A file whose voxels must be decoded (a gzip NIfTI or NRRD, a
//! zlib MetaImage, a compressed or base64 `.vti` array, a DICOM series) cannot be read by box cheaply: a brick of a
//! deflate stream means inflating the file from its start. So while such a file is read into the held level
//! (`read::read_level`), each slab of level-0 voxels it decodes is also written, as the level holds the type (native
//! byte order; 32-bit integers and float64 as float32), at its place in `<key>.level0` beside the cache entry; that
//! file then lies in place like a raw file, and the finer levels' bricks are read from it by box (`finer::Finer`), as
//! an uncompressed file's are. The file is still decoded once. docs/large-volumes.md, "A decoded file's level 0".

use crate::formats::in_place::InPlace;
use crate::formats::Endian;
use crate::pyramid::budget::show;
use crate::volume::VoxelType;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::sync::mpsc::SyncSender;
use std::thread::JoinHandle;

/// Free space left on the cache's disk after level 0 is written: a cache never fills the disk.
pub const RESERVE: u64 = 1 << 30;

/// Whether level `level` of `place` keeps level 0 in the cache: a file that is decoded (not by box), of one step (the
/// finer levels of a series are not read by box), held at a coarser level. A rescaled file's level 0 is kept as
/// stored, as its levels are: the rescale stays the volume's.
pub fn applies(place: &InPlace, level: u32) -> bool {
    level > 0 && place.timesteps == 1 && !place.by_box()
}

/// The type level 0 is kept in: the one the level is made in (`read::level_data`).
pub fn kept_type(t: VoxelType) -> VoxelType {
    match t {
        VoxelType::U8 | VoxelType::I8 | VoxelType::U16 | VoxelType::I16 => t,
        _ => VoxelType::F32,
    }
}

/// Bytes of `place`'s level 0 as kept.
pub fn kept_bytes(place: &InPlace) -> u64 {
    place.dims.iter().map(|&d| u64::from(d)).product::<u64>() * kept_type(place.voxel_type).size() as u64
}

/// Level 0 being written, on its own thread so the read does not wait for the disk: slabs are sent in pieces of at
/// most [`Level0::PIECE`], at most [`Level0::QUEUED`] of them waiting (32 MiB), and written where they belong.
pub struct Level0 {
    partial: PathBuf,
    path: PathBuf,
    bytes: u64,
    queue: Option<SyncSender<(u64, Vec<u8>)>>,
    thread: Option<JoinHandle<std::io::Result<u64>>>,
}

impl Level0 {
    const PIECE: usize = 8 << 20;
    const QUEUED: usize = 4;

    /// Starts writing `bytes` of level 0 to `path` (through `<path>.partial`), where the disk has room for it and
    /// [`RESERVE`]; else why not.
    pub fn begin(path: PathBuf, bytes: u64) -> Result<Level0, String> {
        let folder = path.parent().unwrap_or(Path::new("."));
        room(bytes, free_bytes(folder), folder)?;
        let partial = path.with_extension("level0.partial");
        let file = std::fs::File::create(&partial).map_err(|e| format!("cannot write {}: {e}", partial.display()))?;
        let (queue, pieces) = std::sync::mpsc::sync_channel::<(u64, Vec<u8>)>(Level0::QUEUED);
        let thread = std::thread::spawn(move || {
            let mut written = 0;
            for (at, piece) in pieces {
                file.write_all_at(&piece, at)?;
                written += piece.len() as u64;
            }
            Ok(written)
        });
        Ok(Level0 {
            partial,
            path,
            bytes,
            queue: Some(queue),
            thread: Some(thread),
        })
    }

    /// Writes `bytes` at byte `at` of level 0 (any thread). A failed write is reported by [`finish`](Self::finish),
    /// never here: the read goes on.
    pub fn write_at(&self, at: u64, bytes: &[u8]) {
        let Some(queue) = &self.queue else { return };
        for (k, piece) in bytes.chunks(Level0::PIECE).enumerate() {
            // A send fails only once the thread has stopped on an error, which `finish` reports.
            if queue.send((at + (k * Level0::PIECE) as u64, piece.to_vec())).is_err() {
                return;
            }
        }
    }

    /// The kept level 0, once the read is over: every byte must have been written. A partial file is removed.
    pub fn finish(mut self) -> Result<PathBuf, String> {
        self.queue = None;
        let written = match self.thread.take().map(JoinHandle::join) {
            Some(Ok(written)) => written.map_err(|e| format!("cannot write {}: {e}", self.partial.display())),
            _ => Err("its writing thread panicked".into()),
        };
        let done = written.and_then(|n| match n == self.bytes {
            true => std::fs::rename(&self.partial, &self.path)
                .map_err(|e| format!("cannot write {}: {e}", self.path.display())),
            false => Err(format!("{n} of its {} bytes were written", self.bytes)),
        });
        if done.is_err() {
            let _ = std::fs::remove_file(&self.partial);
        }
        done.map(|_| self.path.clone())
    }
}

impl Drop for Level0 {
    /// A read that failed: the thread ends and the partial file goes.
    fn drop(&mut self) {
        self.queue = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
            let _ = std::fs::remove_file(&self.partial);
        }
    }
}

/// Refuses to write `need` bytes where `free` (None: unknown) leaves less than [`RESERVE`] in `folder`.
fn room(need: u64, free: Option<u64>, folder: &Path) -> Result<(), String> {
    match free {
        Some(free) if free < need.saturating_add(RESERVE) => Err(format!(
            "level 0 takes {}, and {} has {} free (volcast leaves {} of a disk free; --cache-dir names another)",
            show(need),
            folder.display(),
            show(free),
            show(RESERVE)
        )),
        _ => Ok(()),
    }
}

/// Bytes an unprivileged writer may still use on the file system holding `folder` (`None` where unknown).
#[cfg(target_os = "linux")]
fn free_bytes(folder: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let name = std::ffi::CString::new(folder.as_os_str().as_bytes()).ok()?;
    let mut st = std::mem::MaybeUninit::<libc::statvfs>::uninit();
    // SAFETY: `name` is a NUL-terminated path and `st` is writable memory the size of the struct statvfs fills.
    if unsafe { libc::statvfs(name.as_ptr(), st.as_mut_ptr()) } != 0 {
        return None;
    }
    // SAFETY: statvfs returned 0, so it filled `st`.
    let st = unsafe { st.assume_init() };
    // fsblkcnt_t and c_ulong are 32-bit on some Linux targets.
    #[allow(clippy::useless_conversion)]
    let (blocks, size) = (u64::from(st.f_bavail), u64::from(st.f_frsize));
    Some(blocks.saturating_mul(size))
}

#[cfg(not(target_os = "linux"))]
fn free_bytes(_folder: &Path) -> Option<u64> {
    None
}

/// The kept level 0 at `path` as a file in place: `place`'s voxels in the type they are kept in, native byte order,
/// from the file's first byte.
pub fn in_place(place: &InPlace, path: &Path) -> InPlace {
    InPlace {
        data_file: path.to_path_buf(),
        offset: 0,
        voxel_type: kept_type(place.voxel_type),
        endian: Endian::NATIVE,
        inflate: None,
        blocks: None,
        slices: None,
        notes: Vec::new(),
        arrays: Vec::new(),
        ..place.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disk_without_room_for_level_0_and_its_reserve_is_named() {
        let folder = Path::new("/cache/pyramids");
        assert!(room(1 << 30, Some(3 << 30), folder).is_ok());
        assert!(
            room(1 << 30, None, folder).is_ok(),
            "unknown free space: try, and a failed write is a note"
        );
        let e = room(16 << 30, Some(10 << 30), folder).unwrap_err();
        assert!(
            e.contains("level 0 takes 16.0 GiB, and /cache/pyramids has 10.0 GiB free"),
            "{e}"
        );
        assert!(
            room(2 << 30, Some((3 << 30) - 1), folder).is_err(),
            "the reserve is kept"
        );
        assert!(free_bytes(&std::env::temp_dir()).is_some_and(|b| b > 0));
    }

    /// Pieces written out of order, from several threads, land where they belong; a level 0 short of its bytes is
    /// not kept, and a read that failed leaves no partial file.
    #[test]
    fn level_0_is_kept_whole_or_not_at_all() {
        let dir = std::env::temp_dir().join(format!("volcast-level0-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bytes: Vec<u8> = (0..Level0::PIECE * 5 / 2 + 7).map(|i| (i % 251) as u8).collect();
        let l0 = Level0::begin(dir.join("k.level0"), bytes.len() as u64).unwrap();
        let half = bytes.len() / 2;
        std::thread::scope(|s| {
            s.spawn(|| l0.write_at(half as u64, &bytes[half..]));
            s.spawn(|| l0.write_at(0, &bytes[..half]));
        });
        let kept = l0.finish().unwrap();
        assert!(std::fs::read(&kept).unwrap() == bytes);
        let short = Level0::begin(dir.join("s.level0"), 100).unwrap();
        short.write_at(0, &[1; 60]);
        let e = short.finish().unwrap_err();
        assert!(e.contains("60 of its 100 bytes were written"), "{e}");
        let failed = Level0::begin(dir.join("f.level0"), 100).unwrap();
        failed.write_at(0, &[1; 60]);
        drop(failed);
        // A full disk (/dev/full refuses every write): the error, and nothing left.
        std::os::unix::fs::symlink("/dev/full", dir.join("d.level0.partial")).unwrap();
        let full = Level0::begin(dir.join("d.level0"), 100).unwrap();
        full.write_at(0, &[1; 100]);
        let e = full.finish().unwrap_err();
        assert!(e.contains("d.level0.partial: No space left on device"), "{e}");
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(left, vec![std::ffi::OsString::from("k.level0")]);
        std::fs::remove_dir_all(&dir).ok();
    }
}
