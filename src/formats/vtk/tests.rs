//! The legacy VTK reader's unit tests (hand-made files; VTK-written oracles are in tests/formats/vtk.rs).

use super::*;
use crate::volume::{VoxelData, VoxelType};

fn header(kind: &str, extra: &str) -> String {
    format!(
        "# vtk DataFile Version 3.0\nsome title\n{kind}\nDATASET STRUCTURED_POINTS\nDIMENSIONS 3 2 2\n\
         SPACING 0.5 1 2\nORIGIN 1 2 3\nPOINT_DATA 12\n{extra}SCALARS density short 1\nLOOKUP_TABLE default\n"
    )
}

#[test]
fn ascii_and_binary() {
    let values: Vec<i16> = (0..12).map(|i| i * 100 - 500).collect();
    let mut ascii = header("ASCII", "").into_bytes();
    for v in &values {
        ascii.extend(format!("{v}\n").bytes());
    }
    let mut binary = header("BINARY", "").into_bytes();
    for v in &values {
        binary.extend(v.to_be_bytes());
    }
    for bytes in [ascii, binary] {
        let v = from_bytes(&bytes).unwrap();
        assert_eq!(v.dims, [3, 2, 2]);
        assert_eq!(v.spacing(), [0.5, 1.0, 2.0]);
        assert_eq!(v.geometry.origin().to_array(), [1.0, 2.0, 3.0]);
        assert!(!v.geometry.anatomical);
        assert_eq!(v.source_type, VoxelType::I16);
        assert_eq!(v.format, "VTK legacy");
        assert_eq!(v.value(0, 0, 0), -500.0);
        assert_eq!(v.value(2, 1, 1), 600.0);
        assert_eq!(v.range, [-500.0, 600.0]);
    }
}

#[test]
fn every_scalar_type() {
    let cases = [
        ("unsigned_char", VoxelType::U8),
        ("char", VoxelType::I8),
        ("short", VoxelType::I16),
        ("unsigned_short", VoxelType::U16),
        ("int", VoxelType::I32),
        ("unsigned_int", VoxelType::U32),
        ("float", VoxelType::F32),
        ("double", VoxelType::F64),
    ];
    for (name, t) in cases {
        let text = format!(
            "# vtk DataFile Version 2.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 1 1\nPOINT_DATA 2\n\
             SCALARS s {name}\nLOOKUP_TABLE default\n0 100\n"
        );
        let v = from_bytes(text.as_bytes()).unwrap();
        assert_eq!(v.source_type, t, "{name}");
        assert_eq!(v.value(1, 0, 0), 100.0, "{name}");
        assert_eq!(v.spacing(), [1.0; 3]);
    }
    let mut bin = b"# vtk DataFile Version 2.0\nt\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 1 1\nASPECT_RATIO 1 1 3\nPOINT_DATA 2\nSCALARS s char\nLOOKUP_TABLE default\n".to_vec();
    bin.extend([0xff, 0x05]);
    let v = from_bytes(&bin).unwrap();
    assert_eq!((v.value(0, 0, 0), v.value(1, 0, 0)), (-1.0, 5.0));
    assert_eq!(v.spacing(), [1.0, 1.0, 3.0]);
    assert!(matches!(v.data, VoxelData::U8(_)));
}

fn error(text: &str) -> String {
    from_bytes(text.as_bytes()).unwrap_err().to_string()
}

