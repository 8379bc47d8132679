//! A DICOM series read slice by slice: pass 1's headers place it ([`PlacedSeries`]), and its bytes come from a
//! [`SeriesReader`], which decodes any run of output slices from their own files (compressed ones as the loader
//! decodes them, uneven spacing resampled as the loader resamples it). `scale::read` then makes a pyramid level on
//! every core without holding the series: a series larger than the host budget is decoded once, into the level.

use super::frames::Frames;
use super::geometry::resample_slices;
use super::pixels::{append_slice, check_files_back, empty_data};
use super::{headers, plan, temporal_positions, Headers, Slice};
use crate::formats::format::{self, header_error};
use crate::volume::{check_dims, Geometry, Scaling, SeriesInfo, VolumeError, VoxelData, VoxelType};
use std::path::{Path, PathBuf};

/// The sorted slices of one series and how to decode any run of them.
#[derive(Debug)]
pub struct SeriesReader {
    /// Each sorted slice's file.
    files: Vec<PathBuf>,
    slices: Vec<Slice>,
    /// Uneven spacing: each output slice's fractional index into `slices`.
    resample: Option<Vec<f64>>,
    dims: [u32; 3],
    voxel_type: VoxelType,
    label: String,
    /// The folder's series, as the loader gives them to the volume.
    pub series: Vec<SeriesInfo>,
    /// One multi-frame file read frame by frame, and its frames in volume order; `None` for a folder of slices.
    frames: Option<(Frames, Vec<usize>)>,
}

/// A series placed for reading slice by slice: its reader and what the loader would say of the volume (placement,
/// rescale, notes, modality). `formats::in_place` describes the volume from it; DICOM knows nothing of that
/// description, so this room never names the code that uses it.
pub struct PlacedSeries {
    pub reader: SeriesReader,
    pub geometry: Geometry,
    pub scaling: Scaling,
    pub notes: Vec<String>,
    pub modality: Option<String>,
    /// The one file's frames lie uncompressed and in order from this byte: read by box like a raw volume's voxels.
    pub plain_at: Option<u64>,
}

/// The folder `path` as a series read slice by slice, choosing `series` as the loader does; `None` where the loader
/// must read it: one file ([`frames_placed`] reads a multi-frame one), or slices at several temporal positions.
pub(crate) fn series_placed(path: &Path, series: Option<&str>) -> Result<Option<PlacedSeries>, VolumeError> {
    if !path.is_dir() {
        return Ok(None);
    }
    let found: Headers = headers(path, series)?;
    let (files, label, notes) = (found.files, found.label, found.notes);
    if temporal_positions(&found.slices).is_some() || found.slices.iter().any(|s| s.frames > 1) {
        return Ok(None);
    }
    let plan = plan(found.slices, &label)?;
    let needed = check_dims(plan.dims)? * plan.voxel_type.size() as u64;
    check_files_back(&plan, &files, needed, &label)?;
    let files = plan.slices.iter().map(|s| files[s.source].clone()).collect();
    Ok(Some(placed(plan, files, found.listed, None, label, notes)))
}

/// The one multi-frame file `path` as a volume read frame by frame ([`Frames`]), placed, ordered and rescaled as the
/// loader does, where `fits` does not take its frames whole; `None` where the loader reads it (see [`Frames::of`]).
pub(crate) fn frames_placed(
    path: &Path,
    fits: &dyn Fn([u32; 3], VoxelType) -> bool,
) -> Result<Option<PlacedSeries>, VolumeError> {
    let Some(frames) = Frames::of(path, fits)? else {
        return Ok(None);
    };
    let label = format::file_label(path);
    let plan = plan(vec![frames.slice.clone()], &label)?;
    check_dims(plan.dims)?;
    let in_order = plan.frame_order.iter().enumerate().all(|(i, &k)| i == k) && plan.resample.is_none();
    let plain = frames.plain_at().filter(|_| in_order);
    let (files, order) = (vec![frames.path().to_path_buf()], plan.frame_order.clone());
    let mut place = placed(plan, files, Vec::new(), Some((frames, order)), label, Vec::new());
    place.plain_at = plain;
    Ok(Some(place))
}

/// `plan`'s volume read by a [`SeriesReader`] of `files` (or of one file's `frames`).
fn placed(
    mut plan: super::Plan,
    files: Vec<PathBuf>,
    series: Vec<SeriesInfo>,
    frames: Option<(Frames, Vec<usize>)>,
    label: String,
    mut notes: Vec<String>,
) -> PlacedSeries {
    notes.append(&mut plan.notes);
    let modality = Some(plan.modality).filter(|m| !m.is_empty());
    let reader = SeriesReader {
        files,
        resample: plan.resample,
        dims: plan.dims,
        voxel_type: plan.voxel_type,
        label,
        series,
        slices: plan.slices,
        frames,
    };
    PlacedSeries {
        reader,
        geometry: plan.geometry,
        scaling: plan.scaling,
        notes,
        modality,
        plain_at: None,
    }
}

