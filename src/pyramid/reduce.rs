//! How a level follows from the one below: a block of up to 2x2x2 voxels becomes one voxel (the mean for
//! intensities, the most common value or the first voxel for labels), on every core.

use super::geometry::factors_at;
use super::sample::Sample;
use rayon::prelude::*;

/// How a block of fine voxels becomes one coarse voxel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reduce {
    /// The mean of the voxels the block has (a partial block at an odd edge averages fewer); integers round half
    /// away from zero.
    Mean,
    /// Labels: the most common value of the block; ties go to the smallest value.
    Mode,
    /// Labels: the block's first voxel (lowest x, y, z).
    Nearest,
}

/// Reduces `src` (`dims` = width, height, slices; x fastest) by `factor` per axis with `how`; the result has
/// `ceil(dims / factor)` voxels per axis. Rows are reduced on every core.
pub fn downsample<T: Sample>(src: &[T], dims: [usize; 3], factor: [usize; 3], how: Reduce) -> Vec<T> {
    let out = reduced(dims, factor);
    let mut dst = vec![T::default(); out[0] * out[1] * out[2]];
    downsample_into(src, dims, factor, how, &mut dst);
    dst
}

/// [`downsample`] into `dst`, which must hold the result's `ceil(dims / factor)` voxels.
pub fn downsample_into<T: Sample>(src: &[T], dims: [usize; 3], factor: [usize; 3], how: Reduce, dst: &mut [T]) {
    let [w, h, d] = dims;
    assert_eq!(src.len(), w * h * d, "slab size");
    let out = reduced(dims, factor);
    assert_eq!(dst.len(), out[0] * out[1] * out[2], "result size");
    if dst.is_empty() {
        return;
    }
    dst.par_chunks_mut(out[0]).enumerate().for_each(|(row, line)| {
        let (oy, oz) = (row % out[1], row / out[1]);
        let ys = oy * factor[1]..((oy + 1) * factor[1]).min(h);
        let zs = oz * factor[2]..((oz + 1) * factor[2]).min(d);
        // Whole 2x2x2 means straight from the four source rows (the common case, several times faster); the
        // general loop below takes what is left: a partial block at an odd edge, other factors, labels.
        let mut first = 0;
        if how == Reduce::Mean && factor == [2, 2, 2] && ys.len() == 2 && zs.len() == 2 {
            let at = |y: usize, z: usize| &src[w * (y + h * z)..][..w];
            let rows = [
                at(ys.start, zs.start),
                at(ys.start + 1, zs.start),
                at(ys.start, zs.start + 1),
                at(ys.start + 1, zs.start + 1),
            ];
            first = w / 2;
            T::mean_rows(rows, &mut line[..first]);
        }
        let mut block = [T::default(); 8];
        for (ox, slot) in line.iter_mut().enumerate().skip(first) {
            let xs = ox * factor[0]..((ox + 1) * factor[0]).min(w);
            let mut n = 0;
            for z in zs.clone() {
                for y in ys.clone() {
                    for x in xs.clone() {
                        block[n] = src[x + w * (y + h * z)];
                        n += 1;
                    }
                }
            }
            *slot = reduce(&mut block[..n], how);
        }
    });
}

/// `src`, a box of level 0 of a `full` volume (`dims`, its corner on a multiple of 2^`level`, so that the cascade
/// inside it is exactly the pyramid's), reduced level by level with the mean to the box of level `level` over it,
/// into `into`. The factors are the whole level's, not the box's: an axis of length 1 is not halved.
pub fn mean_to_level_into<T: Sample>(src: &[T], dims: [usize; 3], full: [u32; 3], level: u32, into: &mut [T]) {
    let mut dims = dims;
    let mut made: Option<Vec<T>> = None;
    for l in 0..level {
        let f = factors_at(full, l);
        let src = made.as_deref().unwrap_or(src);
        if l + 1 == level {
            return downsample_into(src, dims, f, Reduce::Mean, into);
        }
        made = Some(downsample(src, dims, f, Reduce::Mean));
        dims = reduced(dims, f);
    }
    into.copy_from_slice(src);
}

/// [`mean_to_level_into`], returning the box (`src` itself at level 0) and its shape.
pub fn mean_to_level<T: Sample>(src: Vec<T>, dims: [usize; 3], full: [u32; 3], level: u32) -> (Vec<T>, [usize; 3]) {
    let (mut data, mut dims) = (src, dims);
    for l in 0..level {
        let f = factors_at(full, l);
        data = downsample(&data, dims, f, Reduce::Mean);
        dims = reduced(dims, f);
    }
    (data, dims)
}

