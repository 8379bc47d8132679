//! Reading one level of the resolution pyramid without holding the level above it: output slices are made on every
//! core, each from the 2^L source slices under it (read with positioned reads from a file in place, or copied from a
//! loaded volume), reduced level by level with the pyramid's mean (`pyramid::reduce`). Because the slab is aligned
//! to 2^L, the cascade inside it is exactly the pyramid's: the result equals level L of `volcast convert`'s store.

use super::level0::Level0;
use crate::convert::source::Source;
use crate::pyramid::bricks::{from_level0, to_level0};
use crate::pyramid::budget::show;
use crate::pyramid::geometry::{level_dims, level_geometry};
use crate::pyramid::reduce::mean_to_level_into;
use crate::pyramid::sample::Sample;
use crate::volume::cells::{CellRanges, Element};
use crate::volume::{Volume, VolumeError, VoxelData, VoxelType};
use rayon::prelude::*;

/// Output slices made at once: enough to keep every core busy, few enough to bound the slabs held.
fn batch(threads: usize, slab_bytes: u64, host_budget: u64) -> usize {
    let by_memory = (host_budget / 4 / slab_bytes.max(1)).max(1) as usize;
    (threads * 2).min(by_memory).max(1)
}

/// Level `level` of time step `t` of `source`, held as volcast holds the type (biased 8/16-bit integers, float32
/// for wider types), each slab of level 0 also written to `keep` where given. `progress` gets the fraction of output
/// slices made.
fn level_step<T: Sample + Element>(
    source: &Source,
    (t, level): (u32, u32),
    host_budget: u64,
    keep: Option<&Level0>,
    progress: &mut dyn FnMut(f32),
) -> Result<Read<Vec<T>>, VolumeError> {
    let full = source.dims();
    let out = level_dims(full, level);
    let slice = out[0] as usize * out[1] as usize;
    let span = to_level0(1, level);
    let slice0_bytes = u64::from(full[0]) * u64::from(full[1]) * std::mem::size_of::<T>() as u64;
    let slab_bytes = slice0_bytes * u64::from(span);
    check_slab(source, level, slab_bytes, host_budget)?;
    let step = batch(rayon::current_num_threads(), slab_bytes, host_budget);
    let mut dst = vec![T::default(); slice * out[2] as usize];
    // Slab `oz` into `buf` (its memory reused), and its slices.
    let read = |oz: usize, buf: &mut Vec<T>| -> Result<u32, VolumeError> {
        let z0 = oz as u32 * span;
        let n = span.min(full[2] - z0);
        source.read_slab_into(t, z0, n, crate::volume::Scaling::IDENTITY, buf)?;
        if let Some(keep) = keep {
            keep.write_at(u64::from(z0) * slice0_bytes, bytemuck::cast_slice(buf));
        }
        Ok(n)
    };
    // Level 0's value range, from the voxels read: the level stands in for level 0 and normalises as it does.
    let range = std::sync::Mutex::new(None::<[f64; 2]>);
    let cell = to_level0(CellRanges::SIDE, level);
    let reduce = |slab: &[T], n: u32, into: &mut [T]| -> Vec<Option<(f64, f64)>> {
        let (cells, found) = slab_ranges(slab, [full[0], full[1], n], cell);
        if let (Some([a, b]), Ok(mut r)) = (found, range.lock()) {
            *r = Some(r.map_or([a, b], |[lo, hi]| [lo.min(a), hi.max(b)]));
        }
        let dims = [full[0] as usize, full[1] as usize, n as usize];
        mean_to_level_into(slab, dims, full, level, into);
        cells
    };
    let mut cells = CellRanges::unseen(full, cell);
    let cells_per_layer = from_level0(cell, level) as usize;
    // A stream's batch of slabs, their memory reused from batch to batch.
    let mut slabs: Vec<(Vec<T>, u32)> = Vec::new();
    for first in (0..out[2] as usize).step_by(step) {
        let last = (first + step).min(out[2] as usize);
        let into = dst[first * slice..last * slice].par_chunks_mut(slice);
        if source.is_stream() {
            // A compressed stream is decoded front to back: the batch's slabs are read in order, then reduced on
            // every core.
            slabs.resize_with(last - first, || (Vec::new(), 0));
            for (oz, (buf, n)) in (first..last).zip(slabs.iter_mut()) {
                *n = read(oz, buf)?;
            }
            let layers: Vec<_> = into
                .zip(&slabs[..last - first])
                .map(|(into, (slab, n))| reduce(slab, *n, into))
                .collect();
            for (oz, layer) in (first..last).zip(layers) {
                cells.merge_layer((oz / cells_per_layer) as u32, &layer);
            }
        } else {
            let layers = into
                .zip(first..last)
                .map_init(Vec::new, |buf, (into, oz)| {
                    let n = read(oz, buf)?;
                    Ok::<_, VolumeError>((oz, reduce(buf, n, into)))
                })
                .collect::<Result<Vec<_>, _>>()?;
            for (oz, layer) in layers {
                cells.merge_layer((oz / cells_per_layer) as u32, &layer);
            }
        }
        progress(last as f32 / out[2] as f32);
    }
    let range = range.into_inner().ok().flatten();
    Ok((dst, range, cells))
}

