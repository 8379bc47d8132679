//! Per-cell value ranges of a volume's voxels: the smallest and largest element over each cell of a grid, in one
//! vectorisable sweep. The skip grid (`render::skip`) takes them over 8³-voxel bricks with a one-voxel apron; the
//! refinement rule (`render::refinable`) takes them over level 0 of the pyramid, made while the held level is read
//! (`scale::read`) and kept in the pyramid cache, so that which bricks below the held level can show anything is
//! known before they are read.

use super::{Volume, VoxelData};
use rayon::prelude::*;

/// Level 0's value range per cell of `cell` level-0 voxels per side (x fastest): elements as the volume holds
/// them (biased 8/16-bit integers, float32), NaN ignored, `None` for a cell of only NaN.
#[derive(Clone, Debug, PartialEq)]
pub struct CellRanges {
    pub cell: u32,
    /// Level 0's size; the cells cover it, the last ones partly.
    pub dims: [u32; 3],
    pub grid: [u32; 3],
    pub ranges: Vec<Option<(f64, f64)>>,
}

impl CellRanges {
    /// The cell side, in voxels of the level the ranges are made from.
    pub const SIDE: u32 = 8;

    /// The ranges of `volume`'s own voxels (its shown step) in cells of [`SIDE`](Self::SIDE) voxels.
    pub fn of(volume: &Volume) -> CellRanges {
        CellRanges {
            cell: Self::SIDE,
            dims: volume.dims,
            grid: volume.dims.map(|d| d.div_ceil(Self::SIDE)),
            ranges: extremes(&volume.data, volume.dims, Self::SIDE, 0),
        }
    }

    /// How many cells of `cell` voxels cover `dims`.
    pub fn count(dims: [u32; 3], cell: u32) -> u64 {
        dims.iter().map(|&d| u64::from(d.div_ceil(cell.max(1)))).product()
    }

    /// The bytes [`to_bytes`](Self::to_bytes) writes for cells of `cell` voxels over `dims`.
    pub fn byte_len(dims: [u32; 3], cell: u32) -> u64 {
        (TAG.len() + 16) as u64 + 16 * Self::count(dims, cell)
    }

    /// Cells of `cell` voxels over `dims`, none of them seen yet (each `None` until a layer is merged).
    pub fn unseen(dims: [u32; 3], cell: u32) -> CellRanges {
        let grid = dims.map(|d| d.div_ceil(cell.max(1)));
        CellRanges {
            cell: cell.max(1),
            dims,
            grid,
            ranges: vec![None; grid.iter().map(|&g| g as usize).product()],
        }
    }

    /// Widens layer `cz`'s cells by `layer` (one range per cell of the layer, x fastest), the ranges of some of
    /// the level-0 slices inside it.
    pub fn merge_layer(&mut self, cz: u32, layer: &[Option<(f64, f64)>]) {
        let n = (self.grid[0] * self.grid[1]) as usize;
        let at = cz as usize * n;
        for (cell, &r) in self.ranges[at..at + n].iter_mut().zip(layer) {
            *cell = union(*cell, r);
        }
    }

    /// The range over every cell that overlaps the level-0 box `lo..hi` (clamped to the volume).
    pub fn over(&self, lo: [u32; 3], hi: [u32; 3]) -> Option<(f64, f64)> {
        let first = [0, 1, 2].map(|a| (lo[a] / self.cell).min(self.grid[a] - 1));
        let last = [0, 1, 2].map(|a| (hi[a].min(self.dims[a]).max(1) - 1) / self.cell);
        let [gx, gy, _] = self.grid.map(|g| g as usize);
        let mut range = None;
        for z in first[2]..=last[2] {
            for y in first[1]..=last[1] {
                let row = gx * (y as usize + gy * z as usize);
                for x in first[0]..=last[0] {
                    range = union(range, self.ranges[row + x as usize]);
                }
            }
        }
        range
    }

    /// The bytes the pyramid cache keeps: a tag, the cell, level 0's size, then each cell's two f64 (NaN for
    /// `None`), little-endian.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(24 + 16 * self.ranges.len());
        out.extend_from_slice(TAG);
        for v in [self.cell, self.dims[0], self.dims[1], self.dims[2]] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for r in &self.ranges {
            let (a, b) = r.unwrap_or((f64::NAN, f64::NAN));
            out.extend_from_slice(&a.to_le_bytes());
            out.extend_from_slice(&b.to_le_bytes());
        }
        out
    }

    /// Reads what [`to_bytes`](Self::to_bytes) wrote for a level 0 of `dims`; `None` for anything else (another
    /// size, a truncated or foreign file): the caller reads the level again.
    pub fn from_bytes(bytes: &[u8], dims: [u32; 3]) -> Option<CellRanges> {
        let body = bytes.strip_prefix(TAG)?;
        let word = |i: usize| Some(u32::from_le_bytes(body.get(4 * i..4 * i + 4)?.try_into().ok()?));
        let (cell, stored) = (word(0)?, [word(1)?, word(2)?, word(3)?]);
        let values = &body[16..];
        if cell == 0 || stored != dims || values.len() as u64 != 16 * Self::count(dims, cell) {
            return None;
        }
        let mut out = CellRanges::unseen(dims, cell);
        for (r, pair) in out.ranges.iter_mut().zip(values.chunks_exact(16)) {
            let a = f64::from_le_bytes(pair[..8].try_into().ok()?);
            let b = f64::from_le_bytes(pair[8..].try_into().ok()?);
            *r = (a <= b).then_some((a, b));
        }
        Some(out)
    }
}