impl SeriesReader {
    /// The volume's size in voxels, x fastest.
    pub fn dims(&self) -> [u32; 3] {
        self.dims
    }

    /// The type the files give the voxels.
    pub fn voxel_type(&self) -> VoxelType {
        self.voxel_type
    }

    /// The voxel bytes `at..at + out.len()` as the file types them (little endian, signed values unbiased): whole
    /// output slices, as `scale::read` asks for them.
    pub fn read_at(&self, at: u64, out: &mut [u8]) -> Result<(), VolumeError> {
        let plane = u64::from(self.dims[0]) * u64::from(self.dims[1]) * self.voxel_type.size() as u64;
        let (z0, n) = (at / plane, out.len() as u64 / plane);
        let whole = at.is_multiple_of(plane) && (out.len() as u64).is_multiple_of(plane);
        if !whole || z0 + n > u64::from(self.dims[2]) {
            return Err(header_error(
                &self.label,
                format!(
                    "bytes {at}..{} are not whole slices of the series",
                    at + out.len() as u64
                ),
            ));
        }
        if n == 0 {
            return Ok(());
        }
        match self.held(z0 as usize, n as usize)? {
            VoxelData::U8(v) => {
                let flip = if self.voxel_type == VoxelType::I8 { 0x80 } else { 0 };
                out.iter_mut().zip(v).for_each(|(o, h)| *o = h ^ flip);
            }
            VoxelData::U16(v) => {
                let flip = if self.voxel_type == VoxelType::I16 { 0x8000 } else { 0 };
                out.chunks_exact_mut(2)
                    .zip(v)
                    .for_each(|(o, h)| o.copy_from_slice(&(h ^ flip).to_le_bytes()));
            }
            VoxelData::F32(_) => return Err(header_error(&self.label, "DICOM pixels are integers".into())),
        }
        Ok(())
    }

    /// Output slices `z0..z0 + n` as volcast holds them (signed values biased), decoded from the files under them.
    fn held(&self, z0: usize, n: usize) -> Result<VoxelData, VolumeError> {
        let Some(at) = &self.resample else {
            return self.decode(z0, n);
        };
        // Each output slice blends the two sorted slices around its fractional index.
        let last = self.frames.as_ref().map_or(self.slices.len(), |(_, order)| order.len()) - 1;
        let lo = (at[z0].floor() as usize).min(last);
        let hi = (at[z0 + n - 1].floor() as usize + 1).min(last);
        let data = self.decode(lo, hi + 1 - lo)?;
        let shifted: Vec<f64> = at[z0..z0 + n].iter().map(|f| f - lo as f64).collect();
        let [w, h, _] = self.dims;
        Ok(resample_slices(&data, [w, h, (hi + 1 - lo) as u32], &shifted))
    }

    /// Sorted slices `first..first + n`, decoded.
    fn decode(&self, first: usize, n: usize) -> Result<VoxelData, VolumeError> {
        let [w, h, _] = self.dims;
        let count = w as usize * h as usize * n;
        let bytes = count as u64 * self.voxel_type.size() as u64;
        let mut data = empty_data(self.voxel_type, count, [w, h, n as u32], bytes)?;
        for k in first..first + n {
            match &self.frames {
                Some((frames, order)) => frames.append(order[k], &mut data)?,
                None => append_slice(&self.slices[k], &self.files[k], &[0], &mut data)?,
            }
        }
        Ok(data)
    }

    /// The series' files together (total length, latest modification in nanoseconds): what the pyramid cache
    /// stamps its level with.
    pub fn identity(&self) -> Option<(u64, u128)> {
        self.files.iter().try_fold((0u64, 0u128), |(len, latest), f| {
            let meta = std::fs::metadata(f).ok()?;
            let modified = meta
                .modified()
                .ok()?
                .duration_since(std::time::UNIX_EPOCH)
                .ok()?
                .as_nanos();
            Some((len + meta.len(), latest.max(modified)))
        })
    }

    /// Whether this is one multi-frame file read frame by frame (not a folder of slices).
    pub fn is_one_file(&self) -> bool {
        self.frames.is_some()
    }

    /// The series' instance UID: a folder of several series keeps one cache entry per series.
    pub fn uid(&self) -> &str {
        self.slices.first().map_or("", |s| s.series.as_str())
    }
}

/// An upper bound on the voxels a folder of DICOM slices holds, from its first image's header alone: its files
/// times that image's frames of rows by columns, in that image's type. `None` for anything else.
pub(crate) fn claimed_bound(path: &Path) -> Option<([u32; 3], VoxelType)> {
    if !path.is_dir() {
        return None;
    }
    let files = super::list_folder(path, &format::file_label(path)).ok()?;
    let first = files.iter().find_map(|f| super::slice_header(f))?;
    let depth = u32::try_from(files.len() as u64 * u64::from(first.frames)).ok()?;
    Some((
        [first.columns, first.rows, depth],
        super::voxel_type(first.bits_allocated, first.signed),
    ))
}
