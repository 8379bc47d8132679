//! What the header-based formats (VTK, NRRD, NIfTI, MetaImage) have in common: a parsed [`Header`], where its
//! voxels are, and turning header + byte stream into a [`Volume`] with every claimed size checked against the
//! bytes actually available before anything is allocated.

use super::decode::{self, DecodeError, Endian, Progress};
/// Readers quote header text in their messages as the model's own errors do.
pub(crate) use crate::volume::clip;
use crate::volume::{check_dims, check_spacing, Geometry, Scaling, Volume, VolumeError, VoxelData, VoxelType};
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// Text headers must end within this many bytes: no real header is near it, and it bounds what a hostile file can
/// make us read before the data starts.
pub(crate) const HEADER_LIMIT: usize = 1 << 20;

/// Deflate's worst-case expansion is a little over 1032:1 (258-byte matches coded in ~2 bits); a stream claiming
/// more than this of its compressed size is lying, and is refused before the output is allocated.
const MAX_DEFLATE_RATIO: u64 = 1032;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    Raw,
    Gzip,
    Zlib,
    Ascii,
}

impl Encoding {
    fn name(self) -> &'static str {
        match self {
            Encoding::Raw => "raw",
            Encoding::Gzip => "gzip",
            Encoding::Zlib => "zlib",
            Encoding::Ascii => "ASCII",
        }
    }
}

/// Where the voxels start.
#[derive(Clone, Debug, PartialEq)]
pub enum DataLocation {
    /// In the header's own file, at this byte offset (`None`: the last bytes of the file, NRRD `byte skip: -1`).
    Inline(Option<u64>),
    /// In a file named relative to the header's folder, after `skip` bytes (`None`: the last bytes).
    Detached { name: String, skip: Option<u64> },
}

/// A parsed header. Dims are checked by [`check_dims`] when loading, not when parsing, so the header fuzz
/// targets see every claim.
#[derive(Clone, Debug)]
pub struct Header {
    pub format: &'static str,
    pub dims: [u32; 3],
    pub voxel_type: VoxelType,
    pub endian: Endian,
    pub encoding: Encoding,
    pub spacing: [f64; 3],
    pub origin: Option<[f64; 3]>,
    /// The file's full placement when it has one (orientation, RAS+); otherwise the volume lies along the world's
    /// axes with `spacing`, voxel (0, 0, 0) at `origin`.
    pub geometry: Option<Geometry>,
    pub scaling: Scaling,
    pub location: DataLocation,
    pub notes: Vec<String>,
    /// The file's point-data arrays, for `volcast info` (VTK).
    pub arrays: Vec<crate::volume::ArrayInfo>,
    /// Time steps stored one after another (the slowest, fourth axis of a 4-D file); 1 for a 3-D volume.
    pub timesteps: u32,
    /// Volumes along a fifth axis (NIfTI `dim[5]`: channels) and the one read; 1 and 0 for other files.
    pub channels: u32,
    pub channel: u32,
    /// The steps are stored interleaved, step fastest (a NRRD whose first axis is a list, as a Slicer segmentation
    /// with overlapping segments stores its layers).
    pub interleaved: bool,
}

impl Header {
    pub fn new(format: &'static str) -> Header {
        Header {
            format,
            dims: [1; 3],
            voxel_type: VoxelType::U8,
            endian: Endian::Little,
            encoding: Encoding::Raw,
            spacing: [1.0; 3],
            origin: None,
            geometry: None,
            scaling: Scaling::IDENTITY,
            location: DataLocation::Inline(Some(0)),
            notes: Vec::new(),
            arrays: Vec::new(),
            timesteps: 1,
            channels: 1,
            channel: 0,
            interleaved: false,
        }
    }

    /// Voxel count and byte count of every time step together, checked against the limits (each step's, and
    /// the memory a series needs).
    fn sizes(&self, file: &str) -> Result<(usize, u64), VolumeError> {
        let step = check_dims(self.dims)?;
        check_spacing(self.dims, self.spacing.map(|s| s.abs() as f32))?;
        let steps = u64::from(self.timesteps.max(1));
        // check_dims bounds a step by 2^31 voxels and the fourth axis is at most MAX_DIM, so nothing overflows.
        crate::volume::time::check_series_memory(file, self.timesteps, step * self.voxel_type.size() as u64)?;
        let count = step * steps;
        let bytes = count * self.voxel_type.size() as u64;
        let count = usize::try_from(count).map_err(|_| VolumeError::TooLarge {
            dims: self.dims,
            voxel_type: self.voxel_type,
            bytes,
        })?;
        Ok((count, bytes))
    }

