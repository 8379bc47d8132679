//! Where the converter's voxels come from, slab by slab: a volume loaded once (any format), or a file whose voxels
//! lie in place on disk, read with positioned reads so it is never held whole.

use crate::formats::in_place::{InPlace, Inflate};
use crate::formats::Endian;
use crate::pyramid::sample::Sample;
use crate::volume::{Geometry, Scaling, Volume, VolumeError, VoxelData, VoxelType};
use rayon::prelude::*;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::os::unix::fs::FileExt;
use std::sync::Mutex;

/// The voxels to convert.
pub enum Source {
    /// Loaded whole (held once; its steps are read from memory).
    Loaded(Box<Volume>),
    /// Read slab by slab from the file.
    InPlace(Box<InPlace>, File),
    /// Decoded front to back from a compressed stream (`InPlace::inflate`): read in order, it is decoded once.
    Stream(Box<InPlace>, Mutex<Inflating>),
    /// A DICOM series, its slices decoded from their own files (`InPlace::slices`): any slab, on any core.
    Slices(Box<InPlace>),
}

/// A compressed stream being decoded, and how many of its voxel bytes were read.
pub struct Inflating {
    reader: Box<dyn Read + Send>,
    at: u64,
}

impl Inflating {
    /// Opens `v`'s stream and skips to its first voxel.
    fn open(v: &InPlace) -> Result<Inflating, VolumeError> {
        let io = |source| VolumeError::Io {
            path: v.data_file.clone(),
            source,
        };
        let mut file = File::open(&v.data_file).map_err(io)?;
        file.seek(SeekFrom::Start(v.offset)).map_err(io)?;
        let file = BufReader::new(file);
        let inflate = v.inflate.unwrap_or(Inflate { zlib: false, skip: 0 });
        let reader: Box<dyn Read + Send> = if inflate.zlib {
            Box::new(flate2::read::ZlibDecoder::new(file))
        } else {
            Box::new(flate2::read::MultiGzDecoder::new(file))
        };
        let mut s = Inflating { reader, at: 0 };
        s.skip_to(v, inflate.skip)?;
        s.at = 0;
        Ok(s)
    }

    /// Discards inflated bytes up to `to` (bytes of voxels read so far).
    fn skip_to(&mut self, v: &InPlace, to: u64) -> Result<(), VolumeError> {
        let want = to - self.at;
        let skipped =
            std::io::copy(&mut (&mut self.reader).take(want), &mut std::io::sink()).map_err(|e| corrupt(v, e))?;
        self.at += skipped;
        if skipped < want {
            return Err(truncated(v, self.at));
        }
        Ok(())
    }

    /// `len` bytes of voxels from `at`: read forward (from the stream's start again if `at` was passed).
    fn read_at(&mut self, v: &InPlace, at: u64, out: &mut [u8]) -> Result<(), VolumeError> {
        if at < self.at {
            *self = Inflating::open(v)?;
        }
        self.skip_to(v, at)?;
        let mut got = 0;
        while got < out.len() {
            match self.reader.read(&mut out[got..]) {
                Ok(0) => return Err(truncated(v, self.at + got as u64)),
                Ok(n) => got += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(corrupt(v, e)),
            }
        }
        self.at += got as u64;
        Ok(())
    }
}

fn corrupt(v: &InPlace, source: std::io::Error) -> VolumeError {
    VolumeError::Corrupt {
        file: v.data_file.display().to_string(),
        what: if v.inflate.is_some_and(|i| i.zlib) {
            "zlib"
        } else {
            "gzip"
        },
        source,
    }
}

/// The stream ended after `actual` bytes of voxels.
fn truncated(v: &InPlace, actual: u64) -> VolumeError {
    VolumeError::Truncated {
        file: v.data_file.display().to_string(),
        actual,
        expected: v.step_bytes() * u64::from(v.timesteps),
        dims: v.dims,
        voxel_type: v.voxel_type,
    }
}

impl Source {
    /// Opens `in_place`'s data file for positioned reads, or its compressed stream to decode.
    pub fn in_place(v: InPlace) -> Result<Source, VolumeError> {
        if v.slices.is_some() {
            return Ok(Source::Slices(Box::new(v)));
        }
        if v.inflate.is_some() {
            let stream = Inflating::open(&v)?;
            return Ok(Source::Stream(Box::new(v), Mutex::new(stream)));
        }
        let file = File::open(&v.data_file).map_err(|source| VolumeError::Io {
            path: v.data_file.clone(),
            source,
        })?;
        Ok(Source::InPlace(Box::new(v), file))
    }

    pub fn name(&self) -> &str {
        match self {
            Source::Loaded(v) => &v.name,
            Source::InPlace(v, _) | Source::Stream(v, _) | Source::Slices(v) => &v.name,
        }
    }

    /// Width, height, slices.
    pub fn dims(&self) -> [u32; 3] {
        match self {
            Source::Loaded(v) => v.dims,
            Source::InPlace(v, _) | Source::Stream(v, _) | Source::Slices(v) => v.dims,
        }
    }

