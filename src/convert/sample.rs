//! The element types a store holds: one trait over the eight voxel types, so the slab pipeline, the pyramid and the
//! writer are written once and monomorphised per output type.

use crate::volume::VoxelType;

/// A voxel value as it is written. `from_f64` rounds half away from zero and saturates for integers (a mean of
/// integers, or a scaled value the type was chosen to hold exactly).
pub trait Sample: zarrs::array::Element + bytemuck::Pod + Send + Sync + PartialOrd + Default + 'static {
    const TYPE: VoxelType;
    fn to_f64(self) -> f64;
    fn from_f64(v: f64) -> Self;
}

macro_rules! integer_sample {
    ($t:ty, $vt:expr) => {
        impl Sample for $t {
            const TYPE: VoxelType = $vt;
            fn to_f64(self) -> f64 {
                self as f64
            }
            fn from_f64(v: f64) -> Self {
                // `as` saturates and maps NaN to 0; `round` is half away from zero.
                v.round() as $t
            }
        }
    };
}

integer_sample!(u8, VoxelType::U8);
integer_sample!(i8, VoxelType::I8);
integer_sample!(u16, VoxelType::U16);
integer_sample!(i16, VoxelType::I16);
integer_sample!(u32, VoxelType::U32);
integer_sample!(i32, VoxelType::I32);

impl Sample for f32 {
    const TYPE: VoxelType = VoxelType::F32;
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    fn from_f64(v: f64) -> Self {
        v as f32
    }
}

impl Sample for f64 {
    const TYPE: VoxelType = VoxelType::F64;
    fn to_f64(self) -> f64 {
        self
    }
    fn from_f64(v: f64) -> Self {
        v
    }
}

/// The Zarr data type of `t` (v3 name; `zarrs` spells the v2 one from it).
pub fn zarr_data_type(t: VoxelType) -> zarrs::array::DataType {
    use zarrs::array::data_type as dt;
    match t {
        VoxelType::U8 => dt::uint8(),
        VoxelType::I8 => dt::int8(),
        VoxelType::U16 => dt::uint16(),
        VoxelType::I16 => dt::int16(),
        VoxelType::U32 => dt::uint32(),
        VoxelType::I32 => dt::int32(),
        VoxelType::F32 => dt::float32(),
        VoxelType::F64 => dt::float64(),
    }
}

/// The numpy type string of `t` for Zarr v2 metadata (little-endian).
pub fn numpy_dtype(t: VoxelType) -> &'static str {
    match t {
        VoxelType::U8 => "|u1",
        VoxelType::I8 => "|i1",
        VoxelType::U16 => "<u2",
        VoxelType::I16 => "<i2",
        VoxelType::U32 => "<u4",
        VoxelType::I32 => "<i4",
        VoxelType::F32 => "<f4",
        VoxelType::F64 => "<f8",
    }
}
