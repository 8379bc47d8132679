//! Where the converter's voxels come from, slab by slab: a volume loaded once (any format), or a file whose voxels
//! lie in place on disk, read with positioned reads so it is never held whole.

use super::sample::Sample;
use crate::volume::in_place::InPlace;
use crate::volume::{Endian, Geometry, Scaling, Volume, VolumeError, VoxelData, VoxelType};
use rayon::prelude::*;
use std::fs::File;
use std::os::unix::fs::FileExt;

/// The voxels to convert.
pub enum Source {
    /// Loaded whole (held once; its steps are read from memory).
    Loaded(Box<Volume>),
    /// Read slab by slab from the file.
    InPlace(Box<InPlace>, File),
}

impl Source {
    /// Opens `in_place`'s data file for positioned reads.
    pub fn in_place(v: InPlace) -> Result<Source, VolumeError> {
        let file = File::open(&v.data_file).map_err(|source| VolumeError::Io {
            path: v.data_file.clone(),
            source,
        })?;
        Ok(Source::InPlace(Box::new(v), file))
    }

    pub fn name(&self) -> &str {
        match self {
            Source::Loaded(v) => &v.name,
            Source::InPlace(v, _) => &v.name,
        }
    }

    /// Width, height, slices.
    pub fn dims(&self) -> [u32; 3] {
        match self {
            Source::Loaded(v) => v.dims,
            Source::InPlace(v, _) => v.dims,
        }
    }

    pub fn timesteps(&self) -> u32 {
        match self {
            Source::Loaded(v) => v.timesteps(),
            Source::InPlace(v, _) => v.timesteps,
        }
    }

    pub fn geometry(&self) -> Geometry {
        match self {
            Source::Loaded(v) => v.geometry,
            Source::InPlace(v, _) => v.geometry,
        }
    }

    pub fn scaling(&self) -> Scaling {
        match self {
            Source::Loaded(v) => v.scaling,
            Source::InPlace(v, _) => v.scaling,
        }
    }

    /// The type of the file's voxels.
    pub fn source_type(&self) -> VoxelType {
        match self {
            Source::Loaded(v) => v.source_type,
            Source::InPlace(v, _) => v.voxel_type,
        }
    }

    /// The type the values exist in here: a loaded volume holds 32-bit integers and float64 as float32.
    pub fn held_type(&self) -> VoxelType {
        match self {
            Source::Loaded(v) => match (&v.data, v.source_type) {
                (VoxelData::F32(_), VoxelType::U32 | VoxelType::I32 | VoxelType::F64) => VoxelType::F32,
                (_, t) => t,
            },
            Source::InPlace(v, _) => v.voxel_type,
        }
    }

    /// The stored (unscaled) value range over every step; `None` if no value is finite.
    pub fn stored_range(&self) -> Result<Option<[f64; 2]>, VolumeError> {
        if let Source::Loaded(v) = self {
            return Ok(Some(v.stored_range));
        }
        let d = self.dims()[2];
        let mut range: Option<[f64; 2]> = None;
        // Eight slices at a time as f64: a bounded buffer whatever the volume's size.
        for t in 0..self.timesteps() {
            for z0 in (0..d).step_by(8) {
                let n = 8.min(d - z0);
                let values: Vec<f64> = self.read_slab(t, z0, n, Scaling::IDENTITY)?;
                let found = values
                    .par_chunks(1 << 16)
                    .filter_map(|c| {
                        let mut f = c.iter().copied().filter(|v| v.is_finite());
                        let first = f.next()?;
                        Some(f.fold([first, first], |[lo, hi], v| [lo.min(v), hi.max(v)]))
                    })
                    .reduce_with(|a, b| [a[0].min(b[0]), a[1].max(b[1])]);
                if let Some([lo, hi]) = found {
                    range = Some(range.map_or([lo, hi], |[a, b]| [a.min(lo), b.max(hi)]));
                }
            }
        }
        Ok(range)
    }

