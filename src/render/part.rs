//! One rank's share of a volume rendered over MPI (rule 11, `src/distributed`): the rank's texture holds only its
//! part (its box of whole skip bricks and a ghost layer around it), while the march keeps the whole volume's box,
//! rays and sample grid. So every sample a rank takes lies where the single-process march takes it, and the rank
//! composites only the samples (and the segments ending at them) inside its box.
//!
//! The skip grid is the whole volume's: the classes of the box's bricks and of one ring of bricks around it come
//! from the part's voxels (the ghost layer holds their voxels and apron), every other brick is empty. The ring keeps
//! the walk's strides and segment starts at the box's faces equal to the whole march's (a segment entering the box
//! starts at the last sample the whole march took before it, in the ring), and the empty bricks beyond are leapt.

use super::gpu_volume::{occupancy_image, GpuVolume};
use super::skip::{BrickGrid, BRICK};
use super::{PartInfo, PreparedVolume, Renderer};
use crate::gpu::{Gpu, GpuError};
use crate::volume::{Geometry, Volume};

/// The ghost layer below a box: one ring of skip bricks and the apron their ranges read, rounded up to whole
/// bricks so that the part's bricks are the whole volume's.
pub const GHOST_BELOW: u32 = 2 * BRICK;
/// The ghost layer above a box: one ring of skip bricks, its apron, and the voxel a central difference reads.
pub const GHOST_ABOVE: u32 = BRICK + 2;

/// The whole volume's skip grid as one rank sees it: `part`'s grid (its texture starting at whole voxel
/// `part.origin`, a multiple of [`BRICK`]) for the box's bricks and one ring around them, empty elsewhere.
pub fn whole_grid(part_grid: &BrickGrid, part: PartInfo, whole_dims: [u32; 3]) -> BrickGrid {
    let bricks = whole_dims.map(|d| d.div_ceil(BRICK));
    let first = [0, 1, 2].map(|a| (part.lo[a] / BRICK).saturating_sub(1));
    let end = [0, 1, 2].map(|a| (part.hi[a].div_ceil(BRICK) + 1).min(bricks[a]));
    let offset = part.origin.map(|o| o / BRICK);
    let n = bricks.iter().map(|&b| b as usize).product();
    let (mut min, mut max) = (vec![f32::INFINITY; n], vec![f32::NEG_INFINITY; n]);
    for z in first[2]..end[2] {
        for y in first[1]..end[1] {
            for x in first[0]..end[0] {
                let local = [x - offset[0], y - offset[1], z - offset[2]];
                let pb = part_grid.bricks;
                if (0..3).any(|a| local[a] >= pb[a]) {
                    continue;
                }
                let from = (local[0] + pb[0] * (local[1] + pb[1] * local[2])) as usize;
                let to = (x + bricks[0] * (y + bricks[1] * z)) as usize;
                min[to] = part_grid.min[from];
                max[to] = part_grid.max[from];
            }
        }
    }
    BrickGrid { bricks, min, max }
}

impl Renderer {
    /// Shows one rank's share: `part_volume` holds the whole volume's voxels `part.origin ..` (its range and scaling
    /// already the whole's), the frames march the whole volume of `whole_dims` placed by `geometry`.
    pub fn set_volume_part(
        &mut self,
        gpu: &Gpu,
        part_volume: &Volume,
        part: PartInfo,
        whole_dims: [u32; 3],
        geometry: Geometry,
    ) -> Result<(), GpuError> {
        if part.origin.iter().any(|o| o % BRICK != 0) {
            return Err(GpuError::InvalidSettings(format!(
                "a part must start on a skip brick, not at {:?}",
                part.origin
            )));
        }
        // One brick (no page table): the march maps the whole's texture space into the part's texture.
        let mut v = GpuVolume::new(gpu, self.texel_policy, part_volume, None)?;
        let grid = whole_grid(&v.bricks, part, whole_dims);
        let occupancy = match occupancy_image(gpu, &grid) {
            Ok(o) => o,
            Err(e) => {
                v.destroy(gpu);
                return Err(e);
            }
        };
        std::mem::replace(&mut v.occupancy, occupancy).destroy(gpu);
        v.bricks = grid;
        v.info.dims = whole_dims;
        v.info.geometry = geometry;
        v.info.part = Some(part);
        self.install_volume(gpu, PreparedVolume(v));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_whole_grid_keeps_the_box_and_one_ring_and_empties_the_rest() {
        // A part starting at brick 1 (voxel 8) of a 6-brick axis, owning bricks 2..4, holding bricks 1..5.
        let pb = [4u32, 1, 1];
        let part_grid = BrickGrid {
            bricks: pb,
            min: vec![0.1, 0.2, 0.3, 0.4],
            max: vec![0.5, 0.6, 0.7, 0.8],
        };
        let part = PartInfo {
            origin: [8, 0, 0],
            lo: [16, 0, 0],
            hi: [32, 8, 8],
        };
        let g = whole_grid(&part_grid, part, [48, 8, 8]);
        assert_eq!(g.bricks, [6, 1, 1]);
        assert_eq!(g.min, vec![f32::INFINITY, 0.1, 0.2, 0.3, 0.4, f32::INFINITY]);
        assert_eq!(g.max[1..5], [0.5, 0.6, 0.7, 0.8]);
        assert!(
            g.min[0] > g.max[0] && g.min[5] > g.max[5],
            "bricks past the ring are never visible"
        );
    }
}
