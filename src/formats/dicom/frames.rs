//! One multi-frame DICOM file read frame by frame. Its header, read up to PixelData and never past it, places the
//! volume as the loader does (`plan`); each frame's bytes are found where they lie, native frames one after
//! another from PixelData's value, compressed ones in the fragments its item headers list (grouped into frames as
//! the loader groups them, `codec::frame_groups`). A frame is then read with positioned reads and decoded as the
//! loader decodes it (`pixels`), so `slices::SeriesReader` makes a level of a file larger than the host budget
//! without holding it. docs/large-volumes.md, "How files are read".

use super::codec::{self, Kind};
use super::lengths::{pixel_data_header, PixelDataAt};
use super::pixels::{append_compressed, append_frame, check_backed, short, Pixels};
use super::slice::{slice_info, Slice};
use super::{is_dicom, parse_bytes};
use crate::formats::format::{self, header_error};
use crate::volume::{check_extent, VolumeError, VoxelData, VoxelType};
use std::fs::File;
use std::io::{BufReader, Read, Seek};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// The first header prefix read looking for PixelData; it grows eightfold up to [`HEADER_LIMIT`].
const FIRST_PREFIX: u64 = 1 << 20;
/// The most header bytes read looking for PixelData (an enhanced object's per-frame groups take about 1 KiB a frame):
/// past it, the file is left to the loader.
const HEADER_LIMIT: u64 = 256 << 20;
/// The most fragments listed: more than a frame's worth of 64-byte pieces for 16384 frames is no real file.
const MAX_FRAGMENTS: usize = 1 << 20;

/// A multi-frame file's header slice and where each of its frames lies.
#[derive(Debug)]
pub(crate) struct Frames {
    pub(super) slice: Slice,
    file: File,
    path: PathBuf,
    /// The file's name, as errors name it.
    label: String,
    /// Each frame's byte ranges (offset, length): one for native data, its fragments for compressed data.
    at: Vec<Vec<(u64, u64)>>,
}

impl Frames {
    /// `path` read frame by frame, if it is one DICOM file of several frames whose header ends within
    /// [`HEADER_LIMIT`] and whose frames (columns, rows, frames; the type they are held in) `fits` does not take
    /// whole; `None` for anything else (the loader reads it). A frame index that the file cannot back (cut short,
    /// or a compressed size past [`codec::MAX_RATIO`]) is an error naming the file.
    pub(crate) fn of(path: &Path, fits: &dyn Fn([u32; 3], VoxelType) -> bool) -> Result<Option<Frames>, VolumeError> {
        let label = format::file_label(path);
        if !path.is_file() || !format::read_prefix(path, 132).is_ok_and(|p| is_dicom(&p)) {
            return Ok(None);
        }
        let Some((header, pixels)) = header(path, &label)? else {
            return Ok(None);
        };
        let obj = parse_bytes(&header, &label, true)?;
        let slice = slice_info(&obj, 0, &label)?;
        // Sizes first: no frame index is made for a claimed count past the limits.
        check_extent([slice.columns, slice.rows, slice.frames]).map_err(|e| VolumeError::Header {
            file: path.display().to_string(),
            problem: e.to_string(),
        })?;
        let held = super::voxel_type(slice.bits_allocated, slice.signed);
        let big_endian = slice.kind == Kind::Native && !slice.native_little_endian;
        if slice.frames < 2 || big_endian || fits([slice.columns, slice.rows, slice.frames], held) {
            return Ok(None);
        }
        let io = |source| VolumeError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        let frame_bytes = u64::from(slice.rows) * u64::from(slice.columns) * u64::from(slice.bits_allocated / 8);
        let needed = frame_bytes * u64::from(slice.frames);
        let at = match (slice.kind, pixels.length) {
            (Kind::Native, Some(length)) => {
                let present = length.min(len.saturating_sub(pixels.value as u64));
                if present < needed {
                    return Err(short(&label, present, needed));
                }
                let start = pixels.value as u64;
                (0..u64::from(slice.frames))
                    .map(|k| vec![(start + k * frame_bytes, frame_bytes)])
                    .collect()
            }
            (Kind::Native, None) | (_, Some(_)) => return Ok(None),
            (_, None) => fragments(&file, len, pixels, &slice, &label)?,
        };
        let stored: u64 = at.iter().flatten().map(|&(_, n)| n).sum();
        check_backed(&label, needed, &[(slice.kind, stored)])?;
        Ok(Some(Frames {
            slice,
            file,
            path: path.to_path_buf(),
            label,
            at,
        }))
    }

    /// Appends frame `k` (in the file's order), read and decoded, to `out`.
    pub(super) fn append(&self, k: usize, out: &mut VoxelData) -> Result<(), VolumeError> {
        let parts = &self.at[k];
        let mut bytes = vec![0u8; parts.iter().map(|&(_, n)| n as usize).sum()];
        let mut into = &mut bytes[..];
        for &(offset, n) in parts {
            let (this, rest) = into.split_at_mut(n as usize);
            self.file
                .read_exact_at(this, offset)
                .map_err(|source| VolumeError::Io {
                    path: self.path.clone(),
                    source,
                })?;
            into = rest;
        }
        match self.slice.kind {
            Kind::Native => append_frame(Pixels::Bytes(&bytes), &self.slice, out, &self.label),
            _ => append_compressed(&bytes, k, &self.slice, out, &self.label),
        }
    }

