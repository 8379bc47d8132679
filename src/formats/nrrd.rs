//! NRRD: `.nrrd` with attached data and `.nhdr` headers with a detached data file. Encodings raw, gzip and
//! ascii; `sizes`, `spacings` or `space directions`, `space origin`, `endian`, `byte skip`, `line skip`.

use super::decode::{Endian, Progress};
use super::format::{self, clip, header_error, number, signed_spacing, DataLocation, Encoding, Header, Source};
use crate::volume::geometry::{self, Geometry};
use crate::volume::{Volume, VolumeError, VoxelType};
use glam::{DMat4, DVec3, DVec4};
use std::path::Path;

const FORMAT: &str = "NRRD";

pub(crate) fn is_nrrd(prefix: &[u8]) -> bool {
    prefix.starts_with(b"NRRD000")
}

fn voxel_type(name: &str) -> Option<VoxelType> {
    let n = name.trim().to_ascii_lowercase();
    Some(match n.as_str() {
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => VoxelType::U8,
        "signed char" | "int8" | "int8_t" => VoxelType::I8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => VoxelType::I16,
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => VoxelType::U16,
        "int" | "signed int" | "int32" | "int32_t" => VoxelType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => VoxelType::U32,
        "float" => VoxelType::F32,
        "double" => VoxelType::F64,
        _ => return None,
    })
}

/// Parses a NRRD header (`.nrrd` or `.nhdr`) from the file's first bytes. Attached data start after the blank
/// line that ends the header (plus `line skip` lines and `byte skip` bytes).
pub fn parse_header(bytes: &[u8]) -> Result<Header, VolumeError> {
    parse(bytes, "NRRD data")
}

pub(crate) fn parse(bytes: &[u8], file: &str) -> Result<Header, VolumeError> {
    let err = |problem: String| header_error(file, problem);
    if !is_nrrd(bytes) {
        return Err(err("not a NRRD file: it must start with 'NRRD000'".into()));
    }
    let (lines, blank_found) = format::header_lines(bytes, |line| line.is_empty());
    let header_end = lines.last().map_or(0, |&(_, end)| end);
    let mut h = Header::new(FORMAT);
    let mut f = Fields::default();
    for &(line, _) in lines.iter().skip(1) {
        if line.is_empty() || line.starts_with('#') || line.contains(":=") {
            continue;
        }
        let Some((field, value)) = line.split_once(':') else {
            return Err(err(format!("line '{}' is not 'field: value'", clip(line))));
        };
        f.read(file, &field.trim().to_ascii_lowercase(), value.trim(), &mut h)?;
    }
    let dimension = f.dimension.ok_or_else(|| err("no 'dimension' field".into()))?;
    let sizes = f.sizes.as_deref().ok_or_else(|| err("no 'sizes' field".into()))?;
    if !(1..=4).contains(&dimension) {
        return Err(err(format!(
            "dimension {dimension} is not supported: volcast reads 1 to 4"
        )));
    }
    if sizes.len() != dimension as usize {
        return Err(err(format!(
            "'sizes' has {} values but dimension is {dimension}",
            sizes.len()
        )));
    }
    // A 4-D file's non-spatial axis: the fourth (slowest), time or a list of volumes; or the first, where its kind
    // says so (a list, as a Slicer segmentation stores overlapping layers), its components interleaved. Every step
    // is loaded.
    let first = dimension == 4 && f.kinds.first().is_some_and(|k| !spatial_kind(k));
    h.dims = format::dims_from(file, "sizes", if first { &sizes[1..] } else { sizes })?;
    if dimension == 4 {
        h.timesteps = sizes[if first { 0 } else { 3 }].max(1) as u32;
        h.interleaved = first;
    }
    f.skip_first_axis = first;
    h.voxel_type = f.voxel_type.ok_or_else(|| err("no 'type' field".into()))?;
    h.encoding = f.encoding.ok_or_else(|| err("no 'encoding' field".into()))?;
    let spacing = f.place(file, dimension as usize, &mut h)?;
    signed_spacing(&mut h, spacing);
    if h.voxel_type.size() == 1 {
        h.endian = Endian::Little;
    }
    let skip = |base: u64| f.byte_skip.map(|b| base.saturating_add(b));
    if f.line_skip > 0 {
        return Err(err("'line skip' is not supported; use 'byte skip'".into()));
    }
    h.location = match f.data_file.take() {
        Some(name) => DataLocation::Detached { name, skip: skip(0) },
        None => {
            if !blank_found {
                return Err(err(
                    "no blank line ends the header and no 'data file' is named: where are the voxels?".into(),
                ));
            }
            DataLocation::Inline(skip(header_end as u64))
        }
    };
    if f.byte_skip.is_none() && h.encoding != Encoding::Raw {
        return Err(err("'byte skip: -1' only works with raw encoding".into()));
    }
    Ok(h)
}

