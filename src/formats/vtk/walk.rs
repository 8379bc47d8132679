//! The walk through a VTK legacy file's keywords: the dataset's geometry and every attribute array, each array's
//! values stepped over so that the one to load can be chosen afterwards.

use super::is_vtk;
use super::scan::{ArrayKind, PointArray, Scanner, Section};
use crate::formats::format::{self, clip, header_error, number, numbers};
use crate::volume::{VolumeError, MAX_DIM};
use std::io::{BufRead, Seek};

#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Dataset {
    StructuredPoints,
    Rectilinear,
}

/// What a walk through the whole file found.
pub(super) struct Layout {
    pub binary: bool,
    pub dataset: Option<Dataset>,
    pub dims: Option<[u32; 3]>,
    pub spacing: [f64; 3],
    pub origin: Option<[f64; 3]>,
    pub coordinates: [Option<Vec<f64>>; 3],
    pub point_data: Option<u64>,
    pub arrays: Vec<PointArray>,
    pub notes: Vec<String>,
}

pub(super) fn walk<R: BufRead + Seek>(s: &mut Scanner<R>, file: &str) -> Result<Layout, VolumeError> {
    let notes = read_preamble(s, file)?;
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
        let line = KeywordLine {
            file,
            args: rest.split_whitespace().collect(),
            keyword: keyword.to_ascii_uppercase(),
            rest,
        };
        l.read_keyword(s, &line, &mut section)?;
        if let Some(problem) = &s.truncated {
            l.notes.push(format!("the file is cut short: {problem}"));
            break;
        }
    }
    Ok(l)
}

/// The first three lines: the identifier with the file version, the title, and ASCII or BINARY (which sets
/// `s.binary`). Returns a note on a version volcast does not know.
fn read_preamble<R: BufRead + Seek>(s: &mut Scanner<R>, file: &str) -> Result<Vec<String>, VolumeError> {
    let first = s.line()?.unwrap_or_default();
    if !is_vtk(first.as_bytes()) {
        return Err(header_error(
            file,
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
        _ => {
            return Err(header_error(
                file,
                format!("line 3 must be ASCII or BINARY, not '{}'", clip(&mode)),
            ))
        }
    };
    Ok(notes)
}

/// A keyword line: the keyword in upper case and what follows it, whole and as words.
struct KeywordLine<'a> {
    file: &'a str,
    keyword: String,
    rest: &'a str,
    args: Vec<&'a str>,
}

impl KeywordLine<'_> {
    fn err(&self, problem: String) -> VolumeError {
        header_error(self.file, problem)
    }

    fn need(&self, n: usize, what: &str) -> Result<(), VolumeError> {
        if self.args.len() < n {
            Err(self.err(format!("'{} {}' needs {what}", self.keyword, clip(self.rest))))
        } else {
            Ok(())
        }
    }

    /// The tuple count of the section an attribute is in.
    fn tuples(&self, section: Section) -> Result<u64, VolumeError> {
        match section {
            Section::Point(n) | Section::Cell(n) => Ok(n),
            Section::Dataset => Err(self.err(format!("{} before POINT_DATA or CELL_DATA", self.keyword))),
        }
    }
}

