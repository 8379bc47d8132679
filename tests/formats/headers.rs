//! NIfTI-2, Analyze 7.5 and MetaImage against the libraries that read them: nibabel 5.4.2's own test files and
//! small files it and SimpleITK 2.5.7 wrote (tests/data/nibabel: make_expected.py wrote expected.json), each
//! file's shape, voxel type, RAS affine and voxel values; and hostile NIfTI-2 and Analyze headers refused clearly.

use crate::common;

use glam::DMat4;
use std::path::{Path, PathBuf};
use volcast::formats;
use volcast::formats::{from_bytes, OpenOptions};
use volcast::volume::{self, Volume};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/nibabel")
        .join(name)
}

fn open(path: &Path) -> Result<Volume, volume::VolumeError> {
    formats::open(path, &OpenOptions::default())
}

fn err(path: &Path) -> String {
    open(path).expect_err("should fail").to_string()
}

fn expected() -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(data("expected.json")).expect("tests/data/nibabel/expected.json");
    serde_json::from_str(&text).expect("expected.json is JSON")
}

/// The format volcast should name: by what the library read it as.
fn format_of(entry: &serde_json::Value) -> &'static str {
    let reader = entry["reader"].as_str().expect("reader");
    if reader.contains("Analyze") {
        "Analyze 7.5"
    } else if reader.contains("Nifti2") {
        "NIfTI-2"
    } else {
        "MetaImage"
    }
}

/// The largest difference between `got` and the library's 4x4 affine (row-major).
fn affine_error(got: DMat4, expected: &serde_json::Value) -> f64 {
    let got = got.transpose().to_cols_array_2d();
    (0..4)
        .flat_map(|r| (0..4).map(move |c| (r, c)))
        .map(|(r, c)| (got[r][c] - expected[r][c].as_f64().expect("a number")).abs())
        .fold(0.0, f64::max)
}

fn shape(entry: &serde_json::Value) -> (Vec<u32>, u32) {
    let shape: Vec<u32> = entry["shape"]
        .as_array()
        .expect("shape")
        .iter()
        .map(|s| s.as_u64().expect("a size") as u32)
        .collect();
    let steps = shape.get(3).copied().unwrap_or(1);
    (shape[..3].to_vec(), steps)
}