/// The header's fields that are checked against each other once all are read; the others go straight to the
/// header.
struct Fields {
    dimension: Option<u32>,
    sizes: Option<Vec<i64>>,
    voxel_type: Option<VoxelType>,
    spacings: Option<Vec<f64>>,
    directions: Option<Vec<Option<[f64; 3]>>>,
    space: Option<Space>,
    encoding: Option<Encoding>,
    data_file: Option<String>,
    line_skip: u64,
    /// None for `byte skip: -1` (the data end the file).
    byte_skip: Option<u64>,
    /// Each axis's kind (`domain`, `space`, `list`, ...).
    kinds: Vec<String>,
    /// The first axis is not spatial: placement is read from the others.
    skip_first_axis: bool,
}

impl Default for Fields {
    fn default() -> Self {
        Self {
            dimension: None,
            sizes: None,
            voxel_type: None,
            spacings: None,
            directions: None,
            space: None,
            encoding: None,
            data_file: None,
            line_skip: 0,
            byte_skip: Some(0),
            kinds: Vec::new(),
            skip_first_axis: false,
        }
    }
}

impl Fields {
    /// One `field: value` line (field in lower case). A table: each arm reads one field.
    fn read(&mut self, file: &str, field: &str, value: &str, h: &mut Header) -> Result<(), VolumeError> {
        let err = |problem: String| header_error(file, problem);
        match field {
            "dimension" => self.dimension = Some(number::<u32>(file, "dimension", value)?),
            "type" => {
                self.voxel_type = Some(voxel_type_of(value).ok_or_else(|| VolumeError::UnsupportedType {
                    file: file.to_string(),
                    format: FORMAT,
                    given: clip(value),
                })?)
            }
            "sizes" => {
                let s: Result<Vec<i64>, _> = value.split_whitespace().map(|v| number(file, "sizes", v)).collect();
                self.sizes = Some(s?);
            }
            "spacings" => self.spacings = Some(value.split_whitespace().map(nrrd_float).collect()),
            "space directions" => self.directions = Some(parse_directions(file, value)?),
            "space" => {
                self.space = Some(Space::parse(value).ok_or_else(|| {
                    err(format!(
                        "space '{}' is not one the NRRD format names (e.g. right-anterior-superior, \
                         left-posterior-superior, scanner-xyz, 3D-right-handed)",
                        clip(value)
                    ))
                })?)
            }
            "space origin" => {
                let v =
                    parse_vector(value).ok_or_else(|| err(format!("space origin '{}' is not (x,y,z)", clip(value))))?;
                h.origin = Some(v);
            }
            "encoding" => self.encoding = Some(encoding_of(file, value)?),
            "endian" => {
                h.endian = Endian::parse(value)
                    .ok_or_else(|| err(format!("endian '{}' must be little or big", clip(value))))?
            }
            "data file" | "datafile" => {
                if value.starts_with("LIST") || value.split_whitespace().count() > 1 {
                    return Err(err(format!(
                        "data file '{}': lists and numbered file patterns are not supported, only one file",
                        clip(value)
                    )));
                }
                self.data_file = Some(value.to_string());
            }
            "line skip" | "lineskip" => self.line_skip = number(file, "line skip", value)?,
            "byte skip" | "byteskip" => {
                self.byte_skip = match number::<i64>(file, "byte skip", value)? {
                    -1 => None,
                    n => Some(u64::try_from(n).map_err(|_| err(format!("byte skip {n} must be -1 or at least 0")))?),
                }
            }
            "kinds" => self.kinds = value.split_whitespace().map(str::to_ascii_lowercase).collect(),
            "space dimension" | "centerings" | "labels" | "units" | "space units" | "content" | "min" | "max"
            | "old min" | "oldmin" | "old max" | "oldmax" | "block size" | "blocksize" | "measurement frame"
            | "sample units" | "axis mins" | "axismins" | "axis maxs" | "axismaxs" | "thicknesses" | "number" => {}
            other => h.notes.push(format!("NRRD field '{}' ignored", clip(other))),
        }
        Ok(())
    }