impl Layout {
    /// The dataset's own keywords; attributes go to [`Layout::read_attribute`].
    fn read_keyword<R: BufRead + Seek>(
        &mut self,
        s: &mut Scanner<R>,
        line: &KeywordLine,
        section: &mut Section,
    ) -> Result<(), VolumeError> {
        let (file, keyword, rest) = (line.file, line.keyword.as_str(), line.rest);
        match keyword {
            "DATASET" => {
                self.dataset = Some(match rest.to_ascii_uppercase().as_str() {
                    "STRUCTURED_POINTS" => Dataset::StructuredPoints,
                    "RECTILINEAR_GRID" => Dataset::Rectilinear,
                    _ => {
                        return Err(line.err(format!(
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
                crate::volume::check_dims(dims).map_err(|e| format::named(file, e))?;
                self.dims = Some(dims);
            }
            "SPACING" | "ASPECT_RATIO" => {
                let v: Vec<f64> = numbers(file, keyword, rest, 3)?;
                self.spacing = [v[0], v[1], v[2]];
            }
            "ORIGIN" => {
                let o: Vec<f64> = numbers(file, "ORIGIN", rest, 3)?;
                self.origin = Some([o[0], o[1], o[2]]);
            }
            "X_COORDINATES" | "Y_COORDINATES" | "Z_COORDINATES" => {
                line.need(2, "a count and a type")?;
                let n: u64 = number(file, keyword, line.args[0])?;
                if n == 0 || n > u64::from(MAX_DIM) {
                    return Err(line.err(format!("{keyword} {n}: each axis holds 1 to {MAX_DIM} points")));
                }
                let axis = usize::from(keyword.as_bytes()[0] - b'X');
                self.coordinates[axis] = Some(s.read_numbers(keyword, line.args[1], n as usize)?);
            }
            "POINT_DATA" => {
                let n = number::<u64>(file, "POINT_DATA", rest)?;
                if let Some(d) = self.dims {
                    check_point_count(file, d, n)?;
                }
                self.point_data = Some(n);
                *section = Section::Point(n);
            }
            "CELL_DATA" => *section = Section::Cell(number::<u64>(file, "CELL_DATA", rest)?),
            _ => self.read_attribute(s, line, *section)?,
        }
        Ok(())
    }

    /// An attribute keyword: its array is noted (under POINT_DATA) and its values stepped over.
    fn read_attribute<R: BufRead + Seek>(
        &mut self,
        s: &mut Scanner<R>,
        line: &KeywordLine,
        section: Section,
    ) -> Result<(), VolumeError> {
        let (file, keyword, rest, args) = (line.file, line.keyword.as_str(), line.rest, &line.args);
        match keyword {
            "FIELD" => {
                line.need(2, "a name and an array count")?;
                let count: u64 = number(file, "FIELD array count", args[1])?;
                field(s, file, section, count, &mut self.arrays)?;
            }
            "SCALARS" => {
                line.need(2, "a name and a type")?;
                let n = line.tuples(section)?;
                let components = match args.get(2) {
                    Some(c) => number::<u32>(file, "SCALARS component count", c)?,
                    None => 1,
                };
                if components == 0 {
                    return Err(line.err(format!("'SCALARS {}' has 0 components", clip(rest))));
                }
                // The LOOKUP_TABLE line is optional here: without it the values start on the next line.
                if s.next_starts_with("LOOKUP_TABLE")? {
                    s.line()?;
                }
                let array = (args[0], args[1], ArrayKind::Scalars, components);
                self.step_over(s, section, keyword, array, n)?;
            }
            "COLOR_SCALARS" => {
                line.need(2, "a name and a component count")?;
                let n = line.tuples(section)?;
                let components: u32 = number(file, "COLOR_SCALARS component count", args[1])?;
                let array = (args[0], "unsigned_char", ArrayKind::ColorScalars, components);
                self.step_over(s, section, keyword, array, n)?;
            }
            "LOOKUP_TABLE" => {
                // A lookup table of its own: `size` RGBA entries.
                line.need(2, "a name and a size")?;
                let size: u64 = number(file, "LOOKUP_TABLE size", args[1])?;
                s.skip_values("LOOKUP_TABLE", "unsigned_char", size.saturating_mul(4))?;
            }
            "VECTORS" | "NORMALS" | "TENSORS" | "TENSORS6" | "GLOBAL_IDS" | "PEDIGREE_IDS" => {
                line.need(2, "a name and a type")?;
                let n = line.tuples(section)?;
                let components = match keyword {
                    "VECTORS" | "NORMALS" => 3,
                    "TENSORS" => 9,
                    "TENSORS6" => 6,
                    _ => 1,
                };
                self.step_over(s, section, keyword, (args[0], args[1], ArrayKind::Other, components), n)?;
            }
            "TEXTURE_COORDINATES" => {
                line.need(3, "a name, a dimension and a type")?;
                let n = line.tuples(section)?;
                let components: u32 = number(file, "TEXTURE_COORDINATES dimension", args[1])?;
                self.step_over(s, section, keyword, (args[0], args[2], ArrayKind::Other, components), n)?;
            }
            "METADATA" => skip_metadata(s)?,
            _ => return Err(line.err(format!("unknown keyword '{}'", clip(keyword)))),
        }
        Ok(())
    }

    /// Notes an array `(name, type, kind, components)` of `tuples` tuples that starts here and steps over its
    /// values.
    fn step_over<R: BufRead + Seek>(
        &mut self,
        s: &mut Scanner<R>,
        section: Section,
        keyword: &str,
        (name, type_name, kind, components): (&str, &str, ArrayKind, u32),
        tuples: u64,
    ) -> Result<(), VolumeError> {
        add(&mut self.arrays, section, name, type_name, kind, components, s.pos);
        let what = format!("{keyword} {}", clip(name));
        s.skip_values(&what, type_name, tuples.saturating_mul(u64::from(components)))
    }
}

pub(super) fn check_point_count(file: &str, dims: [u32; 3], n: u64) -> Result<(), VolumeError> {
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
