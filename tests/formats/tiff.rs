//! TIFF stacks against files written by tifffile and read back by it (tests/data/tiff/expected.json, made by
//! tests/data/tiff/make.py); hostile TIFFs built byte by byte; formats volcast does not read named, through
//! `formats::open` and through the `volcast` binary.

use crate::common;

use serde_json::Value;
use std::path::{Path, PathBuf};
use volcast::formats;
use volcast::formats::{Format, OpenOptions, RawOptions};
use volcast::volume::{Volume, VoxelType};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/tiff").join(name)
}

fn err(path: &Path) -> String {
    match formats::open(path, &OpenOptions::default()) {
        Ok(v) => panic!("{} loaded as {:?} {}", path.display(), v.dims, v.format),
        Err(e) => e.to_string(),
    }
}

fn voxel_type(dtype: &str) -> VoxelType {
    match dtype {
        "uint8" => VoxelType::U8,
        "int8" => VoxelType::I8,
        "uint16" => VoxelType::U16,
        "int16" => VoxelType::I16,
        "uint32" => VoxelType::U32,
        "int32" => VoxelType::I32,
        "float32" => VoxelType::F32,
        "float64" => VoxelType::F64,
        other => panic!("dtype {other}"),
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-30)
}

#[test]
fn tifffile_oracles_load_with_their_values_and_spacing() {
    let text = std::fs::read_to_string(data("expected.json")).unwrap();
    let expected: serde_json::Map<String, Value> = serde_json::from_str(&text).unwrap();
    let mut checked = 0;
    for (name, e) in &expected {
        if name.starts_with('_') {
            continue;
        }
        let path = data(name);
        assert_eq!(formats::detect_format(&path).unwrap(), Format::Tiff, "{name}");
        let v = Volume::open(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(v.format, "TIFF");
        let dims: Vec<u32> = e["dims"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap() as u32)
            .collect();
        assert_eq!(v.dims.to_vec(), dims, "{name}");
        assert_eq!(v.source_type, voxel_type(e["dtype"].as_str().unwrap()), "{name}");
        assert!(!v.geometry.anatomical, "{name}: TIFF has no orientation");
        let spacing = v.spacing();
        for (i, s) in e["spacing_mm"].as_array().unwrap().iter().enumerate() {
            let s = s.as_f64().unwrap();
            assert!(
                close(f64::from(spacing[i]), s, 1e-6),
                "{name}: spacing {spacing:?} vs {s} on axis {i}"
            );
        }
        // Volcast keeps 32- and 64-bit values as f32: compare with the oracle's values rounded the same way.
        let mut sum = 0.0;
        for z in 0..v.dims[2] {
            for y in 0..v.dims[1] {
                for x in 0..v.dims[0] {
                    sum += v.value(x, y, z);
                }
            }
        }
        let want = e["sum"].as_f64().unwrap();
        assert!(close(sum, want, 1e-6), "{name}: sum {sum} vs {want}");
        for p in e["voxels"].as_array().unwrap() {
            let p: Vec<f64> = p.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
            let got = v.value(p[0] as u32, p[1] as u32, p[2] as u32);
            assert_eq!(got, f64::from(p[3] as f32), "{name}: voxel {p:?}");
        }
        checked += 1;
    }
    assert_eq!(checked, 13);
}

#[test]
fn hyperstacks_folders_and_rgb() {
    // tifffile's ImageJ hyperstack (make.py): page (z, c) holds ((2z + c)·63 + 9y + x) mod 251; channel 0 is
    // loaded, another by its number, and the channels are listed in ImageJ's colours.
    let v = Volume::open(&data("hyperstack.tif")).unwrap();
    assert!(
        v.notes.iter().any(|n| n.contains("channel 0 of the first frame")),
        "{:?}",
        v.notes
    );
    assert_eq!(
        (v.value(0, 0, 1), v.channels.len(), v.channels[1].color),
        (126.0, 2, [0, 255, 0])
    );
    let second = |channel| volcast::formats::OpenOptions {
        channel: Some(channel),
        ..Default::default()
    };
    let v = volcast::formats::open(&data("hyperstack.tif"), &second(1)).unwrap();
    assert_eq!(
        (v.value(0, 0, 1), v.value(2, 1, 2)),
        (189.0, ((5 * 63 + 9 + 2) % 251) as f64)
    );
    assert!(v.channels[1].loaded && !v.channels[0].loaded);
    let e = volcast::formats::open(&data("hyperstack.tif"), &second(2))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("hyperstack.tif") && e.contains("channel 2 does not exist"),
        "{e}"
    );
    let v = Volume::open(&data("stack")).unwrap();
    assert_eq!(v.dims, [9, 7, 12]);
    // z1 .. z12 in natural order: slice z holds 10·(z+1) + x + 9y.
    for z in 0..12 {
        assert_eq!(v.value(0, 0, z), f64::from(10 * (z + 1)), "slice {z}");
    }
    assert!(v.notes[0].contains("12 TIFF slices"), "{:?}", v.notes);
    let e = err(&data("rgb.tif"));
    assert!(
        e.contains("rgb.tif") && e.contains("RGB colour") && e.contains("grey"),
        "{e}"
    );
}

