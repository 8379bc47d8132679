//! Everything that can go wrong making a volume, with messages that name the problem, the numbers and what to do.

use super::{VoxelType, BUILTIN_NAMES, MAX_DIM, MAX_VOXELS};
use std::fmt;
use std::path::PathBuf;

struct Dims([u32; 3]);

impl fmt::Display for Dims {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}x{}", self.0[0], self.0[1], self.0[2])
    }
}

fn type_list() -> &'static str {
    "uint8, int8, uint16, int16, uint32, int32, float32, float64"
}

/// Everything that can go wrong making a volume. Each message names the problem, the numbers, and what to do.
#[derive(Debug, thiserror::Error)]
pub enum VolumeError {
    #[error("dimensions {} contain a zero; every dimension must be at least 1", Dims(*dims))]
    ZeroDimension { dims: [u32; 3] },
    #[error("dimensions {} exceed the limit of {MAX_DIM} per axis", Dims(*dims))]
    DimensionTooLarge { dims: [u32; 3] },
    #[error("dimensions {} make {count} voxels, more than the limit of {MAX_VOXELS} (2^36)", Dims(*dims))]
    TooManyVoxels { dims: [u32; 3], count: u64 },
    #[error(
        "voxel spacing {} {} {} is invalid: each must be positive and finite (and dims × spacing finite)",
        spacing[0], spacing[1], spacing[2]
    )]
    BadSpacing { spacing: [f32; 3] },
    #[error("the voxel-to-world affine {rows:?} is not finite or not invertible (its axes are parallel or zero)")]
    BadAffine { rows: Box<[[f64; 4]; 4]> },
    #[error("unknown voxel type '{given}': use one of {}", type_list())]
    UnknownType { given: String },
    #[error(
        "unknown voxel type '{given}' in file name {file}: use one of {}, or pass --type T",
        type_list()
    )]
    UnknownTypeInName { file: String, given: String },
    #[error("voxel data for {} has {actual} values but needs {expected}", Dims(*dims))]
    DataLength {
        dims: [u32; 3],
        expected: u64,
        actual: usize,
    },
    #[error("voxel data of kind {data} cannot hold source type {source_type}")]
    TypeMismatch { source_type: VoxelType, data: &'static str },
    #[error("cannot tell the {} of {file}: {}", missing.what(), missing.remedy())]
    MissingLayout { file: String, missing: MissingLayout },
    #[error("cannot read {}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{} is not a regular file", path.display())]
    NotAFile { path: PathBuf },
    #[error("file {file} is {actual} bytes but {} {voxel_type} needs {expected}", Dims(*dims))]
    SizeMismatch {
        file: String,
        actual: u64,
        dims: [u32; 3],
        voxel_type: VoxelType,
        expected: u64,
    },
    #[error("{} {voxel_type} does not fit in memory addressing ({bytes} bytes)", Dims(*dims))]
    TooLarge {
        dims: [u32; 3],
        voxel_type: VoxelType,
        bytes: u64,
    },
    #[error("cannot allocate {bytes} bytes for the voxels of {}", Dims(*dims))]
    OutOfMemory { dims: [u32; 3], bytes: u64 },
    #[error("unknown built-in volume '{given}': choose one of {}", BUILTIN_NAMES.join(", "))]
    UnknownBuiltin { given: String },
    #[error("built-in volume size {size} is out of range: use 2 to 1024")]
    BuiltinSize { size: u32 },
    #[error("rescale slope {slope} / intercept {intercept} is invalid: the slope must be finite and non-zero")]
    BadScaling { slope: f64, intercept: f64 },
    #[error("{file}: {problem}")]
    Header { file: String, problem: String },
    #[error("{file}: unsupported {format} voxel type '{given}': volcast reads {}", type_list())]
    UnsupportedType {
        file: String,
        format: &'static str,
        given: String,
    },
    #[error("{file}: the voxel data end after {actual} of the {expected} bytes that {} {voxel_type} needs (truncated file?)", Dims(*dims))]
    Truncated {
        file: String,
        actual: u64,
        expected: u64,
        dims: [u32; 3],
        voxel_type: VoxelType,
    },
    #[error("{file}: the {what} data is corrupt: {source}")]
    Corrupt {
        file: String,
        what: &'static str,
        source: std::io::Error,
    },
    #[error(
        "{file}: {compressed} bytes of {what} data cannot hold the {expected} bytes that {} {voxel_type} needs \
         (deflate expands at most ~1032:1); the header's sizes are wrong or the file is truncated",
        Dims(*dims)
    )]
    CompressionRatio {
        file: String,
        what: &'static str,
        compressed: u64,
        expected: u64,
        dims: [u32; 3],
        voxel_type: VoxelType,
    },
    #[error("{file}: its data file '{data_file}' cannot be read at {}: {source}", tried.display())]
    DataFile {
        file: String,
        data_file: String,
        tried: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "{} exceeds the maximum dimension {max_dim} and downsampling is off (--no-downsample); \
         raise --max-dim or allow downsampling",
        Dims(*dims)
    )]
    DownsampleRefused { dims: [u32; 3], max_dim: u32 },
    #[error(
        "{file} is {kind}; volcast cannot read {what}. It reads raw, VTK legacy, VTK XML ImageData (.vti), NRRD, \
         NIfTI-1, MetaImage, DICOM and TIFF (convert the file to one of these, or give --dims and --type to read it \
         as raw)"
    )]
    Unsupported { file: String, kind: String, what: String },
    #[error("{file}: no series '{given}' in the folder; pass --series with a number or UID of one it holds:\n{list}")]
    UnknownSeries { file: String, given: String, list: String },
}

/// At most 40 characters of user text in a message.
pub(crate) fn clip(text: &str) -> String {
    let t = text.trim();
    if t.chars().count() > 40 {
        t.chars().take(40).collect::<String>() + "..."
    } else {
        t.to_string()
    }
}

/// What a raw file's layout lacks after `--dims`, `--type` and its name are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MissingLayout {
    Both,
    Dims,
    VoxelType,
}

impl MissingLayout {
    fn what(self) -> &'static str {
        match self {
            MissingLayout::Both => "dimensions and voxel type",
            MissingLayout::Dims => "dimensions",
            MissingLayout::VoxelType => "voxel type",
        }
    }

    /// Names only what is missing: a user who gave `--dims` is told that `--type` is missing, not asked again.
    fn remedy(self) -> String {
        match self {
            MissingLayout::Both => "pass --dims W H D --type T or name the file NAME_WxHxD_TYPE.raw".into(),
            MissingLayout::Dims => "--type is given but --dims is missing; pass --dims W H D".into(),
            MissingLayout::VoxelType => {
                format!(
                    "--dims is given but --type is missing; pass --type T, one of {}",
                    type_list()
                )
            }
        }
    }
}
