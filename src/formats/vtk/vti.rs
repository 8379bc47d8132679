//! VTK XML ImageData `.vti` files as VTK 9 and ParaView write them: one piece, point-data arrays in ascii, inline
//! binary (base64) or appended (raw or base64) form, uncompressed or in zlib, lz4 or lzma blocks, UInt32 or UInt64
//! block headers, either byte order. The XML before `<AppendedData>` is parsed with quick-xml; the bytes are decoded
//! in [`super::vti_data`]. The world is VTK's own (no anatomical convention), as for VTK legacy files:
//! `world = Origin + Direction · (index · Spacing)`, Direction row-major, index counted from the extent's start.

use super::vti_data::{self, Compressor, Layout, Location};
use crate::formats::decode::{Endian, Progress};
use crate::formats::format::{self, clip, header_error, named, Header};
use crate::volume::geometry::{from_columns, Geometry};
use crate::volume::{ArrayInfo, Volume, VolumeError, VoxelType};
use glam::{DMat3, DVec3};
use quick_xml::events::{BytesStart, Event};
use std::path::Path;

const FORMAT: &str = "VTK XML ImageData";

/// A VTK XML file (any dataset type): `<VTKFile` near the start, after an optional declaration and comments.
pub(crate) fn is_vtk_xml(prefix: &[u8]) -> bool {
    let trimmed = prefix.strip_prefix(b"\xef\xbb\xbf").unwrap_or(prefix);
    let start = trimmed.iter().position(|b| !b.is_ascii_whitespace());
    start.is_some_and(|s| trimmed[s] == b'<') && trimmed.windows(8).any(|w| w == b"<VTKFile")
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ArrayFormat {
    Ascii,
    Binary,
    Appended,
}

/// A `<DataArray>` of the piece's `<PointData>`.
#[derive(Clone, Debug)]
struct XmlArray {
    name: String,
    type_name: String,
    components: u32,
    format: ArrayFormat,
    offset: Option<String>,
    /// The element's text (its values for ascii and binary), as a byte range of the file.
    text: (usize, usize),
}

#[derive(Default)]
struct Parsed {
    file_type: Option<String>,
    byte_order: Option<String>,
    header_type: Option<String>,
    compressor: Option<String>,
    whole_extent: Option<String>,
    origin: Option<String>,
    spacing: Option<String>,
    direction: Option<String>,
    piece_extent: Option<String>,
    pieces: u32,
    scalars: Option<String>,
    arrays: Vec<XmlArray>,
    /// `encoding` and the byte just after `<AppendedData ...>`.
    appended: Option<(String, usize)>,
}

fn attributes(e: &BytesStart, file: &str) -> Result<Vec<(String, String)>, VolumeError> {
    let mut out = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|err| header_error(file, format!("malformed XML attribute: {err}")))?;
        let key = a.key.as_ref().to_owned();
        let value = a
            .normalized_value(quick_xml::XmlVersion::Implicit1_0)
            .map_or_else(|_| a.value.to_string(), |v| v.into_owned());
        out.push((key, value));
    }
    Ok(out)
}

fn get(attrs: &[(String, String)], key: &str) -> Option<String> {
    attrs.iter().find(|(k, _)| k == key).map(|(_, v)| v.clone())
}