#[test]
fn folders_are_judged_by_their_files() {
    let dir = common::scratch("formats-tiff-folders_are_judged_by_their_files");
    dir.write("a/readme.txt", b"hello");
    let e = err(&dir.join("a"));
    assert!(e.starts_with("a: the folder holds neither TIFF nor DICOM files"), "{e}");
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    assert!(err(&empty).contains("neither TIFF nor DICOM"));
    let slice = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/slice.dcm")).unwrap();
    dir.write("d/1.dcm", &slice);
    dir.write("d/notes.txt", b"x");
    assert_eq!(formats::detect_format(&dir.join("d")).unwrap(), Format::Dicom);
    dir.write("mixed/1.dcm", &slice);
    dir.write("mixed/z1.tif", &std::fs::read(data("stack/z1.tif")).unwrap());
    let e = err(&dir.join("mixed"));
    assert!(e.contains("both TIFF (1) and DICOM (1)"), "{e}");
    // Slices of different sizes.
    dir.write("sizes/z1.tif", &std::fs::read(data("stack/z1.tif")).unwrap());
    dir.write("sizes/z2.tif", &tiff_u8(3, 2, &[[0u8; 6]]));
    let e = err(&dir.join("sizes"));
    assert!(e.contains("is 3x2 uint8 but the first slice is 9x7 uint8"), "{e}");
    // A multi-page file in a folder.
    dir.write("pages/a.tif", &tiff_u8(2, 2, &[[1u8; 4], [2u8; 4]]));
    let e = err(&dir.join("pages"));
    assert!(e.contains("a.tif: has more than one page"), "{e}");
}

// ---------------------------------------------------------------------------------------------------------------
// Hand-built TIFFs (little-endian, classic).

/// An IFD entry: tag, type (3 SHORT, 4 LONG), count, value or offset.
type Entry = (u16, u16, u32, u32);

fn put_ifd(out: &mut Vec<u8>, entries: &[Entry], next: u32) {
    out.extend((entries.len() as u16).to_le_bytes());
    for &(tag, ty, count, value) in entries {
        out.extend(tag.to_le_bytes());
        out.extend(ty.to_le_bytes());
        out.extend(count.to_le_bytes());
        out.extend(value.to_le_bytes());
    }
    out.extend(next.to_le_bytes());
}

fn grey_entries(w: u32, h: u32, strip_offset: u32, strip_bytes: u32, compression: u32) -> Vec<Entry> {
    vec![
        (256, 4, 1, w),
        (257, 4, 1, h),
        (258, 3, 1, 8),
        (259, 3, 1, compression),
        (262, 3, 1, 1),
        (273, 4, 1, strip_offset),
        (277, 3, 1, 1),
        (278, 4, 1, h),
        (279, 4, 1, strip_bytes),
    ]
}

const IFD_BYTES: u32 = 2 + 9 * 12 + 4;

/// An 8-bit grey TIFF, one strip per page.
fn tiff_u8<const N: usize>(w: u32, h: u32, pages: &[[u8; N]]) -> Vec<u8> {
    let mut out = b"II*\0".to_vec();
    out.extend(8u32.to_le_bytes());
    let data_start = 8 + IFD_BYTES * pages.len() as u32;
    for (i, _) in pages.iter().enumerate() {
        let next = if i + 1 < pages.len() {
            8 + IFD_BYTES * (i as u32 + 1)
        } else {
            0
        };
        put_ifd(
            &mut out,
            &grey_entries(w, h, data_start + (i * N) as u32, N as u32, 1),
            next,
        );
    }
    for p in pages {
        out.extend_from_slice(p);
    }
    out
}