/// Every file opens with nibabel's (or SimpleITK's) shape, type, affine (RAS mm, voxel centres at integer indices
/// in both) and values. nibabel's header-only test files (no .img) are checked through the header parser, and
/// opening them names the missing .img.
#[test]
fn files_read_as_nibabel_and_simpleitk_read_them() {
    let mut failures = Vec::new();
    for entry in expected() {
        let name = entry["file"].as_str().expect("file");
        let (dims, steps) = shape(&entry);
        let dtype = entry["dtype"].as_str().expect("dtype");
        if !entry["open"].as_bool().expect("open") {
            let bytes = std::fs::read(data(name)).expect("the header");
            let h = from_bytes::nifti_header(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(
                (h.format, h.dims.to_vec(), h.timesteps),
                (format_of(&entry), dims, steps),
                "{name}"
            );
            assert_eq!(h.voxel_type.name(), dtype, "{name}");
            let worst = affine_error(h.placement().affine, &entry["affine"]);
            if worst > 1e-5 {
                failures.push(format!(
                    "{name}: affine {:?} is {worst} from nibabel's",
                    h.placement().affine
                ));
            }
            let e = err(&data(name));
            let img = name.replace(".hdr", ".img");
            assert!(e.contains(&img), "{name}: {e}");
            continue;
        }
        let mut v = open(&data(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            (v.format.as_str(), v.dims.to_vec(), v.timesteps()),
            (format_of(&entry), dims, steps),
            "{name}"
        );
        assert_eq!(v.source_type.name(), dtype, "{name}");
        assert!(v.geometry.anatomical, "{name}");
        let worst = affine_error(v.geometry.affine, &entry["affine"]);
        if worst > 1e-5 {
            failures.push(format!(
                "{name}: affine {:?} is {worst} from the library's",
                v.geometry.affine
            ));
        }
        for value in entry["values"].as_array().expect("values") {
            let at: Vec<u32> = (0..4).map(|i| value[i].as_u64().expect("an index") as u32).collect();
            let want = value[4].as_f64().expect("a value");
            v.show_step(at[3]).expect("the step");
            let got = v.value(at[0], at[1], at[2]);
            if (got - want).abs() > 1e-6 * want.abs().max(1.0) {
                failures.push(format!("{name}: voxel {at:?} is {got}, the library reads {want}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `volcast info` names the new formats and says Analyze has no orientation of its own.
#[test]
fn info_names_the_formats() {
    for (file, format) in [
        ("example_nifti2.nii.gz", "NIfTI-2"),
        ("nifti2_pair_be.hdr", "NIfTI-2"),
        ("analyze_spm.hdr", "Analyze 7.5"),
    ] {
        let path = data(file);
        let o = common::volcast(&["info", path.to_str().expect("UTF-8")]);
        assert!(o.status.success(), "{file}: {}", common::stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains(format), "{file}: {text}");
        if format == "Analyze 7.5" {
            assert!(text.contains("Analyze 7.5 records no orientation"), "{text}");
        }
    }
}

/// A NIfTI-2 header to break: `nifti2_qform.nii` (3x4x2 uint16, little-endian, vox_offset 544).
fn nifti2() -> Vec<u8> {
    std::fs::read(data("nifti2_qform.nii")).expect("nifti2_qform.nii")
}

fn put_i64(bytes: &mut [u8], at: usize, v: i64) {
    bytes[at..at + 8].copy_from_slice(&v.to_le_bytes());
}

#[test]
fn hostile_nifti2_headers_are_refused_clearly() {
    let dir = common::scratch("formats-hostile_nifti2_headers");
    let ok = nifti2();
    assert!(open(&dir.write("ok.nii", &ok)).is_ok());
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "short.nii",
            ok[..300].to_vec(),
            "short.nii: 300 bytes is too short for a NIfTI-2 header (540 bytes)",
        ),
        ("negative.nii", patched(&ok, 24, -3), "zero or negative size"),
        ("huge.nii", patched(&ok, 24, 1 << 40), "far beyond the limit"),
        ("overflow.nii", many_dims(&ok, i64::from(u32::MAX)), "exceed the limit"),
        (
            "ndim.nii",
            patched(&ok, 16, 1 << 33),
            "dim[0] = 8589934592: the number of dimensions must be 1 to 7",
        ),
        (
            "offset.nii",
            patched(&ok, 168, -544),
            "vox_offset -544 is not a valid byte offset",
        ),
        (
            "inside.nii",
            patched(&ok, 168, 100),
            "vox_offset 100 points inside the 540-byte header",
        ),
        (
            "claim.nii",
            patched(&ok, 32, 1000),
            "the voxel data end after 48 of the 12000 bytes",
        ),
    ];
    for (name, bytes, expected) in cases {
        let e = err(&dir.write(name, &bytes));
        assert!(e.contains(expected), "{name}: {e}");
        assert!(e.contains(name), "{name}: {e}");
        let gz = format!("{name}.gz");
        assert!(err(&dir.write(&gz, &gzip(&bytes))).contains(&gz), "{gz}");
    }
    // Axes beyond the fourth are not loaded, but their product cannot overflow: only the first group is read.
    let mut five = ok.clone();
    put_i64(&mut five, 16, 7);
    for i in 5..=7 {
        put_i64(&mut five, 16 + 8 * i, i64::from(u32::MAX));
    }
    let v = open(&dir.write("seven.nii", &five)).expect("seven dimensions, one group loaded");
    assert!(v.notes.iter().any(|n| n.contains("only the first of")), "{:?}", v.notes);
    // Found by content whatever the name.
    let p = dir.write("renamed.dat", &ok);
    assert_eq!(formats::detect_format(&p).expect("a format"), formats::Format::Nifti);
    assert_eq!(open(&p).expect("NIfTI-2").format, "NIfTI-2");
    let mut magic = ok.clone();
    magic[4..8].copy_from_slice(b"n+3\0");
    let e = err(&dir.write("magic.hdr", &magic));
    assert!(e.contains("magic.hdr: not a NIfTI-2 file"), "{e}");
}

/// `bytes` with the int64 at `at` replaced.
fn patched(bytes: &[u8], at: usize, v: i64) -> Vec<u8> {
    let mut b = bytes.to_vec();
    put_i64(&mut b, at, v);
    b
}

/// Three axes of `n` voxels each: their product overflows 64 bits.
fn many_dims(bytes: &[u8], n: i64) -> Vec<u8> {
    let mut b = bytes.to_vec();
    for i in 1..=3 {
        put_i64(&mut b, 16 + 8 * i, n);
    }
    b
}

fn gzip(data: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(data).expect("gzip");
    e.finish().expect("gzip")
}

#[test]
fn hostile_analyze_headers_are_refused_clearly() {
    let dir = common::scratch("formats-hostile_analyze_headers");
    let hdr = std::fs::read(data("analyze_spm.hdr")).expect("analyze_spm.hdr");
    let img = std::fs::read(data("analyze_spm.img")).expect("analyze_spm.img");
    let pair = |name: &str, hdr: &[u8], img: &[u8]| {
        dir.write(&format!("{name}.img"), img);
        dir.write(&format!("{name}.hdr"), hdr)
    };
    assert!(open(&pair("ok", &hdr, &img)).is_ok());
    let e = err(&pair("short", &hdr, &img[..100]));
    assert!(
        e.contains("short.hdr: short.img: the voxel data end after 100 of the 120 bytes"),
        "{e}"
    );
    let e = err(&pair("truncated", &hdr[..200], &img));
    assert!(e.contains("truncated.hdr: 200 bytes is too short"), "{e}");
    let mut wrong = hdr.clone();
    wrong[0..4].copy_from_slice(&349i32.to_le_bytes());
    let e = err(&pair("wrong", &wrong, &img));
    assert!(
        e.contains("wrong.hdr: not a NIfTI or Analyze file: sizeof_hdr is neither 348"),
        "{e}"
    );
    let mut negative = hdr.clone();
    negative[42..44].copy_from_slice(&(-5i16).to_le_bytes());
    let e = err(&pair("negative", &negative, &img));
    assert!(e.contains("negative.hdr") && e.contains("zero or negative size"), "{e}");
    let mut big = hdr.clone();
    for i in 1..=3 {
        big[40 + 2 * i..42 + 2 * i].copy_from_slice(&30000i16.to_le_bytes());
    }
    let e = err(&pair("big", &big, &img));
    assert!(e.contains("big.hdr") && e.contains("exceed the limit"), "{e}");
    let mut complex = hdr.clone();
    complex[70..72].copy_from_slice(&32i16.to_le_bytes());
    let e = err(&pair("complex", &complex, &img));
    assert!(
        e.contains("complex.hdr") && e.contains("datatype 32 (complex64)"),
        "{e}"
    );
    // Without the magic a .nii is a broken NIfTI-1, not Analyze (nibabel reads Analyze only from .hdr/.img).
    let mut nii = std::fs::read(data("../time/cine_i16.nii")).expect("a NIfTI-1 file");
    nii[344..348].copy_from_slice(b"abc\0");
    for name in ["nomagic.nii", "nomagic.nii.gz"] {
        let bytes = if name.ends_with(".gz") { gzip(&nii) } else { nii.clone() };
        let e = err(&dir.write(name, &bytes));
        assert!(
            e.contains(&format!("{name}: not a NIfTI-1 file: the magic is neither")),
            "{e}"
        );
    }
    let e = err(&dir.write("lonely.hdr", &hdr));
    assert!(e.contains("lonely.img"), "{e}");
}

/// A 5-D NIfTI as nibabel writes a multi-channel image (make_channels.py): channel 0 opens by default, another by
/// `--channel`, the three are listed, and a fourth is refused naming the file.
#[test]
fn nifti_channels_along_dim5_open_one_by_one() {
    let path = data("channels_5d.nii.gz");
    let channel = |c| OpenOptions {
        channel: Some(c),
        ..OpenOptions::default()
    };
    let v = open(&path).unwrap();
    assert_eq!((v.dims, v.value(1, 2, 3), v.channels.len()), ([6, 5, 4], 103.0, 3));
    assert!(
        v.channels[0].loaded && v.notes.iter().any(|n| n.contains("channel 0 of 3")),
        "{:?}",
        v.notes
    );
    let v = formats::open(&path, &channel(2)).unwrap();
    assert_eq!((v.value(1, 2, 3), v.value(5, 4, 0)), (303.0, 229.0));
    assert!(v.channels[2].loaded);
    let e = formats::open(&path, &channel(3)).unwrap_err().to_string();
    assert!(
        e.contains("channels_5d.nii.gz") && e.contains("channel 3 does not exist"),
        "{e}"
    );
    // Read in place (a file over the host budget, decoded as a stream into its level), it lists them too.
    let place = formats::in_place::compressed(&path, &channel(2))
        .unwrap()
        .expect("a gzip stream");
    let listed: Vec<bool> = place.channels.iter().map(|c| c.loaded).collect();
    assert_eq!(listed, [false, false, true]);
}
