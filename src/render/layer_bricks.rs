//! Empty-space skipping and strides in layered frames (rules 2 and 13): which of the base's skip bricks a layer may
//! show something in. Those bricks take every sample (a layer is point-sampled at each) and are never leapt over;
//! elsewhere the base's own classes hold, since no layer shows anything there.
//!
//! Each layer is summarised once, in blocks of [`BLOCK`]³ of its own voxels: an overlay's value range over every
//! voxel a sample in the block can read (the block and a one-voxel apron), a label map's whether any id there is
//! visible. A frame marks every base brick that the box of a block which may show something touches.

use crate::scene::layers::{LayerKind, LayerStyle};
use crate::volume::labels::LabelMap;
use crate::volume::{Geometry, Volume};
use glam::{DMat4, DVec3};

/// A summary block's side, in the layer's voxels.
const BLOCK: u32 = 4;

/// What a layer's blocks hold, x fastest.
pub(super) enum Blocks {
    /// Per block: the smallest and largest value, and the largest |value| (NaN left out).
    Overlay(Vec<[f32; 3]>),
    /// Per block: whether any id there has a visible colour.
    Labels(Vec<bool>),
}

/// A layer's summary: its blocks, their grid and the layer's placement.
pub(super) struct Summary {
    blocks: Blocks,
    grid: [u32; 3],
    dims: [u32; 3],
    geometry: Geometry,
}

impl Summary {
    /// An overlay's value ranges.
    pub(super) fn overlay(v: &Volume) -> Summary {
        Summary::of(
            v.dims,
            v.geometry,
            |i| v.value_at_index(i) as f32,
            |vals| {
                let mut r = [f32::INFINITY, f32::NEG_INFINITY, 0.0];
                for x in vals.filter(|x| !x.is_nan()) {
                    r = [r[0].min(x), r[1].max(x), r[2].max(x.abs())];
                }
                r
            },
        )
        .map_overlay()
    }

    /// A label map's visible blocks: `rgba` is each dense id's colour (opacity 0: hidden).
    pub(super) fn labels(v: &Volume, map: &LabelMap, rgba: &[[u8; 4]]) -> Summary {
        let visible: Vec<bool> = rgba.iter().map(|c| c[3] > 0).collect();
        Summary::of(
            v.dims,
            v.geometry,
            |i| map.index[i] as f32,
            |ids| ids.into_iter().any(|k| visible[k as usize]),
        )
        .map_labels()
    }

    /// Marks (as 1, every sample taken) each of the base's skip bricks (`bricks`, of `brick` base voxels; the base
    /// `dims` voxels placed by `base`) where this layer, styled `style`, may show something.
    pub(super) fn mark(
        &self,
        style: &LayerStyle,
        levels: &mut [u8],
        bricks: [u32; 3],
        brick: u32,
        base: (&Geometry, [u32; 3]),
    ) {
        for (a, b) in self.boxes_in_base(style, base.0) {
            mark_box(levels, bricks, brick, (a, b));
        }
    }

