//! The pyramid's shape: how big each level is, how many level-0 voxels one of its voxels spans, and where it lies.
//! Level L + 1 halves every axis of level L that is longer than 1, rounding up ([`halve`]); an axis of length 1
//! stays 1. Level L's voxel i therefore covers level-0 voxels [i·2^L, (i + 1)·2^L) along an axis not yet at 1.

use crate::volume::geometry::Geometry;

/// `volcast convert`'s coarsest level fits in this many voxels per axis.
pub const COARSEST: u64 = 64;

/// The halving rule, on one axis: the length of the next level along an axis of `n`.
pub fn halve(n: u64) -> u64 {
    if n > 1 {
        n.div_ceil(2)
    } else {
        1
    }
}

/// The (x, y, z) shape of the level above one of `dims`.
pub fn next_level(dims: [u32; 3]) -> [u32; 3] {
    // A halved length is at most the length it halves: it fits the u32 it came from.
    dims.map(|n| halve(u64::from(n)) as u32)
}

/// The (x, y, z) shape of pyramid level `level` of a `dims` volume.
pub fn level_dims(dims: [u32; 3], level: u32) -> [u32; 3] {
    (0..level).fold(dims, |d, _| next_level(d))
}

/// The level of a `full` volume whose shape is `dims`, if the halving rule makes one (level 0 excepted: a volume is
/// its own level 0 whatever it came from).
pub fn level_of(full: [u32; 3], dims: [u32; 3]) -> Option<u32> {
    (1..32).find(|&l| level_dims(full, l) == dims)
}

/// The (x, y, z) shape of every level `volcast convert` writes, finest first: halving until every axis is at most
/// [`COARSEST`]. A volume already that small has one level.
pub fn store_levels(dims: [u64; 3]) -> Vec<[u64; 3]> {
    let mut levels = vec![dims];
    let mut d = dims;
    while d.iter().any(|&n| n > COARSEST) {
        d = d.map(halve);
        levels.push(d);
    }
    levels
}

/// Per axis, how many voxels of a level of shape `fine` one voxel of the next level spans: 2, or 1 along an axis of
/// length 1.
pub fn factors(fine: [u64; 3]) -> [usize; 3] {
    fine.map(|n| if n > 1 { 2 } else { 1 })
}

/// [`factors`] of level `level` of a `full` volume.
pub fn factors_at(full: [u32; 3], level: u32) -> [usize; 3] {
    factors(level_dims(full, level).map(u64::from))
}

/// Per level of `levels` (shapes, finest first), how many level-0 voxels (x, y, z) one of its voxels spans.
pub fn spans(levels: &[[u64; 3]]) -> Vec<[u64; 3]> {
    let mut span = [1u64; 3];
    let mut out = vec![span];
    for pair in levels.windows(2) {
        let f = factors(pair[0]);
        span = [0, 1, 2].map(|i| span[i] * f[i] as u64);
        out.push(span);
    }
    out
}

/// The geometry of level `level` of a `full` volume placed by `geometry`: each voxel spans the 2 (or 1) voxels of
/// the level below along each axis, centred on them, as `volcast convert` places its levels.
pub fn level_geometry(geometry: Geometry, full: [u32; 3], level: u32) -> Geometry {
    (0..level).fold(geometry, |g, l| {
        let f = factors_at(full, l);
        g.downsampled(f.map(|v| v as u32))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_halve_rounding_up() {
        assert_eq!(level_dims([2048, 1025, 1], 1), [1024, 513, 1]);
        assert_eq!(level_dims([5, 3, 1], 3), [1, 1, 1]);
        assert_eq!(level_of([2048, 1025, 1], [512, 257, 1]), Some(2));
        assert_eq!(level_of([2048, 1025, 1], [512, 256, 1]), None);
    }

    #[test]
    fn store_levels_halve_until_64() {
        assert_eq!(store_levels([64, 10, 1]), vec![[64, 10, 1]]);
        assert_eq!(
            store_levels([257, 65, 1]),
            vec![[257, 65, 1], [129, 33, 1], [65, 17, 1], [33, 9, 1]]
        );
        assert_eq!(factors([129, 33, 1]), [2, 2, 1]);
        assert_eq!(
            spans(&store_levels([257, 65, 1])),
            vec![[1, 1, 1], [2, 2, 1], [4, 4, 1], [8, 8, 1]]
        );
    }
}
