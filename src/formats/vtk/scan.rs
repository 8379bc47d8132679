//! Walking a VTK legacy file section by section: every keyword VTK 2.0 to 5.1 writers put in a structured-points or
//! rectilinear-grid file, with the payload of each array skipped (binary: count × type size bytes, then a newline;
//! ASCII: count values) so the arrays before and after the one volcast loads cost a seek, not a parse.

use crate::formats::format::{clip, header_error, number};
use crate::volume::{VolumeError, VoxelType};
use std::io::{BufRead, Read, Seek, SeekFrom};

/// VTK's own lines are at most 256 characters; a longer one is not a header line.
const MAX_LINE: usize = 4096;

/// Which attribute section a keyword sits in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Section {
    Dataset,
    Point(u64),
    Cell(u64),
}

/// How an array was declared, which decides how its ASCII values are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ArrayKind {
    Scalars,
    /// `COLOR_SCALARS`: unsigned char in binary, floats in 0..1 in ASCII.
    ColorScalars,
    Field,
    /// VECTORS, NORMALS, TENSORS, TEXTURE_COORDINATES, ids: listed, never loaded.
    Other,
}

/// A point-data array found in the file and where its values start.
#[derive(Clone, Debug)]
pub(crate) struct PointArray {
    pub name: String,
    pub type_name: String,
    pub kind: ArrayKind,
    pub components: u32,
    pub offset: u64,
}

impl PointArray {
    /// The voxel type of a loadable array (a scalar type volcast reads), else None.
    pub fn voxel_type(&self) -> Option<VoxelType> {
        if self.kind == ArrayKind::ColorScalars {
            return Some(VoxelType::U8);
        }
        voxel_type(&self.type_name)
    }
}

pub(crate) fn voxel_type(name: &str) -> Option<VoxelType> {
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

/// Bytes per value in a binary payload (`bit`: 0, packed eight to a byte); None for types of no fixed size.
fn binary_size(type_name: &str) -> Option<u64> {
    Some(match type_name.to_ascii_lowercase().as_str() {
        "bit" => 0,
        "unsigned_char" | "char" | "signed_char" => 1,
        "short" | "unsigned_short" => 2,
        // vtkDataWriter writes vtkIdType arrays as 32-bit ints.
        "int" | "unsigned_int" | "float" | "vtkidtype" => 4,
        "long" | "unsigned_long" | "vtktypeint64" | "vtktypeuint64" | "double" => 8,
        _ => return None,
    })
}

/// A cursor over the file that knows its position and length, so every claimed size is checked before a skip.
pub(crate) struct Scanner<'f, R> {
    reader: R,
    pub pos: u64,
    len: u64,
    pub binary: bool,
    file: &'f str,
    /// Set when an array's payload runs past the end of the file: the walk stops there, and loading that array
    /// reports the truncation (an array before it still loads).
    pub truncated: Option<String>,
}

impl<'f, R: BufRead + Seek> Scanner<'f, R> {
    pub fn new(reader: R, len: u64, file: &'f str) -> Self {
        Scanner {
            reader,
            pos: 0,
            len,
            binary: false,
            file,
            truncated: None,
        }
    }

    fn err(&self, problem: String) -> VolumeError {
        header_error(self.file, problem)
    }

    fn io(&self, e: std::io::Error) -> VolumeError {
        self.err(format!("reading the file failed: {e}"))
    }

    /// The next line without its end (`\n` or `\r\n`), None at the end of the file.
    pub fn line(&mut self) -> Result<Option<String>, VolumeError> {
        let mut bytes = Vec::new();
        let read = (&mut self.reader)
            .take(MAX_LINE as u64 + 1)
            .read_until(b'\n', &mut bytes);
        let n = read.map_err(|e| self.io(e))?;
        if n == 0 {
            return Ok(None);
        }
        self.pos += n as u64;
        if bytes.last() == Some(&b'\n') {
            bytes.pop();
        } else if n > MAX_LINE {
            return Err(self.err(format!(
                "a line at byte {} is longer than {MAX_LINE} characters: not a VTK header line (wrong array sizes?)",
                self.pos - n as u64
            )));
        }
        if bytes.last() == Some(&b'\r') {
            bytes.pop();
        }
        Ok(Some(String::from_utf8_lossy(&bytes).into_owned()))
    }

    /// The next line that is not blank (binary payloads end with a newline; ASCII values leave the rest of a line).
    pub fn keyword_line(&mut self) -> Result<Option<String>, VolumeError> {
        while let Some(line) = self.line()? {
            if !line.trim().is_empty() {
                return Ok(Some(line));
            }
        }
        Ok(None)
    }

    /// Whether the next line starts with `keyword` (case-insensitive), without consuming anything; binary data may
    /// follow, so at most 64 bytes are looked at.
    pub fn next_starts_with(&mut self, keyword: &str) -> Result<bool, VolumeError> {
        let start = self.pos;
        let mut head = Vec::new();
        let read = (&mut self.reader).take(64).read_to_end(&mut head);
        read.map_err(|e| self.io(e))?;
        self.seek_to(start)?;
        let text = String::from_utf8_lossy(&head);
        let text = text.trim_start_matches([' ', '\t']);
        Ok(text.len() >= keyword.len() && text[..keyword.len()].eq_ignore_ascii_case(keyword))
    }

    pub fn seek_to(&mut self, pos: u64) -> Result<(), VolumeError> {
        self.reader.seek(SeekFrom::Start(pos)).map_err(|e| self.io(e))?;
        self.pos = pos;
        Ok(())
    }