/// Refuses a level whose slabs (2^`level` whole slices, `slab_bytes`) would take more than half the host budget, or
/// 256 MiB where the budget is smaller: a limit only for very wide slices at high levels (16384² uint16 at level 4
/// takes 8 GiB).
fn check_slab(source: &Source, level: u32, slab_bytes: u64, host_budget: u64) -> Result<(), VolumeError> {
    if slab_bytes <= (host_budget / 2).max(256 << 20) {
        return Ok(());
    }
    let full = source.dims();
    Err(VolumeError::Header {
        file: source.name().to_string(),
        problem: format!(
            "reading pyramid level {level} takes {} slices of {}x{} at once ({}), more than half the host budget ({}) \
             allows; raise --host-budget",
            to_level0(1, level),
            full[0],
            full[1],
            show(slab_bytes),
            show(host_budget)
        ),
    })
}

/// A stored value range (None: no finite value).
type Range = Option<[f64; 2]>;

/// Level 0's range per cell of `cell` voxels over a slab of `dims` (part of one layer of cells), as held (biased
/// 8/16-bit integers), and the slab's stored value range (finite values; integers are all finite, so it is the
/// cells', and floats' infinities are left out).
fn slab_ranges<T: Sample + Element>(slab: &[T], dims: [u32; 3], cell: u32) -> (Vec<Option<(f64, f64)>>, Range) {
    let offset = crate::volume::stored_offset(T::TYPE);
    let extremes = crate::volume::cells::extremes_of(slab, dims, cell, 0);
    let cells: Vec<Option<(f64, f64)>> = extremes
        .into_iter()
        .map(|r| r.map(|(a, b)| (a + offset, b + offset)))
        .collect();
    let union =
        |r: Option<[f64; 2]>, (a, b): (f64, f64)| Some(r.map_or([a, b], |[lo, hi]: [f64; 2]| [lo.min(a), hi.max(b)]));
    let found = if matches!(T::TYPE, VoxelType::F32 | VoxelType::F64) {
        slab.iter()
            .map(|v| v.to_f64())
            .filter(|v| v.is_finite())
            .fold(None, |r, v| union(r, (v, v)))
    } else {
        cells
            .iter()
            .flatten()
            .fold(None, |r, &c| union(r, c))
            .map(|r| r.map(|v| v - offset))
    };
    (cells, found)
}

/// A level of one step as read: its voxels, level 0's stored value range (finite values) and level 0's range per
/// cell.
type Read<V> = (V, Option<[f64; 2]>, CellRanges);