    /// The box in the base's texture space (the base `dims` voxels placed by `base`) holding every point where
    /// this layer, styled `style`, may show something; None where it shows nothing.
    pub(super) fn bounds(&self, style: &LayerStyle, base: (&Geometry, [u32; 3])) -> Option<(DVec3, DVec3)> {
        let n = DVec3::from_array(base.1.map(f64::from));
        self.boxes_in_base(style, base.0)
            .map(|(a, b)| ((a + 0.5) / n, (b + 0.5) / n))
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// Per block that may show something, the box in the base's voxel index space (through `base`'s placement)
    /// around the box of the block's voxels and a one-voxel apron: every point whose sample reads one of them.
    fn boxes_in_base<'a>(
        &'a self,
        style: &'a LayerStyle,
        base: &Geometry,
    ) -> impl Iterator<Item = (DVec3, DVec3)> + 'a {
        let shown = style.visible && style.opacity > 0.0;
        let to_base = base.affine.inverse() * self.geometry.affine;
        self.block_indices()
            .filter(move |&(b, ..)| shown && self.may_show(b, style))
            .map(move |(_, bz, by, bx)| {
                let lo = DVec3::new(bx as f64, by as f64, bz as f64) * f64::from(BLOCK) - 1.0;
                let hi = (lo + f64::from(BLOCK) + 1.0).min(DVec3::from_array(self.dims.map(f64::from)));
                box_through(to_base, (lo, hi))
            })
    }

    fn may_show(&self, b: usize, style: &LayerStyle) -> bool {
        match (&self.blocks, style.kind) {
            (Blocks::Labels(v), LayerKind::Labels) => v[b],
            (Blocks::Overlay(r), LayerKind::Overlay) => {
                let [lo, hi, abs] = r[b].map(f64::from);
                match style.threshold {
                    _ if lo > hi => false,
                    Some(t) if style.signed => abs >= t,
                    Some(t) => hi >= t,
                    None => hi >= style.window[0] && lo <= style.window[1],
                }
            }
            // A style of the other kind is refused before a frame (`GpuLayers::write`); mark it all.
            _ => true,
        }
    }

    fn block_indices(&self) -> impl Iterator<Item = (usize, u32, u32, u32)> + '_ {
        let [gx, gy, gz] = self.grid;
        (0..gz)
            .flat_map(move |z| (0..gy).flat_map(move |y| (0..gx).map(move |x| (z, y, x))))
            .enumerate()
            .map(|(b, (z, y, x))| (b, z, y, x))
    }

    /// Per block of `dims` (with a one-voxel apron), `reduce` of the values `at` gives.
    fn of<T>(
        dims: [u32; 3],
        geometry: Geometry,
        at: impl Fn(usize) -> f32,
        reduce: impl Fn(Box<dyn Iterator<Item = f32> + '_>) -> T,
    ) -> Generic<T> {
        let grid = dims.map(|d| d.div_ceil(BLOCK));
        let [w, h, d] = dims.map(|x| x as i64);
        let mut out = Vec::with_capacity(grid.iter().map(|&g| g as usize).product());
        for bz in 0..grid[2] as i64 {
            for by in 0..grid[1] as i64 {
                for bx in 0..grid[0] as i64 {
                    let span =
                        |b: i64, n: i64| (b * BLOCK as i64 - 1).max(0)..(b * BLOCK as i64 + BLOCK as i64 + 1).min(n);
                    let (xs, ys, zs) = (span(bx, w), span(by, h), span(bz, d));
                    let at = &at;
                    let values = zs.flat_map(move |z| {
                        let xs = xs.clone();
                        ys.clone()
                            .flat_map(move |y| xs.clone().map(move |x| at((x + w * (y + h * z)) as usize)))
                    });
                    out.push(reduce(Box::new(values)));
                }
            }
        }
        Generic {
            blocks: out,
            grid,
            dims,
            geometry,
        }
    }
}

/// A summary before its blocks are typed.
struct Generic<T> {
    blocks: Vec<T>,
    grid: [u32; 3],
    dims: [u32; 3],
    geometry: Geometry,
}

impl Generic<[f32; 3]> {
    fn map_overlay(self) -> Summary {
        Summary {
            blocks: Blocks::Overlay(self.blocks),
            grid: self.grid,
            dims: self.dims,
            geometry: self.geometry,
        }
    }
}

impl Generic<bool> {
    fn map_labels(self) -> Summary {
        Summary {
            blocks: Blocks::Labels(self.blocks),
            grid: self.grid,
            dims: self.dims,
            geometry: self.geometry,
        }
    }
}

/// The box around the image of the box [lo, hi] through `to`.
fn box_through(to: DMat4, (lo, hi): (DVec3, DVec3)) -> (DVec3, DVec3) {
    let corners = (0..8).map(|c| {
        DVec3::new(
            if c & 1 == 0 { lo.x } else { hi.x },
            if c & 2 == 0 { lo.y } else { hi.y },
            if c & 4 == 0 { lo.z } else { hi.z },
        )
    });
    let (mut a, mut b) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in corners.map(|c| to.transform_point3(c)) {
        (a, b) = (a.min(p), b.max(p));
    }
    (a, b)
}

/// Marks the base bricks touched by the box [a, b] of the base's index space (voxel centres are integers, and
/// brick k holds voxels k·brick … (k + 1)·brick − 1).
fn mark_box(levels: &mut [u8], bricks: [u32; 3], brick: u32, (a, b): (DVec3, DVec3)) {
    let range = |axis: usize| {
        let n = i64::from(bricks[axis]);
        let first = ((a[axis] + 0.5) / f64::from(brick)).floor() as i64;
        let last = ((b[axis] + 0.5) / f64::from(brick)).floor() as i64;
        first.max(0)..=last.min(n - 1)
    };
    for z in range(2) {
        for y in range(1) {
            for x in range(0) {
                let i = x + i64::from(bricks[0]) * (y + i64::from(bricks[1]) * z);
                levels[i as usize] = 1;
            }
        }
    }
}