/// Reads the XML up to `<AppendedData>` (whose raw bytes are not XML) or the end.
fn parse_xml(bytes: &[u8], file: &str) -> Result<Parsed, VolumeError> {
    let mut reader = quick_xml::Reader::from_reader(bytes);
    let mut p = Parsed::default();
    let mut in_point_data = false;
    let mut open_array: Option<XmlArray> = None;
    loop {
        let before = reader.buffer_position() as usize;
        let event = reader.read_event().map_err(|e| {
            header_error(
                file,
                format!("the XML is malformed near byte {}: {e}", reader.error_position()),
            )
        })?;
        let (e, is_start) = match &event {
            Event::Start(e) => (e, true),
            Event::Empty(e) => (e, false),
            Event::End(e) => {
                match e.name().as_ref() {
                    "PointData" => in_point_data = false,
                    "DataArray" => {
                        if let Some(mut a) = open_array.take() {
                            a.text.1 = before;
                            p.arrays.push(a);
                        }
                    }
                    _ => {}
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let attrs = attributes(e, file)?;
        match e.name().as_ref() {
            "VTKFile" if p.file_type.is_none() => {
                p.file_type = Some(get(&attrs, "type").unwrap_or_default());
                p.byte_order = get(&attrs, "byte_order");
                p.header_type = get(&attrs, "header_type");
                p.compressor = get(&attrs, "compressor");
            }
            "ImageData" => {
                p.whole_extent = get(&attrs, "WholeExtent");
                p.origin = get(&attrs, "Origin");
                p.spacing = get(&attrs, "Spacing");
                p.direction = get(&attrs, "Direction");
            }
            "Piece" => {
                p.pieces += 1;
                if p.pieces == 1 {
                    p.piece_extent = get(&attrs, "Extent");
                }
            }
            "PointData" if p.pieces == 1 => {
                in_point_data = is_start;
                p.scalars = get(&attrs, "Scalars");
            }
            "DataArray" if in_point_data => {
                let a = data_array(&attrs, file, reader.buffer_position() as usize)?;
                if is_start {
                    open_array = Some(a);
                } else {
                    p.arrays.push(a);
                }
            }
            "AppendedData" => {
                let encoding = get(&attrs, "encoding").unwrap_or_else(|| "raw".into());
                p.appended = Some((encoding, reader.buffer_position() as usize));
                break;
            }
            _ => {}
        }
    }
    Ok(p)
}

/// A `<DataArray>` start tag whose text starts at `text_start`.
fn data_array(attrs: &[(String, String)], file: &str, text_start: usize) -> Result<XmlArray, VolumeError> {
    let format = match get(attrs, "format").unwrap_or_default().as_str() {
        "ascii" => ArrayFormat::Ascii,
        "binary" => ArrayFormat::Binary,
        "appended" => ArrayFormat::Appended,
        other => {
            return Err(header_error(
                file,
                format!("DataArray format '{}' is not ascii, binary or appended", clip(other)),
            ))
        }
    };
    let components = match get(attrs, "NumberOfComponents") {
        Some(c) => format::number::<u32>(file, "NumberOfComponents", &c)?,
        None => 1,
    };
    Ok(XmlArray {
        name: get(attrs, "Name").unwrap_or_default(),
        type_name: get(attrs, "type").unwrap_or_default(),
        components,
        format,
        offset: get(attrs, "offset"),
        text: (text_start, text_start),
    })
}

fn voxel_type(name: &str) -> Option<VoxelType> {
    Some(match name {
        "Int8" => VoxelType::I8,
        "UInt8" => VoxelType::U8,
        "Int16" => VoxelType::I16,
        "UInt16" => VoxelType::U16,
        "Int32" => VoxelType::I32,
        "UInt32" => VoxelType::U32,
        "Float32" => VoxelType::F32,
        "Float64" => VoxelType::F64,
        _ => return None,
    })
}

fn floats<const N: usize>(
    file: &str,
    field: &str,
    text: Option<&str>,
    default: [f64; N],
) -> Result<[f64; N], VolumeError> {
    let Some(text) = text else { return Ok(default) };
    let v: Vec<f64> = format::numbers(file, field, text, N)?;
    let mut out = default;
    out.copy_from_slice(&v);
    if out.iter().any(|x| !x.is_finite()) {
        return Err(header_error(file, format!("{field} '{}' is not finite", clip(text))));
    }
    Ok(out)
}

/// The array to load: the one named, else the `Scalars` attribute's, else the first one-component array.
fn select<'a>(p: &'a Parsed, wanted: Option<&str>, file: &str) -> Result<&'a XmlArray, VolumeError> {
    let list = || {
        let names: Vec<String> = p
            .arrays
            .iter()
            .map(|a| format!("{} ({}, {} components)", clip(&a.name), a.type_name, a.components))
            .collect();
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    };
    let by_name = |name: &str| p.arrays.iter().find(|a| a.name == name);
    let chosen = match wanted {
        Some(name) => by_name(name).ok_or_else(|| {
            header_error(
                file,
                format!("no point array named '{}'; the file has: {}", clip(name), list()),
            )
        })?,
        None => p
            .scalars
            .as_deref()
            .and_then(by_name)
            .filter(|a| a.components == 1)
            .or_else(|| p.arrays.iter().find(|a| a.components == 1))
            .ok_or_else(|| {
                header_error(
                    file,
                    format!("no one-component point array to load; the file has: {}", list()),
                )
            })?,
    };
    if chosen.components != 1 {
        return Err(format::not_one_component(file, &chosen.name, chosen.components));
    }
    Ok(chosen)
}

/// The header of the parsed `p` for the array `wanted` (or the default one), that array, and how binary data are
/// stored (byte order, header word size, compressor).
fn header_of<'p>(
    p: &'p Parsed,
    file: &str,
    wanted: Option<&str>,
) -> Result<(Header, &'p XmlArray, Stored), VolumeError> {
    check_single_image(p, file)?;
    let stored = encoding(p, file)?;
    let (extent, dims) = extent(p, file)?;
    crate::volume::check_dims(dims).map_err(|e| named(file, e))?;
    let (spacing, geometry) = placement(p, file, &extent)?;
    let chosen = select(p, wanted, file)?;
    let voxel_type = voxel_type(&chosen.type_name).ok_or_else(|| VolumeError::UnsupportedType {
        file: file.to_string(),
        format: FORMAT,
        given: clip(&chosen.type_name),
    })?;
    let mut h = Header::new(FORMAT);
    h.dims = dims;
    h.voxel_type = voxel_type;
    h.endian = stored.0;
    h.spacing = spacing.map(f64::abs);
    h.geometry = Some(geometry);
    if p.piece_extent.is_some() && p.whole_extent.is_some() && p.piece_extent != p.whole_extent {
        h.notes
            .push("the piece's Extent differs from WholeExtent; the piece is read".into());
    }
    h.arrays = p
        .arrays
        .iter()
        .map(|a| ArrayInfo {
            name: a.name.clone(),
            type_name: a.type_name.clone(),
            components: a.components,
            loaded: std::ptr::eq(a, chosen),
        })
        .collect();
    Ok((h, chosen, stored))
}

