//! The k-d decomposition of sort-last rendering (as ParaView's `vtkKdTree` splits image data among processes): the
//! volume's voxels are split into one box per rank, each of whole skip bricks, by halving the longest side in
//! proportion to the ranks on each half; the same tree gives the ranks' visibility order for any view. Pure code.

use crate::render::skip::BRICK;

/// A rank's box of the whole volume's voxels, `lo .. hi`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Box3 {
    pub lo: [u32; 3],
    pub hi: [u32; 3],
}

impl Box3 {
    pub fn voxels(&self) -> u64 {
        (0..3).map(|a| u64::from(self.hi[a] - self.lo[a])).product()
    }
}

/// The k-d tree: a leaf is a rank; a split sends voxels below `at` on `axis` to `below`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Tree {
    Rank(usize),
    Split {
        axis: usize,
        at: u32,
        below: Box<Tree>,
        above: Box<Tree>,
    },
}

/// Where the rays come from, in the whole volume's voxel coordinates: a perspective camera's eye, or an
/// orthographic camera's direction of view.
#[derive(Clone, Copy, Debug)]
pub enum Viewer {
    Eye([f64; 3]),
    Direction([f64; 3]),
}

/// The decomposition of a volume of `dims` among `ranks` ranks.
#[derive(Clone, Debug)]
pub struct Decomposition {
    pub tree: Tree,
    /// Each rank's box, by rank.
    pub boxes: Vec<Box3>,
}

impl Decomposition {
    /// Splits `dims` into `ranks` boxes of whole bricks (a box's sides are multiples of [`BRICK`] but at the
    /// volume's far faces). Errs where the volume has fewer bricks along its sides than the ranks need.
    pub fn new(dims: [u32; 3], ranks: usize) -> Result<Decomposition, String> {
        let mut boxes = vec![None; ranks];
        let tree = split(Box3 { lo: [0; 3], hi: dims }, 0, ranks, &mut boxes)?;
        let boxes = boxes.into_iter().map(|b| b.expect("every rank gets a leaf")).collect();
        Ok(Decomposition { tree, boxes })
    }

    /// The ranks front to back as seen by `viewer`: at each split, the side the rays come from first. Every ray
    /// crosses a split plane at most once, from that side, so along every ray the boxes it meets come in this order.
    pub fn front_to_back(&self, viewer: Viewer) -> Vec<usize> {
        let mut order = Vec::with_capacity(self.boxes.len());
        visit(&self.tree, viewer, &mut order);
        order
    }
}

fn split(b: Box3, first: usize, ranks: usize, out: &mut [Option<Box3>]) -> Result<Tree, String> {
    if ranks == 1 {
        out[first] = Some(b);
        return Ok(Tree::Rank(first));
    }
    // The longest side in bricks, of those that can be split at all.
    let bricks = |a: usize| (b.hi[a] - b.lo[a]).div_ceil(BRICK);
    let axis = (0..3).max_by_key(|&a| (bricks(a), a)).expect("three axes");
    let n = bricks(axis);
    let below_ranks = ranks / 2;
    if n < 2 {
        return Err(format!(
            "a box of {:?}..{:?} voxels cannot be split among {ranks} ranks in whole {BRICK}-voxel bricks",
            b.lo, b.hi
        ));
    }
    // The split in whole bricks, in proportion to the ranks on each side, at least one brick each.
    let at_bricks = ((u64::from(n) * below_ranks as u64 + ranks as u64 / 2) / ranks as u64).clamp(1, u64::from(n) - 1);
    let at = b.lo[axis] + at_bricks as u32 * BRICK;
    let (mut lower, mut upper) = (b, b);
    lower.hi[axis] = at;
    upper.lo[axis] = at;
    Ok(Tree::Split {
        axis,
        at,
        below: Box::new(split(lower, first, below_ranks, out)?),
        above: Box::new(split(upper, first + below_ranks, ranks - below_ranks, out)?),
    })
}

fn visit(t: &Tree, viewer: Viewer, order: &mut Vec<usize>) {
    match t {
        Tree::Rank(r) => order.push(*r),
        Tree::Split { axis, at, below, above } => {
            let below_first = match viewer {
                Viewer::Eye(e) => e[*axis] < f64::from(*at),
                Viewer::Direction(d) => d[*axis] >= 0.0,
            };
            let (first, second) = if below_first { (below, above) } else { (above, below) };
            visit(first, viewer, order);
            visit(second, viewer, order);
        }
    }
}

