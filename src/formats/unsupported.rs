//! Formats volcast does not read, recognised so they are named instead of being read as raw and refused with a
//! size mismatch. Consulted after every supported format (magic bytes, then extensions) and before the raw
//! fallback; a file named like a raw file (`NAME_WxHxD_TYPE`, `.raw`) is never judged here.

use std::path::Path;

/// What a file is, for "NAME is KIND; volcast cannot read WHAT".
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Kind {
    pub kind: String,
    pub what: String,
}

fn kind(kind: &str, what: &str) -> Option<Kind> {
    Some(Kind {
        kind: kind.to_string(),
        what: what.to_string(),
    })
}

const HDF5_MAGIC: &[u8] = b"\x89HDF\r\n\x1a\n";

/// A file whose first bytes (`prefix`, up to 512) or name say it is a format volcast does not read.
pub(crate) fn identify(path: &Path, prefix: &[u8]) -> Option<Kind> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let ext = |e: &str| name.ends_with(e);
    // MATLAB first: a v7.3 MAT-file is HDF5 after a 512-byte text header.
    if prefix.starts_with(b"MATLAB 5.0 MAT-file") || prefix.starts_with(b"MATLAB 7.3 MAT-file") {
        return kind("a MATLAB MAT-file", "MATLAB MAT-files");
    }
    if prefix.starts_with(HDF5_MAGIC) {
        return if ext(".nc") || ext(".nc4") || ext(".cdf") {
            kind("a NetCDF-4 file (HDF5)", "NetCDF")
        } else if ext(".mnc") {
            kind("a MINC2 file (HDF5)", "MINC")
        } else {
            kind("an HDF5 file", "HDF5")
        };
    }
    if prefix.starts_with(b"CDF\x01") || prefix.starts_with(b"CDF\x02") || prefix.starts_with(b"CDF\x05") {
        return if ext(".mnc") {
            kind("a MINC1 file (NetCDF)", "MINC")
        } else {
            kind("a NetCDF file", "NetCDF")
        };
    }
    if prefix.starts_with(b"\x93NUMPY") {
        return kind("a NumPy .npy array", "NumPy files");
    }
    if prefix.starts_with(b"PK\x03\x04") || prefix.starts_with(b"PK\x05\x06") {
        return if ext(".npz") {
            kind("a NumPy .npz archive (ZIP)", "NumPy files")
        } else {
            kind("a ZIP archive", "ZIP archives: unpack it first")
        };
    }
    if prefix.starts_with(b"\x89PNG\r\n\x1a\n") {
        return kind("a PNG image", "PNG (a single 2-D image is not a volume)");
    }
    if prefix.starts_with(b"\xff\xd8\xff") {
        return kind("a JPEG image", "JPEG (a single 2-D image is not a volume)");
    }
    if prefix.starts_with(b"GIF87a") || prefix.starts_with(b"GIF89a") {
        return kind("a GIF image", "GIF (a single 2-D image is not a volume)");
    }
    if prefix.starts_with(b"SIMPLE  =") {
        return kind("a FITS file", "FITS");
    }
    if prefix.starts_with(b"ply\n") || prefix.starts_with(b"ply\r\n") {
        return kind("a PLY mesh", "meshes (PLY)");
    }
    if prefix.starts_with(b"solid ") || ext(".stl") {
        return kind("an STL mesh", "meshes (STL)");
    }
    if ext(".obj") {
        return kind("a Wavefront OBJ mesh", "meshes (OBJ)");
    }
    // MRC2014 / CCP4: "MAP " at byte 208.
    if (prefix.len() >= 212 && &prefix[208..212] == b"MAP ")
        || [".mrc", ".mrcs", ".ccp4", ".map", ".rec"].iter().any(|e| ext(e))
    {
        return kind("an MRC/CCP4 map", "MRC/CCP4");
    }
    if ext(".gipl") || ext(".gipl.gz") {
        return kind("a GIPL image", "GIPL");
    }
    // Analyze/NIfTI pair: the .hdr is the file to open.
    if ext(".img") {
        let hdr = path.with_extension("hdr");
        if hdr.is_file() {
            return kind(
                "the data half of an Analyze/NIfTI-1 .hdr/.img pair",
                &format!(
                    "the .img alone: open {} instead",
                    hdr.file_name()
                        .map(|n| n.to_string_lossy().into_owned())
                        .unwrap_or_default()
                ),
            );
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magic_bytes_and_names() {
        let p = Path::new;
        let cases: [(&str, &[u8], &str); 12] = [
            ("brain.h5", b"\x89HDF\r\n\x1a\n\0\0", "an HDF5 file"),
            ("t.nc", b"\x89HDF\r\n\x1a\n\0\0", "a NetCDF-4 file (HDF5)"),
            ("t.mnc", b"\x89HDF\r\n\x1a\n\0\0", "a MINC2 file (HDF5)"),
            ("t.bin", b"CDF\x01\0\0", "a NetCDF file"),
            ("t.npy", b"\x93NUMPY\x01\0", "a NumPy .npy array"),
            ("t.zip", b"PK\x03\x04", "a ZIP archive"),
            ("t", b"\x89PNG\r\n\x1a\n", "a PNG image"),
            ("t", b"\xff\xd8\xff\xe0", "a JPEG image"),
            ("t.fits", b"SIMPLE  =                    T", "a FITS file"),
            ("t", b"ply\nformat ascii 1.0\n", "a PLY mesh"),
            ("t.stl", b"\x00\x00", "an STL mesh"),
            ("t.mat", b"MATLAB 5.0 MAT-file, Platform", "a MATLAB MAT-file"),
        ];
        for (name, bytes, want) in cases {
            assert_eq!(
                identify(p(name), bytes).map(|k| k.kind),
                Some(want.to_string()),
                "{name}"
            );
        }
        assert_eq!(identify(p("plain.dat"), &[1, 2, 3, 4]), None);
        assert_eq!(identify(p("lone.img"), &[1, 2, 3, 4]), None);
    }
}
