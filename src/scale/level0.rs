//! A compressed file's level 0, kept in the pyramid cache. A deflate stream cannot be read by box, so a gzip NIfTI or
//! NRRD, or a zlib MetaImage, held at a coarser level would never show its finer levels. While the stream is decoded
//! into the held level (`read::read_level`), its voxel bytes are copied as they are, in the file's byte order, to
//! `<key>.level0` beside the cache entry ([`Tee`]); that file then lies in place like a raw file, and the finer levels'
//! bricks are read from it by box (`finer::Finer`), as an uncompressed file's are. The stream is still decoded once.
//! docs/large-volumes.md, "Full resolution from the file".

use crate::convert::source::Tee;
use crate::volume::budget::show;
use crate::volume::in_place::InPlace;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Free space left on the cache's disk after level 0 is written: a cache never fills the disk.
pub const RESERVE: u64 = 1 << 30;

/// Whether level `level` of `place` keeps level 0 in the cache: a compressed stream of one step, not rescaled (the
/// finer levels of a series or a rescaled file are not read by box), held at a coarser level.
pub fn applies(place: &InPlace, level: u32) -> bool {
    place.inflate.is_some() && level > 0 && place.timesteps == 1 && place.scaling.is_identity()
}

/// Level 0 being written: the file being written and the one it becomes when whole.
pub struct Level0 {
    partial: PathBuf,
    path: PathBuf,
    bytes: u64,
}

impl Level0 {
    /// Starts writing `bytes` of level 0 to `path` (through `<path>.partial`), where the disk has room for it and
    /// [`RESERVE`]; the tee to give the stream (`Source::tee_stream`), or why not.
    pub fn begin(path: PathBuf, bytes: u64) -> Result<(Level0, Tee), String> {
        let folder = path.parent().unwrap_or(Path::new("."));
        room(bytes, free_bytes(folder), folder)?;
        let partial = path.with_extension("level0.partial");
        let file = std::fs::File::create(&partial).map_err(|e| format!("cannot write {}: {e}", partial.display()))?;
        let tee = Tee::new(Box::new(Behind::new(BufWriter::with_capacity(1 << 20, file))));
        Ok((Level0 { partial, path, bytes }, tee))
    }

    /// The kept level 0, once the stream was read: `tee` (taken back from the stream) must have copied every byte.
    /// A partial file is removed.
    pub fn finish(self, tee: Option<Tee>) -> Result<PathBuf, String> {
        let done = match tee.map(Tee::finish) {
            Some(Ok(n)) if n == self.bytes => std::fs::rename(&self.partial, &self.path)
                .map_err(|e| format!("cannot write {}: {e}", self.path.display())),
            Some(Ok(n)) => Err(format!("{n} of its {} bytes were copied", self.bytes)),
            Some(Err(e)) => Err(format!("cannot write {}: {e}", self.partial.display())),
            None => Err("its stream was not copied".into()),
        };
        if done.is_err() {
            let _ = std::fs::remove_file(&self.partial);
        }
        done.map(|_| self.path)
    }
}

/// A writer that writes on its own thread, so the stream's decode does not wait for the disk: what is written is
/// sent in pieces of at most [`Behind::PIECE`], at most [`Behind::QUEUED`] of them waiting (32 MiB). The first error
/// is returned by the write after it, or by `flush`, which waits for every piece and ends the thread.
struct Behind {
    queue: Option<std::sync::mpsc::SyncSender<Vec<u8>>>,
    thread: Option<std::thread::JoinHandle<std::io::Result<()>>>,
}

impl Behind {
    const PIECE: usize = 8 << 20;
    const QUEUED: usize = 4;

    fn new(mut out: impl Write + Send + 'static) -> Behind {
        let (queue, pieces) = std::sync::mpsc::sync_channel::<Vec<u8>>(Behind::QUEUED);
        let thread = std::thread::spawn(move || {
            for piece in pieces {
                out.write_all(&piece)?;
            }
            out.flush()
        });
        Behind {
            queue: Some(queue),
            thread: Some(thread),
        }
    }

    /// Waits for the thread: its error, or `Ok` once everything sent was written.
    fn join(&mut self) -> std::io::Result<()> {
        self.queue = None;
        match self.thread.take().map(|t| t.join()) {
            Some(Ok(done)) => done,
            Some(Err(_)) => Err(std::io::Error::other("the writing thread panicked")),
            None => Err(std::io::Error::other("written after the end")),
        }
    }
}

impl Write for Behind {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        let piece = &bytes[..bytes.len().min(Behind::PIECE)];
        let sent = self.queue.as_ref().map(|q| q.send(piece.to_vec()));
        match sent {
            Some(Ok(())) => Ok(piece.len()),
            // The thread ended: it failed.
            _ => self.join().and(Err(std::io::Error::other("the writing thread ended"))),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.join()
    }
}

impl Drop for Behind {
    fn drop(&mut self) {
        let _ = self.join();
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

/// The kept level 0 at `path` as a file in place: `place`'s voxels, uncompressed, from the file's first byte.
pub fn in_place(place: &InPlace, path: &Path) -> InPlace {
    InPlace {
        data_file: path.to_path_buf(),
        offset: 0,
        inflate: None,
        blocks: None,
        slices: None,
        notes: Vec::new(),
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

    /// A writer that fails after `room` bytes, as a full disk does.
    struct Full {
        room: usize,
    }

    impl Write for Full {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            if self.room == 0 {
                return Err(std::io::Error::from_raw_os_error(libc::ENOSPC));
            }
            let n = b.len().min(self.room);
            self.room -= n;
            Ok(n)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_full_disk_leaves_no_partial_level_0_and_says_why() {
        let dir = std::env::temp_dir().join(format!("volcast-level0-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (l0, _) = Level0::begin(dir.join("k.level0"), 100).unwrap();
        let partial = dir.join("k.level0.partial");
        assert!(partial.exists());
        let mut failing = Tee::new(Box::new(Full { room: 60 }));
        failing.keep(0, &[7; 100]);
        let e = l0.finish(Some(failing)).unwrap_err();
        assert!(e.contains("k.level0.partial: No space left on device"), "{e}");
        assert!(!partial.exists() && !dir.join("k.level0").exists());
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A `Vec` the writing thread fills and the test reads after.
    struct Shared(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

    impl Write for Shared {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn the_writing_thread_keeps_the_order_and_reports_a_full_disk() {
        let seen = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let mut behind = Behind::new(Shared(seen.clone()));
        let bytes: Vec<u8> = (0..Behind::PIECE * 5 / 2 + 7).map(|i| (i % 251) as u8).collect();
        behind.write_all(&bytes).unwrap();
        behind.write_all(&bytes[..3]).unwrap();
        behind.flush().unwrap();
        assert!(*seen.lock().unwrap() == [&bytes[..], &bytes[..3]].concat());
        assert!(behind.write(b"late").is_err(), "nothing is written after the end");
        let mut full = Behind::new(Full { room: 60 });
        let sent = full.write_all(&[1; 100]);
        let e = sent.and_then(|_| full.flush()).unwrap_err();
        assert_eq!(e.raw_os_error(), Some(libc::ENOSPC), "{e}");
    }
}
