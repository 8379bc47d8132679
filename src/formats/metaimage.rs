//! MetaImage (ITK): `.mha` with the data after the header (`ElementDataFile = LOCAL`) and `.mhd` naming a data file
//! beside it. `CompressedData = True` is a zlib stream.

use super::decode::{Endian, Progress};
use super::format::{
    self, clip, header_error, number, numbers, signed_spacing, DataLocation, Encoding, Header, Source,
};
use crate::volume::geometry::{self, Geometry};
use crate::volume::{Volume, VolumeError, VoxelType};
use glam::DVec3;
use std::path::Path;

const FORMAT: &str = "MetaImage";

/// A MetaImage header starts with one of these keys (ITK writes `ObjectType` first; hand-written ones vary).
pub(crate) fn is_metaimage(prefix: &[u8]) -> bool {
    let start = String::from_utf8_lossy(&prefix[..prefix.len().min(64)]).to_ascii_lowercase();
    ["objecttype", "ndims", "dimsize", "comment"]
        .iter()
        .any(|k| start.trim_start().starts_with(k) && start.contains('='))
}

fn voxel_type(name: &str) -> Option<VoxelType> {
    Some(match name.trim().to_ascii_uppercase().as_str() {
        "MET_UCHAR" => VoxelType::U8,
        "MET_CHAR" => VoxelType::I8,
        "MET_SHORT" => VoxelType::I16,
        "MET_USHORT" => VoxelType::U16,
        "MET_INT" => VoxelType::I32,
        "MET_UINT" => VoxelType::U32,
        "MET_FLOAT" => VoxelType::F32,
        "MET_DOUBLE" => VoxelType::F64,
        _ => return None,
    })
}

/// ITK's orientation codes name where each axis comes *from* (ITK's SpatialOrientation: "RAI" is the identity
/// direction in LPS, axis i running from right to left): the axis directions in LPS.
fn from_orientation_code(code: &str) -> Option<[DVec3; 3]> {
    let letters: Vec<char> = code.trim().chars().map(|c| c.to_ascii_uppercase()).collect();
    if letters.len() != 3 {
        return None;
    }
    let mut seen = [false; 3];
    let mut out = [DVec3::ZERO; 3];
    for (axis, letter) in letters.iter().enumerate() {
        let (world, v) = match letter {
            'R' => (0, DVec3::X),
            'L' => (0, -DVec3::X),
            'A' => (1, DVec3::Y),
            'P' => (1, -DVec3::Y),
            'I' => (2, DVec3::Z),
            'S' => (2, -DVec3::Z),
            _ => return None,
        };
        if std::mem::replace(&mut seen[world], true) {
            return None;
        }
        out[axis] = v;
    }
    Some(out)
}

fn truth(file: &str, key: &str, value: &str) -> Result<bool, VolumeError> {
    match value.trim().to_ascii_lowercase().as_str() {
        "true" | "1" => Ok(true),
        "false" | "0" => Ok(false),
        _ => Err(header_error(
            file,
            format!("{key} = '{}' must be True or False", clip(value)),
        )),
    }
}

/// Parses a MetaImage header; `ElementDataFile` must be its last line.
pub fn parse_header(bytes: &[u8]) -> Result<Header, VolumeError> {
    parse(bytes, "MetaImage data")
}

