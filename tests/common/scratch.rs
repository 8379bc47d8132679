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

/// The raw file `raw` of `dims` voxels of NIfTI `datatype` (little-endian) as a NIfTI-1 file at `path` with the
/// rescale `slope_inter` (`scl_slope`, `scl_inter`), gzip-compressed if `path` ends in `.gz`, as nibabel writes one.
pub fn nifti(raw: &Path, dims: [u32; 3], datatype: i16, slope_inter: (f32, f32), path: &Path) {
    use std::io::Write;
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    let bits = match datatype {
        2 => 8i16,
        4 | 512 => 16,
        _ => 32,
    };
    for (i, d) in [3, dims[0], dims[1], dims[2], 1, 1, 1, 1].into_iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&(d as i16).to_le_bytes());
    }
    h[70..72].copy_from_slice(&datatype.to_le_bytes());
    h[72..74].copy_from_slice(&bits.to_le_bytes());
    for (i, p) in [1.0f32, 1.0, 1.0, 1.0].into_iter().enumerate() {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&p.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[112..116].copy_from_slice(&slope_inter.0.to_le_bytes());
    h[116..120].copy_from_slice(&slope_inter.1.to_le_bytes());
    h[123] = 2;
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend(std::fs::read(raw).expect("the raw file"));
    let bytes = if path.extension().is_some_and(|e| e == "gz") {
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(&h).unwrap();
        e.finish().unwrap()
    } else {
        h
    };
    std::fs::write(path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}
