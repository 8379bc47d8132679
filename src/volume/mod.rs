//! Volumes on the CPU: voxel types, the `Volume` the renderer uploads, and where volumes come from
//! (files through [`open`], generated test volumes in [`builtin`]). Pure code, no Vulkan.
//!
//! Layout everywhere: x fastest, then y, then z; voxel (x, y, z) is at `x + W·(y + H·z)`.
//!
//! Source types and what reaches the GPU: uint8 -> U8; int8 -> U8 biased by +128; uint16 -> U16; int16 -> U16
//! biased by +32768; uint32, int32, float32 and float64 -> F32. 32-bit integers become f32 because no 16-bit
//! texture holds them and imaging data rarely exceeds 2^24 (beyond that, values round to f32's 24-bit mantissa).
//! A linear rescale from the file (NIfTI `scl_slope`/`scl_inter`, DICOM rescale slope/intercept) is *not*
//! applied to the stored voxels: it is kept in [`Volume::scaling`] and folded into [`Volume::value`],
//! [`Volume::range`] and [`Volume::gpu_scale_bias`], so a 12-bit CT with an intercept of -1024 still takes two
//! bytes per voxel on the GPU and no precision is lost.

mod builtin;
mod decode;
mod dicom;
mod dicom_codec;
mod dicom_geometry;
mod downsample;
mod format;
pub mod geometry;
mod metaimage;
mod nifti;
mod nrrd;
mod open;
mod raw;
mod tiff_stack;
mod time;
mod unsupported;
mod vti;
mod vti_data;
mod vtk;
mod vtk_scan;

pub use builtin::{builtin, BUILTIN_NAMES};
pub use decode::Endian;
pub use downsample::downsample_to;
pub use open::{detect_format, open, open_with_progress, Format, OpenOptions};
pub use raw::{load_raw, parse_scivis_name, RawOptions};
pub use time::TimeSteps;

/// Parsers that read from memory and never touch the file system: the fuzz targets drive these.
pub mod from_bytes {
    pub use super::dicom::from_bytes as dicom;
    pub use super::format::{DataLocation, Encoding, Header};
    pub use super::metaimage::{from_bytes as metaimage, parse_header as metaimage_header};
    pub use super::nifti::{from_bytes as nifti, parse_header as nifti_header};
    pub use super::nrrd::{from_bytes as nrrd, parse_header as nrrd_header};
    pub use super::tiff_stack::from_bytes as tiff;
    pub use super::vti::from_bytes as vti;
    pub use super::vtk::{from_bytes as vtk, parse_header as vtk_header};
}

pub use geometry::Geometry;

use rayon::prelude::*;
use std::fmt;
use std::path::PathBuf;

/// Largest dimension accepted at load; the device's own limit is checked later at upload.
pub const MAX_DIM: u32 = 16384;

/// Most voxels accepted at load (2^31): beyond this, byte offsets of 4-byte voxels stop fitting the 32-bit
/// sizes that drivers and `image` handling commonly assume, and the volume no longer fits typical GPU memory.
pub const MAX_VOXELS: u64 = 1 << 31;

/// Voxel type of the *source* (file or generator). See [`VoxelData`] for what reaches the GPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VoxelType {
    U8,
    U16,
    I16,
    F32,
    F64,
    I8,
    U32,
    I32,
}

impl VoxelType {
    pub const ALL: [VoxelType; 8] = [
        VoxelType::U8,
        VoxelType::U16,
        VoxelType::I16,
        VoxelType::F32,
        VoxelType::F64,
        VoxelType::I8,
        VoxelType::U32,
        VoxelType::I32,
    ];

    /// Bytes per voxel in the file.
    pub fn size(self) -> usize {
        match self {
            VoxelType::U8 | VoxelType::I8 => 1,
            VoxelType::U16 | VoxelType::I16 => 2,
            VoxelType::F32 | VoxelType::U32 | VoxelType::I32 => 4,
            VoxelType::F64 => 8,
        }
    }