const TAG: &[u8; 8] = b"VCCELLS1";

fn union(a: Option<(f64, f64)>, b: Option<(f64, f64)>) -> Option<(f64, f64)> {
    match (a, b) {
        (Some((a0, a1)), Some((b0, b1))) => Some((a0.min(b0), a1.max(b1))),
        (a, None) => a,
        (None, b) => b,
    }
}

/// Per cell of `side` voxels (a grid over `dims`, x fastest), the smallest and largest element over its voxels
/// and `apron` voxels either side inside the volume (NaN ignored; `None` for a cell of only NaN).
pub fn extremes(data: &VoxelData, dims: [u32; 3], side: u32, apron: u32) -> Vec<Option<(f64, f64)>> {
    match data {
        VoxelData::U8(v) => extremes_of(v, dims, side, apron),
        VoxelData::U16(v) => extremes_of(v, dims, side, apron),
        VoxelData::F32(v) => extremes_of(v, dims, side, apron),
    }
}

/// An element type as volumes store it, with the values that start a running minimum and maximum.
pub trait Element: Copy + PartialOrd + Into<f64> + Send + Sync {
    /// Not below any value (a running minimum starts here).
    const HIGHEST: Self;
    /// Not above any value.
    const LOWEST: Self;
}

/// Integers run from their type's minimum to its maximum.
macro_rules! integer_element {
    ($($t:ty),*) => {$(
        impl Element for $t {
            const HIGHEST: $t = <$t>::MAX;
            const LOWEST: $t = <$t>::MIN;
        }
    )*};
}

integer_element!(u8, i8, u16, i16);

impl Element for f32 {
    const HIGHEST: f32 = f32::INFINITY;
    const LOWEST: f32 = f32::NEG_INFINITY;
}

/// `lo` takes the element-wise minimum with `values`. NaN compares false, so it never replaces anything.
/// Written as plain selects so that it vectorises.
fn merge_min<T: Element>(lo: &mut [T], values: &[T]) {
    for (l, &v) in lo.iter_mut().zip(values) {
        *l = if v < *l { v } else { *l };
    }
}

/// `hi` takes the element-wise maximum with `values`, as [`merge_min`].
fn merge_max<T: Element>(hi: &mut [T], values: &[T]) {
    for (h, &v) in hi.iter_mut().zip(values) {
        *h = if v > *h { v } else { *h };
    }
}

/// Per cell of `side` voxels, the smallest and largest element over its voxels and `apron` voxels either side
/// (NaN ignored; `None` for a cell of only NaN). Per row of cells: the rows of its y- and z-span reduced element-wise
/// to one row of minima and one of maxima, then each cell's x-span: every step a vectorisable sweep over contiguous
/// elements, each voxel read once (twice in an apron) and nothing allocated but two rows (a per-voxel walk cell by
/// cell took a fifth of loading a 1 GiB volume; reducing whole planes first cost the read pass 70%).
pub fn extremes_of<T: Element>(data: &[T], dims: [u32; 3], side: u32, apron: u32) -> Vec<Option<(f64, f64)>> {
    let [w, h, d] = dims.map(|v| v as usize);
    let [bx, by, bz] = dims.map(|d| d.div_ceil(side) as usize);
    let (b, apron) = (side as usize, apron as usize);
    let span = |k: usize, n: usize| ((k * b).saturating_sub(apron), ((k + 1) * b - 1 + apron).min(n - 1));
    let plane = w * h;
    let mut out: Vec<Option<(f64, f64)>> = vec![None; bx * by * bz];
    // Each layer of cells (k) on its own core: the layers only read the data they share at their seams.
    out.par_chunks_mut(bx * by).enumerate().for_each(|(k, layer)| {
        let (z0, z1) = span(k, d);
        let (mut row_lo, mut row_hi) = (vec![T::HIGHEST; w], vec![T::LOWEST; w]);
        for j in 0..by {
            let (y0, y1) = span(j, h);
            row_lo.fill(T::HIGHEST);
            row_hi.fill(T::LOWEST);
            for z in z0..=z1 {
                for y in y0..=y1 {
                    let row = &data[z * plane + y * w..][..w];
                    merge_min(&mut row_lo, row);
                    merge_max(&mut row_hi, row);
                }
            }
            for i in 0..bx {
                let (x0, x1) = span(i, w);
                let (mut a, mut c) = (T::HIGHEST, T::LOWEST);
                for x in x0..=x1 {
                    a = if row_lo[x] < a { row_lo[x] } else { a };
                    c = if row_hi[x] > c { row_hi[x] } else { c };
                }
                // Only NaN leaves the minimum above the maximum (a value equal to a start value sets both).
                layer[i + bx * j] = (a <= c).then(|| (a.into(), c.into()));
            }
        }
    });
    out
}
