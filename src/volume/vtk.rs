//! VTK legacy `.vtk` files (versions 2.0 to 5.1, as VTK 9 and ParaView write them) holding `DATASET
//! STRUCTURED_POINTS`, or a `RECTILINEAR_GRID` whose coordinates are evenly spaced, ASCII or BINARY (binary is
//! big-endian by the VTK file-format spec). Any number of point and cell arrays (`SCALARS`, `COLOR_SCALARS`,
//! `FIELD`, `VECTORS`, ...) in any order; one one-component point array is loaded: the one `--array` names, else
//! the first `SCALARS`/`COLOR_SCALARS`, else the first one-component `FIELD` array under `POINT_DATA`.

mod scan;
pub(crate) mod vti;
mod vti_data;

use super::decode::{Endian, Progress};
use super::format::{
    self, clip, header_error, number, numbers, signed_spacing, DataLocation, Encoding, Header, Source,
};
use super::{ArrayInfo, Volume, VolumeError, VoxelData, MAX_DIM};
use scan::{ArrayKind, PointArray, Scanner, Section};
use std::io::{BufRead, BufReader, Cursor, Seek};
use std::path::Path;

const FORMAT: &str = "VTK legacy";

pub(crate) fn is_vtk(prefix: &[u8]) -> bool {
    prefix.len() >= 14 && prefix[..14].eq_ignore_ascii_case(b"# vtk DataFile")
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Dataset {
    StructuredPoints,
    Rectilinear,
}

/// What a walk through the whole file found.
struct Layout {
    binary: bool,
    dataset: Option<Dataset>,
    dims: Option<[u32; 3]>,
    spacing: [f64; 3],
    origin: Option<[f64; 3]>,
    coordinates: [Option<Vec<f64>>; 3],
    point_data: Option<u64>,
    arrays: Vec<PointArray>,
    notes: Vec<String>,
}

fn walk<R: BufRead + Seek>(s: &mut Scanner<R>, file: &str) -> Result<Layout, VolumeError> {
    let err = |problem: String| header_error(file, problem);
    let first = s.line()?.unwrap_or_default();
    if !is_vtk(first.as_bytes()) {
        return Err(err(
            "not a VTK legacy file: the first line must be '# vtk DataFile Version x.x'".into(),
        ));
    }
    let mut notes = Vec::new();
    let version = first[14..]
        .trim()
        .trim_start_matches(|c: char| c.is_ascii_alphabetic())
        .trim();
    match version.parse::<f64>() {
        Ok(v) if v <= 5.1 + 1e-9 => {}
        _ => notes.push(format!(
            "file version '{}' is not one volcast knows (2.0 to 5.1); read as 5.1",
            clip(version)
        )),
    }
    let _title = s.line()?;
    let mode = s.line()?.unwrap_or_default();
    s.binary = match mode.trim().to_ascii_uppercase().as_str() {
        "ASCII" => false,
        "BINARY" => true,
        _ => return Err(err(format!("line 3 must be ASCII or BINARY, not '{}'", clip(&mode)))),
    };
    let mut l = Layout {
        binary: s.binary,
        dataset: None,
        dims: None,
        spacing: [1.0; 3],
        origin: None,
        coordinates: [None, None, None],
        point_data: None,
        arrays: Vec::new(),
        notes,
    };
    let mut section = Section::Dataset;
    while let Some(line) = s.keyword_line()? {
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        let rest = line.trim_start()[keyword.len()..].trim();
        let args: Vec<&str> = rest.split_whitespace().collect();
        let keyword = keyword.to_ascii_uppercase();
        let need = |n: usize, what: &str| -> Result<(), VolumeError> {
            if args.len() < n {
                Err(err(format!("'{keyword} {}' needs {what}", clip(rest))))
            } else {
                Ok(())
            }
        };
        // The tuple count of the section an attribute is in.
        let tuples = || match section {
            Section::Point(n) | Section::Cell(n) => Ok(n),
            Section::Dataset => Err(err(format!("{keyword} before POINT_DATA or CELL_DATA"))),
        };
        match keyword.as_str() {
            "DATASET" => {
                l.dataset = Some(match rest.to_ascii_uppercase().as_str() {
                    "STRUCTURED_POINTS" => Dataset::StructuredPoints,
                    "RECTILINEAR_GRID" => Dataset::Rectilinear,
                    _ => {
                        return Err(err(format!(
                            "DATASET {} is not supported: volcast reads STRUCTURED_POINTS and evenly spaced \
                             RECTILINEAR_GRID (regular grids)",
                            clip(rest)
                        )))
                    }
                })
            }
            "DIMENSIONS" => {
                let d: Vec<i64> = numbers(file, "DIMENSIONS", rest, 3)?;
                let dims = format::dims_from(file, "DIMENSIONS", &d)?;
                super::check_dims(dims).map_err(|e| format::named(file, e))?;
                l.dims = Some(dims);
            }
            "SPACING" | "ASPECT_RATIO" => {
                let v: Vec<f64> = numbers(file, &keyword, rest, 3)?;
                l.spacing = [v[0], v[1], v[2]];
            }
            "ORIGIN" => {
                let o: Vec<f64> = numbers(file, "ORIGIN", rest, 3)?;
                l.origin = Some([o[0], o[1], o[2]]);
            }
            "X_COORDINATES" | "Y_COORDINATES" | "Z_COORDINATES" => {
                need(2, "a count and a type")?;
                let n: u64 = number(file, &keyword, args[0])?;
                if n == 0 || n > u64::from(MAX_DIM) {
                    return Err(err(format!("{keyword} {n}: each axis holds 1 to {MAX_DIM} points")));
                }
                let axis = usize::from(keyword.as_bytes()[0] - b'X');
                l.coordinates[axis] = Some(s.read_numbers(&keyword, args[1], n as usize)?);
            }
            "POINT_DATA" => {
                let n = number::<u64>(file, "POINT_DATA", rest)?;
                if let Some(d) = l.dims {
                    check_point_count(file, d, n)?;
                }
                l.point_data = Some(n);
                section = Section::Point(n);
            }
            "CELL_DATA" => section = Section::Cell(number::<u64>(file, "CELL_DATA", rest)?),
            "FIELD" => {
                need(2, "a name and an array count")?;
                let count: u64 = number(file, "FIELD array count", args[1])?;
                field(s, file, section, count, &mut l.arrays)?;
            }
            "SCALARS" => {
                need(2, "a name and a type")?;
                let n = tuples()?;
                let components = match args.get(2) {
                    Some(c) => number::<u32>(file, "SCALARS component count", c)?,
                    None => 1,
                };
                if components == 0 {
                    return Err(err(format!("'SCALARS {}' has 0 components", clip(rest))));
                }
                // The LOOKUP_TABLE line is optional here: without it the values start on the next line.
                if s.next_starts_with("LOOKUP_TABLE")? {
                    s.line()?;
                }
                let what = format!("SCALARS {}", clip(args[0]));
                add(
                    &mut l.arrays,
                    section,
                    args[0],
                    args[1],
                    ArrayKind::Scalars,
                    components,
                    s.pos,
                );
                s.skip_values(&what, args[1], n.saturating_mul(u64::from(components)))?;
            }
            "COLOR_SCALARS" => {
                need(2, "a name and a component count")?;
                let n = tuples()?;
                let components: u32 = number(file, "COLOR_SCALARS component count", args[1])?;
                let what = format!("COLOR_SCALARS {}", clip(args[0]));
                let kind = ArrayKind::ColorScalars;
                add(
                    &mut l.arrays,
                    section,
                    args[0],
                    "unsigned_char",
                    kind,
                    components,
                    s.pos,
                );
                s.skip_values(&what, "unsigned_char", n.saturating_mul(u64::from(components)))?;
            }
            "LOOKUP_TABLE" => {
                // A lookup table of its own: `size` RGBA entries.
                need(2, "a name and a size")?;
                let size: u64 = number(file, "LOOKUP_TABLE size", args[1])?;
                s.skip_values("LOOKUP_TABLE", "unsigned_char", size.saturating_mul(4))?;
            }
            "VECTORS" | "NORMALS" | "TENSORS" | "TENSORS6" | "GLOBAL_IDS" | "PEDIGREE_IDS" => {
                need(2, "a name and a type")?;
                let n = tuples()?;
                let components = match keyword.as_str() {
                    "VECTORS" | "NORMALS" => 3,
                    "TENSORS" => 9,
                    "TENSORS6" => 6,
                    _ => 1,
                };
                let what = format!("{keyword} {}", clip(args[0]));
                add(
                    &mut l.arrays,
                    section,
                    args[0],
                    args[1],
                    ArrayKind::Other,
                    components,
                    s.pos,
                );
                s.skip_values(&what, args[1], n.saturating_mul(u64::from(components)))?;
            }
            "TEXTURE_COORDINATES" => {
                need(3, "a name, a dimension and a type")?;
                let n = tuples()?;
                let components: u32 = number(file, "TEXTURE_COORDINATES dimension", args[1])?;
                let what = format!("TEXTURE_COORDINATES {}", clip(args[0]));
                add(
                    &mut l.arrays,
                    section,
                    args[0],
                    args[2],
                    ArrayKind::Other,
                    components,
                    s.pos,
                );
                s.skip_values(&what, args[2], n.saturating_mul(u64::from(components)))?;
            }
            "METADATA" => skip_metadata(s)?,
            _ => return Err(err(format!("unknown keyword '{}'", clip(&keyword)))),
        }
        if let Some(problem) = &s.truncated {
            l.notes.push(format!("the file is cut short: {problem}"));
            break;
        }
    }
    Ok(l)
}

fn check_point_count(file: &str, dims: [u32; 3], n: u64) -> Result<(), VolumeError> {
    // u128: three u32 sizes can overflow u64.
    let count: u128 = dims.iter().map(|&d| u128::from(d)).product();
    if u128::from(n) != count {
        return Err(header_error(
            file,
            format!(
                "POINT_DATA {n} does not match DIMENSIONS {}x{}x{} ({count} points)",
                dims[0], dims[1], dims[2]
            ),
        ));
    }
    Ok(())
}

/// VTK 9 writes `METADATA` after an array (`COMPONENT_NAMES`, `INFORMATION n` and their lines); a blank line ends it.
fn skip_metadata<R: BufRead + Seek>(s: &mut Scanner<R>) -> Result<(), VolumeError> {
    while let Some(line) = s.line()? {
        if line.trim().is_empty() {
            break;
        }
    }
    Ok(())
}

/// The `count` arrays of a `FIELD`: `name components tuples type` and the values. Under POINT_DATA they are point
/// arrays like any other.
fn field<R: BufRead + Seek>(
    s: &mut Scanner<R>,
    file: &str,
    section: Section,
    count: u64,
    arrays: &mut Vec<PointArray>,
) -> Result<(), VolumeError> {
    let mut read = 0;
    while read < count {
        let line = s
            .keyword_line()?
            .ok_or_else(|| header_error(file, format!("the FIELD ends after {read} of {count} arrays")))?;
        let args: Vec<&str> = line.split_whitespace().collect();
        if args[0].eq_ignore_ascii_case("METADATA") {
            skip_metadata(s)?;
            continue;
        }
        read += 1;
        // VTK 5.1 writes an array it could not write as NULL_ARRAY.
        if args[0].eq_ignore_ascii_case("NULL_ARRAY") {
            continue;
        }
        if args.len() < 4 {
            return Err(header_error(
                file,
                format!(
                    "FIELD array line '{}' needs a name, components, tuples and a type",
                    clip(&line)
                ),
            ));
        }
        let components: u32 = number(file, "FIELD array components", args[1])?;
        let tuples: u64 = number(file, "FIELD array tuples", args[2])?;
        if let Section::Point(n) = section {
            if tuples == n {
                add(arrays, section, args[0], args[3], ArrayKind::Field, components, s.pos);
            }
        }
        let what = format!("FIELD array {}", clip(args[0]));
        s.skip_values(&what, args[3], tuples.saturating_mul(u64::from(components)))?;
    }
    Ok(())
}

fn add(
    arrays: &mut Vec<PointArray>,
    section: Section,
    name: &str,
    type_name: &str,
    kind: ArrayKind,
    components: u32,
    offset: u64,
) {
    if matches!(section, Section::Point(_)) {
        arrays.push(PointArray {
            name: name.to_string(),
            type_name: type_name.to_string(),
            kind,
            components,
            offset,
        });
    }
}

/// Evenly spaced rectilinear coordinates as (origin, spacing); within 1e-4 of a spacing of the straight line
/// through the first and last.
fn uniform(file: &str, axis: char, c: &[f64]) -> Result<(f64, f64), VolumeError> {
    let n = c.len();
    let Some(&first) = c.first() else {
        return Err(header_error(
            file,
            format!("RECTILINEAR_GRID has no {axis}_COORDINATES"),
        ));
    };
    if n < 2 {
        return Ok((first, 1.0));
    }
    let step = (c[n - 1] - c[0]) / (n - 1) as f64;
    for (i, &v) in c.iter().enumerate() {
        let expected = c[0] + step * i as f64;
        let off = (v - expected).abs();
        if off.is_nan() || off > 1e-4 * step.abs() {
            return Err(header_error(
                file,
                format!(
                    "RECTILINEAR_GRID {axis}_COORDINATES are not evenly spaced (coordinate {i} is {v}, {expected} \
                     would be even): volcast reads regular grids only"
                ),
            ));
        }
    }
    Ok((c[0], step))
}

fn array_list(arrays: &[PointArray]) -> String {
    let names: Vec<String> = arrays
        .iter()
        .map(|a| format!("{} ({}, {} components)", clip(&a.name), a.type_name, a.components))
        .collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

/// The array to load: the one named, else the first one-component SCALARS or COLOR_SCALARS, else the first
/// one-component FIELD array.
fn select<'a>(arrays: &'a [PointArray], wanted: Option<&str>, file: &str) -> Result<&'a PointArray, VolumeError> {
    let chosen = match wanted {
        Some(name) => arrays.iter().find(|a| a.name == name).ok_or_else(|| {
            header_error(
                file,
                format!(
                    "no point array named '{}'; the file has: {}",
                    clip(name),
                    array_list(arrays)
                ),
            )
        })?,
        None => arrays
            .iter()
            .find(|a| matches!(a.kind, ArrayKind::Scalars | ArrayKind::ColorScalars) && a.components == 1)
            .or_else(|| arrays.iter().find(|a| a.kind == ArrayKind::Field && a.components == 1))
            .ok_or_else(|| {
                header_error(
                    file,
                    format!(
                        "no one-component point array to load; the file has: {} (volcast reads one value per voxel)",
                        array_list(arrays)
                    ),
                )
            })?,
    };
    if chosen.components != 1 || chosen.kind == ArrayKind::Other {
        return Err(format::not_one_component(file, &chosen.name, chosen.components));
    }
    Ok(chosen)
}