#[test]
fn hand_built_tiff_loads() {
    let dir = common::scratch("formats-tiff-hand_built_tiff_loads");
    let p = dir.write("two.tif", &tiff_u8(2, 2, &[[1, 2, 3, 4], [5, 6, 7, 8]]));
    let v = Volume::open(&p).unwrap();
    assert_eq!(v.dims, [2, 2, 2]);
    assert_eq!(v.value(1, 1, 1), 8.0);
    assert_eq!(v.spacing(), [1.0; 3]);
}

#[test]
fn hostile_tiffs_are_refused_naming_the_file() {
    let dir = common::scratch("formats-tiff-hostile_tiffs_are_refused_naming_the_file");
    // Dimensions beyond the per-axis limit.
    let mut huge = b"II*\0".to_vec();
    huge.extend(8u32.to_le_bytes());
    put_ifd(&mut huge, &grey_entries(100_000, 7, 8 + IFD_BYTES, 4, 1), 0);
    huge.extend([0; 4]);
    let e = err(&dir.write("huge.tif", &huge));
    assert!(
        e.starts_with("huge.tif: page 1 is 100000x7, beyond the limit of 16384"),
        "{e}"
    );
    // A Deflate page claiming 16384x16384 from 10 bytes: refused before its buffer is allocated.
    let mut bomb = b"II*\0".to_vec();
    bomb.extend(8u32.to_le_bytes());
    put_ifd(&mut bomb, &grey_entries(16384, 16384, 8 + IFD_BYTES, 10, 8), 0);
    bomb.extend([0x78, 0x9c, 0, 0, 0, 0, 0, 0, 0, 0]);
    let e = err(&dir.write("bomb.tif", &bomb));
    assert!(e.starts_with("bomb.tif: page 1 claims 16384x16384 uint8"), "{e}");
    // A strip beyond the end of the file.
    let mut short = tiff_u8(4, 4, &[[7u8; 16]]);
    short.truncate(short.len() - 5);
    let e = err(&dir.write("short.tif", &short));
    assert!(
        e.starts_with("short.tif: page 1 has a strip/tile of 16 bytes at offset"),
        "{e}"
    );
    // Every truncation of a real file is an error or a volume, never a panic.
    let full = std::fs::read(data("u16_imagej_lzw.tif")).unwrap();
    for len in 0..full.len() {
        let _ = formats::from_bytes::tiff(&full[..len]);
    }
    let e = err(&dir.write("cut.tif", &full[..full.len() / 2]));
    assert!(e.starts_with("cut.tif: "), "{e}");
    // IFD loops: a directory pointing at itself, two pointing at each other.
    let mut self_loop = b"II*\0".to_vec();
    self_loop.extend(8u32.to_le_bytes());
    put_ifd(&mut self_loop, &grey_entries(1, 1, 8 + IFD_BYTES, 1, 1), 8);
    self_loop.push(1);
    let e = err(&dir.write("loop1.tif", &self_loop));
    assert!(e.starts_with("loop1.tif: "), "{e}");
    let mut pair = b"II*\0".to_vec();
    pair.extend(8u32.to_le_bytes());
    put_ifd(&mut pair, &grey_entries(1, 1, 8 + 2 * IFD_BYTES, 1, 1), 8 + IFD_BYTES);
    put_ifd(&mut pair, &grey_entries(1, 1, 8 + 2 * IFD_BYTES, 1, 1), 8);
    pair.push(1);
    let e = err(&dir.write("loop2.tif", &pair));
    assert!(e.starts_with("loop2.tif: "), "{e}");
    // A page-count bomb: 70 000 one-pixel pages.
    let n = 70_000u32;
    let mut many = b"II*\0".to_vec();
    many.extend(8u32.to_le_bytes());
    for i in 0..n {
        let next = if i + 1 < n { 8 + IFD_BYTES * (i + 1) } else { 0 };
        put_ifd(&mut many, &grey_entries(1, 1, 8 + IFD_BYTES * n, 1, 1), next);
    }
    many.push(9);
    let e = err(&dir.write("many.tif", &many));
    assert!(e.starts_with("many.tif: has more than 65536 pages"), "{e}");
    // Directories sharing one big offset table: the strips they declare cannot fit in the file.
    let h = 16384u32;
    let pages = 1000u32;
    let mut shared = b"II*\0".to_vec();
    shared.extend(8u32.to_le_bytes());
    let tables = 8 + IFD_BYTES * pages;
    let strip = tables + 8 * h;
    for i in 0..pages {
        let next = if i + 1 < pages { 8 + IFD_BYTES * (i + 1) } else { 0 };
        let mut e = grey_entries(1, h, 0, 0, 1);
        e[5] = (273, 4, h, tables);
        e[7] = (278, 4, 1, 1);
        e[8] = (279, 4, h, tables + 4 * h);
        put_ifd(&mut shared, &e, next);
    }
    shared.extend(std::iter::repeat_n(strip.to_le_bytes(), h as usize).flatten());
    shared.extend(std::iter::repeat_n(1u32.to_le_bytes(), h as usize).flatten());
    shared.push(3);
    let e = err(&dir.write("shared.tif", &shared));
    assert!(e.contains("shared.tif: ") && e.contains("more than a"), "{e}");
}