/// One step of level `level` as [`VoxelData`] in the representation `voxel_type` is held in, and the stored value
/// range of the level-0 voxels it was made from.
fn level_data(
    source: &Source,
    at: (u32, u32),
    host_budget: u64,
    keep: Option<&Level0>,
    progress: &mut dyn FnMut(f32),
) -> Result<Read<VoxelData>, VolumeError> {
    fn held<T>((v, r, c): Read<Vec<T>>, f: fn(Vec<T>) -> VoxelData) -> Read<VoxelData> {
        (f(v), r, c)
    }
    fn biased<T: Send, U: Send>((v, r, c): Read<Vec<T>>, f: fn(T) -> U) -> Read<Vec<U>> {
        (v.into_par_iter().map(f).collect(), r, c)
    }
    Ok(match source.held_type() {
        VoxelType::U8 => held::<u8>(level_step(source, at, host_budget, keep, progress)?, VoxelData::U8),
        VoxelType::I8 => {
            let r = biased(level_step::<i8>(source, at, host_budget, keep, progress)?, |v| {
                (i16::from(v) + 128) as u8
            });
            held::<u8>(r, VoxelData::U8)
        }
        VoxelType::U16 => held::<u16>(level_step(source, at, host_budget, keep, progress)?, VoxelData::U16),
        VoxelType::I16 => {
            let r = biased(level_step::<i16>(source, at, host_budget, keep, progress)?, |v| {
                (i32::from(v) + 32768) as u16
            });
            held::<u16>(r, VoxelData::U16)
        }
        _ => held::<f32>(level_step(source, at, host_budget, keep, progress)?, VoxelData::F32),
    })
}

/// Level `level` of every time step of `source` as a volume (named, placed and rescaled like the source), with
/// `notes` added. Level 0 of a loaded source is a copy; callers keep the loaded volume instead.
pub fn read_level(
    source: &Source,
    level: u32,
    host_budget: u64,
    notes: Vec<String>,
    progress: &mut dyn FnMut(f32),
) -> Result<Volume, VolumeError> {
    read_level_keeping(source, level, host_budget, notes, None, progress)
}

