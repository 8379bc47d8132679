//! One level's voxels: a time step and channel of the level's array, decoded by zarrs (chunks, shards, codecs,
//! missing chunks as the fill value) into volcast's [`VoxelData`].

use crate::volume::VoxelData;
use crate::volume::VoxelType;
use zarrs::array::data_type::{
    Float32DataType, Float64DataType, Int16DataType, Int32DataType, Int8DataType, UInt16DataType, UInt32DataType,
    UInt8DataType,
};
use zarrs::array::{Array, ArraySubset, ElementOwned};
use zarrs::storage::ReadableStorageTraits;

/// volcast's type for a level's data type, or the data type's name when volcast does not read it.
pub(crate) fn voxel_type<S: ?Sized>(array: &Array<S>) -> Result<VoxelType, String> {
    let t = array.data_type();
    let known = [
        (t.is::<UInt8DataType>(), VoxelType::U8),
        (t.is::<Int8DataType>(), VoxelType::I8),
        (t.is::<UInt16DataType>(), VoxelType::U16),
        (t.is::<Int16DataType>(), VoxelType::I16),
        (t.is::<UInt32DataType>(), VoxelType::U32),
        (t.is::<Int32DataType>(), VoxelType::I32),
        (t.is::<Float32DataType>(), VoxelType::F32),
        (t.is::<Float64DataType>(), VoxelType::F64),
    ];
    known
        .iter()
        .find(|(is, _)| *is)
        .map(|(_, v)| *v)
        .ok_or_else(|| data_type_name(array))
}

/// The data type as the array's metadata names it (`uint64`, `<i8`, `complex64`, ...).
pub(crate) fn data_type_name<S: ?Sized>(array: &Array<S>) -> String {
    let json = serde_json::to_value(array.metadata()).unwrap_or_default();
    let v = json.get("data_type").or_else(|| json.get("dtype"));
    match v {
        Some(serde_json::Value::String(s)) => s.clone(),
        Some(other) => other
            .get("name")
            .and_then(|n| n.as_str())
            .map_or_else(|| other.to_string(), str::to_string),
        None => "unknown".into(),
    }
}

/// The voxels of time step `t` and channel `c` (positions along those axes, if the array has them); `space` are
/// the space axes' array indices. Returned x fastest, as the array's C order already is.
pub(crate) fn read_step<S: ?Sized + ReadableStorageTraits + 'static>(
    array: &Array<S>,
    voxel_type: VoxelType,
    fixed: &[(usize, u64)],
) -> Result<VoxelData, String> {
    let ranges: Vec<std::ops::Range<u64>> = array
        .shape()
        .iter()
        .enumerate()
        .map(|(i, &n)| match fixed.iter().find(|(axis, _)| *axis == i) {
            Some(&(_, at)) => at..at + 1,
            None => 0..n,
        })
        .collect();
    let subset = ArraySubset::new_with_ranges(&ranges);
    let get = |e: zarrs::array::ArrayError| e.to_string();
    fn vec<T: ElementOwned, S: ?Sized + ReadableStorageTraits + 'static>(
        array: &Array<S>,
        subset: &ArraySubset,
    ) -> Result<Vec<T>, zarrs::array::ArrayError> {
        array.retrieve_array_subset::<Vec<T>>(subset)
    }
    Ok(match voxel_type {
        VoxelType::U8 => VoxelData::U8(vec::<u8, S>(array, &subset).map_err(get)?),
        // A signed value plus the bias is its bits with the sign bit flipped.
        VoxelType::I8 => VoxelData::U8(
            vec::<i8, S>(array, &subset)
                .map_err(get)?
                .into_iter()
                .map(|v| v as u8 ^ 0x80)
                .collect(),
        ),
        VoxelType::U16 => VoxelData::U16(vec::<u16, S>(array, &subset).map_err(get)?),
        VoxelType::I16 => VoxelData::U16(
            vec::<i16, S>(array, &subset)
                .map_err(get)?
                .into_iter()
                .map(|v| v as u16 ^ 0x8000)
                .collect(),
        ),
        VoxelType::U32 => VoxelData::F32(
            vec::<u32, S>(array, &subset)
                .map_err(get)?
                .into_iter()
                .map(|v| v as f32)
                .collect(),
        ),
        VoxelType::I32 => VoxelData::F32(
            vec::<i32, S>(array, &subset)
                .map_err(get)?
                .into_iter()
                .map(|v| v as f32)
                .collect(),
        ),
        VoxelType::F32 => VoxelData::F32(vec::<f32, S>(array, &subset).map_err(get)?),
        VoxelType::F64 => VoxelData::F32(
            vec::<f64, S>(array, &subset)
                .map_err(get)?
                .into_iter()
                .map(|v| v as f32)
                .collect(),
        ),
    })
}