#[test]
fn hostile_headers() {
    let ok = header("BINARY", "");
    let cases = [
        (
            ok.replace("DIMENSIONS 3 2 2", "DIMENSIONS 3 0 2"),
            "zero or negative size",
        ),
        (
            ok.replace("DIMENSIONS 3 2 2", "DIMENSIONS 3 -2 2"),
            "zero or negative size",
        ),
        (
            ok.replace("DIMENSIONS 3 2 2", "DIMENSIONS 100000 100000 100000")
                .replace("POINT_DATA 12", "POINT_DATA 1000000000000000"),
            "exceed the limit",
        ),
        (
            ok.replace("DIMENSIONS 3 2 2", "DIMENSIONS 3 2"),
            "DIMENSIONS needs 3 values",
        ),
        (
            ok.replace("POINT_DATA 12", "POINT_DATA 13"),
            "POINT_DATA 13 does not match",
        ),
        // Three u32 sizes whose product overflows u64.
        (
            ok.replace("DIMENSIONS 3 2 2", "DIMENSIONS 4294967295 4294967295 4294967295"),
            "exceed the limit",
        ),
        (
            ok.replace("short 1", "long 1") + &"\0".repeat(96),
            "unsupported VTK legacy voxel type 'long'",
        ),
        (ok.replace("short 1", "short 3") + &"\0".repeat(72), "3 components"),
        (
            ok.replace("STRUCTURED_POINTS", "POLYDATA"),
            "DATASET POLYDATA is not supported",
        ),
        (ok.replace("BINARY", "HEX"), "line 3 must be ASCII or BINARY"),
        // LOOKUP_TABLE is optional: the values would start right after SCALARS.
        (ok.replace("LOOKUP_TABLE default\n", ""), "end after 0 of the 24 bytes"),
        (
            ok.replace("SPACING 0.5 1 2", "SPACING 0 1 1"),
            "voxel spacing 0 1 1 is invalid",
        ),
        (
            ok.replace("SPACING 0.5 1 2", "SPACING x 1 1"),
            "SPACING 'x' is not a valid number",
        ),
        (ok.replace("# vtk", "# vtx"), "not a VTK legacy file"),
        (
            ok.clone(),
            "the voxel data end after 0 of the 24 bytes that 3x2x2 int16 needs",
        ),
        (ok.clone() + "\u{1}\u{2}\u{3}", "end after 3 of the 24 bytes"),
    ];
    for (text, expected) in cases {
        let e = error(&text);
        assert!(e.contains(expected), "{e} should contain {expected}");
    }
    let ascii = header("ASCII", "") + "1 2 3 4 5";
    assert!(error(&ascii).contains("ASCII data cannot hold 12 values") || error(&ascii).contains("after 5 of 12"));
    let ascii = header("ASCII", "") + "1 2 3 4 5 6 7 8 9 10 11 nan";
    assert!(
        error(&ascii).contains("ASCII value 11 ('nan') is not a valid int16"),
        "{}",
        error(&ascii)
    );
}

#[test]
fn nan_and_inf_load() {
    let mut bytes = b"# vtk DataFile Version 3.0\nt\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 3 1 1\nPOINT_DATA 3\nSCALARS s float\nLOOKUP_TABLE default\n".to_vec();
    for v in [f32::NAN, 2.0, f32::INFINITY] {
        bytes.extend(v.to_be_bytes());
    }
    let v = from_bytes(&bytes).unwrap();
    assert!(v.value(0, 0, 0).is_nan());
    assert_eq!(v.range, [2.0, 2.0]);
}