/// The header of the chosen array and the array itself.
fn header_from<R: BufRead + Seek>(
    s: &mut Scanner<R>,
    file: &str,
    wanted: Option<&str>,
) -> Result<(Header, PointArray), VolumeError> {
    let err = |problem: String| header_error(file, problem);
    let l = walk(s, file)?;
    let dataset = l
        .dataset
        .ok_or_else(|| err("no 'DATASET STRUCTURED_POINTS' or 'DATASET RECTILINEAR_GRID' line".into()))?;
    let dims = l.dims.ok_or_else(|| err("no DIMENSIONS line".into()))?;
    match l.point_data {
        Some(n) => check_point_count(file, dims, n)?,
        None => return Err(err("no POINT_DATA section: the file has no point values".into())),
    }
    let mut h = Header::new(FORMAT);
    h.endian = Endian::Big;
    h.dims = dims;
    h.notes = l.notes;
    let mut spacing = l.spacing;
    h.origin = l.origin;
    if dataset == Dataset::Rectilinear {
        let mut origin = [0.0; 3];
        for (axis, name) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            let c = l.coordinates[axis]
                .as_deref()
                .ok_or_else(|| err(format!("RECTILINEAR_GRID without {name}_COORDINATES")))?;
            if c.len() != dims[axis] as usize {
                return Err(err(format!(
                    "{name}_COORDINATES has {} values but DIMENSIONS says {}",
                    c.len(),
                    dims[axis]
                )));
            }
            (origin[axis], spacing[axis]) = uniform(file, name, c)?;
        }
        h.origin = Some(origin);
    }
    let chosen = select(&l.arrays, wanted, file)?.clone();
    h.voxel_type = chosen.voxel_type().ok_or_else(|| VolumeError::UnsupportedType {
        file: file.to_string(),
        format: FORMAT,
        given: clip(&chosen.type_name),
    })?;
    h.encoding = if l.binary { Encoding::Raw } else { Encoding::Ascii };
    h.location = DataLocation::Inline(Some(chosen.offset));
    h.arrays = l
        .arrays
        .iter()
        .map(|a| ArrayInfo {
            name: a.name.clone(),
            type_name: a.type_name.clone(),
            components: a.components,
            loaded: a.offset == chosen.offset,
        })
        .collect();
    signed_spacing(&mut h, spacing);
    Ok((h, chosen))
}

