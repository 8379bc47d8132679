//! DICOM: a folder of single-frame slices (one series), or one multi-frame file, through `dicom-object`.
//!
//! Native pixel data is read straight from the parsed element. RLE Lossless, JPEG (baseline, extended,
//! lossless), JPEG-LS and JPEG 2000 are decoded frame by frame ([`codec`]), each frame checked to decode to
//! exactly Rows x Columns x BitsAllocated before it lands in the volume; other compressed transfer syntaxes
//! (JPEG XL, HTJ2K, video) are refused with a message naming them. An enhanced multi-frame object's per-frame and shared
//! functional groups (plane position and orientation, pixel measures, pixel value transformation) place and
//! rescale its frames like the slices of a folder.
//!
//! Slices are ordered by their position along the slice normal (ImageOrientationPatient row × column), so file
//! names and InstanceNumber do not matter; the z spacing is the mean step between sorted positions. Rescale
//! slope/intercept becomes [`Volume::scaling`](crate::volume::Volume::scaling); the stored integers reach the GPU as is.

pub(crate) mod codec;
mod frames;
mod geometry;
mod lengths;
mod pixels;
pub(crate) mod series;
mod slice;
pub(crate) mod slices;
mod temporal;

use super::decode::Progress;
use super::format::{self, clip, header_error};
use crate::volume::{check_dims, Geometry, Scaling, SeriesInfo, Volume, VolumeError, VoxelData, VoxelType};
use codec::Kind;
use dicom_object::file::ReadPreamble;
use dicom_object::{DefaultDicomObject, OpenFileOptions, Tag};
use geometry::Placed;
use lengths::check_lengths;
use pixels::{append_file, check_backed, empty_data, load_planned};
use slice::{slice_info, Slice};
use std::path::{Path, PathBuf};

pub(crate) const FORMAT: &str = "DICOM";
const PIXEL_DATA: Tag = Tag(0x7FE0, 0x0010);

/// Most files looked at in a folder: more slices than [`crate::volume::MAX_DIM`] cannot make a volume anyway.
const MAX_FILES: usize = 20_000;

pub(crate) fn is_dicom(prefix: &[u8]) -> bool {
    prefix.len() >= 132 && &prefix[128..132] == b"DICM"
}

struct Plan {
    slices: Vec<Slice>,
    dims: [u32; 3],
    geometry: Geometry,
    /// Uneven slice spacing: the output slices' positions as fractional indices into `slices` (or frames).
    resample: Option<Vec<f64>>,
    /// One multi-frame file: its frames in volume order (identity unless per-frame positions sorted them).
    frame_order: Vec<usize>,
    voxel_type: VoxelType,
    scaling: Scaling,
    modality: String,
    notes: Vec<String>,
}

/// Sorts slices along the normal and works out dims, spacing, type and notes.
fn plan(slices: Vec<Slice>, label: &str) -> Result<Plan, VolumeError> {
    let err = |problem: String| header_error(label, problem);
    let mut notes = Vec::new();
    let first = slices
        .first()
        .cloned()
        .ok_or_else(|| err("no DICOM image files found".into()))?;
    if slices.len() > 1 && slices.iter().any(|s| s.frames > 1) {
        return Err(err(
            "a folder of several multi-frame files is not supported: open one file".into(),
        ));
    }
    check_one_layout(&slices, &first, label)?;
    let depth = if first.frames > 1 {
        first.frames
    } else {
        slices.len() as u32
    };
    let dims = [first.columns, first.rows, depth];
    check_dims(dims)?;
    notes.extend(compression_note(&first));
    let pixel_spacing = first.pixel_spacing.unwrap_or_else(|| {
        notes.push("no PixelSpacing: in-plane spacing 1 is used".into());
        [1.0, 1.0]
    });
    let per_frame = !first.frame_places.is_empty();
    let placed: Vec<Placed> = if per_frame {
        first.frame_places.clone()
    } else {
        slices.iter().map(Slice::placed).collect()
    };
    let arrangement = geometry::arrange(&placed, pixel_spacing, first.slice_step).map_err(err)?;
    notes.extend(arrangement.notes);
    let (slices, frame_order) = if per_frame {
        (slices, arrangement.order.clone())
    } else {
        let mut slots: Vec<Option<Slice>> = slices.into_iter().map(Some).collect();
        let sorted = arrangement.order.iter().filter_map(|&i| slots[i].take()).collect();
        (sorted, (0..first.frames as usize).collect())
    };
    let voxel_type = voxel_type(first.bits_allocated, first.signed);
    Ok(Plan {
        slices,
        dims,
        geometry: arrangement.geometry,
        resample: arrangement.resample,
        frame_order,
        voxel_type,
        scaling: first.scaling,
        modality: first.modality.clone(),
        notes,
    })
}

