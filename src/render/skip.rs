//! Empty-space skipping and brick strides: a grid of 8³-voxel bricks with the min/max of the values their samples
//! can see, and per frame a class per brick: empty, or the stride rule 2 of `RenderSettings` gives it. The march
//! leaps over empty bricks without moving its sample grid, so skipping changes which samples are *taken*, never
//! what they would have contributed; strides take every second or fourth sample of that grid. Pure code.

use crate::scene::settings::{CompositeMode, RenderSettings, STRIDES};
use crate::transfer::preintegrate::extinction;
use crate::volume::Volume;
use rayon::prelude::*;

/// Brick edge in voxels.
pub const BRICK: u32 = 8;

/// Per-brick value range (normalised), over every voxel a trilinear sample inside the brick reads: the brick's
/// own voxels plus a one-voxel apron. NaN is ignored; a brick of only NaN has min > max (never visible).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BrickGrid {
    pub bricks: [u32; 3],
    pub min: Vec<f32>,
    pub max: Vec<f32>,
}

impl BrickGrid {
    pub fn new(volume: &Volume) -> BrickGrid {
        let dims = volume.dims;
        let bricks = dims.map(|d| d.div_ceil(BRICK));
        // The extremes of the elements as stored, by rows (a series uploads a step per frame: this is on the
        // playback path), then normalised: normalisation is affine in the element, so the extremes map to
        // extremes (f32 rounding is monotonic too, so the result equals a per-voxel min/max of normalised f32).
        let extremes = crate::volume::cells::extremes(&volume.data, dims, BRICK, 1);
        let mut min = Vec::with_capacity(extremes.len());
        let mut max = Vec::with_capacity(extremes.len());
        for e in extremes {
            let (lo, hi) = volume.normalize_range(e);
            min.push(lo);
            max.push(hi);
        }
        BrickGrid { bricks, min, max }
    }

    /// One byte per brick (x fastest): 0 where no sample inside can be visible for frame `s` (whose baked table
    /// is `lut`), else the brick's stride (rule 2 of `RenderSettings`: 1, 2 or 4; 1 wherever strides do not
    /// apply). With `s.skip_empty` off no brick is empty.
    ///
    /// - emission/density: some table entry the brick's value range can interpolate has opacity > 0; the
    ///   stride follows from the largest extinction among those entries;
    /// - MIP/MinIP/average: the value range overlaps the window;
    /// - isosurface: the brick reaches the iso value (a crossing or a first sample ≥ iso can only lie there).
    pub fn classify(&self, lut: &[[f32; 4]], s: &RenderSettings) -> Vec<u8> {
        let window = s.colour.window;
        let absorbing = matches!(s.compositing.mode, CompositeMode::Emission | CompositeMode::Density);
        let density = (s.compositing.mode == CompositeMode::Density).then_some(f64::from(s.compositing.density));
        let sigma: Vec<f64> = lut.iter().map(|e| extinction(f64::from(e[3]), density)).collect();
        let sigma_max = RangeMax::new(sigma.clone());
        let sigma_min = RangeMax::new(sigma.iter().map(|v| -v).collect());
        // The longest stride whose segments stay within the frame's depth at extinction `sigma_b` and within
        // the spread bound of depth between the brick's faintest and strongest values (`spread_b`).
        let (depth, spread) = (s.stride_depth(), s.stride_spread());
        let stride = |sigma_b: f64, spread_b: f64| {
            STRIDES
                .into_iter()
                .filter(|&k| {
                    let length = f64::from(k) * f64::from(s.sampling.step_length);
                    k <= s.sampling.max_stride && sigma_b * length <= depth && spread_b * length <= spread
                })
                .max()
                .unwrap_or(1) as u8
        };
        let strided = absorbing && s.sampling.max_stride > 1;
        let last = lut.len().saturating_sub(1) as f32;
        let empty = if s.sampling.skip_empty { 0 } else { 1 };
        self.min
            .iter()
            .zip(&self.max)
            .map(|(&lo, &hi)| {
                if lo > hi {
                    return empty;
                }
                match s.compositing.mode {
                    CompositeMode::Emission | CompositeMode::Density => {
                        // Only values inside the window are classified (the table's entries outside it repeat
                        // its edges for interpolation); values beyond it have no extinction.
                        let beyond = lo < window[0] || hi > window[1];
                        let (lo, hi) = (lo.max(window[0]), hi.min(window[1]));
                        if lo > hi {
                            return empty;
                        }
                        let i = (lo.clamp(0.0, 1.0) * last).floor() as usize;
                        let j = ((hi.clamp(0.0, 1.0) * last).ceil() as usize).min(lut.len() - 1);
                        let sigma_b = sigma_max.max(i, j);
                        let faintest = if beyond { 0.0 } else { -sigma_min.max(i, j) };
                        if sigma_b <= 0.0 {
                            empty
                        } else if strided {
                            stride(sigma_b, sigma_b - faintest)
                        } else {
                            1
                        }
                    }
                    CompositeMode::Mip | CompositeMode::MinIp | CompositeMode::Average => {
                        if hi >= window[0] && lo <= window[1] {
                            1
                        } else {
                            empty
                        }
                    }
                    CompositeMode::Isosurface => {
                        if hi >= s.compositing.iso_value {
                            1
                        } else {
                            empty
                        }
                    }
                }
            })
            .collect()
    }
}

