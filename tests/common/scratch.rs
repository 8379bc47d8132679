//! Folders under `target/tmp` (cargo's `CARGO_TARGET_TMPDIR`) for the files tests write: volumes to read, images
//! to compare.

use std::collections::BTreeSet;
use std::ops::Deref;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// A test's folder: `target/tmp/NAME`.
pub struct Scratch(PathBuf);

impl Scratch {
    /// Writes `bytes` to `NAME` in the folder (subfolders in `NAME` made as needed) and returns its path.
    pub fn write(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let path = self.0.join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).unwrap_or_else(|e| panic!("{}: {e}", parent.display()));
        }
        std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        path
    }
}

impl Deref for Scratch {
    type Target = Path;

    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

/// The folder `target/tmp/NAME`, emptied the first time this test binary asks for `name` and shared by every
/// later ask: a test that wants the folder to itself gives its own name. It is kept after the run, so a person
/// can look at what the tests wrote.
pub fn scratch(name: &str) -> Scratch {
    static HANDED_OUT: Mutex<BTreeSet<String>> = Mutex::new(BTreeSet::new());
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    // A test that failed while holding the lock left the set as it was: still right.
    let mut handed_out = HANDED_OUT.lock().unwrap_or_else(|e| e.into_inner());
    if handed_out.insert(name.to_string()) {
        let _ = std::fs::remove_dir_all(&dir);
    }
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    Scratch(dir)
}

/// Writes a raw volume of `dims` (x fastest) to `path`: `voxel(index, p, out)` appends voxel `index`'s bytes to
/// `out`, `p` being its position in [-0.5, 0.5) along each axis.
pub fn write_raw(path: &Path, dims: [usize; 3], voxel: impl Fn([usize; 3], [f64; 3], &mut Vec<u8>)) {
    let mut bytes = Vec::with_capacity(dims.iter().product::<usize>() * 2);
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let p = [x, y, z].map(|i| i as f64);
                let p = [0, 1, 2].map(|i| p[i] / dims[i] as f64 - 0.5);
                voxel([x, y, z], p, &mut bytes);
            }
        }
    }
    std::fs::write(path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

/// The raw file `raw` of `dims` voxels of NRRD `type_name` (little-endian) as a gzip NRRD at `path` (header and
/// data in one file, as pynrrd and Slicer write it): a compressed stream volcast decodes front to back.
pub fn gzip_nrrd(raw: &Path, dims: [u32; 3], type_name: &str, path: &Path) {
    use std::io::Write;
    let [x, y, z] = dims;
    let mut out =
        format!("NRRD0004\ntype: {type_name}\ndimension: 3\nsizes: {x} {y} {z}\nencoding: gzip\nendian: little\n\n")
            .into_bytes();
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(&std::fs::read(raw).expect("the raw file")).unwrap();
    out.extend(e.finish().unwrap());
    std::fs::write(path, out).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}