    /// Slices `z0..z0 + n` of step `t` (x fastest), each value `scaling` applied to the true source value
    /// (signed integers un-biased, big-endian bytes swapped), converted to `T`.
    pub fn read_slab<T: Sample>(&self, t: u32, z0: u32, n: u32, scaling: Scaling) -> Result<Vec<T>, VolumeError> {
        let [w, h, _] = self.dims();
        let slice = w as usize * h as usize;
        let (start, len) = (z0 as usize * slice, n as usize * slice);
        let apply = move |v: f64| {
            if scaling.is_identity() {
                v
            } else {
                v * scaling.slope + scaling.intercept
            }
        };
        match self {
            Source::Loaded(v) => {
                let data = v.step_data(t).expect("step within the series");
                let offset = match v.source_type {
                    VoxelType::I16 => 32768.0,
                    VoxelType::I8 => 128.0,
                    _ => 0.0,
                };
                // Values held as written (no bias, no rescale): a plain copy.
                if T::TYPE == v.source_type && offset == 0.0 && scaling.is_identity() {
                    let held: &[u8] = match data {
                        VoxelData::U8(d) => &d[start..start + len],
                        VoxelData::U16(d) => bytemuck::cast_slice(&d[start..start + len]),
                        VoxelData::F32(d) => bytemuck::cast_slice(&d[start..start + len]),
                    };
                    return Ok(bytemuck::cast_slice(held).to_vec());
                }
                let mut out = vec![T::default(); len];
                let convert = |out: &mut [T], get: &(dyn Fn(usize) -> f64 + Sync)| {
                    out.par_chunks_mut(1 << 16).enumerate().for_each(|(c, block)| {
                        for (i, o) in block.iter_mut().enumerate() {
                            *o = T::from_f64(apply(get(start + (c << 16) + i) - offset));
                        }
                    })
                };
                match data {
                    VoxelData::U8(d) => convert(&mut out, &|i| f64::from(d[i])),
                    VoxelData::U16(d) => convert(&mut out, &|i| f64::from(d[i])),
                    VoxelData::F32(d) => convert(&mut out, &|i| f64::from(d[i])),
                }
                Ok(out)
            }
            Source::InPlace(v, file) => {
                let size = v.voxel_type.size();
                let at = v.offset + (u64::from(t) * v.step_bytes()) + (start * size) as u64;
                let io = |source| VolumeError::Io {
                    path: v.data_file.clone(),
                    source,
                };
                let (vt, big) = (v.voxel_type, v.endian == Endian::Big);
                // The file's bytes are the values as written: read straight into the slab.
                if T::TYPE == vt && big == cfg!(target_endian = "big") && scaling.is_identity() {
                    let mut out = vec![T::default(); len];
                    file.read_exact_at(bytemuck::cast_slice_mut(&mut out), at).map_err(io)?;
                    return Ok(out);
                }
                let mut bytes = vec![0u8; len * size];
                file.read_exact_at(&mut bytes, at).map_err(io)?;
                let mut out = vec![T::default(); len];
                out.par_chunks_mut(1 << 16)
                    .zip(bytes.par_chunks(size << 16))
                    .for_each(|(block, raw)| {
                        for (o, b) in block.iter_mut().zip(raw.chunks_exact(size)) {
                            *o = T::from_f64(apply(decode(vt, big, b)));
                        }
                    });
                Ok(out)
            }
        }
    }
}

/// One voxel's bytes as its value.
pub(crate) fn decode(t: VoxelType, big: bool, b: &[u8]) -> f64 {
    macro_rules! num {
        ($ty:ty, $n:expr) => {{
            let a: [u8; $n] = b.try_into().expect("voxel size");
            (if big {
                <$ty>::from_be_bytes(a)
            } else {
                <$ty>::from_le_bytes(a)
            }) as f64
        }};
    }
    match t {
        VoxelType::U8 => f64::from(b[0]),
        VoxelType::I8 => f64::from(b[0] as i8),
        VoxelType::U16 => num!(u16, 2),
        VoxelType::I16 => num!(i16, 2),
        VoxelType::U32 => num!(u32, 4),
        VoxelType::I32 => num!(i32, 4),
        VoxelType::F32 => num!(f32, 4),
        VoxelType::F64 => num!(f64, 8),
    }
}