/// Largest element of any index range in O(1): a sparse table (levels of maxima over 2^l entries).
struct RangeMax {
    levels: Vec<Vec<f64>>,
}

impl RangeMax {
    fn new(values: Vec<f64>) -> RangeMax {
        let mut levels = vec![values];
        let mut width = 1;
        while 2 * width <= levels[0].len() {
            let prev = &levels[levels.len() - 1];
            let next = (0..prev.len() - width).map(|i| prev[i].max(prev[i + width])).collect();
            levels.push(next);
            width *= 2;
        }
        RangeMax { levels }
    }

    /// The largest of elements i..=j (i ≤ j).
    fn max(&self, i: usize, j: usize) -> f64 {
        let level = (usize::BITS - 1 - (j - i + 1).leading_zeros()) as usize;
        let row = &self.levels[level];
        row[i].max(row[j + 1 - (1 << level)])
    }
}

/// The largest reach [`encode_reach`] stores (6 bits).
pub const MAX_REACH: u8 = 63;

/// The occupancy texture's bytes: `levels` from [`BrickGrid::classify`] (0 empty, else the stride 1, 2 or 4) as
/// a 2-bit class (0 empty; strides 4, 2, 1 as 1, 2, 3) plus, in the upper 6 bits, the brick's *reach*: the
/// largest r ≤ [`MAX_REACH`] such that every brick within Chebyshev distance r (in bricks; those outside the
/// grid ignored) has the same class (capped where the cube already covers the grid). The march then walks the
/// cube of (2r + 1)³ bricks around the one it is in as one span — a leap over empty space, or a run of samples
/// at one stride without lookups — instead of brick by brick.
pub fn encode_reach(levels: &[u8], bricks: [u32; 3]) -> Vec<u8> {
    // Empty is class 0; a stride s is class 3 − log2(s), which the march turns back into 1 << (3 − class).
    let class = |l: u8| match l {
        0 => 0u8,
        1 => 3,
        2 => 2,
        _ => 1,
    };
    let classes: Vec<u8> = levels.iter().map(|&l| class(l)).collect();
    let [bx, by, bz] = bricks.map(|b| b as usize);
    // Beyond the grid's largest side less one, a larger reach covers no more bricks.
    let cap = (bx.max(by).max(bz).saturating_sub(1)).min(usize::from(MAX_REACH)) as u8;
    // The reach is the Chebyshev distance to the nearest brick of another class (inside the grid) less one, capped.
    // Per class present, that distance comes from a separable transform: the Chebyshev distance to a set is
    // min over z' of max(|dz|, min over y' of max(|dy|, min over x' of |dx|)), so three passes along the axes.
    // Distances are held capped at `far`, which reads as "no other class within reach".
    let far = cap + 1;
    let mut reach = vec![0u8; levels.len()];
    for c in 0..4u8 {
        if !classes.contains(&c) {
            continue;
        }
        let mut dist: Vec<u8> = classes.iter().map(|&k| if k == c { far } else { 0 }).collect();
        for (line, stride) in [(bx, 1), (by, bx), (bz, bx * by)] {
            dist = chebyshev_pass(&dist, line, stride, far);
        }
        for ((r, &k), &d) in reach.iter_mut().zip(&classes).zip(&dist) {
            if k == c {
                *r = d - 1;
            }
        }
    }
    classes.iter().zip(&reach).map(|(&c, &r)| (r << 2) | c).collect()
}