    /// The open-scivis spelling, as used in file names.
    pub fn name(self) -> &'static str {
        match self {
            VoxelType::U8 => "uint8",
            VoxelType::U16 => "uint16",
            VoxelType::I16 => "int16",
            VoxelType::F32 => "float32",
            VoxelType::F64 => "float64",
            VoxelType::I8 => "int8",
            VoxelType::U32 => "uint32",
            VoxelType::I32 => "int32",
        }
    }

    /// Case-insensitive; accepts the open-scivis names and the usual C/numpy aliases.
    pub fn parse(s: &str) -> Option<VoxelType> {
        match s.trim().to_ascii_lowercase().as_str() {
            "uint8" | "u8" | "uchar" | "unsigned_char" => Some(VoxelType::U8),
            "uint16" | "u16" | "ushort" => Some(VoxelType::U16),
            "int16" | "i16" | "short" => Some(VoxelType::I16),
            "float32" | "f32" | "float" => Some(VoxelType::F32),
            "float64" | "f64" | "double" => Some(VoxelType::F64),
            "int8" | "i8" | "char" | "signed_char" => Some(VoxelType::I8),
            "uint32" | "u32" | "uint" | "unsigned_int" => Some(VoxelType::U32),
            "int32" | "i32" | "int" => Some(VoxelType::I32),
            _ => None,
        }
    }
}

impl fmt::Display for VoxelType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for VoxelType {
    type Err = VolumeError;

    fn from_str(s: &str) -> Result<VoxelType, VolumeError> {
        VoxelType::parse(s).ok_or_else(|| VolumeError::UnknownType { given: s.to_string() })
    }
}

/// Voxel values as they go to the GPU: uint8 -> U8 (R8_UNORM), int8 -> U8 with +128 bias, uint16 -> U16
/// (R16_UNORM), int16 -> U16 with +32768 bias (R16_UNORM keeps all 16 bits), float32 -> F32; float64, uint32
/// and int32 -> F32 (converted).
#[derive(Clone, PartialEq)]
pub enum VoxelData {
    U8(Vec<u8>),
    U16(Vec<u16>),
    F32(Vec<f32>),
}

impl VoxelData {
    pub fn len(&self) -> usize {
        match self {
            VoxelData::U8(v) => v.len(),
            VoxelData::U16(v) => v.len(),
            VoxelData::F32(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn kind(&self) -> &'static str {
        match self {
            VoxelData::U8(_) => "U8",
            VoxelData::U16(_) => "U16",
            VoxelData::F32(_) => "F32",
        }
    }

    /// The representation `source_type` must be stored in.
    fn matches(&self, source_type: VoxelType) -> bool {
        matches!(
            (self, source_type),
            (VoxelData::U8(_), VoxelType::U8 | VoxelType::I8)
                | (VoxelData::U16(_), VoxelType::U16 | VoxelType::I16)
                | (
                    VoxelData::F32(_),
                    VoxelType::F32 | VoxelType::F64 | VoxelType::U32 | VoxelType::I32
                )
        )
    }
}

// Volumes run to gigabytes; a derived Debug would print every voxel.
impl fmt::Debug for VoxelData {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "VoxelData::{}(len {})", self.kind(), self.len())
    }
}

/// Offset that maps int16 onto u16 order-preservingly, so R16_UNORM keeps every bit.
const INT16_BIAS: f64 = 32768.0;
/// The same for int8 onto u8.
const INT8_BIAS: f64 = 128.0;

/// Offset between a stored (biased) integer and the source value.
fn stored_offset(source_type: VoxelType) -> f64 {
    match source_type {
        VoxelType::I16 => INT16_BIAS,
        VoxelType::I8 => INT8_BIAS,
        _ => 0.0,
    }
}

/// Physical value = slope × source value + intercept (NIfTI `scl_slope`/`scl_inter`, DICOM rescale).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scaling {
    pub slope: f64,
    pub intercept: f64,
}

impl Scaling {
    pub const IDENTITY: Scaling = Scaling {
        slope: 1.0,
        intercept: 0.0,
    };

    pub fn is_identity(&self) -> bool {
        *self == Scaling::IDENTITY
    }

    fn apply(&self, v: f64) -> f64 {
        if self.is_identity() {
            v
        } else {
            v * self.slope + self.intercept
        }
    }
}

