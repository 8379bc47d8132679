//! One entry point for every file format: [`open`] picks the reader by content (magic bytes) first and by
//! extension second, then applies the caller's overrides and the maximum dimension.

use super::decode::{Endian, Progress};
use super::{dicom, downsample, format, metaimage, nifti, nrrd, raw, vti, vtk};
use super::{RawOptions, Volume, VolumeError};
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Raw,
    Vtk,
    Vti,
    Nrrd,
    Nifti,
    MetaImage,
    Dicom,
}

impl Format {
    pub fn name(self) -> &'static str {
        match self {
            Format::Raw => "raw",
            Format::Vtk => "VTK legacy",
            Format::Vti => "VTK XML ImageData",
            Format::Nrrd => "NRRD",
            Format::Nifti => "NIfTI-1",
            Format::MetaImage => "MetaImage",
            Format::Dicom => "DICOM",
        }
    }
}

/// How to open a file. `raw` (dims, type), `endian` and `header_bytes` only matter for raw files; `raw.spacing`, if
/// given, overrides the spacing of every format.
#[derive(Clone, Debug, Default)]
pub struct OpenOptions {
    pub raw: RawOptions,
    /// Byte order of a raw file's multi-byte voxels (default little).
    pub endian: Endian,
    /// Bytes to skip at the start of a raw file (a header volcast does not read).
    pub header_bytes: u64,
    /// Largest dimension allowed; `None` = no limit beyond [`super::MAX_DIM`].
    pub max_dim: Option<u32>,
    /// If a dimension exceeds `max_dim`: refuse (true) instead of downsampling (false, the default).
    pub no_downsample: bool,
    /// The data array to load from a file holding several (VTK legacy and `.vti`); `None`: the file's active
    /// scalars, else its first one-component array.
    pub array: Option<String>,
}

/// Which reader a path needs. A folder is a DICOM series. Content decides where it can (magic bytes of VTK, NRRD,
/// NIfTI-1, DICOM, VTK XML; gzip only means NIfTI when the name says so); then the extension; anything else is raw.
pub fn detect_format(path: &Path) -> Result<Format, VolumeError> {
    if path.is_dir() {
        return Ok(Format::Dicom);
    }
    let prefix = format::read_prefix(path, 512)?;
    if vtk::is_vtk(&prefix) {
        return Ok(Format::Vtk);
    }
    if vti::is_vtk_xml(&prefix) {
        return Ok(Format::Vti);
    }
    if nrrd::is_nrrd(&prefix) {
        return Ok(Format::Nrrd);
    }
    if nifti::is_nifti(&prefix) {
        return Ok(Format::Nifti);
    }
    if dicom::is_dicom(&prefix) {
        return Ok(Format::Dicom);
    }
    let name = format::file_label(path).to_ascii_lowercase();
    let by_extension = [
        (".vtk", Format::Vtk),
        (".vti", Format::Vti),
        (".nrrd", Format::Nrrd),
        (".nhdr", Format::Nrrd),
        (".nii", Format::Nifti),
        (".nii.gz", Format::Nifti),
        (".hdr", Format::Nifti),
        (".mha", Format::MetaImage),
        (".mhd", Format::MetaImage),
        (".dcm", Format::Dicom),
        (".dicom", Format::Dicom),
    ];
    if let Some((_, f)) = by_extension.iter().find(|(ext, _)| name.ends_with(ext)) {
        return Ok(*f);
    }
    if metaimage::is_metaimage(&prefix) {
        return Ok(Format::MetaImage);
    }
    Ok(Format::Raw)
}

/// Opens a volume file (or a DICOM folder) of any supported format.
pub fn open(path: &Path, opts: &OpenOptions) -> Result<Volume, VolumeError> {
    open_with_progress(path, opts, &mut |_| {})
}

/// [`open`], reporting the fraction of voxel data read so far (0 to 1) as it goes.
pub fn open_with_progress(
    path: &Path,
    opts: &OpenOptions,
    progress: &mut dyn FnMut(f32),
) -> Result<Volume, VolumeError> {
    let mut progress = Progress::new(Some(progress));
    let format = detect_format(path)?;
    let mut volume = match format {
        Format::Raw => {
            let extras = raw::RawExtras {
                endian: opts.endian,
                header_bytes: opts.header_bytes,
            };
            raw::load_raw_with_progress(path, &opts.raw, extras, &mut progress)?
        }
        Format::Vtk => vtk::load(path, opts.array.as_deref(), &mut progress)?,
        Format::Vti => vti::load(path, opts.array.as_deref(), &mut progress)?,
        Format::Nrrd => nrrd::load(path, &mut progress)?,
        Format::Nifti => nifti::load(path, &mut progress)?,
        Format::MetaImage => metaimage::load(path, &mut progress)?,
        Format::Dicom => dicom::load(path, &mut progress)?,
    };
    if format != Format::Raw {
        if let Some(spacing) = opts.raw.spacing {
            volume = volume.with_spacing(spacing)?;
        }
    }
    if let Some(max_dim) = opts.max_dim {
        if volume.dims.iter().any(|&d| d > max_dim) {
            if opts.no_downsample {
                return Err(VolumeError::DownsampleRefused {
                    dims: volume.dims,
                    max_dim,
                });
            }
            volume = downsample::downsample_to(volume, max_dim);
        }
    }
    Ok(volume)
}

impl Volume {
    /// Opens a file of any supported format with default options (see [`open`]).
    pub fn open(path: &Path) -> Result<Volume, VolumeError> {
        open(path, &OpenOptions::default())
    }
}
