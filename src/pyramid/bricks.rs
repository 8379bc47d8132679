//! Bricks across levels: each level is cut into bricks of the same size in voxels, so a level-L brick covers 2^L
//! level-0 bricks per axis (fewer at the far edge), and brick b of level L has the children 2b and 2b + 1 per axis
//! in level L - 1, those that exist. Any box of level L lies over a box of level-0 voxels 2^L times larger.

use super::geometry::level_dims;

/// Bricks per axis of level `l` of a `dims` volume in bricks of `brick`.
pub fn grid_at(dims: [u32; 3], brick: [u32; 3], l: u32) -> [u32; 3] {
    let d = level_dims(dims, l);
    [0, 1, 2].map(|a| d[a].div_ceil(brick[a]))
}

/// The top level for bricks of `brick`: the first whose grid is one brick (at most 16).
pub fn top_level(dims: [u32; 3], brick: [u32; 3]) -> u32 {
    (0..16).find(|&l| grid_at(dims, brick, l) == [1, 1, 1]).unwrap_or(16)
}

/// The level-`l` brick that covers level-0 brick `b0`.
pub fn covering(b0: [u32; 3], l: u32) -> [u32; 3] {
    b0.map(|v| from_level0(v, l))
}

/// Level-`l` voxel `i` (or a length of `i` level-`l` voxels) in level-0 voxels: the first of the 2^`l` it covers.
pub fn to_level0(i: u32, l: u32) -> u32 {
    i << l
}

/// A length of `i` level-0 voxels in level-`l` voxels (`i` a multiple of 2^`l`).
pub fn from_level0(i: u32, l: u32) -> u32 {
    i >> l
}

/// The level-0 bricks under brick `b` of level `l`, as a box (first, one past the last) within `grid0`.
pub fn level0_bricks(b: [u32; 3], l: u32, grid0: [u32; 3]) -> ([u32; 3], [u32; 3]) {
    let lo = b.map(|v| to_level0(v, l));
    let hi = [0, 1, 2].map(|a| to_level0(b[a] + 1, l).min(grid0[a]));
    (lo, hi)
}

/// The bricks of level `l - 1` under brick `b` of level `l` (`l` ≥ 1), within that level's grid.
pub fn children(dims: [u32; 3], brick: [u32; 3], l: u32, b: [u32; 3]) -> Vec<[u32; 3]> {
    let g = grid_at(dims, brick, l - 1);
    (0..8u32)
        .map(|i| [0, 1, 2].map(|a| 2 * b[a] + (i >> a & 1)))
        .filter(|c| (0..3).all(|a| c[a] < g[a]))
        .collect()
}

/// The box of level-0 voxels (corner, size) under the box `lo..lo + size` of level `level` of a `full` volume,
/// clipped at the volume's far edge. Its corner is a multiple of 2^`level`, so the cascade inside it is exactly the
/// pyramid's.
pub fn level0_box(full: [u32; 3], level: u32, lo: [u32; 3], size: [u32; 3]) -> ([u32; 3], [u32; 3]) {
    let lo0 = lo.map(|v| to_level0(v, level));
    let hi0 = [0, 1, 2].map(|a| to_level0(lo[a] + size[a], level).min(full[a]));
    (lo0, [0, 1, 2].map(|a| hi0[a] - lo0[a]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_nest_and_the_top_is_one_brick() {
        assert_eq!(top_level([32, 32, 32], [16; 3]), 1);
        assert_eq!(top_level([40, 24, 16], [8; 3]), 3);
        assert_eq!(grid_at([40, 24, 16], [8; 3], 0), [5, 3, 2]);
        assert_eq!(grid_at([40, 24, 16], [8; 3], 2), [2, 1, 1]);
        assert_eq!(grid_at([40, 24, 16], [8; 3], 3), [1, 1, 1]);
        assert_eq!(covering([4, 2, 1], 2), [1, 0, 0]);
        // Brick (1, 0, 0) of level 2 over a level-0 grid of [5, 3, 2]: level-0 bricks 4..5, 0..3, 0..2.
        assert_eq!(level0_bricks([1, 0, 0], 2, [5, 3, 2]), ([4, 0, 0], [5, 3, 2]));
        // Level 1's grid is [3, 2, 1]: brick (1, 0, 0) of level 2 has two children along x, two along y, one in z.
        assert_eq!(children([40, 24, 16], [8; 3], 2, [1, 0, 0]), vec![[2, 0, 0], [2, 1, 0]]);
        // Level 2's voxels 1..3 along x of a 10-wide volume: level-0 voxels 4..10, the last block cut short.
        assert_eq!(level0_box([10, 8, 1], 2, [1, 0, 0], [2, 2, 1]), ([4, 0, 0], [6, 8, 1]));
    }
}