    /// Skips `count` values of `type_name` (an array's payload).
    pub fn skip_values(&mut self, what: &str, type_name: &str, count: u64) -> Result<(), VolumeError> {
        if !self.binary {
            return self.skip_tokens(what, count);
        }
        let size = binary_size(type_name).ok_or_else(|| {
            self.err(format!(
                "{what} has type '{}', whose binary size is not fixed: volcast cannot step over it",
                clip(type_name)
            ))
        })?;
        let bytes = if size == 0 {
            count.div_ceil(8)
        } else {
            count.saturating_mul(size)
        };
        self.skip_bytes(what, bytes)
    }

    pub fn skip_bytes(&mut self, what: &str, bytes: u64) -> Result<(), VolumeError> {
        let end = self.pos.saturating_add(bytes);
        if end > self.len {
            self.truncated = Some(format!(
                "{what} needs {bytes} bytes at byte {} but the file ends at {} (truncated file?)",
                self.pos, self.len
            ));
            return self.seek_to(self.len);
        }
        self.seek_to(end)
    }

    /// The next whitespace-separated token, None at the end of the file.
    fn token(&mut self) -> Result<Option<String>, VolumeError> {
        let mut token = Vec::new();
        let file = self.file;
        loop {
            let buf = self
                .reader
                .fill_buf()
                .map_err(|e| header_error(file, format!("reading the file failed: {e}")))?;
            if buf.is_empty() {
                break;
            }
            let mut used = 0;
            let mut done = false;
            for &b in buf {
                if b.is_ascii_whitespace() {
                    if !token.is_empty() {
                        done = true;
                        break;
                    }
                } else if token.len() < 64 {
                    token.push(b);
                }
                used += 1;
            }
            self.reader.consume(used);
            self.pos += used as u64;
            if done {
                break;
            }
        }
        Ok((!token.is_empty()).then(|| String::from_utf8_lossy(&token).into_owned()))
    }

    fn skip_tokens(&mut self, what: &str, count: u64) -> Result<(), VolumeError> {
        for i in 0..count {
            if self.token()?.is_none() {
                self.truncated = Some(format!(
                    "{what} ends after {i} of {count} ASCII values (truncated file?)"
                ));
                return Ok(());
            }
        }
        Ok(())
    }

    /// Reads `count` numbers of `type_name` (rectilinear coordinates), `count` already bounded by the caller.
    pub fn read_numbers(&mut self, what: &str, type_name: &str, count: usize) -> Result<Vec<f64>, VolumeError> {
        let t = voxel_type(type_name).ok_or_else(|| {
            self.err(format!(
                "{what} has type '{}': volcast reads numeric coordinates",
                clip(type_name)
            ))
        })?;
        let mut out = Vec::with_capacity(count);
        if self.binary {
            let size = t.size();
            let bytes = (count * size) as u64;
            if self.pos.saturating_add(bytes) > self.len {
                return Err(self.err(format!(
                    "{what} needs {bytes} bytes but the file ends first (truncated file?)"
                )));
            }
            let mut buf = vec![0u8; count * size];
            self.reader.read_exact(&mut buf).map_err(|e| self.io(e))?;
            self.pos += bytes;
            for b in buf.chunks_exact(size) {
                out.push(big_endian_value(t, b));
            }
        } else {
            for i in 0..count {
                let token = self
                    .token()?
                    .ok_or_else(|| self.err(format!("{what} ends after {i} of {count} values (truncated file?)")))?;
                out.push(number::<f64>(self.file, what, &token)?);
            }
        }
        Ok(out)
    }

    /// Reads `count` ASCII colour values (floats in 0..1) as VTK's reader does: × 255, rounded half up. VTK casts
    /// values outside 0..1 to unsigned char (wrapping); volcast clamps them to 0..255 instead.
    pub fn read_color_ascii(&mut self, count: usize) -> Result<Vec<u8>, VolumeError> {
        let mut out = Vec::new();
        out.try_reserve_exact(count)
            .map_err(|_| self.err(format!("cannot allocate {count} colour values")))?;
        for i in 0..count {
            let token = self.token()?.ok_or_else(|| {
                self.err(format!(
                    "the ASCII data end after {i} of {count} values (truncated file?)"
                ))
            })?;
            let v: f64 = token
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| self.err(format!("ASCII colour value {i} ('{}') is not a number", clip(&token))))?;
            out.push((v * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8);
        }
        Ok(out)
    }
}

fn big_endian_value(t: VoxelType, b: &[u8]) -> f64 {
    let a = |n: usize| -> [u8; 8] {
        let mut w = [0u8; 8];
        w[..n].copy_from_slice(&b[..n]);
        w
    };
    let w = a(b.len());
    match t {
        VoxelType::U8 => f64::from(b[0]),
        VoxelType::I8 => f64::from(b[0] as i8),
        VoxelType::U16 => f64::from(u16::from_be_bytes([w[0], w[1]])),
        VoxelType::I16 => f64::from(i16::from_be_bytes([w[0], w[1]])),
        VoxelType::U32 => f64::from(u32::from_be_bytes([w[0], w[1], w[2], w[3]])),
        VoxelType::I32 => f64::from(i32::from_be_bytes([w[0], w[1], w[2], w[3]])),
        VoxelType::F32 => f64::from(f32::from_be_bytes([w[0], w[1], w[2], w[3]])),
        VoxelType::F64 => f64::from_be_bytes(w),
    }
}