    pub fn timesteps(&self) -> u32 {
        match self {
            Source::Loaded(v) => v.timesteps(),
            Source::InPlace(v, _) | Source::Stream(v, _) | Source::Slices(v) => v.timesteps,
        }
    }

    pub fn geometry(&self) -> Geometry {
        match self {
            Source::Loaded(v) => v.geometry,
            Source::InPlace(v, _) | Source::Stream(v, _) | Source::Slices(v) => v.geometry,
        }
    }

    pub fn scaling(&self) -> Scaling {
        match self {
            Source::Loaded(v) => v.scaling,
            Source::InPlace(v, _) | Source::Stream(v, _) | Source::Slices(v) => v.scaling,
        }
    }

    /// The type of the file's voxels.
    pub fn source_type(&self) -> VoxelType {
        match self {
            Source::Loaded(v) => v.source_type,
            Source::InPlace(v, _) | Source::Stream(v, _) | Source::Slices(v) => v.voxel_type,
        }
    }

    /// The type the values exist in here: a loaded volume holds 32-bit integers and float64 as float32.
    pub fn held_type(&self) -> VoxelType {
        match self {
            Source::Loaded(v) => match (&v.data, v.source_type) {
                (VoxelData::F32(_), VoxelType::U32 | VoxelType::I32 | VoxelType::F64) => VoxelType::F32,
                (_, t) => t,
            },
            Source::InPlace(v, _) | Source::Stream(v, _) | Source::Slices(v) => v.voxel_type,
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
        let mut out = Vec::new();
        self.read_slab_into(t, z0, n, scaling, &mut out)?;
        Ok(out)
    }

    /// [`read_slab`](Self::read_slab) into `out`, reusing its memory (a reader of many slabs allocates once: fresh
    /// pages for every slab cost a fifth of reading a level).
    pub fn read_slab_into<T: Sample>(
        &self,
        t: u32,
        z0: u32,
        n: u32,
        scaling: Scaling,
        out: &mut Vec<T>,
    ) -> Result<(), VolumeError> {
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
                    out.clear();
                    out.extend_from_slice(bytemuck::cast_slice(held));
                    return Ok(());
                }
                out.clear();
                out.resize(len, T::default());
                let convert = |out: &mut [T], get: &(dyn Fn(usize) -> f64 + Sync)| {
                    out.par_chunks_mut(1 << 16).enumerate().for_each(|(c, block)| {
                        for (i, o) in block.iter_mut().enumerate() {
                            *o = T::from_f64(apply(get(start + (c << 16) + i) - offset));
                        }
                    })
                };
                match data {
                    VoxelData::U8(d) => convert(out, &|i| f64::from(d[i])),
                    VoxelData::U16(d) => convert(out, &|i| f64::from(d[i])),
                    VoxelData::F32(d) => convert(out, &|i| f64::from(d[i])),
                }
                Ok(())
            }
            Source::InPlace(v, _) | Source::Stream(v, _) | Source::Slices(v) => {
                let size = v.voxel_type.size();
                let at = u64::from(t) * v.step_bytes() + (start * size) as u64;
                let (vt, big) = (v.voxel_type, v.endian == Endian::Big);
                // The file's bytes are the values as written: read straight into the slab.
                // Every element is written below: a reused buffer of the right size is not cleared first.
                if out.len() != len {
                    out.clear();
                    out.resize(len, T::default());
                }
                if T::TYPE == vt && big == cfg!(target_endian = "big") && scaling.is_identity() {
                    return self.read_bytes(at, bytemuck::cast_slice_mut(out));
                }
                let mut bytes = vec![0u8; len * size];
                self.read_bytes(at, &mut bytes)?;
                out.par_chunks_mut(1 << 16)
                    .zip(bytes.par_chunks(size << 16))
                    .for_each(|(block, raw)| {
                        for (o, b) in block.iter_mut().zip(raw.chunks_exact(size)) {
                            *o = T::from_f64(apply(decode(vt, big, b)));
                        }
                    });
                Ok(())
            }
        }
    }

    /// The box of voxels `lo..lo + size` of step `t` of a file read in place (x fastest), as [`read_slab`] converts
    /// them (identity scaling), slices on every core. Where the file's rows are short, one positioned read per slice
    /// takes the span from the box's first row to its last (the rows between are copied and dropped: cheaper than a
    /// read per row, each a system call); else one read per row.
    ///
    /// [`read_slab`]: Self::read_slab
    pub fn read_box<T: Sample>(&self, t: u32, lo: [u32; 3], size: [u32; 3]) -> Result<Vec<T>, VolumeError> {
        let Source::InPlace(v, _) = self else {
            return Err(VolumeError::Header {
                file: self.name().to_string(),
                problem: "only a file read in place gives boxes of voxels".into(),
            });
        };
        let [w, h, _] = v.dims.map(|d| d as usize);
        let (vsize, vt, big) = (v.voxel_type.size(), v.voxel_type, v.endian == Endian::Big);
        let [sx, sy, sz] = size.map(|s| s as usize);
        let row_bytes = w * vsize;
        let span = row_bytes <= SPAN_ROW_BYTES;
        // The file's bytes are the values as written: copied as they are.
        let plain = T::TYPE == vt && big == cfg!(target_endian = "big");
        let convert = |bytes: &[u8], dst: &mut [T]| {
            if plain {
                bytemuck::cast_slice_mut::<T, u8>(dst).copy_from_slice(bytes);
            } else {
                for (o, b) in dst.iter_mut().zip(bytes.chunks_exact(vsize)) {
                    *o = T::from_f64(decode(vt, big, b));
                }
            }
        };
        let mut out = vec![T::default(); sx * sy * sz];
        if out.is_empty() {
            return Ok(out);
        }
        out.par_chunks_mut(sx * sy)
            .enumerate()
            .try_for_each_init(Vec::new, |bytes: &mut Vec<u8>, (k, dst)| {
                let first = lo[0] as usize + w * (lo[1] as usize + h * (lo[2] as usize + k));
                let at = u64::from(t) * v.step_bytes() + (first * vsize) as u64;
                if span {
                    bytes.resize(((sy - 1) * w + sx) * vsize, 0);
                    self.read_bytes(at, bytes)?;
                    for (r, d) in dst.chunks_exact_mut(sx).enumerate() {
                        convert(&bytes[r * row_bytes..][..sx * vsize], d);
                    }
                } else {
                    bytes.resize(sx * vsize, 0);
                    for (r, d) in dst.chunks_exact_mut(sx).enumerate() {
                        self.read_bytes(at + (r * row_bytes) as u64, bytes)?;
                        convert(bytes, d);
                    }
                }
                Ok(())
            })?;
        Ok(out)
    }

    /// Whether slabs are best read in order (a compressed stream: reading back starts it again).
    pub fn is_stream(&self) -> bool {
        matches!(self, Source::Stream(..))
    }

    /// The voxel bytes `at..at + out.len()` (from the first voxel of the first step) of a file read in place or
    /// decoded.
    fn read_bytes(&self, at: u64, out: &mut [u8]) -> Result<(), VolumeError> {
        match self {
            Source::InPlace(v, file) => match &v.blocks {
                Some(blocks) => blocks.read_at((file, &v.data_file), at, out),
                None => file
                    .read_exact_at(out, v.offset + at)
                    .map_err(|source| VolumeError::Io {
                        path: v.data_file.clone(),
                        source,
                    }),
            },
            Source::Stream(v, stream) => stream
                .lock()
                .map_err(|_| VolumeError::Header {
                    file: v.data_file.display().to_string(),
                    problem: "a reader of its stream panicked".into(),
                })?
                .read_at(v, at, out),
            Source::Slices(v) => match &v.slices {
                Some(series) => series.read_at(at, out),
                None => Err(VolumeError::Header {
                    file: v.data_file.display().to_string(),
                    problem: "a series without its slices".into(),
                }),
            },
            Source::Loaded(v) => Err(VolumeError::Header {
                file: v.name.clone(),
                problem: "a loaded volume has no file bytes".into(),
            }),
        }
    }
}