    /// Places the axes by `space directions` (in `space`), else sizes them by `spacings`; returns the spacing.
    fn place(&self, file: &str, dimension: usize, h: &mut Header) -> Result<[f64; 3], VolumeError> {
        let err = |problem: String| header_error(file, problem);
        let mut spacing = [1.0; 3];
        if let Some(dirs) = &self.directions {
            if dirs.len() != dimension {
                return Err(err(format!(
                    "'space directions' has {} entries but dimension is {dimension}",
                    dirs.len()
                )));
            }
            // Columns of the voxel-to-space matrix; a non-spatial axis ("none") keeps a unit step along its own
            // axis.
            let mut columns = [DVec3::X, DVec3::Y, DVec3::Z];
            for (i, d) in dirs.iter().skip(usize::from(self.skip_first_axis)).take(3).enumerate() {
                if let Some(v) = d {
                    columns[i] = DVec3::from_array(*v);
                    spacing[i] = columns[i].length();
                }
            }
            let space = self.space.unwrap_or(Space::Unnamed);
            let origin = DVec3::from_array(h.origin.unwrap_or([0.0; 3]));
            let affine = space.to_world() * geometry::from_columns(columns, origin);
            h.geometry = Some(Geometry {
                affine,
                anatomical: space.anatomical(),
            });
            if space == Space::LeftHanded {
                h.notes
                    .push("space 3D-left-handed: x is mirrored to place it in volcast's right-handed world".into());
            }
        } else if let Some(s) = &self.spacings {
            if s.len() != dimension {
                return Err(err(format!(
                    "'spacings' has {} values but dimension is {dimension}",
                    s.len()
                )));
            }
            for (i, v) in s.iter().skip(usize::from(self.skip_first_axis)).take(3).enumerate() {
                // NaN marks a non-spatial axis in NRRD.
                if !v.is_nan() {
                    spacing[i] = *v;
                }
            }
            if self.space.is_some_and(|s| s.anatomical()) {
                h.notes.push(
                    "a space is named but no 'space directions' place the axes in it: no orientation applied".into(),
                );
            }
        }
        Ok(spacing)
    }
}

/// Whether an axis of this NRRD kind is spatial (or time): `domain`, `space`, `time`; `???` and `none` count as
/// such, as readers take an axis of unknown kind.
fn spatial_kind(kind: &str) -> bool {
    matches!(kind, "domain" | "space" | "time" | "???" | "none")
}

fn encoding_of(file: &str, value: &str) -> Result<Encoding, VolumeError> {
    Ok(match value.to_ascii_lowercase().as_str() {
        "raw" => Encoding::Raw,
        "gzip" | "gz" => Encoding::Gzip,
        "ascii" | "text" | "txt" => Encoding::Ascii,
        other => {
            return Err(header_error(
                file,
                format!("encoding '{}' is not supported: use raw, gzip or ascii", clip(other)),
            ))
        }
    })
}

/// The NRRD format's `space` values (teem's nrrdSpace), and how each maps to volcast's world.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Space {
    /// right-anterior-superior (RAS), with or without time.
    Ras,
    /// left-anterior-superior (LAS).
    Las,
    /// left-posterior-superior (LPS): DICOM's and ITK's.
    Lps,
    /// scanner-xyz, 3D-right-handed: a right-handed space without anatomical names.
    Plain,
    /// 3D-left-handed: mirrored into the right-handed world.
    LeftHanded,
    /// No `space` field, only `space dimension`.
    Unnamed,
}

impl Space {
    fn parse(value: &str) -> Option<Space> {
        Some(match value.trim().to_ascii_lowercase().as_str() {
            "right-anterior-superior" | "ras" | "right-anterior-superior-time" | "rast" => Space::Ras,
            "left-anterior-superior" | "las" | "left-anterior-superior-time" | "last" => Space::Las,
            "left-posterior-superior" | "lps" | "left-posterior-superior-time" | "lpst" => Space::Lps,
            "scanner-xyz" | "scanner-xyz-time" | "3d-right-handed" | "3d-right-handed-time" => Space::Plain,
            "3d-left-handed" | "3d-left-handed-time" => Space::LeftHanded,
            _ => return None,
        })
    }

