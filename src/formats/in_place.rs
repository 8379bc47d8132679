//! Volumes whose voxels lie on disk as they are used (raw files; NRRD, NIfTI-1 and MetaImage with uncompressed
//! data): where they start, so a converter can read them slab by slab with positioned reads instead of loading them
//! whole. The formats' own header parsers decide everything; this only says where the bytes are.
//! Compressed streams, a `.vti`'s compressed blocks and a DICOM series' slices are described here too, each with how
//! to decode it; the readers only parse, and never name this description.

use super::decode::Endian;
use super::dicom::{
    self,
    slices::{self, PlacedSeries},
};
use super::format::{self, DataLocation, Encoding, Header};
use super::open::{detect_format, Format, OpenOptions};
use super::vtk::vti;
use super::vtk::vti_blocks::{BlockIndex, Text};
use super::{metaimage, nifti, nrrd, raw};
use crate::volume::{check_extent, Geometry, Scaling, VolumeError, VoxelType};
use std::path::{Path, PathBuf};

/// A volume read in place: `timesteps` steps of `dims` voxels of `voxel_type`, one after another from `offset` in
/// `data_file`, x fastest.
#[derive(Clone, Debug)]
pub struct InPlace {
    pub name: String,
    pub format: &'static str,
    pub data_file: PathBuf,
    pub offset: u64,
    pub dims: [u32; 3],
    pub voxel_type: VoxelType,
    pub endian: Endian,
    pub geometry: Geometry,
    pub scaling: Scaling,
    pub timesteps: u32,
    pub notes: Vec<String>,
    /// The bytes from `offset` are a compressed stream (gzip NIfTI or NRRD, zlib MetaImage), decoded front to back;
    /// `None`: they lie in place.
    pub inflate: Option<Inflate>,
    /// The values are in independently compressed blocks (an appended `.vti` array): any range is read by decoding
    /// the blocks under it (`vtk::vti_blocks`); `None`: they lie in place or `inflate` says how to decode them.
    pub blocks: Option<std::sync::Arc<BlockIndex>>,
    /// The voxels are a DICOM series' slices, each decoded from its own file (`dicom::slices`); `data_file` is the
    /// folder.
    pub slices: Option<std::sync::Arc<slices::SeriesReader>>,
    /// The file's data arrays, as `volcast info` lists them (a multi-array `.vti`); empty for one-array formats.
    pub arrays: Vec<crate::volume::ArrayInfo>,
    /// The modality a DICOM file names ("CT", "MR"), as its loader gives it to the volume.
    pub modality: Option<String>,
    /// The file's channels (a 5-D NIfTI's `dim[5]`), the one read marked; empty for a file of one.
    pub channels: Vec<crate::volume::ChannelInfo>,
}

/// A compressed stream's kind, and the inflated bytes before the voxels (a `.nii.gz`'s header and extensions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Inflate {
    pub zlib: bool,
    pub skip: u64,
}

impl InPlace {
    /// Whether any box of voxels can be read with positioned reads (uncompressed, one step): the finer levels of a
    /// level held from such a file stay in it (`scale::finer`), read as stored, as the level is (a rescale is the
    /// volume's, applied to every level alike).
    pub fn by_box(&self) -> bool {
        let decoded = self.inflate.is_some() || self.blocks.is_some() || self.slices.is_some();
        !decoded && self.timesteps == 1
    }

    /// Bytes of one time step.
    pub fn step_bytes(&self) -> u64 {
        self.dims.iter().map(|&d| u64::from(d)).product::<u64>() * self.voxel_type.size() as u64
    }
}

/// `path` as an [`InPlace`] volume if its voxels lie uncompressed on disk; `None` for every other format or
/// encoding (those are loaded whole). Sizes are checked: a data file shorter than its header claims is refused.
pub fn in_place(path: &Path, opts: &OpenOptions) -> Result<Option<InPlace>, VolumeError> {
    let explicit_raw = opts.raw.dims.is_some() && opts.raw.voxel_type.is_some();
    let format = match detect_format(path) {
        Err(VolumeError::Unsupported { .. }) if explicit_raw && !path.is_dir() => Format::Raw,
        other => other?,
    };
    let file = format::file_label(path);
    let header = match format {
        Format::Raw => return raw_in_place(path, opts).map(Some),
        Format::Nrrd => nrrd::parse(&format::read_prefix(path, format::HEADER_LIMIT)?, &file)?,
        Format::MetaImage => metaimage::parse(&format::read_prefix(path, format::HEADER_LIMIT)?, &file)?,
        Format::Vti => return vti_uncompressed(path, opts),
        Format::Nifti => {
            // 544 bytes: NIfTI-2's 540-byte header and its extension flag; NIfTI-1 and Analyze need 348.
            let prefix = format::read_prefix(path, 544)?;
            if nifti::is_gzip(&prefix) {
                return Ok(None);
            }
            let mut h = nifti::parse_file(&prefix, &file)?;
            nifti::pick_channel(&mut h, opts.channel, &file)?;
            if let DataLocation::Detached { skip, .. } = h.location {
                // A .hdr/.img pair, as the loader reads it.
                let img = path.with_extension("img");
                h.location = DataLocation::Detached {
                    name: format::file_label(&img),
                    skip,
                };
            }
            h
        }
        _ => return Ok(None),
    };
    if header.encoding != Encoding::Raw {
        return Ok(None);
    }
    header_in_place(path, header, opts).map(Some)
}

