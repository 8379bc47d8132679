//! What a pool texel holds and how rows of texels are written from the levels the host holds: the whole pool at
//! once (gpu_volume.rs) or one slot at a time (brick_upload.rs), rows on every core.

use super::pool::{Pool, PoolRows, Source};
use crate::volume::{Volume, VoxelData};

/// Each level's elements, level 0 (the volume) first, as the pool's sources index them (`pool::Source`).
pub(super) enum Levels<'a> {
    U8(Vec<&'a [u8]>),
    U16(Vec<&'a [u16]>),
    F32(Vec<&'a [f32]>),
}

impl<'a> Levels<'a> {
    /// `volume` and the levels above it (all of one element type).
    pub(super) fn of(volume: &'a Volume, pyramid: &'a [Volume]) -> Levels<'a> {
        Levels::held(volume, pyramid, 0)
    }

    /// `volume` as level `held` and the levels above it; levels below it are empty (read from the file by brick).
    pub(super) fn held(volume: &'a Volume, pyramid: &'a [Volume], held: u32) -> Levels<'a> {
        let all = std::iter::once(volume).chain(pyramid);
        let below = held as usize;
        match &volume.data {
            VoxelData::U8(_) => Levels::U8(
                vec![&[][..]; below]
                    .into_iter()
                    .chain(all.filter_map(|v| v.data.as_u8()))
                    .collect(),
            ),
            VoxelData::U16(_) => Levels::U16(
                vec![&[][..]; below]
                    .into_iter()
                    .chain(all.filter_map(|v| v.data.as_u16()))
                    .collect(),
            ),
            VoxelData::F32(_) => Levels::F32(
                vec![&[][..]; below]
                    .into_iter()
                    .chain(all.filter_map(|v| v.data.as_f32()))
                    .collect(),
            ),
        }
    }

    /// One box of voxels read from a file as the only level.
    pub(super) fn single(data: &'a VoxelData) -> Levels<'a> {
        match data {
            VoxelData::U8(v) => Levels::U8(vec![v]),
            VoxelData::U16(v) => Levels::U16(vec![v]),
            VoxelData::F32(v) => Levels::F32(vec![v]),
        }
    }
}

/// What a pool texel holds: the voxel as stored (R8, R16 or R32 float data), 8- and 16-bit voxels widened to
/// float as a UNORM texture would return them (stored / 255 or / 65535, so `Volume::gpu_scale_bias` holds
/// unchanged), or a corner texel: the four values of the 2×2 square of the cell it starts in x and y (neighbours
/// clamped to the rows' end; within a slot they are the brick's own voxels and border), which the march fetches
/// at z and z + 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum TexelKind {
    Native,
    Widened,
    Corners8,
    Corners16,
}

impl TexelKind {
    pub(super) fn bytes(self, levels: &Levels) -> usize {
        match (self, levels) {
            (TexelKind::Native, Levels::U8(_)) => 1,
            (TexelKind::Native, Levels::U16(_)) => 2,
            (TexelKind::Corners16, _) => 8,
            _ => 4,
        }
    }
}

/// Writes a row that is one level's contiguous elements: `(level, first element, row)`.
pub(super) type Run<'a, T> = Option<&'a (dyn Fn(u32, usize, &mut [T]) + Sync)>;

/// Rows of pool texels to write: the whole pool from a texel on (`PoolFrom`), or one slot (brick_upload.rs).
pub(super) trait TexelRows: Sync {
    /// Fills `dst` row by row with `texel(row sources, x)`; the next row's sources only where `pairs` asks (a
    /// corner texel reads them; the others read their own row). Where `run` is given, a row whose texel x is
    /// element `first + x` of one level (a slot's row away from the level's x edges) is written by
    /// `run(level, first, row)` instead, without its sources.
    fn fill<T: Send>(&self, dst: &mut [T], pairs: bool, texel: impl Fn(&PoolRows, usize) -> T + Sync, run: Run<T>);
    /// The last x of a row.
    fn last_x(&self) -> usize;
}

/// The whole pool's texels from texel `first` on (`Pool::fill`).
pub(super) struct PoolFrom<'a> {
    pub pool: &'a Pool,
    pub first: usize,
}