pub(crate) fn parse(bytes: &[u8], file: &str) -> Result<Header, VolumeError> {
    let err = |problem: String| header_error(file, problem);
    let (lines, complete) = format::header_lines(bytes, |line| {
        line.split('=')
            .next()
            .is_some_and(|k| k.trim().eq_ignore_ascii_case("ElementDataFile"))
    });
    if !complete {
        return Err(err(
            "no 'ElementDataFile' line ends the header (truncated file or not MetaImage)".into(),
        ));
    }
    let mut h = Header::new(FORMAT);
    let mut keys = Keys::default();
    for &(line, end) in &lines {
        if line.trim().is_empty() {
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            return Err(err(format!("line '{}' is not 'Key = Value'", clip(line))));
        };
        keys.read(file, key.trim(), value.trim(), end, &mut h)?;
    }
    let ndims = keys.size(file, &mut h)?;
    h.voxel_type = keys.element_type.ok_or_else(|| err("no ElementType line".into()))?;
    if let Some(text) = keys.spacing.take().or(keys.element_size.take()) {
        let s: Vec<f64> = numbers(file, "ElementSpacing", &text, ndims as usize)?;
        let mut sp = [1.0; 3];
        for (i, v) in s.iter().take(3).enumerate() {
            sp[i] = *v;
        }
        signed_spacing(&mut h, sp);
    }
    keys.place(ndims, &mut h);
    h.encoding = match (keys.binary, keys.compressed) {
        (true, false) => Encoding::Raw,
        (true, true) => Encoding::Zlib,
        (false, false) => Encoding::Ascii,
        (false, true) => return Err(err("CompressedData = True needs BinaryData = True".into())),
    };
    if keys.compressed_size.is_some_and(|c| c == 0) {
        return Err(err("CompressedDataSize = 0".into()));
    }
    h.location = keys.location(file, h.encoding)?;
    Ok(h)
}

/// The header's keys that are checked against each other once all are read; the others go straight to the header.
struct Keys {
    ndims: Option<u32>,
    dim_size: Option<Vec<i64>>,
    element_type: Option<VoxelType>,
    spacing: Option<String>,
    element_size: Option<String>,
    compressed: bool,
    compressed_size: Option<u64>,
    binary: bool,
    /// `HeaderSize`: None if absent, Some(None) for -1 (the data end the file).
    header_size: Option<Option<u64>>,
    channels: u32,
    /// `ElementDataFile` and the byte after its line.
    data_file: Option<(String, usize)>,
    matrix: Option<Vec<f64>>,
    /// `AnatomicalOrientation` as written and the axis directions (LPS) it names.
    anatomical_code: Option<(String, [DVec3; 3])>,
}

impl Default for Keys {
    fn default() -> Self {
        Self {
            ndims: None,
            dim_size: None,
            element_type: None,
            spacing: None,
            element_size: None,
            compressed: false,
            compressed_size: None,
            binary: true,
            header_size: None,
            channels: 1,
            data_file: None,
            matrix: None,
            anatomical_code: None,
        }
    }
}

impl Keys {
    /// One `Key = Value` line ending at byte `end`. A table: each arm reads one key (in any case).
    fn read(&mut self, file: &str, key: &str, value: &str, end: usize, h: &mut Header) -> Result<(), VolumeError> {
        let err = |problem: String| header_error(file, problem);
        match key.to_ascii_lowercase().as_str() {
            "objecttype" if !value.eq_ignore_ascii_case("image") => {
                return Err(err(format!("ObjectType = {}: volcast reads images", clip(value))))
            }
            "ndims" => self.ndims = Some(number::<u32>(file, "NDims", value)?),
            "dimsize" => {
                let d: Result<Vec<i64>, _> = value.split_whitespace().map(|v| number(file, "DimSize", v)).collect();
                self.dim_size = Some(d?);
            }
            "elementtype" => {
                self.element_type = Some(voxel_type(value).ok_or_else(|| VolumeError::UnsupportedType {
                    file: file.to_string(),
                    format: FORMAT,
                    given: clip(value),
                })?)
            }
            "elementspacing" => self.spacing = Some(value.to_string()),
            "elementsize" => self.element_size = Some(value.to_string()),
            "offset" | "origin" | "position" => {
                let parts: Vec<f64> = value.split_whitespace().filter_map(|p| p.parse().ok()).collect();
                if parts.len() >= 3 {
                    h.origin = Some([parts[0], parts[1], parts[2]]);
                }
            }
            "binarydatabyteordermsb" | "elementbyteordermsb" => {
                h.endian = if truth(file, key, value)? {
                    Endian::Big
                } else {
                    Endian::Little
                }
            }
            "binarydata" => self.binary = truth(file, key, value)?,
            "compresseddata" => self.compressed = truth(file, key, value)?,
            "compresseddatasize" => self.compressed_size = Some(number(file, "CompressedDataSize", value)?),
            "headersize" => {
                self.header_size = Some(match number::<i64>(file, "HeaderSize", value)? {
                    -1 => None,
                    n => Some(u64::try_from(n).map_err(|_| err(format!("HeaderSize {n} must be -1 or at least 0")))?),
                })
            }
            "elementnumberofchannels" => self.channels = number(file, "ElementNumberOfChannels", value)?,
            "transformmatrix" | "rotation" | "orientation" => self.matrix = Some(direction_matrix(file, key, value)?),
            // ITK writes '????' (one '?' per axis) where it has no code: 4-D images, oblique directions.
            "anatomicalorientation" if !value.is_empty() && value.chars().all(|c| c == '?') => {}
            "anatomicalorientation" => {
                let stated = from_orientation_code(value).ok_or_else(|| {
                    err(format!(
                        "AnatomicalOrientation '{}' is not three of R/L, A/P, S/I, one of each",
                        clip(value)
                    ))
                })?;
                self.anatomical_code = Some((value.to_ascii_uppercase(), stated));
            }
            "elementdatafile" => self.data_file = Some((value.to_string(), end)),
            _ => {}
        }
        Ok(())
    }