/// Parses and loads a `.vti` held in memory; `file` names it in messages.
fn read(
    bytes: &[u8],
    file: &str,
    name: String,
    wanted: Option<&str>,
    progress: &mut Progress,
) -> Result<Volume, VolumeError> {
    let p = parse_xml(bytes, file)?;
    let (h, chosen, (endian, word, compressor)) = header_of(&p, file, wanted)?;
    let location = location(bytes, &p, chosen, file)?;
    let layout = Layout {
        file,
        word,
        endian,
        compressor,
        voxel_type: h.voxel_type,
        dims: h.dims,
        count: crate::volume::check_dims(h.dims).map_err(|e| named(file, e))?,
    };
    let data = vti_data::decode(&layout, location, progress)?;
    h.into_volume(name, data).map_err(|e| named(file, e))
}

/// Where an appended array lies in its file: the byte its block header (compressed) or byte count starts at, how it
/// is written (raw or base64), the header's word size and byte order, and the compressor.
pub(crate) struct Appended {
    pub at: u64,
    pub text: super::vti_blocks::Text,
    pub word: usize,
    pub endian: Endian,
    pub compressor: Option<Compressor>,
}

/// The header of `path`'s array `wanted` and where its values lie, when it is appended (raw, as ParaView writes,
/// or base64, VTK's default) and the XML before it fits [`format::HEADER_LIMIT`]: such a file is read where it lies
/// (`in_place`). `None` for every other layout (ascii and inline arrays): those are read whole.
pub(crate) fn appended(path: &Path, wanted: Option<&str>) -> Result<Option<(Header, Appended)>, VolumeError> {
    let file = format::file_label(path);
    let prefix = format::read_prefix(path, format::HEADER_LIMIT)?;
    // A head cut by the prefix does not parse: the whole-file reader says what is wrong, if anything.
    let Ok(p) = parse_xml(&prefix, &file) else {
        return Ok(None);
    };
    let Some((encoding, after_tag)) = p.appended.clone() else {
        return Ok(None);
    };
    let (h, chosen, (endian, word, compressor)) = header_of(&p, &file, wanted)?;
    let text = match encoding.as_str() {
        "raw" => super::vti_blocks::Text::Raw,
        "base64" => super::vti_blocks::Text::Base64,
        _ => return Ok(None),
    };
    if chosen.format != ArrayFormat::Appended {
        return Ok(None);
    }
    // The array's offset counts from the byte after the underscore that opens the appended bytes (which may lie
    // past the prefix: the caller checks the file's length).
    let err = |problem: String| header_error(&file, problem);
    let rest = &prefix[after_tag..];
    let underscore = rest
        .iter()
        .position(|&b| !b.is_ascii_whitespace())
        .filter(|&i| rest[i] == b'_')
        .ok_or_else(|| err("<AppendedData> must start with '_'".into()))?;
    let offset_text = chosen
        .offset
        .as_deref()
        .ok_or_else(|| err(format!("appended array '{}' has no offset", clip(&chosen.name))))?;
    let offset: u64 = format::number(&file, "DataArray offset", offset_text)?;
    let at = (after_tag + underscore + 1) as u64 + offset;
    let stored = Appended {
        at,
        text,
        word,
        endian,
        compressor,
    };
    Ok(Some((h, stored)))
}