/// The shape [`downsample`] makes of `dims` by `factor`.
fn reduced(dims: [usize; 3], factor: [usize; 3]) -> [usize; 3] {
    [0, 1, 2].map(|i| dims[i].div_ceil(factor[i]))
}

/// One coarse voxel from the fine voxels of its block (at least one).
fn reduce<T: Sample>(block: &mut [T], how: Reduce) -> T {
    match how {
        Reduce::Nearest => block[0],
        Reduce::Mean => T::from_f64(block.iter().map(|v| v.to_f64()).sum::<f64>() / block.len() as f64),
        Reduce::Mode => {
            block.sort_by(|a, b| a.to_f64().total_cmp(&b.to_f64()));
            // Sorted ascending, and only a strictly longer run replaces the best: ties keep the smallest value.
            let (mut best, mut best_run, mut run) = (block[0], 0, 0);
            for i in 0..block.len() {
                run = if i > 0 && block[i] == block[i - 1] { run + 1 } else { 1 };
                if run > best_run {
                    best_run = run;
                    best = block[i];
                }
            }
            best
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The documented rule, voxel by voxel, with nothing shared with [`downsample`]'s indexing.
    fn mean_by_definition(src: &[i16], [w, h, d]: [usize; 3]) -> Vec<i16> {
        let mut out = Vec::new();
        for z in (0..d).step_by(2) {
            for y in (0..h).step_by(2) {
                for x in (0..w).step_by(2) {
                    let mut values = Vec::new();
                    for (dz, dy, dx) in (0..8).map(|i| (i / 4, (i / 2) % 2, i % 2)) {
                        if x + dx < w && y + dy < h && z + dz < d {
                            values.push(f64::from(src[x + dx + w * (y + dy + h * (z + dz))]));
                        }
                    }
                    let mean = values.iter().sum::<f64>() / values.len() as f64;
                    out.push(mean.round() as i16);
                }
            }
        }
        out
    }

    #[test]
    fn mean_matches_the_rule_at_odd_edges() {
        let dims = [5, 3, 3];
        // Signed values with halves of both signs, so rounding half away from zero is exercised.
        let src: Vec<i16> = (0..45).map(|i| ((i * 37) % 23) as i16 - 11).collect();
        let got = downsample(&src, dims, [2, 2, 2], Reduce::Mean);
        assert_eq!(got, mean_by_definition(&src, dims));
        assert_eq!(got.len(), 3 * 2 * 2);
        // A lone corner voxel (4, 2, 2) is its own mean.
        assert_eq!(*got.last().unwrap(), src[44]);
        assert_eq!(reduce(&mut [-1i16, -2], Reduce::Mean), -2, "-1.5 rounds away from zero");
        assert_eq!(reduce(&mut [1u8, 2], Reduce::Mean), 2, "1.5 rounds away from zero");
    }

    #[test]
    fn whole_blocks_and_edges_agree_with_the_rule() {
        // Even and odd widths, heights and depths: the whole-block path and the general one side by side.
        for dims in [[6, 4, 4], [7, 5, 3], [8, 3, 2]] {
            let n = dims[0] * dims[1] * dims[2];
            let src: Vec<i16> = (0..n).map(|i| ((i * 7919) % 257) as i16 - 128).collect();
            assert_eq!(
                downsample(&src, dims, [2, 2, 2], Reduce::Mean),
                mean_by_definition(&src, dims),
                "{dims:?}"
            );
        }
    }

    #[test]
    fn labels_take_the_most_common_or_the_first() {
        assert_eq!(
            reduce(&mut [3u16, 7, 7, 3, 9, 7, 3, 1], Reduce::Mode),
            3,
            "tie 3/7 goes to 3"
        );
        assert_eq!(reduce(&mut [5u8, 2, 2], Reduce::Mode), 2);
        let src: Vec<u8> = (0..8).collect();
        assert_eq!(downsample(&src, [2, 2, 2], [2, 2, 2], Reduce::Nearest), vec![0]);
        // An axis of length 1 is not halved.
        let flat: Vec<f32> = vec![1.0, 2.0, 3.0, 5.0];
        assert_eq!(downsample(&flat, [2, 2, 1], [2, 2, 1], Reduce::Mean), vec![2.75]);
    }
}