/// The type of a slice's pixels: 8-bit stays 8-bit, wider is held in 16 bits.
fn voxel_type(bits_allocated: u16, signed: bool) -> VoxelType {
    match (bits_allocated, signed) {
        (8, false) => VoxelType::U8,
        (8, true) => VoxelType::I8,
        (_, false) => VoxelType::U16,
        (_, true) => VoxelType::I16,
    }
}

/// Every slice must share the first one's size, bit depth, signedness and rescale.
fn check_one_layout(slices: &[Slice], first: &Slice, label: &str) -> Result<(), VolumeError> {
    for s in slices {
        let same = (s.rows, s.columns, s.bits_allocated, s.signed)
            == (first.rows, first.columns, first.bits_allocated, first.signed);
        if !same {
            return Err(header_error(
                label,
                format!(
                    "slices differ: {}x{} {}-bit{} against {}x{} {}-bit{} in the first; one series must share one \
                     layout",
                    s.columns,
                    s.rows,
                    s.bits_allocated,
                    if s.signed { " signed" } else { "" },
                    first.columns,
                    first.rows,
                    first.bits_allocated,
                    if first.signed { " signed" } else { "" },
                ),
            ));
        }
        if s.scaling != first.scaling {
            return Err(header_error(
                label,
                format!(
                    "slices have different rescale slope/intercept ({} {} and {} {}); volcast needs one per series",
                    s.scaling.slope, s.scaling.intercept, first.scaling.slope, first.scaling.intercept
                ),
            ));
        }
    }
    Ok(())
}

/// Says how compressed pixel data were decoded, and warns of a syntax that can be lossy.
fn compression_note(first: &Slice) -> Option<String> {
    if first.kind == Kind::Native {
        return None;
    }
    let lossy = matches!(
        first.transfer_syntax.as_str(),
        "1.2.840.10008.1.2.4.50" | "1.2.840.10008.1.2.4.51" | "1.2.840.10008.1.2.4.91"
    );
    Some(format!(
        "pixel data compressed as {} ({}), decoded{}",
        codec::name(&first.transfer_syntax),
        clip(&first.transfer_syntax),
        if lossy {
            "; this syntax can be lossy, so values may differ from the original scan"
        } else {
            ""
        }
    ))
}

/// The volume from the assembled pixels, placed and (for uneven spacing) resampled as `plan` says.
fn finish(name: String, plan: Plan, data: VoxelData) -> Result<Volume, VolumeError> {
    let data = match &plan.resample {
        Some(at) => geometry::resample_slices(&data, plan.dims, at),
        None => data,
    };
    let spacing = plan.geometry.spacing().map(|s| s as f32);
    let mut v = Volume::new(name, plan.dims, spacing, plan.voxel_type, data)?
        .with_scaling(plan.scaling)?
        .with_geometry(plan.geometry)?;
    v.format = FORMAT.into();
    v.modality = Some(plan.modality).filter(|m| !m.is_empty());
    v.notes = plan.notes;
    Ok(v)
}

fn parse_bytes(bytes: &[u8], label: &str, header_only: bool) -> Result<DefaultDicomObject, VolumeError> {
    let end = check_lengths(bytes, label)?;
    let options = OpenFileOptions::new().read_preamble(ReadPreamble::Auto);
    let options = if header_only {
        options.read_until(PIXEL_DATA)
    } else {
        options
    };
    options
        .from_reader(&bytes[..end])
        .map_err(|e| header_error(label, format!("not a readable DICOM file: {e}")))
}

/// Loads one DICOM file (single- or multi-frame) held in memory.
pub fn from_bytes(bytes: &[u8]) -> Result<Volume, VolumeError> {
    let label = "DICOM data";
    let obj = parse_bytes(bytes, label, false)?;
    let slice = slice_info(&obj, 0, label)?;
    let plan = plan(vec![slice], label)?;
    let count = check_dims(plan.dims)? as usize;
    let bytes_needed = count as u64 * plan.voxel_type.size() as u64;
    check_backed(label, bytes_needed, &[(plan.slices[0].kind, bytes.len() as u64)])?;
    let mut data = empty_data(plan.voxel_type, count, plan.dims, bytes_needed)?;
    append_file(&obj, &plan.slices[0], &plan.frame_order, &mut data, label)?;
    finish("dicom".into(), plan, data)
}