    /// The placement: the file's own geometry, or its spacing along the world's axes from its origin.
    pub fn placement(&self) -> Geometry {
        self.geometry.unwrap_or_else(|| {
            let mut g = Geometry::from_spacing(self.spacing);
            let [x, y, z] = self.origin.unwrap_or([0.0; 3]);
            g.affine.w_axis = glam::DVec4::new(x, y, z, 1.0);
            g
        })
    }

    /// The finished volume: spacing as f32 (a zero one is refused by [`Volume::new`]), placement, scaling, notes.
    pub fn into_volume(self, name: String, data: VoxelData) -> Result<Volume, VolumeError> {
        let spacing = self.spacing.map(|s| s.abs() as f32);
        let geometry = self.placement();
        let mut steps = if self.interleaved {
            data.deinterleave(self.timesteps.max(1) as usize)
        } else {
            data.split_steps(self.timesteps.max(1) as usize)
        }
        .into_iter();
        let first = steps.next().expect("at least one step");
        let mut v = Volume::new(name, self.dims, spacing, self.voxel_type, first)?
            .with_time_steps(steps.collect())?
            .with_scaling(self.scaling)?
            .with_geometry(geometry)?;
        v.format = self.format.to_string();
        v.notes = self.notes;
        v.arrays = self.arrays;
        v.channels = crate::volume::ChannelInfo::numbered(self.channels as usize, self.channel as usize);
        Ok(v)
    }
}

/// Parses a header field's number, naming the field on failure.
pub(crate) fn number<T: std::str::FromStr>(file: &str, field: &str, text: &str) -> Result<T, VolumeError> {
    text.trim().parse::<T>().map_err(|_| VolumeError::Header {
        file: file.to_string(),
        problem: format!("{field} '{}' is not a valid number", clip(text)),
    })
}

/// Parses `n` whitespace-separated numbers.
pub(crate) fn numbers<T: std::str::FromStr>(
    file: &str,
    field: &str,
    text: &str,
    n: usize,
) -> Result<Vec<T>, VolumeError> {
    let parts: Vec<&str> = text.split_whitespace().collect();
    if parts.len() != n {
        return Err(header_error(
            file,
            format!("{field} needs {n} values, found {} ('{}')", parts.len(), clip(text)),
        ));
    }
    parts.iter().map(|p| number(file, field, p)).collect()
}

/// Dimensions from signed numbers as written, refusing zero and negative ones with the header's own values.
pub(crate) fn dims_from(file: &str, field: &str, values: &[i64]) -> Result<[u32; 3], VolumeError> {
    let mut dims = [1u32; 3];
    for (i, &v) in values.iter().enumerate() {
        if v <= 0 {
            return Err(header_error(
                file,
                format!("{field} {values:?} has a zero or negative size; every size must be at least 1"),
            ));
        }
        let v = u32::try_from(v).map_err(|_| VolumeError::Header {
            file: file.to_string(),
            problem: format!(
                "{field} {values:?} is far beyond the limit of {} per axis",
                crate::volume::MAX_DIM
            ),
        })?;
        if i < 3 {
            dims[i] = v;
        }
        if i == 3 && v > crate::volume::MAX_DIM {
            return Err(header_error(
                file,
                format!(
                    "{field} {values:?} has {v} time steps, more than the limit of {}",
                    crate::volume::MAX_DIM
                ),
            ));
        }
    }
    Ok(dims)
}

pub(crate) fn header_error(file: &str, problem: String) -> VolumeError {
    VolumeError::Header {
        file: file.to_string(),
        problem,
    }
}

/// `e`, made to say which file it is about where it does not already (the dimension and spacing checks).
pub(crate) fn named(file: &str, e: VolumeError) -> VolumeError {
    if e.to_string().contains(file) {
        e
    } else {
        header_error(file, e.to_string())
    }
}