/// One pass of [`encode_reach`]'s distance transform along an axis whose lines are `line` bricks long, `stride`
/// apart in `dist`: each brick gets min over the bricks b' of its line of max(|b − b'|, dist[b']) (bricks past
/// the grid's edge ignored), by one sweep per distance d until d reaches the largest distance left (at most 64).
/// Along y and z the lines are swept together, a row (or plane) of `stride` bricks at a time (contiguous: it
/// vectorises), rows on every core; along x, line by line.
fn chebyshev_pass(dist: &[u8], line: usize, stride: usize, far: u8) -> Vec<u8> {
    let pad = usize::from(far);
    if stride == 1 {
        return along_x(dist, line, pad);
    }
    let mut out = dist.to_vec();
    out.par_chunks_mut(stride).enumerate().for_each(|(r, row)| {
        // Row k of block c: the rows of that block at k ± d are its line neighbours at distance d.
        let (block, k) = (r / line * line, r % line);
        let at = |j: usize| &dist[(block + j) * stride..][..stride];
        for d in 1..pad {
            if row.iter().all(|&b| usize::from(b) <= d) {
                break;
            }
            let (before, after) = (k.checked_sub(d).map(at), (k + d < line).then(|| at(k + d)));
            let d8 = d as u8;
            match (before, after) {
                (Some(a), Some(b)) => {
                    for ((o, &x), &y) in row.iter_mut().zip(a).zip(b) {
                        *o = (*o).min(x.min(y).max(d8));
                    }
                }
                (Some(a), None) | (None, Some(a)) => {
                    for (o, &x) in row.iter_mut().zip(a) {
                        *o = (*o).min(x.max(d8));
                    }
                }
                (None, None) => break,
            }
        }
    });
    out
}