#[test]
fn too_many_slices_for_one_axis() {
    let dir = common::scratch("formats-tiff-too_many_slices_for_one_axis");
    let n = 20_000u32;
    let mut deep = b"II*\0".to_vec();
    deep.extend(8u32.to_le_bytes());
    for i in 0..n {
        let next = if i + 1 < n { 8 + IFD_BYTES * (i + 1) } else { 0 };
        put_ifd(&mut deep, &grey_entries(1, 1, 8 + IFD_BYTES * n, 1, 1), next);
    }
    deep.push(9);
    let e = err(&dir.write("deep.tif", &deep));
    assert!(
        e.starts_with("deep.tif: dimensions 1x1x20000 exceed the limit of 16384 per axis"),
        "{e}"
    );
}

// ---------------------------------------------------------------------------------------------------------------
// Formats volcast does not read.

/// (file name, first bytes, what the message must say).
fn unsupported_cases() -> Vec<(&'static str, Vec<u8>, &'static str)> {
    let mut mrc = vec![0u8; 1024];
    mrc[208..212].copy_from_slice(b"MAP ");
    vec![
        (
            "brain.h5",
            b"\x89HDF\r\n\x1a\n\0\0\0\0".to_vec(),
            "brain.h5 is an HDF5 file; volcast cannot read HDF5",
        ),
        (
            "t.nc",
            b"\x89HDF\r\n\x1a\n\0\0\0\0".to_vec(),
            "t.nc is a NetCDF-4 file (HDF5); volcast cannot read NetCDF",
        ),
        (
            "t.mnc",
            b"\x89HDF\r\n\x1a\n\0\0\0\0".to_vec(),
            "t.mnc is a MINC2 file (HDF5); volcast cannot read MINC",
        ),
        ("classic.nc", b"CDF\x01\0\0\0\0".to_vec(), "classic.nc is a NetCDF file"),
        ("big.nc", b"CDF\x02\0\0\0\0".to_vec(), "big.nc is a NetCDF file"),
        (
            "a.stl",
            b"solid cube\n facet normal 0 0 1\n".to_vec(),
            "a.stl is an STL mesh",
        ),
        ("b.stl", vec![0u8; 84], "b.stl is an STL mesh"),
        ("m.ply", b"ply\nformat ascii 1.0\n".to_vec(), "m.ply is a PLY mesh"),
        ("m.obj", b"v 0 0 0\nv 1 0 0\n".to_vec(), "m.obj is a Wavefront OBJ mesh"),
        ("a.zip", b"PK\x03\x04\x14\0".to_vec(), "a.zip is a ZIP archive"),
        (
            "p.png",
            b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR".to_vec(),
            "p.png is a PNG image",
        ),
        ("j.jpg", b"\xff\xd8\xff\xe0\0\x10JFIF".to_vec(), "j.jpg is a JPEG image"),
        ("m.mrc", mrc, "m.mrc is an MRC/CCP4 map"),
        ("g.gipl", vec![0u8; 256], "g.gipl is a GIPL image"),
        (
            "s.fits",
            b"SIMPLE  =                    T / conforms".to_vec(),
            "s.fits is a FITS file",
        ),
        (
            "d.mat",
            b"MATLAB 5.0 MAT-file, Platform: GLNXA64".to_vec(),
            "d.mat is a MATLAB MAT-file",
        ),
        (
            "a.npy",
            b"\x93NUMPY\x01\0v\0{'descr'".to_vec(),
            "a.npy is a NumPy .npy array",
        ),
        ("noext", b"\x89HDF\r\n\x1a\n\0\0\0\0".to_vec(), "noext is an HDF5 file"),
    ]
}