/// Everything VTK 9 may write around the point scalars, binary: field data, cell arrays, vectors with METADATA,
/// a lookup table, tensors, texture coordinates, a FIELD under POINT_DATA, and SCALARS without LOOKUP_TABLE.
#[test]
fn sections_around_the_scalars_are_stepped_over() {
    let mut b =
        b"# vtk DataFile Version 5.1\nt\nBINARY\nDATASET STRUCTURED_POINTS\nFIELD FieldData 1\nnote 1 2 double\n"
            .to_vec();
    b.extend([0u8; 16]);
    b.extend(b"\nDIMENSIONS 3 2 1\nSPACING 1 1 1\nORIGIN 0 0 0\nCELL_DATA 2\nSCALARS c int\nLOOKUP_TABLE default\n");
    b.extend([1u8; 8]);
    b.extend(b"\nPOINT_DATA 6\nVECTORS v float\n");
    b.extend([2u8; 72]);
    b.extend(b"\nMETADATA\nCOMPONENT_NAMES\nx y z\nINFORMATION 1\nNAME L LOCATION k\nDATA 1\n\n");
    b.extend(b"LOOKUP_TABLE lut 2\n");
    b.extend([3u8; 8]);
    b.extend(b"\nTENSORS6 t double\n");
    b.extend([4u8; 6 * 6 * 8]);
    b.extend(b"\nTEXTURE_COORDINATES tc 2 float\n");
    b.extend([5u8; 48]);
    b.extend(b"\nFIELD FieldData 2\nf 1 6 unsigned_short\n");
    for v in [10u16, 20, 30, 40, 50, 60] {
        b.extend(v.to_be_bytes());
    }
    b.extend(b"\nbits 1 6 bit\n\x00\nSCALARS s unsigned_char 1\n");
    b.extend([7u8, 8, 9, 10, 11, 12]);
    b.extend(b"\n");
    let v = from_bytes(&b).unwrap();
    assert_eq!(v.value(2, 1, 0), 12.0);
    let names: Vec<(&str, u32, bool)> = v
        .arrays
        .iter()
        .map(|a| (a.name.as_str(), a.components, a.loaded))
        .collect();
    assert_eq!(
        names,
        [
            ("v", 3, false),
            ("t", 6, false),
            ("tc", 2, false),
            ("f", 1, false),
            ("bits", 1, false),
            ("s", 1, true)
        ]
    );
    let f = from_bytes_with(&b, Some("f")).unwrap();
    assert_eq!((f.source_type, f.value(1, 1, 0)), (VoxelType::U16, 50.0));
    let e = from_bytes_with(&b, Some("v")).unwrap_err().to_string();
    assert!(e.contains("'v' has 3 components"), "{e}");
    let e = from_bytes_with(&b, Some("bits")).unwrap_err().to_string();
    assert!(e.contains("voxel type 'bit'"), "{e}");
}

#[test]
fn ascii_color_scalars_round_as_vtk_reads_them() {
    // VTK's reader gives 3 128 255 254 for the first four (× 255 + 0.5, truncated); beyond 0..1 it wraps where
    // volcast clamps.
    let text = "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 6 1 1\n\
                POINT_DATA 6\nCOLOR_SCALARS c 1\n0.0117647 0.5 0.999 0.998 1.5 -0.2\n";
    let v = from_bytes(text.as_bytes()).unwrap();
    let values: Vec<f64> = (0..6).map(|x| v.value(x, 0, 0)).collect();
    assert_eq!(values, [3.0, 128.0, 255.0, 254.0, 255.0, 0.0]);
    assert_eq!(v.source_type, VoxelType::U8);
    let rgb = text.replace("COLOR_SCALARS c 1", "COLOR_SCALARS c 3") + &"0 ".repeat(12);
    let e = from_bytes(rgb.as_bytes()).unwrap_err().to_string();
    assert!(
        e.contains("no one-component point array") && e.contains("c (unsigned_char, 3 components)"),
        "{e}"
    );
}

#[test]
fn rectilinear_grids_must_be_even() {
    let grid = |ys: &str| {
        format!(
            "# vtk DataFile Version 4.2\nx\nASCII\nDATASET RECTILINEAR_GRID\nDIMENSIONS 2 3 1\n\
             X_COORDINATES 2 float\n5 5.5\nY_COORDINATES 3 double\n{ys}\nZ_COORDINATES 1 float\n-2\n\
             POINT_DATA 6\nSCALARS s short\n1 2 3 4 5 6\n"
        )
    };
    let v = from_bytes(grid("10 8 6").as_bytes()).unwrap();
    assert_eq!(v.geometry.rows()[1][1], -2.0);
    assert_eq!(v.geometry.origin().to_array(), [5.0, 10.0, -2.0]);
    assert_eq!(v.spacing(), [0.5, 2.0, 1.0]);
    let e = from_bytes(grid("10 8.5 6").as_bytes()).unwrap_err().to_string();
    assert!(e.contains("Y_COORDINATES are not evenly spaced"), "{e}");
}