/// A volume ready for upload.
#[derive(Clone, Debug)]
pub struct Volume {
    pub name: String,
    /// x fastest, then y, then z.
    pub dims: [u32; 3],
    /// Where the voxels are: the voxel-to-world affine (RAS+ millimetres for anatomical files) and whether the
    /// file said which way the patient lies. Set through [`Volume::with_geometry`] and [`Volume::with_spacing`].
    pub geometry: Geometry,
    pub source_type: VoxelType,
    pub data: VoxelData,
    /// min/max of the values after [`Volume::scaling`] (as the GPU sees them, i.e. after float64->f32),
    /// NaN/Inf ignored. `[0, 0]` if no voxel is finite.
    pub range: [f64; 2],
    /// min/max of the source values before scaling.
    pub stored_range: [f64; 2],
    /// Applied to every source value by [`Volume::value`]; identity unless the file asked for a rescale.
    pub scaling: Scaling,
    /// Where the volume came from: "raw", "VTK legacy", "NRRD", "NIfTI-1", "MetaImage", "DICOM", "TIFF", "built-in".
    pub format: String,
    /// The acquisition's modality as the file names it ("CT", "MR", ... from DICOM's Modality), if it does.
    pub modality: Option<String>,
    /// Things the user should know that are not errors: orientation ignored, 4-D reduced, downsampled, ...
    pub notes: Vec<String>,
    /// Every point-data array the file holds (VTK files can hold several); empty for single-array formats.
    pub arrays: Vec<ArrayInfo>,
    /// A time series' other steps ([`Volume::timesteps`], [`Volume::show_step`]); `data` is the step shown.
    pub time: TimeSteps,
}

/// One data array of a multi-array file, as `volcast info` lists it.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ArrayInfo {
    pub name: String,
    /// The type as the file names it (`unsigned_char`, `Float32`, ...).
    #[serde(rename = "type")]
    pub type_name: String,
    pub components: u32,
    /// This is the array the volume holds.
    pub loaded: bool,
}

impl Volume {
    /// Validates data length == product of dims, dims within [`MAX_DIM`] and [`MAX_VOXELS`], spacing positive and
    /// finite, `data` in the representation `source_type` maps to; computes `range`.
    pub fn new(
        name: impl Into<String>,
        dims: [u32; 3],
        spacing: [f32; 3],
        source_type: VoxelType,
        data: VoxelData,
    ) -> Result<Volume, VolumeError> {
        let count = check_dims(dims)?;
        check_spacing(dims, spacing)?;
        if !data.matches(source_type) {
            return Err(VolumeError::TypeMismatch {
                source_type,
                data: data.kind(),
            });
        }
        if data.len() as u64 != count {
            return Err(VolumeError::DataLength {
                dims,
                expected: count,
                actual: data.len(),
            });
        }
        let range = compute_range(source_type, &data);
        Ok(Volume {
            name: name.into(),
            dims,
            geometry: Geometry::from_spacing(spacing.map(f64::from)),
            source_type,
            data,
            range,
            stored_range: range,
            scaling: Scaling::IDENTITY,
            format: "memory".into(),
            modality: None,
            notes: Vec::new(),
            arrays: Vec::new(),
            time: TimeSteps::default(),
        })
    }

    /// The voxel size along each index axis (the lengths of the affine's columns).
    pub fn spacing(&self) -> [f32; 3] {
        self.geometry.spacing().map(|s| s as f32)
    }

    /// Replaces the voxel size, keeping the directions and origin; refused (naming it) unless positive and finite.
    pub fn with_spacing(mut self, spacing: [f32; 3]) -> Result<Volume, VolumeError> {
        check_spacing(self.dims, spacing)?;
        self.geometry = self.geometry.with_spacing(spacing.map(f64::from));
        Ok(self)
    }

    /// Places the volume by `geometry`; refused if its voxel sizes are not positive and finite or its affine is
    /// singular or not finite.
    pub fn with_geometry(mut self, geometry: Geometry) -> Result<Volume, VolumeError> {
        let spacing = geometry.spacing().map(|s| s as f32);
        check_spacing(self.dims, spacing)?;
        let finite = geometry.affine.to_cols_array().iter().all(|v| v.is_finite());
        if !finite || geometry.linear().determinant().abs() < 1e-12 {
            return Err(VolumeError::BadAffine {
                rows: Box::new(geometry.rows()),
            });
        }
        self.geometry = geometry;
        Ok(self)
    }