/// Refuses VTK XML files other than ImageData, and ImageData of no or several pieces.
fn check_single_image(p: &Parsed, file: &str) -> Result<(), VolumeError> {
    let err = |problem: String| header_error(file, problem);
    match p.file_type.as_deref() {
        Some("ImageData") => {}
        Some(other) => {
            return Err(err(format!(
                "a VTK XML {} file; volcast reads ImageData (.vti) only",
                clip(other)
            )))
        }
        None => return Err(err("no <VTKFile> element: not a VTK XML file".into())),
    }
    match p.pieces {
        0 => Err(err("no <Piece>: the file holds no data".into())),
        1 => Ok(()),
        n => Err(err(format!(
            "{n} pieces: volcast reads single-piece ImageData (save the data set again as one piece)"
        ))),
    }
}

/// How binary data are stored: byte order, the block headers' word size in bytes, and the compressor.
type Stored = (Endian, usize, Option<Compressor>);

/// How the binary data are stored ([`Stored`]).
fn encoding(p: &Parsed, file: &str) -> Result<Stored, VolumeError> {
    let err = |problem: String| header_error(file, problem);
    let endian = match p.byte_order.as_deref() {
        None | Some("LittleEndian") => Endian::Little,
        Some("BigEndian") => Endian::Big,
        Some(other) => {
            return Err(err(format!(
                "byte_order '{}' is not LittleEndian or BigEndian",
                clip(other)
            )))
        }
    };
    let word = match p.header_type.as_deref() {
        None | Some("UInt32") => 4,
        Some("UInt64") => 8,
        Some(other) => return Err(err(format!("header_type '{}' is not UInt32 or UInt64", clip(other)))),
    };
    let compressor = match p.compressor.as_deref() {
        None | Some("") => None,
        Some("vtkZLibDataCompressor") => Some(Compressor::Zlib),
        Some("vtkLZ4DataCompressor") => Some(Compressor::Lz4),
        Some("vtkLZMADataCompressor") => Some(Compressor::Lzma),
        Some(other) => {
            return Err(err(format!(
                "compressor '{}' is unknown: volcast reads vtkZLibDataCompressor, vtkLZ4DataCompressor and \
                 vtkLZMADataCompressor",
                clip(other)
            )))
        }
    };
    Ok((endian, word, compressor))
}

/// The piece's extent (the whole extent if the piece has none) and the dimensions it spans.
fn extent(p: &Parsed, file: &str) -> Result<(Vec<i64>, [u32; 3]), VolumeError> {
    let extent_text = p
        .piece_extent
        .as_deref()
        .or(p.whole_extent.as_deref())
        .ok_or_else(|| header_error(file, "no Extent on the Piece and no WholeExtent".into()))?;
    let extent: Vec<i64> = format::numbers(file, "Extent", extent_text, 6)?;
    let sizes: Vec<i64> = (0..3)
        .map(|a| {
            extent[2 * a + 1]
                .checked_sub(extent[2 * a])
                .and_then(|d| d.checked_add(1))
                .unwrap_or(0)
        })
        .collect();
    let dims = format::dims_from(file, "Extent sizes", &sizes)?;
    Ok((extent, dims))
}