    /// Checks NDims, DimSize and the channels and sets the header's size; returns NDims.
    fn size(&self, file: &str, h: &mut Header) -> Result<u32, VolumeError> {
        let err = |problem: String| header_error(file, problem);
        let ndims = self.ndims.ok_or_else(|| err("no NDims line".into()))?;
        if !(1..=4).contains(&ndims) {
            return Err(err(format!("NDims = {ndims} is not supported: volcast reads 1 to 4")));
        }
        let dim_size = self.dim_size.as_deref().ok_or_else(|| err("no DimSize line".into()))?;
        if dim_size.len() != ndims as usize {
            return Err(err(format!(
                "DimSize has {} values but NDims is {ndims}",
                dim_size.len()
            )));
        }
        h.dims = format::dims_from(file, "DimSize", dim_size)?;
        // The fourth (slowest) axis is time: every step is loaded.
        if ndims == 4 {
            h.timesteps = dim_size[3].max(1) as u32;
        }
        if self.channels != 1 {
            return Err(err(format!(
                "ElementNumberOfChannels = {}: volcast reads one value per voxel",
                self.channels
            )));
        }
        Ok(ndims)
    }

    /// ITK's physical space is LPS, and ITK (so SimpleITK and 3D Slicer) reads every MetaImage in it: the direction
    /// matrix holds axis i's direction in its i-th triple (MetaImageIO::Read: SetDirection(i, m[3i..3i + 3])), and
    /// is the identity when the file has none. AnatomicalOrientation does not enter: ITK's reader ignores it
    /// (SimpleITK 2.5.7 reads `AnatomicalOrientation = RAS` without a matrix as the identity), so it is only noted
    /// where it disagrees.
    fn place(&self, ndims: u32, h: &mut Header) {
        let directions = match &self.matrix {
            // A 4-D image's matrix is 4x4 (ITK writes NDims x NDims); its spatial part is the first three of the
            // first three rows.
            Some(m) => {
                let n = if ndims == 4 && m.len() >= 16 { 4 } else { 3 };
                [0, 1, 2].map(|i| DVec3::new(m[n * i], m[n * i + 1], m[n * i + 2]))
            }
            None => [DVec3::X, DVec3::Y, DVec3::Z],
        };
        if let Some((code, stated)) = &self.anatomical_code {
            let agrees = (0..3).all(|i| directions[i].normalize_or_zero().dot(stated[i]) > 1.0 - 1e-6);
            if !agrees {
                h.notes.push(format!(
                    "AnatomicalOrientation {code} disagrees with the direction ({}): ignored, as ITK does",
                    if self.matrix.is_some() {
                        "TransformMatrix"
                    } else {
                        "the identity, as the file has no TransformMatrix"
                    }
                ));
            }
        }
        let columns = [0, 1, 2].map(|i| directions[i].normalize_or_zero() * h.spacing[i]);
        let origin = DVec3::from_array(h.origin.unwrap_or([0.0; 3]));
        h.geometry = Some(Geometry::anatomical(
            geometry::LPS_TO_RAS * geometry::from_columns(columns, origin),
        ));
    }