    /// Sets the rescale and the scaled range. A slope of 0 or a non-finite slope or intercept is refused.
    pub fn with_scaling(mut self, scaling: Scaling) -> Result<Volume, VolumeError> {
        if !(scaling.slope.is_finite() && scaling.slope != 0.0 && scaling.intercept.is_finite()) {
            return Err(VolumeError::BadScaling {
                slope: scaling.slope,
                intercept: scaling.intercept,
            });
        }
        self.scaling = scaling;
        let [a, b] = self.stored_range.map(|v| scaling.apply(v));
        self.range = [a.min(b), a.max(b)];
        Ok(self)
    }

    /// Bytes the voxels take on the GPU.
    pub fn gpu_memory_bytes(&self) -> u64 {
        self.voxel_count() as u64 * self.gpu_texel_size() as u64
    }

    pub fn voxel_count(&self) -> usize {
        self.data.len()
    }

    fn index(&self, x: u32, y: u32, z: u32) -> usize {
        let [w, h, d] = self.dims;
        assert!(x < w && y < h && z < d, "voxel ({x}, {y}, {z}) outside {w}x{h}x{d}");
        x as usize + w as usize * (y as usize + h as usize * z as usize)
    }

    /// Value after [`Volume::scaling`] (int16/int8 un-biased); float64 sources give the stored f32.
    /// Panics if (x, y, z) is outside `dims`, like slice indexing.
    pub fn value(&self, x: u32, y: u32, z: u32) -> f64 {
        self.scaling.apply(self.stored(x, y, z))
    }

    /// Value in source units before scaling (int16/int8 un-biased).
    pub fn stored(&self, x: u32, y: u32, z: u32) -> f64 {
        let i = self.index(x, y, z);
        stored_value(self.source_type, &self.data, i)
    }

    /// `(value - min) / (max - min)`; 0.0 if max == min; NaN stays NaN (the renderer treats it as transparent).
    pub fn normalized(&self, x: u32, y: u32, z: u32) -> f64 {
        self.normalize_value(self.value(x, y, z))
    }

    /// A value (after scaling) normalised to the range, as [`Volume::normalized`].
    fn normalize_value(&self, v: f64) -> f64 {
        let [min, max] = self.range;
        if v.is_nan() {
            f64::NAN
        } else if max == min {
            0.0
        } else {
            (v - min) / (max - min)
        }
    }

    /// [`Volume::normalized`] of an element as `data` holds it (a biased integer, or the f32): affine in it, so
    /// the extremes of a block of elements map to the extremes of its normalised values (swapped for a negative
    /// slope).
    pub fn normalize_element(&self, element: f64) -> f64 {
        self.normalize_value(self.scaling.apply(element - stored_offset(self.source_type)))
    }

    /// Physical box, dims × spacing, scaled so the largest side is 1.
    pub fn extent(&self) -> glam::Vec3 {
        let spacing = self.geometry.spacing();
        let size = [0, 1, 2].map(|i| f64::from(self.dims[i]) * spacing[i]);
        let largest = size[0].max(size[1]).max(size[2]);
        // `new` guarantees positive, finite sides, so `largest` > 0.
        glam::Vec3::new(
            (size[0] / largest) as f32,
            (size[1] / largest) as f32,
            (size[2] / largest) as f32,
        )
    }

    /// The voxel data as bytes in native byte order (what a staging buffer copies).
    pub fn gpu_bytes(&self) -> &[u8] {
        match &self.data {
            VoxelData::U8(v) => v,
            VoxelData::U16(v) => bytemuck::cast_slice(v),
            VoxelData::F32(v) => bytemuck::cast_slice(v),
        }
    }

    /// Bytes per texel on the GPU: 1 (R8_UNORM), 2 (R16_UNORM) or 4 (R32_SFLOAT).
    pub fn gpu_texel_size(&self) -> usize {
        match &self.data {
            VoxelData::U8(_) => 1,
            VoxelData::U16(_) => 2,
            VoxelData::F32(_) => 4,
        }
    }

    /// The affine map from what a shader samples (UNORM -> stored/255 or stored/65535; float -> as stored) to the
    /// normalised value: `v = sampled * scale + bias`. Agrees with [`Volume::normalized`] in real arithmetic.
    /// `(0, 0)` if max == min.
    pub fn gpu_scale_bias(&self) -> (f32, f32) {
        let [min, max] = self.range;
        if max == min {
            return (0.0, 0.0);
        }
        // stored = sampled * unorm_max - offset, value = slope * stored + intercept,
        // then v = (value - min) / (max - min).
        let unorm_max = match self.data {
            VoxelData::U8(_) => 255.0,
            VoxelData::U16(_) => 65535.0,
            VoxelData::F32(_) => 1.0,
        };
        let offset = stored_offset(self.source_type);
        let Scaling { slope, intercept } = self.scaling;
        let span = max - min;
        (
            (slope * unorm_max / span) as f32,
            ((intercept - slope * offset - min) / span) as f32,
        )
    }
}