#[test]
fn unsupported_formats_are_named_by_open_and_the_cli() {
    let dir = common::scratch("formats-tiff-unsupported_formats_are_named_by_open_and_the_cli");
    for (name, bytes, want) in unsupported_cases() {
        let p = dir.write(name, &bytes);
        let e = err(&p);
        assert!(e.starts_with(want), "{name}: {e}");
        assert!(!e.contains("bytes but"), "{name}: read as raw: {e}");
        let o = common::volcast(&["info", p.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {stderr}");
        assert!(stderr.contains(want), "{name}: {stderr}");
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    }
    // Zarr stores are folders, read as OME-Zarr: one without OME metadata is refused, naming the store.
    for (i, marker) in [".zarray", ".zgroup", "zarr.json", ".zattrs"].iter().enumerate() {
        let store = dir.join(format!("img{i}.zarr"));
        dir.write(&format!("img{i}.zarr/{marker}"), b"{}");
        let e = err(&store);
        assert!(
            e.contains(&format!("img{i}.zarr")) && e.contains("Zarr"),
            "{marker}: {e}"
        );
        let o = common::volcast(&["info", store.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(1));
        assert!(String::from_utf8_lossy(&o.stderr).contains("Zarr"));
    }
    // The data half of an Analyze pair.
    dir.write("pair.hdr", &[0u8; 10]);
    let e = err(&dir.write("pair.img", &[0u8; 64]));
    assert!(
        e.contains("pair.img is the data half of an Analyze/NIfTI-1 .hdr/.img pair") && e.contains("open pair.hdr"),
        "{e}"
    );
}

#[test]
fn h5py_file_is_named() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/unsupported/brain.h5");
    let e = err(&p);
    assert!(
        e.starts_with("brain.h5 is an HDF5 file; volcast cannot read HDF5"),
        "{e}"
    );
}

#[test]
fn raw_files_still_load_whatever_their_first_bytes() {
    let dir = common::scratch("formats-tiff-raw_files_still_load_whatever_their_first_bytes");
    // Named like a raw file: raw, even with PNG magic.
    let p = dir.write("t_8x1x1_uint8.raw", b"\x89PNG\r\n\x1a\n");
    assert_eq!(formats::detect_format(&p).unwrap(), Format::Raw);
    assert_eq!(Volume::open(&p).unwrap().value(1, 0, 0), f64::from(b'P'));
    let p = dir.write("plain.raw", b"\x89HDF\r\n\x1a\n");
    assert_eq!(formats::detect_format(&p).unwrap(), Format::Raw);
    // An unnamed file without magic is raw and still asks for its layout.
    let p = dir.write("plain.dat", &[1, 2, 3, 4]);
    assert_eq!(formats::detect_format(&p).unwrap(), Format::Raw);
    assert!(err(&p).contains("cannot tell the dimensions and voxel type of plain.dat"));
    // An unsupported format read as raw when the layout is given explicitly.
    let p = dir.write("x.h5", b"\x89HDF\r\n\x1a\n");
    let opts = OpenOptions {
        raw: RawOptions {
            dims: Some([8, 1, 1]),
            voxel_type: Some(VoxelType::U8),
            spacing: None,
        },
        ..OpenOptions::default()
    };
    let v = formats::open(&p, &opts).unwrap();
    assert_eq!(v.format, "raw");
    assert_eq!(v.value(1, 0, 0), f64::from(b'H'));
}

#[test]
fn cli_reads_a_tiff_folder_and_renders_it() {
    let stack = data("stack");
    let o = common::volcast(&["info", stack.to_str().unwrap()]);
    let out = common::stdout(&o);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert!(out.contains("9 x 7 x 12") && out.contains("TIFF"), "{out}");
    let png = common::scratch("formats-tiff").join("tiff-stack.png");
    let o = common::volcast(&[
        "render",
        stack.to_str().unwrap(),
        "--size",
        "48x40",
        "-o",
        png.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(png.is_file());
}

/// Found by the tiff fuzz target: a directory entry claiming ~89 M values made the tiff crate reserve 2 GiB for
/// their list before reading them (its list limit is `decoding_buffer_size`, which volcast had set to the
/// largest page). While directories are read the limit is now what the file can hold, so the claim is refused
/// as a limit before any allocation (before the fix: the 2 GiB list, then a read error).
#[test]
fn fuzz_ifd_value_claim_is_refused_as_a_limit() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz-tiff-oom-ifd-values.tif");
    let e = err(&path);
    assert!(
        e.contains("fuzz-tiff-oom-ifd-values.tif")
            && e.contains("a TIFF value or page is larger than the file can hold"),
        "{e}"
    );
}
