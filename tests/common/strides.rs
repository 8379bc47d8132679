//! Rule 2's brick strides, written from the definition in `RenderSettings`' docs: per 8³-voxel brick the range of
//! its values and a one-voxel apron, the largest extinction of the classification over the table entries that
//! range reaches inside the window, and from it the longest stride whose segments stay within the frame's depth
//! bound. No code shared with `render::skip` (the GPU's brick grid and classes).

use super::segments::Segments;
use glam::DVec3;
use volcast::scene::settings::{CompositeMode, RenderSettings, STRIDES};

/// Brick edge in voxels (rule 2).
const BRICK: usize = 8;
/// The classification table's entries (rule 4).
const ENTRIES: usize = 4096;

/// Per brick (x fastest) the smallest and largest normalised value over its voxels and a one-voxel apron, NaN
/// ignored (None: only NaN).
pub struct BrickRanges {
    bricks: [usize; 3],
    ranges: Vec<Option<(f64, f64)>>,
}

impl BrickRanges {
    pub fn new(values: &[f64], dims: [usize; 3]) -> BrickRanges {
        let bricks = dims.map(|d| d.div_ceil(BRICK));
        let mut ranges = Vec::with_capacity(bricks.iter().product());
        // The voxels a brick's samples read along one axis: its own and one either side, inside the grid.
        let reach = |b: usize, n: usize| (b * BRICK).saturating_sub(1)..=((b + 1) * BRICK).min(n - 1);
        for bz in 0..bricks[2] {
            for by in 0..bricks[1] {
                for bx in 0..bricks[0] {
                    let mut range: Option<(f64, f64)> = None;
                    for z in reach(bz, dims[2]) {
                        for y in reach(by, dims[1]) {
                            for x in reach(bx, dims[0]) {
                                let v = values[x + dims[0] * (y + dims[1] * z)];
                                if v.is_nan() {
                                    continue;
                                }
                                range = Some(range.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
                            }
                        }
                    }
                    ranges.push(range);
                }
            }
        }
        BrickRanges { bricks, ranges }
    }
}

impl BrickRanges {
    /// Widens each brick's range by that of the brick over it in `coarse`, level `l`'s ranges (a level-L brick of
    /// 8 voxels covers 2^L bricks of level 0 per axis).
    pub fn widen(&mut self, coarse: &BrickRanges, l: usize) {
        for (k, range) in self.ranges.iter_mut().enumerate() {
            let b = [
                k % self.bricks[0],
                k / self.bricks[0] % self.bricks[1],
                k / (self.bricks[0] * self.bricks[1]),
            ];
            let c = [0, 1, 2].map(|a| (b[a] >> l).min(coarse.bricks[a] - 1));
            if let Some((lo, hi)) = coarse.ranges[c[0] + coarse.bricks[0] * (c[1] + coarse.bricks[1] * c[2])] {
                *range = Some(range.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))));
            }
        }
    }
}

/// Extinction of the classification at each table entry's value, clamped into the window (the table's entries
/// beyond it repeat its edges).
fn extinctions(s: &RenderSettings, segments: &Segments) -> Vec<f64> {
    let (window, last) = (s.colour.window.map(f64::from), (ENTRIES - 1) as f64);
    (0..ENTRIES)
        .map(|e| segments.point((e as f64 / last).clamp(window[0], window[1])).1)
        .collect()
}

/// Rule 2's test of emptiness for emission, as a function of a value range: some table entry that the part of the
/// range inside the window reaches has extinction above 0.
pub fn visible_emission(s: &RenderSettings, segments: &Segments) -> impl Fn(f64, f64) -> bool {
    let (sigma, window) = (extinctions(s, segments), s.colour.window.map(f64::from));
    let last = (ENTRIES - 1) as f64;
    move |lo, hi| {
        let (lo, hi) = (lo.max(window[0]), hi.min(window[1]));
        if lo > hi {
            return false;
        }
        let i = (lo.clamp(0.0, 1.0) * last).floor() as usize;
        let j = ((hi.clamp(0.0, 1.0) * last).ceil() as usize).min(ENTRIES - 1);
        sigma[i..=j].iter().any(|&v| v > 0.0)
    }
}