    fn anatomical(self) -> bool {
        matches!(self, Space::Ras | Space::Las | Space::Lps)
    }

    /// The file's space to volcast's world (RAS+ for the anatomical spaces).
    fn to_world(self) -> DMat4 {
        let flip = |x: f64, y: f64| DMat4::from_diagonal(DVec4::new(x, y, 1.0, 1.0));
        match self {
            Space::Ras | Space::Plain | Space::Unnamed => DMat4::IDENTITY,
            Space::Las | Space::LeftHanded => flip(-1.0, 1.0),
            Space::Lps => flip(-1.0, -1.0),
        }
    }
}

fn voxel_type_of(value: &str) -> Option<VoxelType> {
    voxel_type(value)
}

/// NRRD writes NaN for "no value" (`nan`, `NaN`).
fn nrrd_float(s: &str) -> f64 {
    s.parse::<f64>().unwrap_or(f64::NAN)
}

/// `(x,y,z)`, or `(x,y,z,t)` in a space with time, whose time component is left out.
fn parse_vector(s: &str) -> Option<[f64; 3]> {
    let inner = s.trim().strip_prefix('(')?.strip_suffix(')')?;
    let v: Vec<f64> = inner
        .split(',')
        .map(|c| c.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .ok()?;
    ((v.len() == 3 || v.len() == 4) && v.iter().all(|c| c.is_finite())).then(|| [v[0], v[1], v[2]])
}

/// `(a,b,c) (d,e,f) none ...`.
fn parse_directions(file: &str, s: &str) -> Result<Vec<Option<[f64; 3]>>, VolumeError> {
    s.split_whitespace()
        .map(|part| {
            if part.eq_ignore_ascii_case("none") {
                Ok(None)
            } else {
                parse_vector(part)
                    .map(Some)
                    .ok_or_else(|| header_error(file, format!("space direction '{}' is not (x,y,z)", clip(part))))
            }
        })
        .collect()
}

/// Loads a NRRD file with attached data held in memory.
pub fn from_bytes(bytes: &[u8]) -> Result<Volume, VolumeError> {
    let header = parse_header(bytes)?;
    format::load(
        header,
        "nrrd".into(),
        "NRRD data",
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
    use flate2::write::GzEncoder;
    use std::io::Write;

    fn nrrd(fields: &str, data: &[u8]) -> Vec<u8> {
        let mut v = format!("NRRD0004\n# comment\n{fields}\n").into_bytes();
        v.extend_from_slice(data);
        v
    }

    fn gzip(data: &[u8]) -> Vec<u8> {
        let mut e = GzEncoder::new(Vec::new(), flate2::Compression::default());
        e.write_all(data).unwrap();
        e.finish().unwrap()
    }

    const FIELDS: &str =
        "type: unsigned short\ndimension: 3\nsizes: 2 3 4\nendian: big\nencoding: raw\nspacings: 0.5 0.75 2\n";

    fn values() -> Vec<u16> {
        (0..24).map(|i| i * 1000).collect()
    }

    #[test]
    fn raw_gzip_ascii() {
        let be: Vec<u8> = values().iter().flat_map(|v| v.to_be_bytes()).collect();
        let text: String = values().iter().map(|v| format!("{v} ")).collect();
        for bytes in [
            nrrd(FIELDS, &be),
            nrrd(&FIELDS.replace("raw", "gzip"), &gzip(&be)),
            nrrd(&FIELDS.replace("raw", "ascii"), text.as_bytes()),
        ] {
            let v = from_bytes(&bytes).unwrap();
            assert_eq!(v.dims, [2, 3, 4]);
            assert_eq!(v.spacing(), [0.5, 0.75, 2.0]);
            assert_eq!(v.source_type, VoxelType::U16);
            assert_eq!(v.value(1, 2, 3), 23000.0);
            assert_eq!(v.range, [0.0, 23000.0]);
        }
    }

    #[test]
    fn space_directions_and_origin() {
        let fields = "type: float\ndimension: 3\nsizes: 2 1 1\nencoding: raw\nendian: little\nspace: RAS\n\
                      space directions: (0,-2,0) (0.5,0,0) (0,0,3)\nspace origin: (1,2,3)\n";
        let data: Vec<u8> = [1.5f32, -2.0].iter().flat_map(|v| v.to_le_bytes()).collect();
        let v = from_bytes(&nrrd(fields, &data)).unwrap();
        assert_eq!(v.spacing(), [2.0, 0.5, 3.0]);
        assert_eq!(v.geometry.origin().to_array(), [1.0, 2.0, 3.0]);
        assert_eq!(
            v.geometry.rows()[0],
            [0.0, 0.5, 0.0, 1.0],
            "x row: +j steps 0.5 along x"
        );
        assert_eq!(v.geometry.axcodes(), Some(['P', 'R', 'S']));
        assert_eq!(v.value(1, 0, 0), -2.0);
        // 4-D with a non-spatial axis: every step, the range over all of them.
        let fields = "type: int8\ndimension: 4\nsizes: 2 1 1 3\nencoding: raw\nspacings: 1 1 1 nan\n";
        let mut v = from_bytes(&nrrd(fields, &[0xff, 7, 1, 2, 3, 4])).unwrap();
        assert_eq!((v.dims, v.timesteps()), ([2, 1, 1], 3));
        assert_eq!((v.value(0, 0, 0), v.value(1, 0, 0)), (-1.0, 7.0));
        assert_eq!(v.stored_range, [-1.0, 7.0]);
        v.show_step(2).unwrap();
        assert_eq!((v.value(0, 0, 0), v.value(1, 0, 0)), (3.0, 4.0));
    }

    fn error(fields: &str, data: &[u8]) -> String {
        from_bytes(&nrrd(fields, data)).unwrap_err().to_string()
    }

    #[test]
    fn hostile_headers() {
        let be: Vec<u8> = values().iter().flat_map(|v| v.to_be_bytes()).collect();
        let cases = [
            (FIELDS.replace("2 3 4", "2 0 4"), "zero or negative size"),
            (FIELDS.replace("2 3 4", "2 -3 4"), "zero or negative size"),
            (
                FIELDS.replace("2 3 4", "100000 100000 100000"),
                "exceed the limit of 16384",
            ),
            (
                FIELDS.replace("2 3 4", "2 3"),
                "'sizes' has 2 values but dimension is 3",
            ),
            (
                FIELDS.replace("unsigned short", "int64"),
                "unsupported NRRD voxel type 'int64'",
            ),
            (
                FIELDS.replace("encoding: raw", "encoding: bzip2"),
                "encoding 'bzip2' is not supported",
            ),
            (FIELDS.replace("encoding: raw\n", ""), "no 'encoding' field"),
            (
                FIELDS.replace("dimension: 3", "dimension: 7"),
                "dimension 7 is not supported",
            ),
            (FIELDS.replace("big", "middle"), "endian 'middle' must be little or big"),
            (
                FIELDS.replace("0.5 0.75 2", "0.5 0 2"),
                "voxel spacing 0.5 0 2 is invalid",
            ),
            (
                FIELDS.to_string() + "data file: LIST\n",
                "lists and numbered file patterns",
            ),
            (
                FIELDS.to_string() + "data file: ../../etc/passwd\n",
                "cannot be read from memory",
            ),
            (
                FIELDS.replace("encoding: raw", "encoding: gzip"),
                "gzip data is corrupt",
            ),
            (FIELDS.replace("encoding: raw", "encoding: ascii"), "ASCII value 0"),
        ];
        for (fields, expected) in cases {
            let e = error(&fields, &be);
            assert!(e.contains(expected), "{e} should contain {expected}");
        }
        let e = error(FIELDS, &be[..40]);
        assert!(
            e.contains("end after 40 of the 48 bytes that 2x3x4 uint16 needs"),
            "{e}"
        );
        let gz = gzip(&be);
        let e = error(&FIELDS.replace("raw", "gzip"), &gz[..gz.len() / 2]);
        assert!(e.contains("gzip data is corrupt") || e.contains("end after"), "{e}");
        // A tiny gzip stream claiming a huge volume is refused before allocating.
        let e = error(&FIELDS.replace("raw", "gzip").replace("2 3 4", "1000 1000 1000"), &gz);
        assert!(e.contains("cannot hold the 2000000000 bytes"), "{e}");
        let e = from_bytes(b"NRRD0004\ntype: uchar\ndimension: 1\nsizes: 3\nencoding: raw").unwrap_err();
        assert!(e.to_string().contains("no blank line ends the header"), "{e}");
        assert!(from_bytes(b"NRRX")
            .unwrap_err()
            .to_string()
            .contains("must start with 'NRRD000'"));
    }
}
