//! Voxel types: the source's type, what reaches the GPU ([`VoxelData`]), the bias that keeps signed integers in
//! unsigned textures, the file's linear rescale, and the value range of the stored voxels.

use super::VolumeError;
use rayon::prelude::*;
use std::fmt;

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
    /// The elements, where they are 8-bit.
    pub fn as_u8(&self) -> Option<&[u8]> {
        match self {
            VoxelData::U8(v) => Some(v),
            _ => None,
        }
    }

    /// The elements, where they are 16-bit.
    pub fn as_u16(&self) -> Option<&[u16]> {
        match self {
            VoxelData::U16(v) => Some(v),
            _ => None,
        }
    }

    /// The elements, where they are float.
    pub fn as_f32(&self) -> Option<&[f32]> {
        match self {
            VoxelData::F32(v) => Some(v),
            _ => None,
        }
    }

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

    pub(super) fn kind(&self) -> &'static str {
        match self {
            VoxelData::U8(_) => "U8",
            VoxelData::U16(_) => "U16",
            VoxelData::F32(_) => "F32",
        }
    }

    /// The representation `source_type` must be stored in.
    pub(super) fn matches(&self, source_type: VoxelType) -> bool {
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
pub(crate) fn stored_offset(source_type: VoxelType) -> f64 {
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

    pub(super) fn apply(&self, v: f64) -> f64 {
        if self.is_identity() {
            v
        } else {
            v * self.slope + self.intercept
        }
    }
}

pub(super) fn stored_value(source_type: VoxelType, data: &VoxelData, i: usize) -> f64 {
    match data {
        VoxelData::U8(v) => f64::from(v[i]) - stored_offset(source_type),
        VoxelData::U16(v) => f64::from(v[i]) - stored_offset(source_type),
        VoxelData::F32(v) => f64::from(v[i]),
    }
}

pub(super) fn compute_range(source_type: VoxelType, data: &VoxelData) -> [f64; 2] {
    compute_range_of(source_type, data).unwrap_or([0.0, 0.0])
}

/// The extremes of `data`'s finite elements as held (biased integers stay biased); `None` if none is finite.
pub fn element_range(data: &VoxelData) -> Option<[f64; 2]> {
    let held = match data {
        VoxelData::U8(_) => VoxelType::U8,
        VoxelData::U16(_) => VoxelType::U16,
        VoxelData::F32(_) => VoxelType::F32,
    };
    compute_range_of(held, data)
}

/// The data's min/max as source values (NaN/Inf ignored); `None` if no voxel is finite.
pub(super) fn compute_range_of(source_type: VoxelType, data: &VoxelData) -> Option<[f64; 2]> {
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