/// Parses the header of a VTK legacy file from its bytes; the header's location is the default array's values.
pub fn parse_header(bytes: &[u8]) -> Result<Header, VolumeError> {
    let mut s = Scanner::new(Cursor::new(bytes), bytes.len() as u64, "VTK data");
    Ok(header_from(&mut s, "VTK data", None)?.0)
}

/// Loads a VTK legacy file held in memory.
pub fn from_bytes(bytes: &[u8]) -> Result<Volume, VolumeError> {
    from_bytes_with(bytes, None)
}

/// [`from_bytes`] loading the point array `array` (None: the default one).
pub fn from_bytes_with(bytes: &[u8], array: Option<&str>) -> Result<Volume, VolumeError> {
    let file = "VTK data";
    let mut s = Scanner::new(Cursor::new(bytes), bytes.len() as u64, file);
    let (header, chosen) = header_from(&mut s, file, array)?;
    finish(
        &mut s,
        header,
        &chosen,
        "vtk".into(),
        file,
        Source::Bytes(bytes),
        &mut Progress::none(),
    )
}

pub(crate) fn load(path: &Path, array: Option<&str>, progress: &mut Progress) -> Result<Volume, VolumeError> {
    let file = format::file_label(path);
    let io = |source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let len = std::fs::metadata(path).map_err(io)?.len();
    let reader = BufReader::new(std::fs::File::open(path).map_err(io)?);
    let mut s = Scanner::new(reader, len, &file);
    let (header, chosen) = header_from(&mut s, &file, array)?;
    finish(
        &mut s,
        header,
        &chosen,
        format::volume_name(path),
        &file,
        Source::File(path),
        progress,
    )
}

/// Reads the chosen array: ASCII colour scalars here (floats to bytes), everything else by the shared loader.
fn finish<R: BufRead + Seek>(
    s: &mut Scanner<R>,
    header: Header,
    chosen: &PointArray,
    name: String,
    file: &str,
    source: Source,
    progress: &mut Progress,
) -> Result<Volume, VolumeError> {
    if chosen.kind == ArrayKind::ColorScalars && header.encoding == Encoding::Ascii {
        let count = super::check_dims(header.dims).map_err(|e| format::named(file, e))? as usize;
        s.seek_to(chosen.offset)?;
        let values = s.read_color_ascii(count)?;
        return header
            .into_volume(name, VoxelData::U8(values))
            .map_err(|e| format::named(file, e));
    }
    format::load(header, name, file, source, progress).map_err(|e| format::named(file, e))
}

#[cfg(test)]
mod tests;