/// The DICOM folder `path` as a series read slice by slice, choosing `series` as the loader does; `None` where the
/// loader must read it: one file ([`frames_in_place`] reads a multi-frame one), or slices at several temporal
/// positions.
pub(crate) fn series_in_place(path: &Path, series: Option<&str>) -> Result<Option<InPlace>, VolumeError> {
    Ok(slices::series_placed(path, series)?.map(|s| series_of(path, s)))
}

/// The one multi-frame DICOM file `path` as a volume read frame by frame, where `fits` does not take its frames
/// whole; `None` where the loader reads it.
pub(crate) fn frames_in_place(
    path: &Path,
    fits: &dyn Fn([u32; 3], VoxelType) -> bool,
) -> Result<Option<InPlace>, VolumeError> {
    Ok(slices::frames_placed(path, fits)?.map(|s| series_of(path, s)))
}

/// A placed DICOM series as an [`InPlace`] at `path`, its bytes from the series' reader.
fn series_of(path: &Path, s: PlacedSeries) -> InPlace {
    let mut place = InPlace {
        name: format::volume_name(path),
        format: dicom::FORMAT,
        data_file: path.to_path_buf(),
        offset: 0,
        dims: s.reader.dims(),
        voxel_type: s.reader.voxel_type(),
        endian: Endian::Little,
        geometry: s.geometry,
        scaling: s.scaling,
        timesteps: 1,
        notes: s.notes,
        inflate: None,
        blocks: None,
        slices: Some(std::sync::Arc::new(s.reader)),
        arrays: Vec::new(),
        modality: s.modality,
        channels: Vec::new(),
    };
    if let Some(offset) = s.plain_at {
        // The frames lie in the file as a raw volume's voxels do: read by box like one (`InPlace::by_box`).
        place.offset = offset;
        place.slices = None;
        place.notes.push(
            "its frames lie uncompressed and in order in the file: read in place like a raw file's voxels".into(),
        );
    }
    place
}

/// What a NRRD, MetaImage, NIfTI or Analyze header claims (dims, voxel type, time steps) whatever its encoding, a
/// gzip NIfTI's header decompressed from the file's first bytes: what reading the file whole would need, known before
/// anything else is read. `None` for other formats and for headers that do not parse (the loader says why).
pub fn claimed_shape(path: &Path) -> Option<([u32; 3], VoxelType, u32)> {
    let file = format::file_label(path);
    let header = match detect_format(path).ok()? {
        Format::Nrrd => nrrd::parse(&format::read_prefix(path, format::HEADER_LIMIT).ok()?, &file).ok()?,
        Format::MetaImage => metaimage::parse(&format::read_prefix(path, format::HEADER_LIMIT).ok()?, &file).ok()?,
        Format::Nifti => {
            let prefix = format::read_prefix(path, 544).ok()?;
            let prefix = if nifti::is_gzip(&prefix) {
                use std::io::Read;
                let mut head = Vec::with_capacity(544);
                let gz = flate2::read::GzDecoder::new(std::fs::File::open(path).ok()?);
                gz.take(544).read_to_end(&mut head).ok()?;
                head
            } else {
                prefix
            };
            nifti::parse_file(&prefix, &file).ok()?
        }
        _ => return None,
    };
    Some((header.dims, header.voxel_type, header.timesteps.max(1)))
}