/// The longest row of a file that [`Source::read_box`] reads as part of a slice's span (a row longer than this costs
/// more to copy than the system call reading it alone).
const SPAN_ROW_BYTES: usize = 4096;

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

#[cfg(test)]
mod tests {
    use super::*;

    /// Boxes of a file whose rows are read as spans (short rows) and one whose rows are read one by one (long
    /// rows), as the file's own type and converted: the voxels of a slab read whole.
    #[test]
    fn boxes_equal_the_slab_they_lie_in() {
        for (dims, tag) in [([37u32, 21, 9], "short"), ([2100, 5, 4], "long")] {
            let n = (dims[0] * dims[1] * dims[2]) as usize;
            let src: Vec<i16> = (0..n).map(|i| ((i * 7919) % 601) as i16 - 300).collect();
            let (path, opts) = crate::scale::test_file::int16_raw(&format!("box-{tag}"), dims, &src, None);
            let place = crate::formats::in_place::in_place(&path, &opts).unwrap().unwrap();
            let source = Source::in_place(place).unwrap();
            let whole: Vec<i16> = source.read_slab(0, 0, dims[2], Scaling::IDENTITY).unwrap();
            let (lo, size) = ([3, 1, 1], [dims[0] - 5, dims[1] - 2, dims[2] - 2]);
            let as_is: Vec<i16> = source.read_box(0, lo, size).unwrap();
            let as_f32: Vec<f32> = source.read_box(0, lo, size).unwrap();
            let mut k = 0;
            for z in lo[2]..lo[2] + size[2] {
                for y in lo[1]..lo[1] + size[1] {
                    for x in lo[0]..lo[0] + size[0] {
                        let want = whole[(x + dims[0] * (y + dims[1] * z)) as usize];
                        assert_eq!((as_is[k], as_f32[k]), (want, f32::from(want)), "{tag} at {x},{y},{z}");
                        k += 1;
                    }
                }
            }
            std::fs::remove_dir_all(path.parent().unwrap()).ok();
        }
    }
}
