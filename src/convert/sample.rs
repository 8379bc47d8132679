//! The Zarr names of the element types a store holds (the types themselves are [`crate::pyramid::sample::Sample`]).

use crate::volume::VoxelType;

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
