//! VTK legacy `.vtk` files holding `DATASET STRUCTURED_POINTS` with one scalar point-data array, ASCII or BINARY
//! (binary is big-endian by the VTK file-format spec).

use super::decode::{Endian, Progress};
use super::format::{
    self, clip, header_error, number, numbers, signed_spacing, DataLocation, Encoding, Header, Source,
};
use super::{Volume, VolumeError, VoxelType};
use std::path::Path;

const FORMAT: &str = "VTK legacy";

pub(crate) fn is_vtk(prefix: &[u8]) -> bool {
    prefix.len() >= 14 && prefix[..14].eq_ignore_ascii_case(b"# vtk DataFile")
}

fn voxel_type(name: &str) -> Option<VoxelType> {
    Some(match name.to_ascii_lowercase().as_str() {
        "unsigned_char" => VoxelType::U8,
        "char" | "signed_char" => VoxelType::I8,
        "short" => VoxelType::I16,
        "unsigned_short" => VoxelType::U16,
        "int" => VoxelType::I32,
        "unsigned_int" => VoxelType::U32,
        "float" => VoxelType::F32,
        "double" => VoxelType::F64,
        _ => return None,
    })
}

/// Parses the header of a VTK legacy file from its first bytes; the data start right after the
/// `LOOKUP_TABLE` line.
pub fn parse_header(bytes: &[u8]) -> Result<Header, VolumeError> {
    parse(bytes, "VTK data")
}

fn parse(bytes: &[u8], file: &str) -> Result<Header, VolumeError> {
    let err = |problem: String| header_error(file, problem);
    if !is_vtk(bytes) {
        return Err(err(
            "not a VTK legacy file: the first line must be '# vtk DataFile Version x.x'".into(),
        ));
    }
    let (lines, complete) = format::header_lines(bytes, |line| {
        line.trim_start().to_ascii_uppercase().starts_with("LOOKUP_TABLE")
    });
    if !complete {
        return Err(err(
            "the header has no 'LOOKUP_TABLE' line (it must follow 'SCALARS'); truncated file or not STRUCTURED_POINTS"
                .into(),
        ));
    }
    let mut h = Header::new(FORMAT);
    h.endian = Endian::Big;
    let mut dims = None;
    let mut point_data = None;
    let mut scalars = None;
    let mut spacing = [1.0; 3];
    let mut dataset = false;
    // Line 1 is the version, line 2 a free-form title.
    for (i, &(line, end)) in lines.iter().enumerate().skip(2) {
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        let rest = line.trim_start()[keyword.len()..].trim();
        match keyword.to_ascii_uppercase().as_str() {
            "ASCII" if i == 2 => h.encoding = Encoding::Ascii,
            "BINARY" if i == 2 => h.encoding = Encoding::Raw,
            _ if i == 2 => return Err(err(format!("line 3 must be ASCII or BINARY, not '{}'", clip(line)))),
            "DATASET" => {
                if !rest.eq_ignore_ascii_case("STRUCTURED_POINTS") {
                    return Err(err(format!(
                        "DATASET {} is not supported: volcast reads STRUCTURED_POINTS (a regular grid)",
                        clip(rest)
                    )));
                }
                dataset = true;
            }
            "DIMENSIONS" => {
                let d: Vec<i64> = numbers(file, "DIMENSIONS", rest, 3)?;
                dims = Some(format::dims_from(file, "DIMENSIONS", &d)?);
            }
            "SPACING" | "ASPECT_RATIO" => {
                let s: Vec<f64> = numbers(file, keyword, rest, 3)?;
                spacing = [s[0], s[1], s[2]];
            }
            "ORIGIN" => {
                let o: Vec<f64> = numbers(file, "ORIGIN", rest, 3)?;
                h.origin = Some([o[0], o[1], o[2]]);
            }
            "POINT_DATA" => point_data = Some(number::<u64>(file, "POINT_DATA", rest)?),
            "SCALARS" => {
                let parts: Vec<&str> = rest.split_whitespace().collect();
                if parts.len() < 2 {
                    return Err(err(format!("'SCALARS {}' needs a name and a type", clip(rest))));
                }
                let t = voxel_type(parts[1]).ok_or_else(|| VolumeError::UnsupportedType {
                    file: file.to_string(),
                    format: FORMAT,
                    given: clip(parts[1]),
                })?;
                if let Some(components) = parts.get(2) {
                    if number::<u32>(file, "SCALARS component count", components)? != 1 {
                        return Err(err(format!(
                            "SCALARS with {} components: volcast reads one value per voxel",
                            clip(components)
                        )));
                    }
                }
                scalars = Some(t);
            }
            "LOOKUP_TABLE" => {
                h.location = DataLocation::Inline(Some(end as u64));
            }
            "CELL_DATA" | "VECTORS" | "NORMALS" | "TENSORS" | "FIELD" | "COLOR_SCALARS" | "TEXTURE_COORDINATES" => {
                return Err(err(format!(
                    "{keyword} before the point SCALARS: volcast reads one SCALARS array of POINT_DATA"
                )))
            }
            _ => return Err(err(format!("unknown keyword '{}'", clip(keyword)))),
        }
    }
    if lines.len() < 3 {
        return Err(err("the header ends before the ASCII/BINARY line".into()));
    }
    if !dataset {
        return Err(err("no 'DATASET STRUCTURED_POINTS' line".into()));
    }
    let dims = dims.ok_or_else(|| err("no DIMENSIONS line".into()))?;
    let voxel_type = scalars.ok_or_else(|| err("no SCALARS line before LOOKUP_TABLE".into()))?;
    // u128: three u32 sizes can overflow u64.
    let count: u128 = dims.iter().map(|&d| u128::from(d)).product();
    match point_data {
        Some(n) if u128::from(n) == count => {}
        Some(n) => {
            return Err(err(format!(
                "POINT_DATA {n} does not match DIMENSIONS {}x{}x{} ({count} points)",
                dims[0], dims[1], dims[2]
            )))
        }
        None => return Err(err("no POINT_DATA line before SCALARS".into())),
    }
    h.dims = dims;
    h.voxel_type = voxel_type;
    signed_spacing(&mut h, spacing);
    Ok(h)
}

/// Loads a VTK legacy file held in memory.
pub fn from_bytes(bytes: &[u8]) -> Result<Volume, VolumeError> {
    let header = parse_header(bytes)?;
    format::load(
        header,
        "vtk".into(),
        "VTK data",
        Source::Bytes(bytes),
        &mut Progress::none(),
    )
}

pub(crate) fn load(path: &Path, progress: &mut Progress) -> Result<Volume, VolumeError> {
    let file = format::file_label(path);
    let prefix = format::read_prefix(path, format::HEADER_LIMIT)?;
    let header = parse(&prefix, &file)?;
    format::load(header, format::volume_name(path), &file, Source::File(path), progress)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelData;

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
                "POINT_DATA 12 does not match",
            ),
            (
                ok.replace("short 1", "long 1"),
                "unsupported VTK legacy voxel type 'long'",
            ),
            (ok.replace("short 1", "short 3"), "3 components"),
            (
                ok.replace("STRUCTURED_POINTS", "POLYDATA"),
                "DATASET POLYDATA is not supported",
            ),
            (ok.replace("BINARY", "HEX"), "line 3 must be ASCII or BINARY"),
            (ok.replace("LOOKUP_TABLE default\n", ""), "no 'LOOKUP_TABLE' line"),
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
}