fn stored_value(source_type: VoxelType, data: &VoxelData, i: usize) -> f64 {
    match data {
        VoxelData::U8(v) => f64::from(v[i]) - stored_offset(source_type),
        VoxelData::U16(v) => f64::from(v[i]) - stored_offset(source_type),
        VoxelData::F32(v) => f64::from(v[i]),
    }
}

fn compute_range(source_type: VoxelType, data: &VoxelData) -> [f64; 2] {
    compute_range_of(source_type, data).unwrap_or([0.0, 0.0])
}

/// The data's min/max as source values (NaN/Inf ignored); `None` if no voxel is finite.
fn compute_range_of(source_type: VoxelType, data: &VoxelData) -> Option<[f64; 2]> {
    // In blocks on every core (a 1 GiB volume is read once more here), each block a vectorisable fold.
    fn min_max<T: Copy + PartialOrd + Send + Sync>(values: &[T]) -> Option<(T, T)> {
        let pick = |(lo, hi): (T, T), (a, b): (T, T)| (if a < lo { a } else { lo }, if b > hi { b } else { hi });
        values
            .par_chunks(1 << 20)
            .map(|block| {
                let first = block[0];
                block.iter().fold((first, first), |acc, &v| pick(acc, (v, v)))
            })
            .reduce_with(pick)
    }
    let found = match data {
        VoxelData::U8(v) => {
            let offset = stored_offset(source_type);
            min_max(v).map(|(lo, hi)| (f64::from(lo) - offset, f64::from(hi) - offset))
        }
        VoxelData::U16(v) => {
            let offset = stored_offset(source_type);
            min_max(v).map(|(lo, hi)| (f64::from(lo) - offset, f64::from(hi) - offset))
        }
        VoxelData::F32(v) => v
            .par_chunks(1 << 20)
            .filter_map(|block| {
                let mut finite = block.iter().copied().filter(|x| x.is_finite());
                let first = finite.next()?;
                Some(finite.fold((first, first), |(lo, hi), x| (lo.min(x), hi.max(x))))
            })
            .reduce_with(|(a, b), (c, d)| (a.min(c), b.max(d)))
            .map(|(lo, hi)| (f64::from(lo), f64::from(hi))),
    };
    found.map(|(lo, hi)| [lo, hi])
}

/// Checks dims and returns the voxel count.
pub(crate) fn check_dims(dims: [u32; 3]) -> Result<u64, VolumeError> {
    if dims.contains(&0) {
        return Err(VolumeError::ZeroDimension { dims });
    }
    if dims.iter().any(|&d| d > MAX_DIM) {
        return Err(VolumeError::DimensionTooLarge { dims });
    }
    // Each factor is at most 2^14, so the product fits easily in u64.
    let count = dims.iter().map(|&d| u64::from(d)).product::<u64>();
    if count > MAX_VOXELS {
        return Err(VolumeError::TooManyVoxels { dims, count });
    }
    Ok(count)
}

fn check_spacing(dims: [u32; 3], spacing: [f32; 3]) -> Result<(), VolumeError> {
    let physical_ok = (0..3).all(|i| {
        let s = spacing[i];
        s.is_finite() && s > 0.0 && (f64::from(dims[i]) * f64::from(s)) < f64::from(f32::MAX)
    });
    if physical_ok {
        Ok(())
    } else {
        Err(VolumeError::BadSpacing { spacing })
    }
}

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
    #[error("dimensions {} make {count} voxels, more than the limit of {MAX_VOXELS} (2^31)", Dims(*dims))]
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
    #[error("cannot tell the {missing} of {file}: pass --dims W H D --type T or name the file NAME_WxHxD_TYPE.raw")]
    MissingLayout { file: String, missing: &'static str },
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
    #[error(
        "{file}: data file '{data_file}' is outside the header's folder; volcast only reads data files in the \
         header's folder or below it"
    )]
    PathEscape { file: String, data_file: String },
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
}

#[cfg(test)]
mod tests;