    /// Where the voxels are: after the header (`LOCAL`) or in the one file named, after `HeaderSize` bytes.
    fn location(self, file: &str, encoding: Encoding) -> Result<DataLocation, VolumeError> {
        let err = |problem: String| header_error(file, problem);
        let (name, end) = self.data_file.ok_or_else(|| err("no ElementDataFile line".into()))?;
        let skip = self.header_size.unwrap_or(Some(0));
        if skip.is_none() && encoding != Encoding::Raw {
            return Err(err("HeaderSize = -1 only works with uncompressed binary data".into()));
        }
        if name.eq_ignore_ascii_case("LOCAL") {
            Ok(DataLocation::Inline(Some(end as u64)))
        } else if name.eq_ignore_ascii_case("LIST") || name.contains('%') || name.split_whitespace().count() > 1 {
            Err(err(format!(
                "ElementDataFile = {}: lists and numbered file patterns are not supported, only LOCAL or one file",
                clip(&name)
            )))
        } else {
            Ok(DataLocation::Detached { name, skip })
        }
    }
}

/// `TransformMatrix` (or its synonyms `Rotation`, `Orientation`): at least nine finite numbers.
fn direction_matrix(file: &str, key: &str, value: &str) -> Result<Vec<f64>, VolumeError> {
    let m: Vec<f64> = value.split_whitespace().filter_map(|p| p.parse().ok()).collect();
    if m.len() < 9 || m.iter().any(|v| !v.is_finite()) {
        return Err(header_error(
            file,
            format!("{key} '{}' is not nine numbers (a 3-D direction matrix)", clip(value)),
        ));
    }
    Ok(m)
}