/// `path` as a compressed stream to decode front to back (gzip NIfTI, gzip NRRD, zlib MetaImage), so that a level of
/// it can be made without holding the whole volume (`scale::open`); `None` for every other file. A claim larger than
/// the compressed bytes can inflate to is refused before anything is decoded.
pub fn compressed(path: &Path, opts: &OpenOptions) -> Result<Option<InPlace>, VolumeError> {
    let file = format::file_label(path);
    let header = match detect_format(path) {
        Ok(Format::Nrrd) => nrrd::parse(&format::read_prefix(path, format::HEADER_LIMIT)?, &file)?,
        Ok(Format::MetaImage) => metaimage::parse(&format::read_prefix(path, format::HEADER_LIMIT)?, &file)?,
        Ok(Format::Nifti) => {
            if !nifti::is_gzip(&format::read_prefix(path, 4)?) {
                return Ok(None);
            }
            let mut h = nifti::parse_file(&gzip_prefix(path, 544)?, &file)?;
            nifti::pick_channel(&mut h, opts.channel, &file)?;
            let DataLocation::Inline(Some(vox_offset)) = h.location else {
                return Ok(None);
            };
            // The stream starts at the file's first byte; the voxels `vox_offset` inflated bytes into it.
            h.location = DataLocation::Inline(Some(0));
            h.encoding = Encoding::Gzip;
            return stream_of(path, h, vox_offset, opts).map(Some);
        }
        Ok(Format::Vti) => return vti_compressed(path, opts),
        _ => return Ok(None),
    };
    if !matches!(header.encoding, Encoding::Gzip | Encoding::Zlib) {
        return Ok(None);
    }
    stream_of(path, header, 0, opts).map(Some)
}

/// The first `n` inflated bytes of a gzip file (fewer if it is shorter).
fn gzip_prefix(path: &Path, n: u64) -> Result<Vec<u8>, VolumeError> {
    use std::io::Read;
    let io = |source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut head = Vec::with_capacity(n as usize);
    let gz = flate2::read::MultiGzDecoder::new(std::fs::File::open(path).map_err(io)?);
    gz.take(n)
        .read_to_end(&mut head)
        .map_err(|source| VolumeError::Corrupt {
            file: format::file_label(path),
            what: "gzip",
            source,
        })?;
    Ok(head)
}

/// A compressed stream from where `header` puts it, its voxels `skip` inflated bytes in.
fn stream_of(path: &Path, header: Header, skip: u64, opts: &OpenOptions) -> Result<InPlace, VolumeError> {
    let file = format::file_label(path);
    let needed = claimed_bytes(&header)?;
    let (data_file, offset) = match &header.location {
        DataLocation::Inline(Some(o)) => (path.to_path_buf(), *o),
        DataLocation::Detached { name, skip: Some(s) } => (format::resolve_data_file(path, name)?, *s),
        _ => {
            return Err(VolumeError::Header {
                file,
                problem: "a data offset of -1 (data at the end of the file) only works with raw encoding".into(),
            })
        }
    };
    let len = file_len(&data_file)?;
    let available = len.saturating_sub(offset);
    format::check_compressed(&header, &file, available, needed.saturating_add(skip))?;
    let inflate = Inflate {
        zlib: header.encoding == Encoding::Zlib,
        skip,
    };
    let mut place = header_in_place_unchecked(path, header, data_file, offset, opts);
    place.inflate = Some(inflate);
    Ok(place)
}

/// A `.vti` whose array is appended raw and uncompressed: its values lie in place after the one header word that
/// counts their bytes (which must agree with the extent and type). `None` for any other layout.
fn vti_uncompressed(path: &Path, opts: &OpenOptions) -> Result<Option<InPlace>, VolumeError> {
    let Some((mut header, stored)) = vti::appended(path, opts.array.as_deref())? else {
        return Ok(None);
    };
    if stored.compressor.is_some() || stored.text != Text::Raw {
        return Ok(None);
    }
    let needed = claimed_bytes(&header)?;
    let mut word = [0u8; 8];
    let n = stored.word;
    let read = std::fs::File::open(path).and_then(|f| {
        use std::os::unix::fs::FileExt;
        f.read_exact_at(&mut word[..n], stored.at)
    });
    let count = match stored.endian {
        Endian::Little => u64::from_le_bytes(word),
        Endian::Big => u64::from_be_bytes(word) >> (8 * (8 - n)),
    };
    if read.is_err() || count != needed {
        // Not what the extent needs, or past the file's end: the whole-file reader says which.
        return Ok(None);
    }
    header.location = DataLocation::Inline(Some(stored.at + n as u64));
    header.encoding = Encoding::Raw;
    header_in_place(path, header, opts).map(Some)
}

/// The largest compressed block read by range: VTK writes 32 KiB blocks; a file of larger ones is read whole.
const MAX_BLOCK: u64 = 64 << 20;