/// The stride of every brick for one frame.
pub struct Strides {
    dims: [usize; 3],
    bricks: [usize; 3],
    stride: Vec<u64>,
}

impl Strides {
    /// Rule 2's strides for frame `s`, or None where the rule does not apply (every sample is taken).
    pub fn new(ranges: &BrickRanges, dims: [usize; 3], s: &RenderSettings, segments: &Segments) -> Option<Strides> {
        if !matches!(s.compositing.mode, CompositeMode::Emission | CompositeMode::Density) || s.sampling.max_stride <= 1
        {
            return None;
        }
        let window = s.colour.window.map(f64::from);
        let last = (ENTRIES - 1) as f64;
        let sigma = extinctions(s, segments);
        let (step, depth, spread) = (f64::from(s.sampling.step_length), s.stride_depth(), s.stride_spread());
        let stride = ranges
            .ranges
            .iter()
            .map(|range| {
                let Some((lo, hi)) = *range else {
                    return 1;
                };
                let beyond = lo < window[0] || hi > window[1];
                let (lo, hi) = (lo.max(window[0]), hi.min(window[1]));
                if lo > hi {
                    return 1;
                }
                let i = (lo.clamp(0.0, 1.0) * last).floor() as usize;
                let j = ((hi.clamp(0.0, 1.0) * last).ceil() as usize).min(ENTRIES - 1);
                let sigma_b = sigma[i..=j].iter().copied().fold(0.0, f64::max);
                if sigma_b <= 0.0 {
                    // Empty: every sample is taken (none adds anything).
                    return 1;
                }
                let sigma_min = if beyond {
                    0.0
                } else {
                    sigma[i..=j].iter().copied().fold(f64::INFINITY, f64::min)
                };
                STRIDES
                    .into_iter()
                    .filter(|&k| {
                        let length = f64::from(k) * step;
                        k <= s.sampling.max_stride
                            && sigma_b * length <= depth
                            && (sigma_b - sigma_min) * length <= spread
                    })
                    .max()
                    .map_or(1, u64::from)
            })
            .collect();
        Some(Strides {
            dims,
            bricks: ranges.bricks,
            stride,
        })
    }

    /// Rule 13: every brick that the box with corners `corners` (base voxel index, centres at integers) touches
    /// takes every sample.
    pub fn take_every_sample(&mut self, corners: &[DVec3; 8]) {
        let (lo, hi) = corners
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), &p| {
                (a.min(p), b.max(p))
            });
        let brick = |v: f64| ((v + 0.5) / BRICK as f64).floor();
        if (0..3).any(|a| brick(lo[a]) > (self.bricks[a] - 1) as f64 || brick(hi[a]) < 0.0) {
            return;
        }
        let span = |a: usize| {
            let last = (self.bricks[a] - 1) as f64;
            (brick(lo[a]).max(0.0) as usize)..=(brick(hi[a]).min(last) as usize)
        };
        for z in span(2) {
            for y in span(1) {
                for x in span(0) {
                    self.stride[x + self.bricks[0] * (y + self.bricks[1] * z)] = 1;
                }
            }
        }
    }

    /// The stride of the brick holding texture point `tex` (1 in empty bricks, whose samples add nothing).
    pub fn at(&self, tex: DVec3) -> u64 {
        let brick = |a: usize| {
            let b = (tex[a] * self.dims[a] as f64 / BRICK as f64).floor();
            b.clamp(0.0, (self.bricks[a] - 1) as f64) as usize
        };
        self.stride[brick(0) + self.bricks[0] * (brick(1) + self.bricks[1] * brick(2))]
    }
}