/// The error for a chosen VTK point array that holds more than one value per voxel.
pub(crate) fn not_one_component(file: &str, name: &str, components: u32) -> VolumeError {
    header_error(
        file,
        format!(
            "point array '{}' has {components} components: volcast reads one value per voxel (choose another with \
             --array)",
            clip(name)
        ),
    )
}

/// Spacing must be positive: the absolute value is used (a negative one flips the axis in the file's physical
/// space, which volcast does not apply) and zero or non-finite is refused later by [`Volume::new`].
pub(crate) fn signed_spacing(header: &mut Header, spacing: [f64; 3]) {
    if spacing.iter().any(|&s| s < 0.0) {
        header
            .notes
            .push("negative spacing: the axis runs the other way in space (the volume is mirrored)".into());
    }
    header.spacing = spacing;
}

/// The name of `path` for messages.
pub(crate) fn file_label(path: &Path) -> String {
    path.file_name()
        .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// The volume's name: the file name without its extensions.
pub(crate) fn volume_name(path: &Path) -> String {
    let label = file_label(path);
    label
        .split('.')
        .next()
        .filter(|s| !s.is_empty())
        .unwrap_or(&label)
        .to_string()
}

/// Resolves a detached data file named in a header as the NRRD and MetaImage specifications, ITK and pynrrd do: an
/// absolute path as it is, a relative one from the header's folder, symbolic links followed. It must exist and be a
/// regular file (not a device or a pipe, which could be endless); the error names the path tried.
pub(crate) fn resolve_data_file(header_path: &Path, name: &str) -> Result<PathBuf, VolumeError> {
    let file = file_label(header_path);
    let folder = header_path.parent().unwrap_or(Path::new(""));
    let tried = if Path::new(name).is_absolute() {
        PathBuf::from(name)
    } else {
        folder.join(name)
    };
    let missing = |source| VolumeError::DataFile {
        file: file.clone(),
        data_file: clip(name),
        tried: std::path::absolute(&tried).unwrap_or_else(|_| tried.clone()),
        source,
    };
    if name.is_empty() {
        return Err(missing(std::io::ErrorKind::NotFound.into()));
    }
    // Follows links: a link to a regular file is read; a link to a device, a folder or nothing is refused.
    let meta = std::fs::metadata(&tried).map_err(missing)?;
    if !meta.is_file() {
        return Err(VolumeError::NotAFile { path: tried });
    }
    Ok(tried)
}

/// Where the voxel bytes come from.
pub(crate) enum Source<'a> {
    Bytes(&'a [u8]),
    File(&'a Path),
}

/// Loads the voxels a parsed header describes from `source` (the header's own bytes or file).
pub(crate) fn load(
    header: Header,
    name: String,
    file: &str,
    source: Source,
    progress: &mut Progress,
) -> Result<Volume, VolumeError> {
    let (count, needed) = header.sizes(file)?;
    let data = match (&header.location, source) {
        (DataLocation::Inline(offset), Source::Bytes(bytes)) => {
            let len = bytes.len() as u64;
            let start = data_start(&header, file, *offset, len, needed)?;
            let mut rest = &bytes[start as usize..];
            decode_stream(&header, file, &mut rest, None, len - start, count, needed, progress)?
        }
        (DataLocation::Detached { .. }, Source::Bytes(_)) => {
            return Err(header_error(
                file,
                "the voxels are in a separate data file, which cannot be read from memory".into(),
            ))
        }
        (DataLocation::Inline(offset), Source::File(path)) => {
            read_file_data(&header, file, path, *offset, count, needed, progress)?
        }
        (DataLocation::Detached { name: data_name, skip }, Source::File(path)) => {
            let data_path = resolve_data_file(path, data_name)?;
            read_file_data(&header, file, &data_path, *skip, count, needed, progress)?
        }
    };
    header.into_volume(name, data)
}

/// Offset of the data, `None` meaning the last `needed` bytes (raw encoding only).
fn data_start(header: &Header, file: &str, offset: Option<u64>, len: u64, needed: u64) -> Result<u64, VolumeError> {
    let truncated = |actual| VolumeError::Truncated {
        file: file.to_string(),
        actual,
        expected: needed,
        dims: header.dims,
        voxel_type: header.voxel_type,
    };
    match offset {
        Some(o) if o <= len => Ok(o),
        Some(_) => Err(truncated(0)),
        None if header.encoding != Encoding::Raw => Err(header_error(
            file,
            "a data offset of -1 (data at the end of the file) only works with raw encoding".into(),
        )),
        None => len.checked_sub(needed).ok_or_else(|| truncated(len)),
    }
}

fn read_file_data(
    header: &Header,
    file: &str,
    path: &Path,
    offset: Option<u64>,
    count: usize,
    needed: u64,
    progress: &mut Progress,
) -> Result<VoxelData, VolumeError> {
    let io = |source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let metadata = std::fs::metadata(path).map_err(io)?;
    if !metadata.is_file() {
        return Err(VolumeError::NotAFile {
            path: path.to_path_buf(),
        });
    }
    let len = metadata.len();
    let start = data_start(header, file, offset, len, needed)?;
    let f = File::open(path).map_err(io)?;
    // `&File` reads and seeks the file itself, so the raw case can also read it in parallel at `start`.
    let mut reader = &f;
    reader.seek(SeekFrom::Start(start)).map_err(io)?;
    decode_stream(
        header,
        file,
        &mut reader,
        Some((&f, start)),
        len - start,
        count,
        needed,
        progress,
    )
}

/// Refuses a compressed stream of `available` bytes that claims to inflate to more than deflate can produce.
pub(crate) fn check_compressed(header: &Header, file: &str, available: u64, needed: u64) -> Result<(), VolumeError> {
    if needed > available.saturating_mul(MAX_DEFLATE_RATIO).saturating_add(1024) {
        return Err(VolumeError::CompressionRatio {
            file: file.to_string(),
            what: header.encoding.name(),
            compressed: available,
            expected: needed,
            dims: header.dims,
            voxel_type: header.voxel_type,
        });
    }
    Ok(())
}

/// Decodes `count` voxels from `reader`, which holds `available` bytes, checking the claim first. Raw data that is
/// `file_at` (the file and the data's offset) is read in parallel where its layout allows
/// (`decode::read_file_at`).
#[allow(clippy::too_many_arguments)] // The header's claim, the two ways to the bytes and the progress.
pub(crate) fn decode_stream(
    header: &Header,
    file: &str,
    reader: &mut dyn Read,
    file_at: Option<(&File, u64)>,
    available: u64,
    count: usize,
    needed: u64,
    progress: &mut Progress,
) -> Result<VoxelData, VolumeError> {
    let truncated = |actual| VolumeError::Truncated {
        file: file.to_string(),
        actual,
        expected: needed,
        dims: header.dims,
        voxel_type: header.voxel_type,
    };
    let (t, e) = (header.voxel_type, header.endian);
    let chunk = decode::CHUNK_BYTES;
    let result = match header.encoding {
        Encoding::Raw => {
            if available < needed {
                return Err(truncated(available));
            }
            match file_at {
                Some((f, at)) => decode::read_file_at(f, at, t, e, count, progress),
                None => decode::read_binary(reader, t, e, count, chunk, progress),
            }
        }
        Encoding::Gzip | Encoding::Zlib => {
            check_compressed(header, file, available, needed)?;
            let mut inflated: Box<dyn Read> = if header.encoding == Encoding::Gzip {
                Box::new(flate2::read::MultiGzDecoder::new(BufReader::new(reader)))
            } else {
                Box::new(flate2::read::ZlibDecoder::new(BufReader::new(reader)))
            };
            decode::read_binary(&mut inflated, t, e, count, chunk, progress)
        }
        Encoding::Ascii => {
            // Each value takes at least one character and one separator.
            if count as u64 > available / 2 + 1 {
                return Err(header_error(
                    file,
                    format!("{available} bytes of ASCII data cannot hold {count} values"),
                ));
            }
            decode::read_ascii(&mut BufReader::new(reader), t, count, progress)
        }
    };
    result.map_err(|e| match e {
        DecodeError::Truncated { got } if header.encoding == Encoding::Ascii => header_error(
            file,
            format!("the ASCII data end after {got} of {count} values (truncated file?)"),
        ),
        DecodeError::Truncated { got } => truncated(got),
        DecodeError::OutOfMemory => VolumeError::OutOfMemory {
            dims: header.dims,
            bytes: needed,
        },
        DecodeError::BadValue { index, token } => header_error(
            file,
            format!("ASCII value {index} ('{token}') is not a valid {}", header.voxel_type),
        ),
        DecodeError::Io(source) if header.encoding == Encoding::Gzip || header.encoding == Encoding::Zlib => {
            VolumeError::Corrupt {
                file: file.to_string(),
                what: header.encoding.name(),
                source,
            }
        }
        DecodeError::Io(source) => header_error(file, format!("reading the voxel data failed: {source}")),
    })
}

/// The first bytes of a file (at most `limit`), where a text header lives.
pub(crate) fn read_prefix(path: &Path, limit: usize) -> Result<Vec<u8>, VolumeError> {
    let io = |source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let metadata = std::fs::metadata(path).map_err(io)?;
    if !metadata.is_file() {
        return Err(VolumeError::NotAFile {
            path: path.to_path_buf(),
        });
    }
    let mut prefix = Vec::new();
    File::open(path)
        .map_err(io)?
        .take(limit as u64)
        .read_to_end(&mut prefix)
        .map_err(io)?;
    Ok(prefix)
}

/// Splits a text header into lines: returns the lines and, for each, the byte offset just after it.
/// Stops after `stop` returns true for a line (the line that ends the header) or at `HEADER_LIMIT`.
pub(crate) fn header_lines(bytes: &[u8], mut stop: impl FnMut(&str) -> bool) -> (Vec<(&str, usize)>, bool) {
    let mut lines = Vec::new();
    let mut pos = 0;
    let end = bytes.len().min(HEADER_LIMIT);
    while pos < end {
        let rest = &bytes[pos..end];
        let (line, next) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], pos + i + 1),
            None => (rest, end),
        };
        let line = std::str::from_utf8(line).unwrap_or("\u{fffd}");
        let line = line.strip_suffix('\r').unwrap_or(line);
        lines.push((line, next));
        pos = next;
        if stop(line) {
            return (lines, true);
        }
    }
    (lines, false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_files_are_found_as_itk_finds_them() {
        let dir = std::env::temp_dir().join(format!("volcast-resolve-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("data.raw"), b"x").unwrap();
        std::fs::write(dir.join("sub/data.raw"), b"x").unwrap();
        let header = dir.join("sub/h.nhdr");
        // Relative from the header's folder, `..` included; absolute as given.
        assert_eq!(
            resolve_data_file(&header, "data.raw").unwrap(),
            dir.join("sub/data.raw")
        );
        assert_eq!(
            resolve_data_file(&header, "../data.raw").unwrap(),
            dir.join("sub/../data.raw")
        );
        let absolute = dir.join("data.raw");
        assert_eq!(
            resolve_data_file(&header, absolute.to_str().unwrap()).unwrap(),
            absolute
        );
        // Missing: the message names the path tried, absolute.
        let e = resolve_data_file(&header, "nothere.raw").unwrap_err().to_string();
        assert!(e.contains(&format!("{}", dir.join("sub/nothere.raw").display())), "{e}");
        assert!(resolve_data_file(&header, "").is_err());
        // Not a regular file: a folder, or a device reached through a link.
        assert!(matches!(
            resolve_data_file(&header, "..").unwrap_err(),
            VolumeError::NotAFile { .. }
        ));
        #[cfg(unix)]
        {
            let _ = std::fs::remove_file(dir.join("sub/link.raw"));
            std::os::unix::fs::symlink("../data.raw", dir.join("sub/link.raw")).unwrap();
            assert!(resolve_data_file(&header, "link.raw").is_ok());
            let _ = std::fs::remove_file(dir.join("sub/zero.raw"));
            std::os::unix::fs::symlink("/dev/zero", dir.join("sub/zero.raw")).unwrap();
            let e = resolve_data_file(&header, "zero.raw").unwrap_err();
            assert!(matches!(e, VolumeError::NotAFile { .. }), "{e}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn names() {
        assert_eq!(volume_name(Path::new("/a/b/ch2.nii.gz")), "ch2");
        assert_eq!(volume_name(Path::new(".hidden")), ".hidden");
        assert_eq!(clip(&"x".repeat(50)), "x".repeat(40) + "...");
    }
}
