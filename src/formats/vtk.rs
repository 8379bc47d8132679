//! VTK legacy `.vtk` files (versions 2.0 to 5.1, as VTK 9 and ParaView write them) holding `DATASET
//! STRUCTURED_POINTS`, or a `RECTILINEAR_GRID` whose coordinates are evenly spaced, ASCII or BINARY (binary is
//! big-endian by the VTK file-format spec). Any number of point and cell arrays (`SCALARS`, `COLOR_SCALARS`,
//! `FIELD`, `VECTORS`, ...) in any order; one one-component point array is loaded: the one `--array` names, else
//! the first `SCALARS`/`COLOR_SCALARS`, else the first one-component `FIELD` array under `POINT_DATA`.

mod scan;
pub(crate) mod vti;
pub(crate) mod vti_blocks;
pub(crate) mod vti_data;
mod walk;

use super::decode::{Endian, Progress};
use super::format::{self, clip, header_error, signed_spacing, DataLocation, Encoding, Header, Source};
use crate::volume::{ArrayInfo, Volume, VolumeError, VoxelData};
use scan::{ArrayKind, PointArray, Scanner};
use std::io::{BufRead, BufReader, Cursor, Seek};
use std::path::Path;
use walk::{check_point_count, walk, Dataset};

const FORMAT: &str = "VTK legacy";

pub(crate) fn is_vtk(prefix: &[u8]) -> bool {
    prefix.len() >= 14 && prefix[..14].eq_ignore_ascii_case(b"# vtk DataFile")
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
        let count = crate::volume::check_dims(header.dims).map_err(|e| format::named(file, e))? as usize;
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