/// The box of voxels a rank holds for `owned` within a volume of `dims`: the box with the ghost layer (rule 11)
/// below and above it, clamped to the volume.
pub fn held_box(owned: Box3, dims: [u32; 3]) -> Box3 {
    use crate::render::{GHOST_ABOVE, GHOST_BELOW};
    Box3 {
        lo: owned.lo.map(|l| l.saturating_sub(GHOST_BELOW)),
        hi: [0, 1, 2].map(|a| (owned.hi[a] + GHOST_ABOVE).min(dims[a])),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_tile_the_volume_in_whole_bricks() {
        for (dims, ranks) in [
            ([64, 64, 64], 8),
            ([100, 37, 61], 4),
            ([256, 256, 113], 3),
            ([64, 16, 8], 2),
        ] {
            let d = Decomposition::new(dims, ranks).unwrap();
            let total: u64 = d.boxes.iter().map(Box3::voxels).sum();
            assert_eq!(total, dims.iter().map(|&v| u64::from(v)).product::<u64>());
            for b in &d.boxes {
                for (a, &d) in dims.iter().enumerate() {
                    assert!(b.lo[a] % BRICK == 0 && (b.hi[a] % BRICK == 0 || b.hi[a] == d));
                    assert!(b.lo[a] < b.hi[a]);
                }
            }
            // No voxel in two boxes: the sum above equals the whole only if they do not overlap (boxes inside).
            for (i, p) in d.boxes.iter().enumerate() {
                for q in &d.boxes[i + 1..] {
                    assert!((0..3).any(|a| p.hi[a] <= q.lo[a] || q.hi[a] <= p.lo[a]), "{p:?} {q:?}");
                }
            }
        }
        assert!(Decomposition::new([8, 8, 8], 2).is_err(), "one brick cannot be split");
    }

    #[test]
    fn the_order_puts_the_eyes_side_first() {
        let d = Decomposition::new([64, 16, 16], 2).unwrap();
        assert_eq!(d.boxes[0].hi[0], 32);
        assert_eq!(d.front_to_back(Viewer::Eye([-10.0, 8.0, 8.0])), vec![0, 1]);
        assert_eq!(d.front_to_back(Viewer::Eye([100.0, 8.0, 8.0])), vec![1, 0]);
        // Inside the volume, in the upper box.
        assert_eq!(d.front_to_back(Viewer::Eye([40.0, 8.0, 8.0])), vec![1, 0]);
        assert_eq!(d.front_to_back(Viewer::Direction([-1.0, 0.0, 0.0])), vec![1, 0]);
        let eight = Decomposition::new([64, 64, 64], 8).unwrap();
        let mut order = eight.front_to_back(Viewer::Eye([70.0, -5.0, 30.0]));
        assert_eq!(order.len(), 8);
        // Along any ray from the eye the boxes met come in the order's order.
        let eye = [70.0, -5.0, 30.0];
        for target in [[1.0, 60.0, 2.0], [33.0, 40.0, 63.0], [5.0, 63.0, 60.0]] {
            let mut met = Vec::new();
            for i in 0..=1000 {
                let t = f64::from(i) / 1000.0;
                let p: Vec<f64> = (0..3).map(|a| eye[a] + t * (target[a] - eye[a])).collect();
                if let Some(r) = eight
                    .boxes
                    .iter()
                    .position(|b| (0..3).all(|a| f64::from(b.lo[a]) <= p[a] && p[a] < f64::from(b.hi[a])))
                {
                    if met.last() != Some(&r) {
                        met.push(r);
                    }
                }
            }
            let pos: Vec<usize> = met.iter().map(|r| order.iter().position(|o| o == r).unwrap()).collect();
            assert!(pos.windows(2).all(|w| w[0] < w[1]), "{met:?} against {order:?}");
        }
        order.sort();
        assert_eq!(order, (0..8).collect::<Vec<_>>());
    }

    #[test]
    fn held_boxes_add_the_ghost_layer_within_the_volume() {
        let b = held_box(
            Box3 {
                lo: [32, 0, 0],
                hi: [64, 16, 40],
            },
            [100, 16, 40],
        );
        assert_eq!(b.lo, [16, 0, 0]);
        assert_eq!(b.hi, [74, 16, 40]);
    }
}