fn open_dicom(path: &Path, header_only: bool) -> Result<DefaultDicomObject, VolumeError> {
    // Read whole (one slice at a time) so every element length can be checked before dicom-object parses it.
    let bytes = std::fs::read(path).map_err(|source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_bytes(&bytes, &format::file_label(path), header_only)
}

/// What pass 1 found: the files, the chosen series' slices (unsorted), notes so far and the folder's series.
struct Headers {
    files: Vec<PathBuf>,
    slices: Vec<Slice>,
    notes: Vec<String>,
    listed: Vec<SeriesInfo>,
    label: String,
}

/// Pass 1: every header of the folder (or the one file), stopping before the pixels, and the series chosen.
fn headers(path: &Path, series: Option<&str>) -> Result<Headers, VolumeError> {
    let label = format::file_label(path);
    let files: Vec<PathBuf> = if path.is_dir() {
        list_folder(path, &label)?
    } else {
        vec![path.to_path_buf()]
    };
    let mut slices = Vec::new();
    let mut skipped = 0;
    for (i, f) in files.iter().enumerate() {
        let f_label = format::file_label(f);
        // In a folder, only DICOM Part 10 files (DICM at byte 128) are slices; DICOMDIR, notes etc. are skipped.
        if files.len() > 1 && !format::read_prefix(f, 132).is_ok_and(|p| is_dicom(&p)) {
            skipped += 1;
            continue;
        }
        match open_dicom(f, true).and_then(|obj| slice_info(&obj, i, &f_label)) {
            Ok(s) => slices.push(s),
            // One file: say why. In a folder, DICOMDIR, notes and other files are skipped.
            Err(e) if files.len() == 1 => return Err(e),
            Err(VolumeError::Header { problem, .. }) if problem.starts_with("not a readable") => skipped += 1,
            Err(e) => return Err(e),
        }
    }
    let mut notes = Vec::new();
    if skipped > 0 {
        notes.push(format!(
            "{skipped} file(s) in the folder are not DICOM images and were skipped"
        ));
    }
    let (slices, mut listed) = series::choose(slices, series, &label)?;
    // A folder lists its series (one included, for its description and modality); one file has none to list.
    if !path.is_dir() {
        listed.clear();
    }
    notes.extend(series::note(&listed));
    Ok(Headers {
        files,
        slices,
        notes,
        listed,
        label,
    })
}

/// The distinct temporal positions of `slices`, if they are one series at several times.
fn temporal_positions(slices: &[Slice]) -> Option<Vec<i64>> {
    let mut times: Vec<i64> = slices.iter().filter_map(|s| s.temporal).collect();
    times.sort_unstable();
    times.dedup();
    (times.len() >= 2 && slices.iter().all(|s| s.temporal.is_some())).then_some(times)
}

/// Loads a folder of slices (or one file). Pass 1 reads every header (stopping before the pixels) to sort the
/// slices; pass 2 reads the pixels slice by slice into the final buffer, so the peak is one volume plus one slice.
pub(crate) fn load(path: &Path, series: Option<&str>, progress: &mut Progress) -> Result<Volume, VolumeError> {
    let Headers {
        files,
        slices,
        mut notes,
        listed,
        label,
    } = headers(path, series)?;
    // Several temporal positions (TemporalPositionIdentifier): one volume per position, as time steps.
    let Some(times) = temporal_positions(&slices) else {
        let mut plan = plan(slices, &label)?;
        notes.append(&mut plan.notes);
        plan.notes = notes;
        let mut v = load_planned(plan, &files, format::volume_name(path), &label, progress)?;
        v.series = listed;
        return Ok(v);
    };
    let mut v = temporal::load_steps(
        slices,
        &times,
        &files,
        format::volume_name(path),
        &label,
        notes,
        progress,
    )?;
    v.series = listed;
    Ok(v)
}

/// The largest file [`series_of_file`] reads to learn its series: a 4096² slice of 32-bit pixels is 64 MiB.
const MAX_SLICE_FILE: u64 = 64 << 20;

/// The header of `f` as one slice, if it is a DICOM Part 10 file (DICM at byte 128) that reads as one.
fn slice_header(f: &Path) -> Option<Slice> {
    if !format::read_prefix(f, 132).is_ok_and(|p| is_dicom(&p)) {
        return None;
    }
    let obj = open_dicom(f, true).ok()?;
    slice_info(&obj, 0, &format::file_label(f)).ok()
}

/// The folder and series that one DICOM file stands for: as in Slicer and every DICOM viewer, opening one slice of
/// a series opens the whole series, with the folder's other series listed beside it. `None` for a folder, a file that
/// is not DICOM or holds several frames (a volume of its own), and a file alone in its series in its folder.
pub fn series_of_file(path: &Path) -> Option<(PathBuf, String)> {
    // A file larger than any one slice is a multi-frame volume: not read whole just to find that out.
    let slice_sized = std::fs::metadata(path).is_ok_and(|m| m.is_file() && m.len() <= MAX_SLICE_FILE);
    if !slice_sized {
        return None;
    }
    let own = slice_header(path)?;
    let uid = own.series;
    if own.frames > 1 || uid.is_empty() {
        return None;
    }
    let folder = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let files = list_folder(folder, &format::file_label(folder)).ok()?;
    let sibling = files
        .iter()
        .filter(|f| f.file_name() != path.file_name())
        .any(|f| slice_header(f).is_some_and(|s| s.series == uid));
    sibling.then(|| (folder.to_path_buf(), uid))
}

/// The visible files of a folder, sorted by name; at most [`MAX_FILES`].
fn list_folder(path: &Path, label: &str) -> Result<Vec<PathBuf>, VolumeError> {
    let io = |source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(path).map_err(io)? {
        let entry = entry.map_err(io)?;
        let p = entry.path();
        let hidden = p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.'));
        if p.is_file() && !hidden {
            files.push(p);
            if files.len() > MAX_FILES {
                return Err(header_error(
                    label,
                    format!("more than {MAX_FILES} files in the folder"),
                ));
            }
        }
    }
    files.sort();
    Ok(files)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    pub(super) fn slice(pos: f64, instance: i64) -> Slice {
        Slice {
            source: instance as usize,
            rows: 2,
            columns: 3,
            frames: 1,
            bits_allocated: 16,
            bits_stored: 12,
            signed: true,
            scaling: Scaling::IDENTITY,
            pixel_spacing: Some([0.5, 0.25]),
            position: Some([0.0, 0.0, pos]),
            orientation: Some([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
            series: "1".into(),
            series_number: Some(1),
            series_description: String::new(),
            modality: "CT".into(),
            instance,
            slice_step: Some(9.0),
            native_little_endian: true,
            kind: Kind::Native,
            transfer_syntax: "1.2.840.10008.1.2.1".into(),
            frame_places: Vec::new(),
            temporal: None,
        }
    }

    #[test]
    fn slices_sort_by_position_not_instance() {
        let Plan {
            slices: sorted,
            dims,
            geometry,
            voxel_type: t,
            notes,
            ..
        } = plan(vec![slice(5.0, 1), slice(-5.0, 2), slice(0.0, 3)], "x").unwrap();
        assert_eq!(sorted.iter().map(|s| s.instance).collect::<Vec<_>>(), [2, 3, 1]);
        assert_eq!(dims, [3, 2, 3]);
        assert_eq!(geometry.spacing(), [0.25, 0.5, 5.0]);
        assert_eq!(t, VoxelType::I16);
        assert!(notes.is_empty(), "{notes:?}");
    }

    #[test]
    fn bad_series() {
        let err = |p: Result<Plan, VolumeError>| p.err().expect("refused").to_string();
        let e = err(plan(vec![slice(1.0, 1), slice(1.0, 2)], "x"));
        assert!(e.contains("same position"), "{e}");
        let e = err(plan(vec![slice(0.0, 1), slice(1.0, 2), slice(1.0, 3)], "x"));
        assert!(e.contains("share a position"), "{e}");
        let mut other = slice(2.0, 2);
        other.rows = 4;
        let e = err(plan(vec![slice(0.0, 1), other], "x"));
        assert!(e.contains("slices differ: 3x4 16-bit signed against 3x2"), "{e}");
        let Plan {
            geometry,
            notes,
            resample,
            ..
        } = plan(vec![slice(0.0, 1), slice(1.0, 2), slice(3.0, 3)], "x").unwrap();
        assert_eq!(geometry.spacing()[2], 1.5);
        assert!(
            notes[0].contains("uneven slice spacing") && resample.is_some(),
            "{notes:?}"
        );
        let e = err(plan(vec![], "x"));
        assert!(e.contains("no DICOM image files"), "{e}");
    }

    #[test]
    fn garbage_is_an_error() {
        for bytes in [
            &b""[..],
            b"DICM",
            &[0u8; 200],
            b"not dicom at all, not even close......",
        ] {
            assert!(from_bytes(bytes).is_err());
        }
    }
}
