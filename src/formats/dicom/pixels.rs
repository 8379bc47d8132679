//! DICOM pixel data into the volume: native frames as found (keeping BitsStored, sign-extending), compressed
//! frames decoded one by one through [`codec`], and the check that the files can back the volume before it
//! is allocated.

use super::codec::{self, FrameShape, Kind};
use super::{finish, open_dicom, Plan, Slice, PIXEL_DATA};
use crate::formats::decode::try_vec;
use crate::formats::decode::Progress;
use crate::formats::format;
use crate::formats::format::{clip, header_error};
use crate::volume::{check_dims, Volume};
use crate::volume::{VolumeError, VoxelData, VoxelType};
use dicom_core::value::PrimitiveValue as P;
use dicom_object::DefaultDicomObject;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Pixel data as found: little-endian bytes (OB, decoded, or read from the file) or 16-bit words (OW).
#[derive(Clone, Copy)]
pub(super) enum Pixels<'a> {
    Bytes(&'a [u8]),
    Words(&'a [u16]),
}

/// Appends one frame (Rows x Columns values) in the stored representation, keeping only `bits_stored` bits and
/// sign-extending signed values.
pub(super) fn append_frame(pixels: Pixels, s: &Slice, out: &mut VoxelData, label: &str) -> Result<(), VolumeError> {
    let count = s.rows as usize * s.columns as usize;
    let bits = u32::from(s.bits_stored);
    let mask = if bits >= 32 { u32::MAX } else { (1u32 << bits) - 1 };
    let to_signed = |v: u32| -> i32 {
        let v = v & mask;
        if v & (1 << (bits - 1)) != 0 {
            v as i32 - (1i32 << bits)
        } else {
            v as i32
        }
    };
    let words: Vec<u16> = match (pixels, s.bits_allocated) {
        (Pixels::Bytes(bytes), 8) => {
            let bytes = bytes
                .get(..count)
                .ok_or_else(|| short(label, bytes.len() as u64, count as u64))?;
            let VoxelData::U8(v) = out else {
                unreachable_layout(label)?
            };
            if s.signed {
                v.extend(bytes.iter().map(|&b| (to_signed(u32::from(b)) + 128) as u8));
            } else {
                v.extend(bytes.iter().map(|&b| (u32::from(b) & mask) as u8));
            }
            return Ok(());
        }
        (Pixels::Bytes(bytes), _) => {
            let need = count as u64 * 2;
            let bytes = bytes
                .get(..count * 2)
                .ok_or_else(|| short(label, bytes.len() as u64, need))?;
            bytes
                .chunks_exact(2)
                .map(|b| u16::from_le_bytes([b[0], b[1]]))
                .collect()
        }
        (Pixels::Words(w), 16) => {
            if w.len() < count {
                return Err(short(label, w.len() as u64 * 2, count as u64 * 2));
            }
            w[..count].to_vec()
        }
        (Pixels::Words(_), _) => return Err(header_error(label, "16-bit PixelData in an 8-bit image".into())),
    };
    let VoxelData::U16(v) = out else {
        unreachable_layout(label)?
    };
    if s.signed {
        v.extend(words.iter().map(|&w| (to_signed(u32::from(w)) + 32768) as u16));
    } else {
        v.extend(words.iter().map(|&w| (u32::from(w) & mask) as u16));
    }
    Ok(())
}

/// Appends native pixel data's frames in `order`.
pub(super) fn append_native(
    pixels: Pixels,
    s: &Slice,
    order: &[usize],
    out: &mut VoxelData,
    label: &str,
) -> Result<(), VolumeError> {
    let frame_values = s.rows as usize * s.columns as usize;
    let value_bytes = usize::from(s.bits_allocated / 8);
    let needed = (frame_values * s.frames as usize * value_bytes) as u64;
    let available = match pixels {
        Pixels::Bytes(b) => b.len() as u64,
        Pixels::Words(w) => w.len() as u64 * 2,
    };
    if available < needed {
        return Err(short(label, available, needed));
    }
    for &k in order {
        let frame = match pixels {
            Pixels::Bytes(b) => Pixels::Bytes(&b[k * frame_values * value_bytes..]),
            Pixels::Words(w) => Pixels::Words(&w[k * frame_values..]),
        };
        append_frame(frame, s, out, label)?;
    }
    Ok(())
}

/// Appends one file's frames in `order`: native pixel data as found, compressed data decoded frame by frame.
pub(super) fn append_file(
    obj: &DefaultDicomObject,
    s: &Slice,
    order: &[usize],
    out: &mut VoxelData,
    label: &str,
) -> Result<(), VolumeError> {
    let err = |problem: String| header_error(label, problem);
    let element = obj
        .element_opt(PIXEL_DATA)
        .ok()
        .flatten()
        .ok_or_else(|| err("no PixelData element".into()))?;
    if s.kind == Kind::Native {
        let Some(value) = element.value().primitive() else {
            return Err(err("encapsulated PixelData in an uncompressed transfer syntax".into()));
        };
        let words: Vec<u16>;
        let pixels = match value {
            P::U8(bytes) => Pixels::Bytes(bytes),
            P::U16(w) => Pixels::Words(w),
            P::I16(w) => {
                words = w.iter().map(|&x| x as u16).collect();
                Pixels::Words(&words)
            }
            _ => return Err(err("PixelData has a value representation volcast cannot read".into())),
        };
        return append_native(pixels, s, order, out, label);
    }
    let fragments = element.value().fragments().ok_or_else(|| {
        err(format!(
            "{} ({}) needs encapsulated PixelData, the file has native",
            codec::name(&s.transfer_syntax),
            clip(&s.transfer_syntax)
        ))
    })?;
    let offsets = element.value().offset_table().unwrap_or(&[]);
    let frames = codec::frames(fragments, offsets, s.frames).map_err(err)?;
    for &k in order {
        append_compressed(&frames[k], k, s, out, label)?;
    }
    Ok(())
}

/// Decodes frame `k` of slice `s` from its compressed bytes `data` and appends it.
pub(super) fn append_compressed(
    data: &[u8],
    k: usize,
    s: &Slice,
    out: &mut VoxelData,
    label: &str,
) -> Result<(), VolumeError> {
    let shape = FrameShape {
        rows: s.rows as u16,
        columns: s.columns as u16,
        samples: 1,
        bits_allocated: s.bits_allocated,
        bits_stored: s.bits_stored,
    };
    let decoded = codec::decode(s.kind, &s.transfer_syntax, data, &shape)
        .map_err(|e| header_error(label, format!("frame {} of {}: {e}", k + 1, s.frames)))?;
    append_frame(Pixels::Bytes(&decoded), s, out, label)
}

/// The files must back the volume before it is allocated: native pixels byte for byte, compressed ones within
/// [`codec::MAX_RATIO`] (past that, a small file claiming a large volume is a decompression bomb).
pub(super) fn check_backed(label: &str, needed: u64, files: &[(Kind, u64)]) -> Result<(), VolumeError> {
    let native: u64 = files.iter().filter(|f| f.0 == Kind::Native).map(|f| f.1).sum();
    let compressed: u64 = files.iter().filter(|f| f.0 != Kind::Native).map(|f| f.1).sum();
    if compressed == 0 {
        return if needed > native {
            Err(short(label, native, needed))
        } else {
            Ok(())
        };
    }
    if needed > native.saturating_add(compressed.saturating_mul(codec::MAX_RATIO)) {
        return Err(header_error(
            label,
            format!(
                "{compressed} bytes of compressed pixel data claim to decode to {needed} bytes, more than {}x: \
                 refused as a decompression bomb",
                codec::MAX_RATIO
            ),
        ));
    }
    Ok(())
}

/// Finds uncompressed little-endian PixelData of exactly `needed` bytes in a file that dicom-object could not
/// read to the end (junk after the pixels): the last `(7FE0,0010)` element header, explicit (OB/OW) or implicit
/// VR, whose length covers `needed` bytes that are present.
pub(super) fn find_pixel_bytes(bytes: &[u8], needed: usize) -> Option<&[u8]> {
    let u32_at = |i: usize| {
        bytes
            .get(i..i + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    (0..bytes.len().saturating_sub(8)).rev().find_map(|i| {
        if bytes[i..i + 4] != [0xE0, 0x7F, 0x10, 0x00] {
            return None;
        }
        let explicit = matches!(&bytes[i + 4..i + 6], b"OW" | b"OB") && bytes[i + 6..i + 8] == [0, 0];
        let (len, start) = if explicit {
            (u32_at(i + 8)?, i + 12)
        } else {
            (u32_at(i + 4)?, i + 8)
        };
        (len >= needed)
            .then(|| bytes.get(start..start.checked_add(needed)?))
            .flatten()
    })
}

pub(super) fn short(label: &str, actual: u64, needed: u64) -> VolumeError {
    header_error(
        label,
        format!("PixelData has {actual} bytes but the image needs {needed} (truncated file?)"),
    )
}

pub(super) fn unreachable_layout<T>(label: &str) -> Result<T, VolumeError> {
    Err(header_error(label, "slices differ in bit depth".into()))
}

pub(super) fn empty_data(
    voxel_type: VoxelType,
    count: usize,
    dims: [u32; 3],
    bytes: u64,
) -> Result<VoxelData, VolumeError> {
    let oom = |_| VolumeError::OutOfMemory { dims, bytes };
    Ok(match voxel_type {
        VoxelType::U8 | VoxelType::I8 => VoxelData::U8(try_vec(count).map_err(oom)?),
        _ => VoxelData::U16(try_vec(count).map_err(oom)?),
    })
}

/// Reads the planned slices' pixels into a volume.
pub(super) fn load_planned(
    plan: Plan,
    files: &[PathBuf],
    name: String,
    label: &str,
    progress: &mut Progress,
) -> Result<Volume, VolumeError> {
    let (dims, voxel_type) = (plan.dims, plan.voxel_type);
    let count = check_dims(dims)? as usize;
    let bytes_needed = count as u64 * voxel_type.size() as u64;
    check_files_back(&plan, files, bytes_needed, label)?;
    let mut data = empty_data(voxel_type, count, dims, bytes_needed)?;
    // Batches of slices decoded on every core (parsing and decompressing a slice is CPU work), then appended in
    // order: the peak is the volume and one batch of slices.
    let plane = dims[0] as usize * dims[1] as usize * plan.frame_order.len();
    let mut done = 0;
    for batch in plan.slices.chunks(rayon::current_num_threads() * 2) {
        let decoded = batch
            .par_iter()
            .map(|s| {
                let bytes = plane as u64 * voxel_type.size() as u64;
                let mut one = empty_data(voxel_type, plane, dims, bytes)?;
                append_slice(s, &files[s.source], &plan.frame_order, &mut one)?;
                Ok(one)
            })
            .collect::<Result<Vec<VoxelData>, VolumeError>>()?;
        for one in decoded {
            match (&mut data, one) {
                (VoxelData::U8(all), VoxelData::U8(v)) => all.extend_from_slice(&v),
                (VoxelData::U16(all), VoxelData::U16(v)) => all.extend_from_slice(&v),
                _ => unreachable_layout(label)?,
            }
        }
        done += batch.len();
        progress.report(done as f64 / plan.slices.len() as f64);
    }
    finish(name, plan, data)
}

/// The files must at least hold the pixels they claim (`needed` bytes) before anything is allocated for them.
pub(super) fn check_files_back(plan: &Plan, files: &[PathBuf], needed: u64, label: &str) -> Result<(), VolumeError> {
    let file_bytes: Vec<(Kind, u64)> = plan
        .slices
        .iter()
        .map(|s| (s.kind, std::fs::metadata(&files[s.source]).map_or(0, |m| m.len())))
        .collect();
    check_backed(label, needed, &file_bytes)
}

/// Appends slice `s`'s frames in `order`, read from `file` and decoded, to `data`.
pub(super) fn append_slice(s: &Slice, file: &Path, order: &[usize], data: &mut VoxelData) -> Result<(), VolumeError> {
    let f_label = format::file_label(file);
    match open_dicom(file, false) {
        Ok(obj) => append_file(&obj, s, order, data, &f_label),
        Err(e) => {
            // Pass 1 read this header, so the file is DICOM; dicom-object stops on bytes after the pixels.
            if !s.native_little_endian {
                return Err(e);
            }
            let bytes = std::fs::read(file).map_err(|source| VolumeError::Io {
                path: file.to_path_buf(),
                source,
            })?;
            let frame_bytes =
                s.rows as usize * s.columns as usize * s.frames as usize * usize::from(s.bits_allocated / 8);
            let pixels = find_pixel_bytes(&bytes, frame_bytes).ok_or(e)?;
            append_native(Pixels::Bytes(pixels), s, order, data, &f_label)
        }
    }
}