    pub(super) fn path(&self) -> &Path {
        &self.path
    }

    /// Where the frames start when their bytes are the values as volcast reads a raw file's: native little-endian
    /// frames one after another, every allocated bit stored (nothing to mask or sign-extend).
    pub(super) fn plain_at(&self) -> Option<u64> {
        let s = &self.slice;
        let plain = s.kind == Kind::Native && s.bits_stored == s.bits_allocated && matches!(s.bits_allocated, 8 | 16);
        plain.then(|| self.at[0][0].0)
    }
}

/// The header of `path` (every byte before PixelData) and where PixelData lies, read in prefixes of growing size;
/// `None` where PixelData is not found within [`HEADER_LIMIT`] or the file.
fn header(path: &Path, label: &str) -> Result<Option<(Vec<u8>, PixelDataAt)>, VolumeError> {
    let len = std::fs::metadata(path)
        .map_err(|source| VolumeError::Io {
            path: path.to_path_buf(),
            source,
        })?
        .len();
    let mut size = FIRST_PREFIX;
    loop {
        let prefix = format::read_prefix(path, size.min(len) as usize)?;
        let whole = prefix.len() as u64 >= len;
        match pixel_data_header(&prefix, label) {
            Ok(Some(at)) => {
                let mut header = prefix;
                header.truncate(at.header);
                return Ok(Some((header, at)));
            }
            // An element cut by the prefix reads as one running past the file: read more.
            Ok(None) | Err(_) if !whole && size < HEADER_LIMIT => size = (size * 8).min(HEADER_LIMIT),
            // The loader reads the file and says what is wrong with it.
            _ => return Ok(None),
        }
    }
}

/// The fragments of encapsulated PixelData whose value starts at `pixels.value`, grouped into `slice.frames`
/// frames as the loader groups them: its item headers are read in order (the fragments skipped), the first item
/// being the Basic Offset Table.
fn fragments(
    file: &File,
    len: u64,
    pixels: PixelDataAt,
    slice: &Slice,
    label: &str,
) -> Result<Vec<Vec<(u64, u64)>>, VolumeError> {
    let bad = |problem: String| header_error(label, problem);
    let mut reader = BufReader::with_capacity(1 << 16, file);
    let mut pos = pixels.value as u64;
    reader
        .seek(std::io::SeekFrom::Start(pos))
        .map_err(|e| bad(e.to_string()))?;
    let (mut table, mut items) = (None, Vec::new());
    loop {
        let mut head = [0u8; 8];
        reader.read_exact(&mut head).map_err(|_| {
            bad("the compressed pixel data end before their sequence delimiter (truncated file)".into())
        })?;
        let tag = (
            u16::from_le_bytes([head[0], head[1]]),
            u16::from_le_bytes([head[2], head[3]]),
        );
        let n = u64::from(u32::from_le_bytes([head[4], head[5], head[6], head[7]]));
        pos += 8;
        match tag {
            (0xFFFE, 0xE0DD) => break,
            (0xFFFE, 0xE000) if pos + n <= len => {}
            (0xFFFE, 0xE000) => {
                return Err(bad(format!(
                    "a compressed pixel data fragment claims {n} bytes but only {} follow (truncated or corrupt file)",
                    len - pos
                )))
            }
            (g, e) => {
                return Err(bad(format!(
                    "({g:04X},{e:04X}) inside the compressed pixel data (corrupt file)"
                )))
            }
        }
        if table.is_none() {
            // The Basic Offset Table: a u32 per frame, or empty.
            if n > 4 * u64::from(slice.frames) || n % 4 != 0 {
                return Err(bad(format!(
                    "a Basic Offset Table of {n} bytes for {} frames",
                    slice.frames
                )));
            }
            let mut bytes = vec![0u8; n as usize];
            reader.read_exact(&mut bytes).map_err(|e| bad(e.to_string()))?;
            table = Some(
                bytes
                    .chunks_exact(4)
                    .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect::<Vec<u32>>(),
            );
        } else {
            if items.len() == MAX_FRAGMENTS {
                return Err(bad(format!(
                    "more than {MAX_FRAGMENTS} compressed pixel data fragments"
                )));
            }
            items.push((pos, n));
            reader.seek_relative(n as i64).map_err(|e| bad(e.to_string()))?;
        }
        pos += n;
    }
    let lengths: Vec<u64> = items.iter().map(|&(_, n)| n).collect();
    let groups = codec::frame_groups(&lengths, table.as_deref().unwrap_or(&[]), slice.frames).map_err(bad)?;
    Ok(groups.into_iter().map(|r| items[r].to_vec()).collect())
}