/// [`chebyshev_pass`] along x: each line (contiguous) on its own, on every core.
fn along_x(dist: &[u8], line: usize, pad: usize) -> Vec<u8> {
    let mut out = dist.to_vec();
    out.par_chunks_mut(line)
        .zip(dist.par_chunks(line))
        .for_each_init(Vec::new, |padded, (best, src)| {
            // The line with `pad` ignored bricks (u8::MAX, never the minimum) on either side.
            padded.clear();
            padded.resize(line + 2 * pad, u8::MAX);
            padded[pad..pad + line].copy_from_slice(src);
            let mut d = 1;
            while d < pad && best.iter().any(|&b| usize::from(b) > d) {
                let (before, after) = (&padded[pad - d..pad - d + line], &padded[pad + d..pad + d + line]);
                for ((b, &x), &y) in best.iter_mut().zip(before).zip(after) {
                    *b = (*b).min(x.min(y).max(d as u8));
                }
                d += 1;
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{VoxelData, VoxelType};

    /// A 20×9×8 volume that is 0 everywhere except one voxel of 200 at (17, 4, 3).
    fn spike() -> Volume {
        let dims = [20u32, 9, 8];
        let mut data = vec![0u8; (dims[0] * dims[1] * dims[2]) as usize];
        data[(17 + 20 * (4 + 9 * 3)) as usize] = 200;
        Volume::new("spike", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap()
    }

    #[test]
    fn grid_covers_the_apron_and_partial_bricks() {
        let g = BrickGrid::new(&spike());
        assert_eq!(g.bricks, [3, 2, 1]);
        let at = |i: u32, j: u32, k: u32| (i + 3 * (j + 2 * k)) as usize;
        assert_eq!(g.max[at(2, 0, 0)], 1.0, "the spike's own brick");
        assert_eq!(g.max[at(1, 0, 0)], 0.0, "x = 17 is outside brick 1's apron (7..=16)");
        assert_eq!(g.max[at(2, 1, 0)], 0.0, "y = 4 is outside brick (2,1)'s apron (7..=8)");
        let mut v = spike();
        if let VoxelData::U8(d) = &mut v.data {
            d[(16 + 20 * (8 + 9 * 3)) as usize] = 100;
        }
        let v = Volume::new("s2", v.dims, v.spacing(), v.source_type, v.data).unwrap();
        let g = BrickGrid::new(&v);
        assert_eq!(
            g.max[at(1, 1, 0)],
            0.5,
            "x = 16 is brick 1's last voxel, y = 8 inside brick (·,1)"
        );
        assert_eq!(
            g.max[at(2, 1, 0)],
            0.5,
            "x = 16 is in brick 2's apron (15..=19), the spike's y = 4 is not"
        );
    }

    /// The row-wise extremes equal the definition: per brick, min/max over the brick and its apron of the
    /// normalised f32 of every non-NaN voxel; with int16 bias, a negative slope, NaN and a NaN-only brick.
    #[test]
    fn grid_equals_the_per_voxel_definition() {
        let dims = [19u32, 10, 9];
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let words: Vec<u16> = (0..n).map(|i| ((i * 7919) % 65536) as u16).collect();
        let i16v = Volume::new("i16", dims, [1.0; 3], VoxelType::I16, VoxelData::U16(words))
            .unwrap()
            .with_scaling(crate::volume::Scaling {
                slope: -2.5,
                intercept: 7.0,
            })
            .unwrap();
        let mut floats: Vec<f32> = (0..n).map(|i| ((i * 31) % 97) as f32 - 40.0).collect();
        for (i, f) in floats.iter_mut().enumerate() {
            let (x, y, z) = (i % 19, (i / 19) % 10, i / 190);
            if (x < 9 && y < 9 && z < 9) || i % 13 == 0 {
                *f = f32::NAN;
            }
        }
        let f32v = Volume::new("f32", dims, [1.0; 3], VoxelType::F32, VoxelData::F32(floats)).unwrap();
        for v in [i16v, f32v] {
            let g = BrickGrid::new(&v);
            for k in 0..g.bricks[2] {
                for j in 0..g.bricks[1] {
                    for i in 0..g.bricks[0] {
                        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
                        let r = |b: u32, d: u32| (b * BRICK).saturating_sub(1)..=((b + 1) * BRICK).min(d - 1);
                        for z in r(k, dims[2]) {
                            for y in r(j, dims[1]) {
                                for x in r(i, dims[0]) {
                                    let n = v.normalized(x, y, z) as f32;
                                    if !n.is_nan() {
                                        lo = lo.min(n);
                                        hi = hi.max(n);
                                    }
                                }
                            }
                        }
                        let b = (i + g.bricks[0] * (j + g.bricks[1] * k)) as usize;
                        assert_eq!((g.min[b], g.max[b]), (lo, hi), "{} brick ({i}, {j}, {k})", v.name);
                    }
                }
            }
        }
    }

    #[test]
    fn reach_is_the_chebyshev_distance_to_another_class_minus_one() {
        // 9×7×5 bricks at stride 1 except one empty brick at (6, 2, 1) and one at stride 4 at (0, 0, 0).
        let bricks = [9u32, 7, 5];
        let at = |x: u32, y: u32, z: u32| (x + 9 * (y + 7 * z)) as usize;
        let mut levels = vec![1u8; 9 * 7 * 5];
        levels[at(6, 2, 1)] = 0;
        levels[at(0, 0, 0)] = 4;
        let code = encode_reach(&levels, bricks);
        let class = |i: usize| code[i] & 3;
        let reach = |i: usize| code[i] >> 2;
        assert_eq!((class(at(6, 2, 1)), reach(at(6, 2, 1))), (0, 0));
        assert_eq!(class(at(0, 0, 0)), 1);
        for z in 0..5u32 {
            for y in 0..7u32 {
                for x in 0..9u32 {
                    let i = at(x, y, z);
                    if levels[i] != 1 {
                        continue;
                    }
                    let cheb = |(a, b, c): (u32, u32, u32)| x.abs_diff(a).max(y.abs_diff(b)).max(z.abs_diff(c));
                    let expected = cheb((6, 2, 1)).min(cheb((0, 0, 0))) - 1;
                    assert_eq!((class(i), u32::from(reach(i))), (3, expected), "brick ({x}, {y}, {z})");
                }
            }
        }
        // One class everywhere: a reach of 3 spans a 4³ grid from any brick, and is where it stops.
        let all = encode_reach(&[0u8; 4 * 4 * 4], [4, 4, 4]);
        assert!(all.iter().all(|&c| c == 3 << 2), "{all:?}");
    }

    #[test]
    fn reach_matches_its_definition_on_random_grids() {
        // The definition checked brick by brick: the largest r ≤ the cap with every brick within Chebyshev
        // distance r (inside the grid) of the same class. Grids of blobs (runs of one class) and of noise.
        let mut state = 12345u32;
        let mut next = move || {
            state = state.wrapping_mul(1664525).wrapping_add(1013904223);
            state >> 8
        };
        for (bricks, run) in [
            ([13u32, 6, 9], 1u32),
            ([17, 11, 7], 40),
            ([1, 1, 1], 1),
            ([70, 3, 2], 300),
        ] {
            let n = (bricks[0] * bricks[1] * bricks[2]) as usize;
            let mut levels = Vec::with_capacity(n);
            while levels.len() < n {
                let level = [0u8, 1, 2, 4][(next() % 4) as usize];
                let len = 1 + next() % run;
                levels.extend(std::iter::repeat_n(level, len as usize));
            }
            levels.truncate(n);
            let code = encode_reach(&levels, bricks);
            let [bx, by, bz] = bricks.map(|b| b as i64);
            let cap = (bx.max(by).max(bz) - 1).min(i64::from(MAX_REACH));
            let index = |x: i64, y: i64, z: i64| (x + bx * (y + by * z)) as usize;
            for z in 0..bz {
                for y in 0..by {
                    for x in 0..bx {
                        let own = levels[index(x, y, z)];
                        let same_within = |r: i64| {
                            (z - r..=z + r).all(|k| {
                                (y - r..=y + r).all(|j| {
                                    (x - r..=x + r).all(|i| {
                                        let inside = i >= 0 && j >= 0 && k >= 0 && i < bx && j < by && k < bz;
                                        !inside || levels[index(i, j, k)] == own
                                    })
                                })
                            })
                        };
                        let expected = (0..=cap).take_while(|&r| same_within(r)).last().unwrap();
                        let got = i64::from(code[index(x, y, z)] >> 2);
                        assert_eq!(got, expected, "brick ({x}, {y}, {z}) of {bricks:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn classes_follow_the_classification_and_the_stride_rule() {
        let g = BrickGrid::new(&spike());
        let mut s = RenderSettings::new(8, 8, glam::Vec3::ONE);
        let mut lut = vec![[0.0f32; 4]; 4096];
        for e in &mut lut[4000..] {
            e[3] = 0.5;
        }
        let occ = g.classify(&lut, &s);
        assert_eq!(occ.iter().filter(|&&o| o > 0).count(), 1, "{occ:?}");
        assert_eq!(occ[2], 1);
        assert!(g.classify(&vec![[0.0; 4]; 4096], &s).iter().all(|&o| o == 0));
        s.sampling.skip_empty = false;
        assert!(
            g.classify(&vec![[0.0; 4]; 4096], &s).iter().all(|&o| o == 1),
            "nothing leapt"
        );
        s.sampling.skip_empty = true;
        s.compositing.mode = CompositeMode::Mip;
        s.colour.window = [0.0, 0.1];
        assert!(
            g.classify(&lut, &s).iter().all(|&o| o == 1),
            "every brick has zeros inside the window"
        );
        s.compositing.mode = CompositeMode::Isosurface;
        s.colour.window = [0.0, 1.0];
        s.compositing.iso_value = 0.9;
        assert_eq!(g.classify(&lut, &s).iter().filter(|&&o| o > 0).count(), 1);
        // Strides: opacity 0.01 per voxel is extinction 0.01005; at 0.4-voxel steps four steps carry 0.016 ≤ 0.05.
        s.compositing.mode = CompositeMode::Emission;
        s.sampling.step_length = 0.4;
        s.sampling.max_stride = 4;
        let faint = vec![[0.2, 0.2, 0.2, 0.01f32]; 4096];
        assert!(g.classify(&faint, &s).iter().all(|&o| o == 4));
        s.sampling.max_stride = 2;
        assert!(
            g.classify(&faint, &s).iter().all(|&o| o == 2),
            "no more than the longest stride"
        );
        s.sampling.max_stride = 4;
        // Only the spike's brick reaches the opaque entries (extinction 0.69: stride 1); the others stay faint.
        let mut mixed = faint.clone();
        for e in &mut mixed[4000..] {
            e[3] = 0.5;
        }
        let classes = g.classify(&mixed, &s);
        assert_eq!((classes[2], classes[0]), (1, 4), "{classes:?}");
        // Opacity 0.05: extinction 0.0513; 0.4 × 2 × 0.0513 = 0.041 ≤ 0.05 < 0.082: stride 2. Lit frames halve
        // the bound: stride 1.
        let light = vec![[0.2, 0.2, 0.2, 0.05f32]; 4096];
        assert!(g.classify(&light, &s).iter().all(|&o| o == 2));
        s.lighting.shading = Some(crate::scene::settings::Shading::default());
        assert!(g.classify(&light, &s).iter().all(|&o| o == 1));
        s.lighting.shading = None;
        s.compositing.mode = CompositeMode::Mip;
        assert!(
            g.classify(&faint, &s).iter().all(|&o| o == 1),
            "projections never stride"
        );
    }

    #[test]
    fn range_maxima_match_a_scan() {
        let values: Vec<f64> = (0..300).map(|i| ((i * 7919) % 101) as f64).collect();
        let table = RangeMax::new(values.clone());
        for (i, j) in [(0, 0), (0, 299), (5, 6), (17, 200), (299, 299), (64, 191)] {
            let scan = values[i..=j].iter().copied().fold(f64::MIN, f64::max);
            assert_eq!(table.max(i, j), scan, "{i}..={j}");
        }
    }
}
