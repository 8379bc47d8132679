//! VTK legacy and VTK XML ImageData files written by VTK 9.7's own writers (tests/data/vtk/make.py), loaded through
//! `formats::open` and compared with what VTK's readers read back from the same files (tests/data/vtk/expected.json):
//! dims, spacing, placement, every one-component point array's sum and samples. Then hostile `.vti` files built
//! here: each must give an error that names the file, never a panic or an allocation the file cannot back.

use crate::common;

use serde_json::Value;
use std::path::{Path, PathBuf};
use volcast::formats;
use volcast::formats::OpenOptions;
use volcast::volume::{self, Volume};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk")
}

fn expected() -> Value {
    let text = std::fs::read_to_string(data().join("expected.json")).expect("expected.json (run make.py)");
    serde_json::from_str(&text).expect("expected.json is JSON")
}

fn open(path: &Path, array: Option<&str>) -> Result<Volume, volume::VolumeError> {
    let opts = OpenOptions {
        array: array.map(str::to_string),
        ..OpenOptions::default()
    };
    formats::open(path, &opts)
}

fn f(v: &Value) -> f64 {
    v.as_f64().expect("a number")
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-4 * (1.0 + b.abs())
}

fn voxel(v: &Volume, index: u64) -> f64 {
    let [w, h, _] = v.dims.map(u64::from);
    v.value((index % w) as u32, ((index / w) % h) as u32, (index / (w * h)) as u32)
}