/// Loads a MetaImage with `ElementDataFile = LOCAL` held in memory.
pub fn from_bytes(bytes: &[u8]) -> Result<Volume, VolumeError> {
    let header = parse_header(bytes)?;
    format::load(
        header,
        "metaimage".into(),
        "MetaImage data",
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
    use std::io::Write;

    const HEADER: &str = "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n\
                          CompressedData = False\nElementSpacing = 0.5 1 1.5\nOffset = 10 20 30\nDimSize = 3 2 2\n\
                          ElementType = MET_FLOAT\nElementDataFile = LOCAL\n";

    fn values() -> Vec<f32> {
        (0..12).map(|i| i as f32 * 0.5 - 1.0).collect()
    }

    fn mha(header: &str, data: &[u8]) -> Vec<u8> {
        let mut v = header.as_bytes().to_vec();
        v.extend_from_slice(data);
        v
    }

    fn zlib(data: &[u8]) -> Vec<u8> {
        let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        e.write_all(data).unwrap();
        e.finish().unwrap()
    }

    #[test]
    fn plain_big_endian_compressed_ascii() {
        let le: Vec<u8> = values().iter().flat_map(|v| v.to_le_bytes()).collect();
        let be: Vec<u8> = values().iter().flat_map(|v| v.to_be_bytes()).collect();
        let text: String = values().iter().map(|v| format!("{v} ")).collect();
        for bytes in [
            mha(HEADER, &le),
            mha(&HEADER.replace("MSB = False", "MSB = True"), &be),
            mha(
                &HEADER.replace("CompressedData = False", "CompressedData = True"),
                &zlib(&le),
            ),
            mha(
                &HEADER.replace("BinaryData = True", "BinaryData = False"),
                text.as_bytes(),
            ),
        ] {
            let v = from_bytes(&bytes).unwrap();
            assert_eq!(v.dims, [3, 2, 2]);
            assert_eq!(v.spacing(), [0.5, 1.0, 1.5]);
            // No TransformMatrix: ITK's identity direction in LPS, so x and y run to the right and front.
            assert!(v.geometry.anatomical);
            assert_eq!(v.geometry.origin().to_array(), [-10.0, -20.0, 30.0]);
            assert_eq!(
                v.geometry.linear(),
                glam::DMat3::from_diagonal(DVec3::new(-0.5, -1.0, 1.5))
            );
            assert_eq!(v.source_type, VoxelType::F32);
            assert_eq!(v.value(2, 1, 1), 4.5);
            assert_eq!(v.range, [-1.0, 4.5]);
            assert_eq!(v.format, "MetaImage");
        }
        let chars = HEADER.replace("MET_FLOAT", "MET_CHAR");
        let v = from_bytes(&mha(&chars, &[0x80, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 0x7f])).unwrap();
        assert_eq!(v.range, [-128.0, 127.0]);
        assert!(is_metaimage(HEADER.as_bytes()));
        assert!(!is_metaimage(b"NRRD0004\n"));
    }

    /// ITK reads the direction from TransformMatrix alone (identity without one): AnatomicalOrientation changes
    /// nothing and is noted where it disagrees.
    #[test]
    fn anatomical_orientation_is_ignored_as_itk_does() {
        let le: Vec<u8> = values().iter().flat_map(|v| v.to_le_bytes()).collect();
        let plain = from_bytes(&mha(HEADER, &le)).unwrap();
        let with = |extra: &str| {
            let header = HEADER.replace("DimSize", &format!("{extra}\nDimSize"));
            from_bytes(&mha(&header, &le)).unwrap()
        };
        let ras = with("AnatomicalOrientation = RAS");
        assert_eq!(ras.geometry.affine, plain.geometry.affine);
        assert!(
            ras.notes
                .iter()
                .any(|n| n.contains("AnatomicalOrientation RAS disagrees")),
            "{:?}",
            ras.notes
        );
        let rai = with("AnatomicalOrientation = RAI");
        assert!(
            rai.notes.is_empty(),
            "RAI is ITK's name for the identity: {:?}",
            rai.notes
        );
        let turned = with("TransformMatrix = 0 1 0 -1 0 0 0 0 1\nAnatomicalOrientation = RAI");
        // Axis i along LPS +y (posterior) is RAS −y; axis j along LPS −x (right) is RAS +x.
        assert_eq!(turned.geometry.linear().x_axis, DVec3::new(0.0, -0.5, 0.0));
        assert_eq!(turned.geometry.linear().y_axis, DVec3::new(1.0, 0.0, 0.0));
        assert!(turned
            .notes
            .iter()
            .any(|n| n.contains("disagrees with the direction (TransformMatrix)")));
    }

    #[test]
    fn hostile_headers() {
        let le: Vec<u8> = values().iter().flat_map(|v| v.to_le_bytes()).collect();
        let cases = [
            (HEADER.replace("3 2 2", "3 0 2"), "zero or negative size"),
            (HEADER.replace("3 2 2", "3 -2 2"), "zero or negative size"),
            (HEADER.replace("3 2 2", "100000 100000 100000"), "exceed the limit"),
            (HEADER.replace("3 2 2", "3 2"), "DimSize has 2 values but NDims is 3"),
            (
                HEADER.replace("MET_FLOAT", "MET_LONG_LONG"),
                "unsupported MetaImage voxel type 'MET_LONG_LONG'",
            ),
            (HEADER.replace("LOCAL", "../secret.raw"), "cannot be read from memory"),
            (
                HEADER.replace("LOCAL", "slice%03d.raw 1 10 1"),
                "numbered file patterns",
            ),
            (
                HEADER.replace("CompressedData = False", "CompressedData = True"),
                "zlib data is corrupt",
            ),
            (
                HEADER.replace("CompressedData = False", "CompressedData = Maybe"),
                "must be True or False",
            ),
            (
                HEADER.replace("ElementDataFile = LOCAL\n", ""),
                "no 'ElementDataFile' line",
            ),
            (HEADER.replace("NDims = 3", "NDims = 9"), "NDims = 9 is not supported"),
        ];
        for (header, expected) in cases {
            let e = from_bytes(&mha(&header, &le)).unwrap_err().to_string();
            assert!(e.contains(expected), "{e} should contain {expected}");
        }
        let e = from_bytes(&mha(HEADER, &le[..47])).unwrap_err().to_string();
        assert!(
            e.contains("end after 47 of the 48 bytes that 3x2x2 float32 needs"),
            "{e}"
        );
        let z = zlib(&le);
        let e = from_bytes(&mha(
            &HEADER.replace("CompressedData = False", "CompressedData = True"),
            &z[..z.len() - 6],
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("zlib data is corrupt") || e.contains("end after"), "{e}");
    }
}