/// A `.vti` whose array is appended in compressed blocks or as base64: read by range, decoding the characters and
/// blocks each range needs. `None` for any other layout (a raw uncompressed array lies in place).
fn vti_compressed(path: &Path, opts: &OpenOptions) -> Result<Option<InPlace>, VolumeError> {
    let Some((header, stored)) = vti::appended(path, opts.array.as_deref())? else {
        return Ok(None);
    };
    if stored.compressor.is_none() && stored.text == Text::Raw {
        return Ok(None);
    }
    let needed = claimed_bytes(&header)?;
    let at = (stored.at, stored.text);
    let index = BlockIndex::read(path, at, (stored.word, stored.endian), stored.compressor, needed)?;
    if index.block > MAX_BLOCK {
        return Ok(None);
    }
    let mut place = header_in_place_unchecked(path, header, path.to_path_buf(), 0, opts);
    place.blocks = Some(std::sync::Arc::new(index));
    Ok(Some(place))
}

fn header_in_place(path: &Path, header: Header, opts: &OpenOptions) -> Result<InPlace, VolumeError> {
    let needed = claimed_bytes(&header)?;
    let (data_file, offset) = match &header.location {
        DataLocation::Inline(offset) => (path.to_path_buf(), *offset),
        DataLocation::Detached { name, skip } => (format::resolve_data_file(path, name)?, *skip),
    };
    let len = file_len(&data_file)?;
    let truncated = |actual| VolumeError::Truncated {
        file: format::file_label(&data_file),
        actual,
        expected: needed,
        dims: header.dims,
        voxel_type: header.voxel_type,
    };
    let offset = match offset {
        Some(o) => o,
        None => len.checked_sub(needed).ok_or_else(|| truncated(len))?,
    };
    if len < offset.saturating_add(needed) {
        return Err(truncated(len.saturating_sub(offset)));
    }
    Ok(header_in_place_unchecked(path, header, data_file, offset, opts))
}

/// Bytes of voxels `header` claims, every step.
fn claimed_bytes(header: &Header) -> Result<u64, VolumeError> {
    Ok(check_extent(header.dims)? * header.voxel_type.size() as u64 * u64::from(header.timesteps.max(1)))
}

fn file_len(data_file: &Path) -> Result<u64, VolumeError> {
    std::fs::metadata(data_file)
        .map(|m| m.len())
        .map_err(|source| VolumeError::Io {
            path: data_file.to_path_buf(),
            source,
        })
}

/// The [`InPlace`] `header` describes at `offset` of `data_file`, sizes already checked.
fn header_in_place_unchecked(
    path: &Path,
    header: Header,
    data_file: PathBuf,
    offset: u64,
    opts: &OpenOptions,
) -> InPlace {
    let mut geometry = header.placement();
    if let Some(s) = opts.raw.spacing {
        geometry = geometry.with_spacing(s.map(f64::from));
    }
    InPlace {
        name: format::volume_name(path),
        format: header.format,
        data_file,
        offset,
        dims: header.dims,
        voxel_type: header.voxel_type,
        endian: header.endian,
        geometry,
        scaling: header.scaling,
        timesteps: header.timesteps.max(1),
        notes: header.notes,
        inflate: None,
        blocks: None,
        slices: None,
        channels: crate::volume::ChannelInfo::numbered(header.channels as usize, header.channel as usize),
        arrays: header.arrays,
        modality: None,
    }
}

fn raw_in_place(path: &Path, opts: &OpenOptions) -> Result<InPlace, VolumeError> {
    let file = format::file_label(path);
    let (name, dims, voxel_type) = raw::layout(path, &file, &opts.raw)?;
    let spacing = opts.raw.spacing.unwrap_or([1.0; 3]);
    let expected = check_extent(dims)? * voxel_type.size() as u64;
    if !spacing.iter().all(|s| s.is_finite() && *s > 0.0) {
        return Err(VolumeError::BadSpacing { spacing });
    }
    let extras = raw::RawExtras {
        endian: opts.endian,
        header_bytes: opts.header_bytes,
    };
    raw::check_file_size(path, &file, extras, dims, voxel_type, expected)?;
    Ok(InPlace {
        name,
        format: "raw",
        data_file: path.to_path_buf(),
        offset: opts.header_bytes,
        dims,
        voxel_type,
        endian: opts.endian,
        geometry: Geometry::from_spacing(spacing.map(f64::from)),
        scaling: Scaling::IDENTITY,
        timesteps: 1,
        notes: Vec::new(),
        inflate: None,
        blocks: None,
        slices: None,
        arrays: Vec::new(),
        modality: None,
        channels: Vec::new(),
    })
}