#[test]
fn every_file_matches_what_vtk_reads_back() {
    let expected = expected();
    let files = expected["files"].as_object().expect("files");
    assert!(files.len() >= 20, "{} files", files.len());
    let mut failures = Vec::new();
    for (name, want) in files {
        let path = data().join(name);
        let v = match open(&path, None) {
            Ok(v) => v,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        let mut check = |ok: bool, what: String| {
            if !ok {
                failures.push(format!("{name}: {what}"));
            }
        };
        let dims: Vec<u64> = want["dims"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap())
            .collect();
        check(
            v.dims.map(u64::from).to_vec() == dims,
            format!("dims {:?} vs {dims:?}", v.dims),
        );
        assert!(!v.geometry.anatomical, "{name}: VTK has no anatomical convention");
        let spacing: Vec<f64> = want["spacing"].as_array().unwrap().iter().map(f).collect();
        let origin: Vec<f64> = want["origin"].as_array().unwrap().iter().map(f).collect();
        let direction: Vec<f64> = want["direction"].as_array().unwrap().iter().map(f).collect();
        // The affine's column a is Direction's column a times spacing a; its last column the first voxel.
        let rows = v.geometry.rows();
        for r in 0..3 {
            for c in 0..3 {
                let want = direction[3 * r + c] * spacing[c];
                check(
                    close(rows[r][c], want),
                    format!("affine[{r}][{c}] {} vs {want}", rows[r][c]),
                );
            }
            check(
                close(rows[r][3], origin[r]),
                format!("origin[{r}] {} vs {}", rows[r][3], origin[r]),
            );
        }
        // The default array is VTK's active scalars.
        let active = want["active_scalars"].as_str().unwrap();
        let loaded: Vec<&str> = v.arrays.iter().filter(|a| a.loaded).map(|a| a.name.as_str()).collect();
        check(
            loaded == [active],
            format!("loaded {loaded:?}, VTK's active scalars {active}"),
        );
        // Every array VTK lists, volcast lists with the same components.
        for a in want["arrays"].as_array().unwrap() {
            let (an, ac) = (a["name"].as_str().unwrap(), a["components"].as_u64().unwrap());
            let listed = v.arrays.iter().any(|x| x.name == an && u64::from(x.components) == ac);
            check(
                listed,
                format!("array {an} ({ac} components) not listed in {:?}", v.arrays),
            );
        }
        for a in want["arrays"].as_array().unwrap() {
            let an = a["name"].as_str().unwrap();
            if a["components"].as_u64() != Some(1) {
                let e = open(&path, Some(an))
                    .expect_err("multi-component arrays are refused")
                    .to_string();
                check(
                    e.contains(name) && e.contains("components"),
                    format!("--array {an}: {e}"),
                );
                continue;
            }
            let v = match open(&path, Some(an)) {
                Ok(v) => v,
                Err(e) => {
                    check(false, format!("--array {an}: {e}"));
                    continue;
                }
            };
            let t = a["type"].as_str().unwrap();
            check(
                v.source_type.name() == t,
                format!("{an}: type {} vs {t}", v.source_type.name()),
            );
            let count = v.voxel_count() as u64;
            let sum: f64 = (0..count).map(|i| voxel(&v, i)).sum();
            check(close(sum, f(&a["sum"])), format!("{an}: sum {sum} vs {}", a["sum"]));
            for s in a["samples"].as_array().unwrap() {
                let (i, want) = (s[0].as_u64().unwrap(), f(&s[1]));
                let got = voxel(&v, i);
                check(close(got, want), format!("{an}[{i}] {got} vs {want}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn info_lists_arrays_in_json() {
    let path = data().join("legacy_multi_binary.vtk");
    let v = open(&path, Some("label")).unwrap();
    let json = serde_json::to_value(volcast::render::info::Info::of(&v)).unwrap();
    let arrays = json["arrays"].as_array().unwrap();
    let names: Vec<&str> = arrays.iter().map(|a| a["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["ramp", "grad", "density", "label"]);
    assert_eq!(arrays[3]["type"], "short");
    assert_eq!(arrays[3]["loaded"], true);
    assert_eq!(arrays[1]["components"], 3);
    assert!(volcast::render::info::Info::of(&v)
        .text(&v)
        .contains("label: short, 1 component(s) (loaded)"));
}

#[test]
fn clear_refusals_name_the_file() {
    let e = open(&data().join("legacy_rectilinear_uneven.vtk"), None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("legacy_rectilinear_uneven.vtk") && e.contains("Y_COORDINATES are not evenly spaced"),
        "{e}"
    );
    let e = open(&data().join("unsupported.vtu"), None).unwrap_err().to_string();
    assert!(
        e.contains("unsupported.vtu: a VTK XML UnstructuredGrid file; volcast reads ImageData (.vti) only"),
        "{e}"
    );
    let e = open(&data().join("vti_zlib.vti"), Some("nope"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("vti_zlib.vti") && e.contains("no point array named 'nope'") && e.contains("density"),
        "{e}"
    );
    let e = open(&data().join("legacy_u8_ascii.vtk"), Some("nope"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("legacy_u8_ascii.vtk") && e.contains("ramp"), "{e}");
    assert_eq!(
        formats::detect_format(&data().join("vti_ascii.vti")).unwrap(),
        formats::Format::Vti
    );
    assert_eq!(
        formats::detect_format(&data().join("unsupported.vtu")).unwrap(),
        formats::Format::Vti
    );
}

/// A one-array `.vti` with raw appended bytes: `words` (the block header, UInt32) then `payload`.
fn vti(extent: &str, compressor: &str, words: &[u32], payload: &[u8], offset: &str) -> Vec<u8> {
    let compressor = if compressor.is_empty() {
        String::new()
    } else {
        format!(" compressor=\"{compressor}\"")
    };
    let mut out = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt32\"{compressor}>\n<ImageData WholeExtent=\"{extent}\" Origin=\"0 0 0\" Spacing=\"1 1 1\">\n\
         <Piece Extent=\"{extent}\">\n<PointData Scalars=\"v\">\n<DataArray type=\"UInt8\" Name=\"v\" \
         format=\"appended\" offset=\"{offset}\"/>\n</PointData>\n</Piece>\n</ImageData>\n\
         <AppendedData encoding=\"raw\">\n_"
    )
    .into_bytes();
    for w in words {
        out.extend(w.to_le_bytes());
    }
    out.extend(payload);
    out.extend(b"\n</AppendedData>\n</VTKFile>\n");
    out
}

fn zlib(data: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}

#[test]
fn hostile_vti_files_are_refused() {
    let s = common::scratch("formats-vtk-hostile_vti_files_are_refused");
    let small = "0 6 0 5 0 4"; // 210 bytes of UInt8
    let huge = "0 1023 0 1023 0 1023"; // 1 GiB of UInt8
    let zeros = vec![0u8; 4 << 20];
    let (z, l) = (zlib(&zeros), lz4_flex::block::compress(&zeros));
    let xz = std::fs::read(data().join("bomb.xz")).unwrap();
    let block = |c: &[u8]| [1, 210, 210, c.len() as u32];
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        // Each compressor's stream holds 4 MiB; the header claims the 210 bytes the extent needs.
        (
            "bomb-zlib.vti",
            vti(small, "vtkZLibDataCompressor", &block(&z), &z, "0"),
            "more than",
        ),
        (
            "bomb-lz4.vti",
            vti(small, "vtkLZ4DataCompressor", &block(&l), &l, "0"),
            "lz4 block 0 is corrupt",
        ),
        (
            "bomb-lzma.vti",
            vti(small, "vtkLZMADataCompressor", &block(&xz), &xz, "0"),
            "lzma block 0 is corrupt",
        ),
        // A header claiming 1 GiB from a few compressed bytes, per compressor.
        (
            "claim-zlib.vti",
            vti(huge, "vtkZLibDataCompressor", &[1, 1 << 30, 0, 20], &[0; 20], "0"),
            "claims",
        ),
        (
            "claim-lz4.vti",
            vti(huge, "vtkLZ4DataCompressor", &[1, 1 << 30, 0, 20], &[0; 20], "0"),
            "claims",
        ),
        (
            "claim-lzma.vti",
            vti(huge, "vtkLZMADataCompressor", &[1, 1 << 30, 0, 20], &[0; 20], "0"),
            "claims",
        ),
        // Sizes that disagree with the extent.
        (
            "sizes.vti",
            vti(small, "vtkZLibDataCompressor", &[1, 300, 300, 9], &[0; 9], "0"),
            "does not add up",
        ),
        (
            "blocks.vti",
            vti(small, "vtkZLibDataCompressor", &[5_000_000, 64, 18, 9], &[0; 9], "0"),
            "does not add up",
        ),
        (
            "raw-size.vti",
            vti(small, "", &[1 << 31], &[0; 210], "0"),
            "says 2147483648 bytes",
        ),
        // Data missing.
        (
            "truncated.vti",
            vti(small, "", &[210], &[7; 100], "0"),
            "needs 210 bytes",
        ),
        (
            "truncated-blocks.vti",
            vti(small, "vtkZLibDataCompressor", &[1, 210, 210, 900], &[0; 9], "0"),
            "compressed blocks",
        ),
        (
            "huge-extent.vti",
            vti("0 99999 0 99999 0 99999", "", &[0], &[], "0"),
            "exceed the limit",
        ),
        (
            "many-voxels.vti",
            vti("0 16000 0 16000 0 16000", "", &[0], &[], "0"),
            "more than the limit",
        ),
        (
            "empty-extent.vti",
            vti("5 4 0 1 0 1", "", &[0], &[], "0"),
            "zero or negative",
        ),
        (
            "offset-past-end.vti",
            vti(small, "", &[210], &[0; 210], "999999"),
            "offset 999999, outside",
        ),
        (
            "negative-offset.vti",
            vti(small, "", &[210], &[0; 210], "-4"),
            "offset -4, outside",
        ),
        ("not-xml.vti", b"<VTKFile type=\"ImageData\" <<<".to_vec(), "malformed"),
    ];
    for (name, bytes, expected) in cases {
        let path = s.write(name, &bytes);
        let e = open(&path, None).expect_err(name).to_string();
        assert!(e.contains(name), "{name}: the message should name the file: {e}");
        assert!(e.contains(expected), "{name}: {e} should contain '{expected}'");
        // Within a host budget smaller than the claim, an appended array is read where it lies (by range): refused
        // as clearly, before any block is decoded past what the file holds.
        let budgets = volcast::pyramid::budget::Budgets::host(Some(100));
        let e = volcast::scale::open(&path, &Default::default(), budgets, None, &mut |_| {}).expect_err(name);
        assert!(e.to_string().contains(name), "{name}: within the budget: {e}");
    }
}
