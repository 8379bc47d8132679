//! The element types a level is made of: one trait over the eight voxel types, so that the reduction, the slab
//! pipeline and the store writer are written once and monomorphised per type.

use crate::volume::voxel::VoxelType;

/// A voxel value as it is written. `from_f64` rounds half away from zero and saturates for integers (a mean of
/// integers, or a scaled value the type was chosen to hold exactly). `Element` because the store's writer and
/// reader move levels in these types.
pub trait Sample: zarrs::array::Element + bytemuck::Pod + Send + Sync + PartialOrd + Default + 'static {
    const TYPE: VoxelType;
    fn to_f64(self) -> f64;
    fn from_f64(v: f64) -> Self;

    /// `out[i]` = the mean of the 2×2×2 block at x = 2i and 2i + 1 of the four `rows` (y and z pairs), rounded as
    /// [`from_f64`](Self::from_f64) rounds. Integers sum exactly in a wider integer (the same result, a vectorisable
    /// loop: the pyramid's whole blocks are most of reading a level).
    fn mean_rows(rows: [&[Self]; 4], out: &mut [Self]) {
        for (ox, slot) in out.iter_mut().enumerate() {
            let x = 2 * ox;
            let sum: f64 = rows.iter().map(|r| r[x].to_f64() + r[x + 1].to_f64()).sum();
            *slot = Self::from_f64(sum / 8.0);
        }
    }
}

/// An integer sample; `$wide` holds the sum of eight, and `$round` rounds a sum over 8 half away from zero.
macro_rules! integer_sample {
    ($t:ty, $vt:expr, $wide:ty, $round:expr) => {
        impl Sample for $t {
            const TYPE: VoxelType = $vt;
            fn to_f64(self) -> f64 {
                self as f64
            }
            fn from_f64(v: f64) -> Self {
                // `as` saturates and maps NaN to 0; `round` is half away from zero.
                v.round() as $t
            }
            fn mean_rows([a, b, c, d]: [&[Self]; 4], out: &mut [Self]) {
                // The four rows' column sums first (contiguous: it vectorises), then adjacent pairs of them.
                let round: fn($wide) -> $wide = $round;
                let n = 2 * out.len();
                let columns: Vec<$wide> = (a[..n].iter().zip(&b[..n]))
                    .zip(c[..n].iter().zip(&d[..n]))
                    .map(|((&a, &b), (&c, &d))| a as $wide + b as $wide + c as $wide + d as $wide)
                    .collect();
                for (slot, pair) in out.iter_mut().zip(columns.chunks_exact(2)) {
                    *slot = round(pair[0] + pair[1]) as $t;
                }
            }
        }
    };
}

integer_sample!(u8, VoxelType::U8, u16, |s| (s + 4) / 8);
integer_sample!(i8, VoxelType::I8, i16, |s| (s + if s < 0 { -4 } else { 4 }) / 8);
integer_sample!(u16, VoxelType::U16, u32, |s| (s + 4) / 8);
integer_sample!(i16, VoxelType::I16, i32, |s| (s + if s < 0 { -4 } else { 4 }) / 8);
integer_sample!(u32, VoxelType::U32, u64, |s| (s + 4) / 8);
integer_sample!(i32, VoxelType::I32, i64, |s| (s + if s < 0 { -4 } else { 4 }) / 8);

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