/// [`read_level`], writing each slab of level 0 it reads to `keep` as well (`scale::level0`; one step only).
pub fn read_level_keeping(
    source: &Source,
    level: u32,
    host_budget: u64,
    notes: Vec<String>,
    keep: Option<&Level0>,
    progress: &mut dyn FnMut(f32),
) -> Result<Volume, VolumeError> {
    let steps = source.timesteps().max(1);
    let mut data = Vec::with_capacity(steps as usize);
    let mut stored: Option<[f64; 2]> = None;
    let mut cells = None;
    for t in 0..steps {
        let (t0, n) = (t as f32, steps as f32);
        let keep = keep.filter(|_| steps == 1);
        let (d, r, c) = level_data(source, (t, level), host_budget, keep, &mut |f| progress((t0 + f) / n))?;
        data.push(d);
        // One step's cells: a series streams no finer levels.
        cells = (steps == 1 && level > 0).then_some(c);
        if let Some([a, b]) = r {
            stored = Some(stored.map_or([a, b], |[lo, hi]| [lo.min(a), hi.max(b)]));
        }
    }
    let dims = level_dims(source.dims(), level);
    let first = data.remove(0);
    let mut v = Volume::new(source.name(), dims, [1.0; 3], source.source_type(), first)?
        .with_geometry(level_geometry(source.geometry(), source.dims(), level))?
        .with_time_steps(data)?;
    // The level stands in for level 0: it normalises by level 0's range, as the levels above a held volume do.
    v = v.with_stored_range(stored.unwrap_or([0.0, 0.0]));
    let scaling = source.scaling();
    if !scaling.is_identity() {
        v = v.with_scaling(scaling)?;
    }
    v.notes = notes;
    v.cells = cells.map(std::sync::Arc::new);
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::in_place::in_place;

    /// Level `l` voxel (x, y, z) by the pyramid's definition, recursively: the mean of the up-to-8 voxels of level
    /// `l - 1` it covers (an axis of length 1 is not halved), rounded half away from zero.
    fn by_definition(src: &[i16], dims: [u32; 3], l: u32, at: [u32; 3]) -> f64 {
        if l == 0 {
            let [x, y, z] = at.map(|v| v as usize);
            return f64::from(src[x + dims[0] as usize * (y + dims[1] as usize * z)]);
        }
        let below = level_dims(dims, l - 1);
        let f = below.map(|n| if n > 1 { 2 } else { 1 });
        let mut values = Vec::new();
        for dz in 0..f[2] {
            for dy in 0..f[1] {
                for dx in 0..f[0] {
                    let c = [at[0] * f[0] + dx, at[1] * f[1] + dy, at[2] * f[2] + dz];
                    if (0..3).all(|i| c[i] < below[i]) {
                        values.push(by_definition(src, dims, l - 1, c));
                    }
                }
            }
        }
        (values.iter().sum::<f64>() / values.len() as f64).round()
    }

    #[test]
    fn levels_read_in_place_and_from_memory_match_the_definition() {
        let dims = [37u32, 21, 40];
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let src: Vec<i16> = (0..n).map(|i| ((i * 7919) % 601) as i16 - 300).collect();
        let (path, opts) = crate::scale::test_file::int16_raw("level", dims, &src, None);
        let place = in_place(&path, &opts).unwrap().expect("raw is read in place");
        let from_file = Source::in_place(place).unwrap();
        let loaded = Source::Loaded(Box::new(crate::formats::open(&path, &opts).unwrap()));
        for level in 1..=3 {
            let a = read_level(&from_file, level, 1 << 30, Vec::new(), &mut |_| {}).unwrap();
            let b = read_level(&loaded, level, 1 << 30, Vec::new(), &mut |_| {}).unwrap();
            let out = level_dims(dims, level);
            assert_eq!(a.dims, out);
            for z in 0..out[2] {
                for y in 0..out[1] {
                    for x in 0..out[0] {
                        let want = by_definition(&src, dims, level, [x, y, z]);
                        assert_eq!(a.value(x, y, z), want, "level {level} at ({x}, {y}, {z})");
                        assert_eq!(b.value(x, y, z), want, "loaded, level {level} at ({x}, {y}, {z})");
                    }
                }
            }
            // Level 0's range per cell of 8 voxels of the level read, as held (int16 biased by 32768).
            let cells = a.cells.as_deref().expect("the pass made level 0's ranges");
            let side = 8 << level;
            assert_eq!((cells.cell, cells.dims), (side, dims));
            for (k, &range) in cells.ranges.iter().enumerate() {
                let c = [
                    k as u32 % cells.grid[0],
                    k as u32 / cells.grid[0] % cells.grid[1],
                    k as u32 / (cells.grid[0] * cells.grid[1]),
                ];
                let mut want: Option<(f64, f64)> = None;
                for z in c[2] * side..((c[2] + 1) * side).min(dims[2]) {
                    for y in c[1] * side..((c[1] + 1) * side).min(dims[1]) {
                        for x in c[0] * side..((c[0] + 1) * side).min(dims[0]) {
                            let v = f64::from(src[(x + dims[0] * (y + dims[1] * z)) as usize]) + 32768.0;
                            want = Some(want.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
                        }
                    }
                }
                assert_eq!(range, want, "level {level}, cell {c:?}");
            }
            // Level 1's first voxel is centred between voxels 0 and 1 of level 0 on every halved axis.
            if level == 1 {
                let centre = a.geometry.affine.transform_point3(glam::DVec3::ZERO);
                assert_eq!(centre, glam::DVec3::splat(0.5));
            }
        }
        std::fs::remove_dir_all(path.parent().unwrap()).ok();
    }

    #[test]
    fn slabs_wider_than_the_budget_allows_are_refused_before_reading() {
        // 16384x16384x4 uint8, sparse (no disk): level 1 takes 2 slices of 256 MiB at once.
        let dir = std::env::temp_dir().join(format!("volcast-wide-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("wide_16384x16384x4_uint8.raw");
        std::fs::File::create(&path)
            .unwrap()
            .set_len(16384 * 16384 * 4)
            .unwrap();
        let place = in_place(&path, &Default::default()).unwrap().unwrap();
        let source = Source::in_place(place).unwrap();
        let e = read_level(&source, 1, 1 << 28, Vec::new(), &mut |_| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("takes 2 slices of 16384x16384 at once (512 MiB)"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