impl TexelRows for PoolFrom<'_> {
    fn fill<T: Send>(&self, dst: &mut [T], pairs: bool, texel: impl Fn(&PoolRows, usize) -> T + Sync, _: Run<T>) {
        // The pool's rows cross slots: no row is one level's run.
        self.pool.fill(self.first, dst, pairs, texel);
    }

    fn last_x(&self) -> usize {
        self.pool.texels()[0] as usize - 1
    }
}

/// Writes `rows`' texels of `kind` from `levels` into `dst`, rows on every core.
pub(super) fn write_texels(rows: &impl TexelRows, levels: &Levels, kind: TexelKind, dst: &mut [u8]) {
    let last = rows.last_x();
    let square = |r: &PoolRows, x: usize, at: &dyn Fn(Option<Source>) -> u32| {
        let x1 = (x + 1).min(last);
        [at(r.this[x]), at(r.this[x1]), at(r.next[x]), at(r.next[x1])]
    };
    let floats = bytemuck::cast_slice_mut::<u8, f32>;
    let pairs = matches!(kind, TexelKind::Corners8 | TexelKind::Corners16);
    match (levels, kind) {
        (Levels::U8(v), TexelKind::Native) => rows.fill(
            dst,
            pairs,
            |r, x| r.this[x].map_or(0, |(l, i)| v[l as usize][i]),
            Some(&|l, i, out: &mut [u8]| out.copy_from_slice(&v[l as usize][i..i + out.len()])),
        ),
        (Levels::U16(v), TexelKind::Native) => rows.fill(
            bytemuck::cast_slice_mut::<u8, u16>(dst),
            pairs,
            |r, x| r.this[x].map_or(0, |(l, i)| v[l as usize][i]),
            Some(&|l, i, out: &mut [u16]| out.copy_from_slice(&v[l as usize][i..i + out.len()])),
        ),
        (Levels::U8(v), TexelKind::Widened) => rows.fill(
            floats(dst),
            pairs,
            |r, x| r.this[x].map_or(0.0, |(l, i)| f32::from(v[l as usize][i]) / 255.0),
            Some(&|l, i, out: &mut [f32]| widen(&v[l as usize][i..i + out.len()], 255.0, out)),
        ),
        (Levels::U16(v), TexelKind::Widened) => rows.fill(
            floats(dst),
            pairs,
            |r, x| r.this[x].map_or(0.0, |(l, i)| f32::from(v[l as usize][i]) / 65535.0),
            Some(&|l, i, out: &mut [f32]| widen(&v[l as usize][i..i + out.len()], 65535.0, out)),
        ),
        (Levels::F32(v), _) => rows.fill(
            floats(dst),
            pairs,
            |r, x| r.this[x].map_or(0.0, |(l, i)| v[l as usize][i]),
            Some(&|l, i, out: &mut [f32]| out.copy_from_slice(&v[l as usize][i..i + out.len()])),
        ),
        (Levels::U8(v), _) => {
            let at = |s: Option<Source>| s.map_or(0, |(l, i)| u32::from(v[l as usize][i]));
            let corners = |r: &PoolRows, x| {
                let c = square(r, x, &at);
                c[0] | c[1] << 8 | c[2] << 16 | c[3] << 24
            };
            rows.fill(bytemuck::cast_slice_mut::<u8, u32>(dst), pairs, corners, None)
        }
        (Levels::U16(v), _) => {
            let at = |s: Option<Source>| s.map_or(0, |(l, i)| u32::from(v[l as usize][i]));
            let corners = |r: &PoolRows, x| {
                let c = square(r, x, &at);
                [c[0] | c[1] << 16, c[2] | c[3] << 16]
            };
            rows.fill(bytemuck::cast_slice_mut::<u8, [u32; 2]>(dst), pairs, corners, None)
        }
    }
}

/// `out[x]` = `from[x] / max`: 8- and 16-bit elements as a UNORM texture returns them.
fn widen<E: Copy + Into<f32>>(from: &[E], max: f32, out: &mut [f32]) {
    for (o, &e) in out.iter_mut().zip(from) {
        *o = e.into() / max;
    }
}