/// The spacing as written and where the voxels sit in VTK's world, the extent's start counted in.
fn placement(p: &Parsed, file: &str, extent: &[i64]) -> Result<([f64; 3], Geometry), VolumeError> {
    let spacing = floats(file, "Spacing", p.spacing.as_deref(), [1.0; 3])?;
    let origin = floats(file, "Origin", p.origin.as_deref(), [0.0; 3])?;
    let d = floats(
        file,
        "Direction",
        p.direction.as_deref(),
        [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
    )?;
    // Row-major: column a of the matrix is where index axis a points.
    let direction = DMat3::from_cols(
        DVec3::new(d[0], d[3], d[6]),
        DVec3::new(d[1], d[4], d[7]),
        DVec3::new(d[2], d[5], d[8]),
    );
    let start = DVec3::new(extent[0] as f64, extent[2] as f64, extent[4] as f64);
    let first_voxel = DVec3::from(origin) + direction * (start * DVec3::from(spacing));
    let columns = [0, 1, 2].map(|a| direction.col(a) * spacing[a]);
    let geometry = Geometry {
        affine: from_columns(columns, first_voxel),
        anatomical: false,
    };
    Ok((spacing, geometry))
}

/// Where the chosen array's values are: its element's text, or its offset into `<AppendedData>`.
fn location<'b>(bytes: &'b [u8], p: &Parsed, chosen: &XmlArray, file: &str) -> Result<Location<'b>, VolumeError> {
    let err = |problem: String| header_error(file, problem);
    let (encoding, after_tag) = match chosen.format {
        ArrayFormat::Ascii => return Ok(Location::Ascii(&bytes[chosen.text.0..chosen.text.1])),
        ArrayFormat::Binary => return Ok(Location::Base64(&bytes[chosen.text.0..chosen.text.1])),
        ArrayFormat::Appended => p.appended.as_ref().ok_or_else(|| {
            err(format!(
                "array '{}' is appended but there is no <AppendedData>",
                clip(&chosen.name)
            ))
        })?,
    };
    let offset_text = chosen
        .offset
        .as_deref()
        .ok_or_else(|| err(format!("appended array '{}' has no offset", clip(&chosen.name))))?;
    let offset: i64 = format::number(file, "DataArray offset", offset_text)?;
    let rest = &bytes[*after_tag..];
    // The appended bytes start after an underscore (whitespace before it).
    let underscore = rest
        .iter()
        .position(|&b| !b.is_ascii_whitespace())
        .filter(|&i| rest[i] == b'_')
        .ok_or_else(|| err("<AppendedData> must start with '_'".into()))?;
    let data = &rest[underscore + 1..];
    let offset = u64::try_from(offset)
        .ok()
        .and_then(|o| usize::try_from(o).ok())
        .filter(|&o| o <= data.len())
        .ok_or_else(|| {
            err(format!(
                "array '{}' has offset {offset}, outside the {} bytes of appended data",
                clip(&chosen.name),
                data.len()
            ))
        })?;
    match encoding.as_str() {
        "raw" => Ok(Location::Raw(&data[offset..])),
        "base64" => Ok(Location::Base64(&data[offset..])),
        other => Err(err(format!(
            "AppendedData encoding '{}' is not raw or base64",
            clip(other)
        ))),
    }
}

/// Loads a `.vti` held in memory.
pub fn from_bytes(bytes: &[u8]) -> Result<Volume, VolumeError> {
    read(bytes, "VTI data", "vti".into(), None, &mut Progress::none())
}

/// Loads a `.vti` file. The whole file is read into memory first: appended data sits after XML whose length is only
/// known by parsing it, and inline arrays are base64 text inside the XML.
pub(crate) fn load(path: &Path, array: Option<&str>, progress: &mut Progress) -> Result<Volume, VolumeError> {
    let file = format::file_label(path);
    let io = |source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let metadata = std::fs::metadata(path).map_err(io)?;
    if !metadata.is_file() {
        return Err(VolumeError::NotAFile {
            path: path.to_path_buf(),
        });
    }
    let bytes = std::fs::read(path).map_err(io)?;
    read(&bytes, &file, format::volume_name(path), array, progress)
}
