//! Rule 1's placement of the volume's box in the world, written for the reference from the rule.

use glam::{DMat3, DMat4, DVec3};

/// Rule 1's placement of the volume's texture-space box [0, 1]³ in the world: voxel centres at (i + ½)/dims,
/// through the file's affine to millimetres (or, with `voxel_axes`, along the world's axes by the voxel sizes),
/// then moved so the box's centre is the origin and scaled so its longest side (voxels × voxel size) is 1.
pub struct Placement {
    /// Texture space to world.
    to_world: DMat4,
    to_tex: DMat4,
    /// Voxel index steps in world units (the columns: one voxel along i, j, k).
    index_to_world: DMat3,
    /// World units per millimetre: one over the box's longest side.
    world_per_mm: f64,
}

impl Placement {
    pub fn new(affine: DMat4, dims: [usize; 3], voxel_axes: bool) -> Placement {
        let n = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64);
        let linear = DMat3::from_mat4(affine);
        let sides = DVec3::new(linear.x_axis.length(), linear.y_axis.length(), linear.z_axis.length());
        let (a, t) = if voxel_axes {
            (DMat3::from_diagonal(sides), DVec3::ZERO)
        } else {
            (linear, affine.w_axis.truncate())
        };
        // mm(tex) = a·(tex ⊙ n − ½) + t; its centre (tex = ½) is a·(n − 1)/2 + t.
        let centre = a * ((n - 1.0) / 2.0) + t;
        let scale = 1.0 / (n * sides).max_element();
        let linear_tex = a * DMat3::from_diagonal(n) * scale;
        let offset = (a * DVec3::splat(-0.5) + t - centre) * scale;
        let to_world = DMat4::from_mat3_translation(linear_tex, offset);
        Placement {
            to_tex: to_world.inverse(),
            to_world,
            index_to_world: a * scale,
            world_per_mm: scale,
        }
    }

    pub fn to_world(&self, tex: DVec3) -> DVec3 {
        self.to_world.transform_point3(tex)
    }

    pub fn to_tex(&self, world: DVec3) -> DVec3 {
        self.to_tex.transform_point3(world)
    }

    /// A world direction (per world unit) in texture space.
    pub fn dir_to_tex(&self, dir: DVec3) -> DVec3 {
        self.to_tex.transform_vector3(dir)
    }

    /// World units per millimetre (the box's centre is the world's origin, so a point c + x mm from the centre is
    /// at `x·world_per_mm`).
    pub fn world_per_mm(&self) -> f64 {
        self.world_per_mm
    }

    /// A voxel's side along each index axis, in world units.
    pub fn voxel_sides(&self) -> DVec3 {
        let m = self.index_to_world;
        DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length())
    }

    /// Rule 5: the world gradient of a gradient in value per voxel: `(index_to_world)⁻ᵀ·g`.
    pub fn normal(&self, g: DVec3) -> DVec3 {
        self.index_to_world.inverse().transpose() * g
    }
}
