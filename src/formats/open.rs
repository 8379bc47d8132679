//! One entry point for every file format: [`open`] picks the reader by content (magic bytes) first and by
//! extension second, then applies the caller's overrides and the maximum dimension.

use super::decode::{Endian, Progress};
use super::raw::RawOptions;
use super::{dicom, format, metaimage, nifti, nrrd, raw, tiff_stack, unsupported, vtk, zarr};
use crate::pyramid::budget::Budgets;
use crate::pyramid::max_dim::downsample_to;
use crate::volume::{Volume, VolumeError};
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Raw,
    Vtk,
    Vti,
    Nrrd,
    /// NIfTI-1, NIfTI-2 and Analyze 7.5: one reader, the header tells which ([`Volume::format`] names it).
    Nifti,
    MetaImage,
    Dicom,
    Tiff,
    OmeZarr,
}

impl Format {
    pub fn name(self) -> &'static str {
        match self {
            Format::Raw => "raw",
            Format::Vtk => "VTK legacy",
            Format::Vti => "VTK XML ImageData",
            Format::Nrrd => "NRRD",
            Format::Nifti => "NIfTI / Analyze 7.5",
            Format::MetaImage => "MetaImage",
            Format::Dicom => "DICOM",
            Format::Tiff => "TIFF",
            Format::OmeZarr => "OME-Zarr",
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
    /// Largest dimension allowed; `None` = no limit beyond [`crate::volume::MAX_DIM`].
    pub max_dim: Option<u32>,
    /// If a dimension exceeds `max_dim`: refuse (true) instead of downsampling (false, the default).
    pub no_downsample: bool,
    /// The data array to load from a file holding several (VTK legacy and `.vti`); `None`: the file's active
    /// scalars, else its first one-component array.
    pub array: Option<String>,
    /// The series to load from a DICOM folder holding several: a SeriesNumber or SeriesInstanceUID (`None`: the
    /// largest).
    pub series: Option<String>,
    /// The channel to load from an OME-Zarr image with a `c` axis, an ImageJ hyperstack, an OME-TIFF or a NIfTI's
    /// `dim[5]` (`None`: channel 0).
    pub channel: Option<u32>,
}

/// Which reader a path needs. A folder is decided by its files: TIFFs make a TIFF stack, DICOM files a DICOM
/// series, a Zarr store OME-Zarr. For a file, content decides where it can (magic bytes of VTK,
/// VTK XML, NRRD, NIfTI-1/2, DICOM, TIFF; gzip only means NIfTI when the name says so); then the extension (an
/// Analyze `.hdr` has no magic); then a format volcast does not read is named ([`VolumeError::Unsupported`]);
/// anything else is raw. A file named like a raw
/// file (`NAME_WxHxD_TYPE`, `.raw`) is raw whatever its first bytes.
pub fn detect_format(path: &Path) -> Result<Format, VolumeError> {
    if path.is_dir() {
        return folder_format(path);
    }
    let prefix = format::read_prefix(path, 512)?;
    if vtk::is_vtk(&prefix) {
        return Ok(Format::Vtk);
    }
    if vtk::vti::is_vtk_xml(&prefix) {
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
    if tiff_stack::is_tiff(&prefix) {
        return Ok(Format::Tiff);
    }
    if let Some(f) = format_by_name(path) {
        return Ok(f);
    }
    let name = format::file_label(path).to_ascii_lowercase();
    if metaimage::is_metaimage(&prefix) {
        return Ok(Format::MetaImage);
    }
    let named_raw = name.ends_with(".raw") || raw::parse_scivis_name(&name).is_some();
    if !named_raw {
        if let Some(k) = unsupported::identify(path, &prefix) {
            return Err(VolumeError::Unsupported {
                file: format::file_label(path),
                kind: k.kind,
                what: k.what,
            });
        }
    }
    Ok(Format::Raw)
}

/// The format a file's extension names, if it names one (raw files have none of their own).
pub fn format_by_name(path: &Path) -> Option<Format> {
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
        (".tif", Format::Tiff),
        (".tiff", Format::Tiff),
    ];
    by_extension
        .iter()
        .find(|(ext, _)| name.ends_with(ext))
        .map(|(_, f)| *f)
}

/// A folder: a Zarr store is OME-Zarr (whether it holds OME metadata is checked when it opens); otherwise its
/// files decide (TIFF stack or DICOM series, never both).
fn folder_format(path: &Path) -> Result<Format, VolumeError> {
    let label = format::file_label(path);
    if zarr::is_zarr_folder(path) {
        return Ok(Format::OmeZarr);
    }
    let io = |source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let (mut tiffs, mut dicoms, mut seen) = (0usize, 0usize, 0usize);
    for entry in std::fs::read_dir(path).map_err(io)? {
        let p = entry.map_err(io)?.path();
        let hidden = p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.'));
        if hidden || !p.is_file() {
            continue;
        }
        seen += 1;
        if seen > tiff_stack::MAX_FILES {
            break;
        }
        match format::read_prefix(&p, 132) {
            Ok(prefix) if tiff_stack::is_tiff(&prefix) => tiffs += 1,
            Ok(prefix) if dicom::is_dicom(&prefix) => dicoms += 1,
            _ => {}
        }
    }
    match (tiffs, dicoms) {
        (0, 0) => Err(format::header_error(
            &label,
            "the folder holds neither TIFF nor DICOM files; a folder opens as a TIFF stack (one slice per file) or \
             a DICOM series"
                .into(),
        )),
        (_, 0) => Ok(Format::Tiff),
        (0, _) => Ok(Format::Dicom),
        (t, d) => Err(format::header_error(
            &label,
            format!("the folder holds both TIFF ({t}) and DICOM ({d}) files; put the slices of one stack in a folder of their own"),
        )),
    }
}

/// Opens a volume file (or a DICOM or TIFF folder) of any supported format.
pub fn open(path: &Path, opts: &OpenOptions) -> Result<Volume, VolumeError> {
    open_with_progress(path, opts, &mut |_| {})
}

/// [`open`], reporting the fraction of voxel data read so far (0 to 1) as it goes. Every error names the file:
/// one that does not (a size limit found before anything was read, say) is prefixed with it.
pub fn open_with_progress(
    path: &Path,
    opts: &OpenOptions,
    progress: &mut dyn FnMut(f32),
) -> Result<Volume, VolumeError> {
    open_within(path, opts, None, progress)
}

/// [`open_with_progress`], an OME-Zarr store's level chosen within `budgets` (`None`: the finest that fits
/// `opts.max_dim`). Other formats are read whole here; `crate::scale::open` reads them within the budgets, and is
/// where budgets come in.
pub fn open_within(
    path: &Path,
    opts: &OpenOptions,
    budgets: Option<&Budgets>,
    progress: &mut dyn FnMut(f32),
) -> Result<Volume, VolumeError> {
    open_unnamed(path, opts, budgets, progress).map_err(|e| {
        let text = e.to_string();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.is_empty() || text.contains(&name) {
            e
        } else {
            VolumeError::Header {
                file: path.display().to_string(),
                problem: text,
            }
        }
    })
}

fn open_unnamed(
    path: &Path,
    opts: &OpenOptions,
    budgets: Option<&Budgets>,
    progress: &mut dyn FnMut(f32),
) -> Result<Volume, VolumeError> {
    let mut progress = Progress::new(Some(progress));
    // A file of a format volcast does not read can still be read as raw when the layout is given explicitly.
    let explicit_raw = opts.raw.dims.is_some() && opts.raw.voxel_type.is_some();
    let format = match detect_format(path) {
        Err(VolumeError::Unsupported { .. }) if explicit_raw && !path.is_dir() => Format::Raw,
        other => other?,
    };
    let mut volume = match format {
        Format::Raw => {
            let extras = raw::RawExtras {
                endian: opts.endian,
                header_bytes: opts.header_bytes,
            };
            raw::load_raw_with_progress(path, &opts.raw, extras, &mut progress)?
        }
        Format::Vtk => vtk::load(path, opts.array.as_deref(), &mut progress)?,
        Format::Vti => vtk::vti::load(path, opts.array.as_deref(), &mut progress)?,
        Format::Nrrd => nrrd::load(path, &mut progress)?,
        Format::Nifti => nifti::load(path, opts.channel, &mut progress)?,
        Format::MetaImage => metaimage::load(path, &mut progress)?,
        Format::Dicom => dicom::load(path, opts.series.as_deref(), &mut progress)?,
        Format::Tiff => tiff_stack::load(path, opts.channel, &mut progress)?,
        Format::OmeZarr => {
            let zarr_opts = zarr::ZarrOptions {
                channel: opts.channel,
                max_dim: opts.max_dim,
                budgets: budgets.copied(),
            };
            zarr::load(path, zarr_opts, &mut progress)?
        }
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
            volume = volume.map_steps(|step| downsample_to(step, max_dim));
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
