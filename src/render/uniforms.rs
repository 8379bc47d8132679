//! The frame's uniform block and what it is computed from: the volume's GPU facts and the render settings.

use super::skip;
use crate::scene::layers::LayerKind;
use crate::scene::lighting::IsoSurface;
use crate::scene::settings::RenderSettings;
use crate::transfer::function::srgb_to_linear;
use crate::volume::Geometry;
use glam::{DMat3, DMat4, DVec3};

/// The uniform block `Frame` in shaders/frame.glsl (std140: only mat4 and vec4 members, so no padding rules bite).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    pub tex_to_clip: [f32; 16],
    /// Texture space to the render world (its linear part measures world lengths and directions).
    pub tex_to_world: [f32; 16],
    /// A gradient in value per voxel (index space) to a vector along the world normal: `(L·diag(1/dims))⁻ᵀ`.
    pub gradient_to_world: [f32; 16],
    pub eye_tex: [f32; 4],
    pub ray_forward: [f32; 4],
    pub ray_right: [f32; 4],
    pub ray_down: [f32; 4],
    pub origin_dx: [f32; 4],
    pub origin_dy: [f32; 4],
    pub slab_lo: [f32; 4],
    pub slab_hi: [f32; 4],
    pub extent: [f32; 4],
    pub value_map: [f32; 4],
    pub alpha: [f32; 4],
    pub background: [f32; 4],
    pub viewport: [f32; 4],
    pub texel: [f32; 4],
    pub voxel_world: [f32; 4],
    pub shading: [f32; 4],
    pub mode_params: [f32; 4],
    pub flags: [u32; 4],
    pub brick: [f32; 4],
    pub dims: [f32; 4],
    /// Rule 7's surfaces by value (`mode_params.w` of them).
    pub iso_values: [f32; 4],
    /// Per surface: linear rgb (r < 0: the classification's colour at the value) and opacity.
    pub iso_colors: [[f32; 4]; 4],
    /// xyz: unit direction towards the light (world); w: 1 directional, 0 headlight.
    pub light_dir: [f32; 4],
    /// rgb: the light's linear colour × intensity.
    pub light_color: [f32; 4],
    /// Rule 9: xyz the shadow read's offset (texture space); w: 1 shadows + 2 occlusion.
    pub light_grid: [f32; 4],
    /// Rule 10's clipping plane in texture space: p is kept where `xyz·p + w ≥ 0` (`clip::KEEP_ALL` without one).
    pub clip_plane: [f32; 4],
    /// The brick pool (render/pool.rs): xyz 1 / its size in texels.
    pub pool_inv: [f32; 4],
    /// xyz: a brick's size in voxels of its level; w: the border (`pool::BORDER`).
    pub pool_brick: [f32; 4],
    /// xyz: a slot's size in texels.
    pub pool_slot: [f32; 4],
    /// xyz: level-0 bricks per axis (the page table's size).
    pub pool_grid: [f32; 4],
    /// Rule 11 (a rank's share, src/distributed): xyz the whole volume's voxel where this texture starts; w: 1 =
    /// the partial output.
    pub part_origin: [f32; 4],
    /// xyz: the box owned, texture space of the whole (open sides at ±1e30).
    pub part_lo: [f32; 4],
    pub part_hi: [f32; 4],
}

/// GPU facts about the loaded volume that the uniforms need.
#[derive(Clone, Copy, Debug)]
pub struct VolumeInfo {
    pub dims: [u32; 3],
    /// Where the voxels are (the render world follows it unless `RenderSettings::voxel_axes`).
    pub geometry: Geometry,
    pub scale_bias: (f32, f32),
    /// The data's value range (for transfer functions in data units).
    pub range: [f64; 2],
    /// Where the march finds the bricks.
    pub pool: PoolInfo,
    /// The level the host holds: 0, or the level of a file whose finer levels' bricks are read from it
    /// (`scale::finer`). The skip grid is that level's, in bricks of `skip::BRICK` of its voxels.
    pub held: u32,
    /// The march's step is `step_length` voxels of this level: the finest level the pool shows (a cut of coarser
    /// levels takes longer steps; a file's finer levels their own voxel once they are shown).
    pub step_level: u32,
    /// Where this is one rank's share of a volume rendered over MPI (rule 11): `dims` and `geometry` are then the
    /// whole volume's, and the texture holds only the part.
    pub part: Option<PartInfo>,
    /// How many of its source's voxels one voxel of level 0 spans ([`crate::volume::Volume::source_voxels`]): a
    /// segment's opacity counts the source's voxels it crosses, so a stand-in keeps the source's optical depth.
    pub source_voxels: f32,
}

/// One rank's share of a volume (rule 11, src/distributed): its texture holds the whole volume's voxels
/// `origin .. origin + texture dims`; it composites the samples (and segments ending at them) inside `lo .. hi`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PartInfo {
    pub origin: [u32; 3],
    pub lo: [u32; 3],
    pub hi: [u32; 3],
}

impl PartInfo {
    /// The uniforms' `part_origin`, `part_lo`, `part_hi` for a volume of `dims` (a whole volume: everything owned).
    fn uniforms(part: Option<PartInfo>, dims: [u32; 3]) -> [[f32; 4]; 3] {
        let Some(p) = part else {
            return [[0.0; 4], [-1e30, -1e30, -1e30, 0.0], [1e30, 1e30, 1e30, 0.0]];
        };
        let side = |v: u32, a: usize, open: f32| {
            if (open < 0.0 && v == 0) || (open > 0.0 && v >= dims[a]) {
                open
            } else {
                (f64::from(v) / f64::from(dims[a])) as f32
            }
        };
        [
            [p.origin[0] as f32, p.origin[1] as f32, p.origin[2] as f32, 1.0],
            [
                side(p.lo[0], 0, -1e30),
                side(p.lo[1], 1, -1e30),
                side(p.lo[2], 2, -1e30),
                0.0,
            ],
            [
                side(p.hi[0], 0, 1e30),
                side(p.hi[1], 1, 1e30),
                side(p.hi[2], 2, 1e30),
                0.0,
            ],
        ]
    }
}

/// The brick pool's shape, as the uniforms carry it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PoolInfo {
    /// A brick's size in voxels.
    pub brick: [u32; 3],
    /// The pool texture's size in texels.
    pub texels: [u32; 3],
}

impl PoolInfo {
    /// One brick holding a whole volume of `dims`.
    pub fn whole(dims: [u32; 3]) -> PoolInfo {
        PoolInfo {
            brick: dims,
            texels: dims.map(super::pool::slot_side),
        }
    }
}

impl VolumeInfo {
    /// Texture space to the render world for `s` (the volume's placement, or its voxel axes).
    pub fn tex_to_world(&self, s: &RenderSettings) -> DMat4 {
        self.geometry.tex_to_world(self.dims, s.voxel_axes)
    }

    /// Rule 10's clipping plane of `s` in texture space, as the uniforms carry it.
    pub fn clip_plane(&self, s: &RenderSettings) -> [f32; 4] {
        let world_per_mm = self.geometry.world_per_mm(self.dims);
        crate::scene::clip::texture_plane_or_all(s.cut.clip_plane.as_ref(), self.tex_to_world(s), world_per_mm)
    }

    /// A voxel's step along each index axis in the render world: the columns of `L·diag(1/dims)`, L the linear
    /// part of [`VolumeInfo::tex_to_world`].
    pub fn index_to_world(&self, s: &RenderSettings) -> DMat3 {
        let dims = DVec3::from_array(self.dims.map(f64::from));
        DMat3::from_mat4(self.tex_to_world(s)) * DMat3::from_diagonal(1.0 / dims)
    }

    /// The march's step in voxels of level 0: `s.step_length` voxels of the finest level shown.
    pub fn step_length(&self, s: &RenderSettings) -> f32 {
        s.sampling.step_length * (1u32 << self.step_level) as f32
    }

    /// `s` as the march takes it on this volume: its step ([`step_length`](Self::step_length)), and no strides where
    /// the step is coarser than the held level's voxel (a skip brick, 8 of those voxels, then holds at most 4
    /// samples: a strided span would be shorter than the lookups it costs). A stand-in's segments cross
    /// `source_voxels` times as many of its source's voxels, so rule 2's stride bounds are that much tighter.
    pub fn stepped(&self, s: &RenderSettings) -> RenderSettings {
        let mut stepped = s.clone();
        stepped.sampling.step_length = self.step_length(s);
        stepped.sampling.stride_tolerance /= self.source_voxels;
        if self.step_level > self.held {
            stepped.sampling.max_stride = 1;
        }
        stepped
    }

    /// The smallest voxel side in world units (rule 2's and rule 9's voxel).
    pub fn smallest_voxel(&self, s: &RenderSettings) -> f64 {
        let m = self.index_to_world(s);
        [m.x_axis, m.y_axis, m.z_axis]
            .iter()
            .map(|c| c.length())
            .fold(f64::INFINITY, f64::min)
    }
}

/// Whether a texture-to-world transform mirrors: its box's faces then wind the other way on screen, so the
/// entry pass must cull front faces and the exit pass back faces.
pub fn mirrors(tex_to_world: DMat4) -> bool {
    DMat3::from_mat4(tex_to_world).determinant() < 0.0
}

/// The camera's rays in the world: its basis, the half-height of the view at unit distance (`tan`), the
/// image's aspect, and how much of the view widens with distance (`fan`, 1 perspective) or is laid out over the
/// eye's plane (`spread`, the orthographic view's distance).
struct CameraRays {
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    tan: f64,
    aspect: f64,
    fan: f64,
    spread: f64,
}

impl CameraRays {
    fn of(s: &RenderSettings) -> CameraRays {
        let cam = &s.camera;
        let forward = cam.forward().as_dvec3();
        let right = forward.cross(cam.up.as_dvec3()).normalize();
        // Perspective rays fan out from the eye; orthographic rays start spread over the eye's plane.
        let (fan, spread) = if cam.ortho {
            (0.0, f64::from((cam.eye - cam.target).length()))
        } else {
            (1.0, 0.0)
        };
        CameraRays {
            forward,
            right,
            up: right.cross(forward),
            tan: f64::from((cam.fov_y_deg.to_radians() * 0.5).tan()),
            aspect: f64::from(aspect(s)),
            fan,
            spread,
        }
    }
}

/// The output's width over its height, as the projection takes it (f32; rule 12: also where rays are spaced).
fn aspect(s: &RenderSettings) -> f32 {
    s.width as f32 / s.height as f32
}

/// The most steps a ray can take at world step `h`: the box's longest diagonal (under `linear`, texture space to
/// the world) in steps, and two to spare.
fn max_steps(linear: DMat3, h: f32) -> f32 {
    let diagonal = [
        DVec3::ONE,
        DVec3::new(-1.0, 1.0, 1.0),
        DVec3::new(1.0, -1.0, 1.0),
        DVec3::new(1.0, 1.0, -1.0),
    ]
    .iter()
    .map(|d| (linear * *d).length())
    .fold(0.0, f64::max) as f32;
    (diagonal / h).ceil() + 2.0
}

/// Rule 7's surfaces (the first four): their values, and per surface its linear colour and opacity.
fn iso_tables(surfaces: &[IsoSurface]) -> ([f32; 4], [[f32; 4]; 4]) {
    let mut iso_values = [0.0; 4];
    let mut iso_colors = [[0.0; 4]; 4];
    for (i, surface) in surfaces.iter().take(4).enumerate() {
        iso_values[i] = surface.value;
        let rgb = surface.color.map_or([-1.0; 3], |c| [c.x, c.y, c.z].map(srgb_to_linear));
        iso_colors[i] = [rgb[0], rgb[1], rgb[2], surface.opacity];
    }
    (iso_values, iso_colors)
}

/// The light's direction (w 1) where it has one, else zero (the headlight).
fn light_dir(s: &RenderSettings) -> [f32; 4] {
    s.light_direction().map_or([0.0; 4], |d| {
        let d = d.normalize();
        [d.x, d.y, d.z, 1.0]
    })
}

fn light_color(s: &RenderSettings) -> [f32; 4] {
    let c = s.lighting.light.color;
    let rgb = [c.x, c.y, c.z].map(|v| srgb_to_linear(v) * s.lighting.light.intensity);
    [rgb[0], rgb[1], rgb[2], 0.0]
}

/// Rule 9's light grid: the shadow read's offset and which of shadows and occlusion are on.
fn light_grid(s: &RenderSettings, v: &VolumeInfo) -> [f32; 4] {
    if s.uses_light_volume() {
        let offset = super::light_volume::grid_for(s, v).read_offset();
        let bits = u32::from(s.lighting.shadows) + 2 * u32::from(s.lighting.ambient_occlusion);
        v4(offset, bits as f32)
    } else {
        [0.0; 4]
    }
}

fn v4(a: DVec3, w: f32) -> [f32; 4] {
    [a.x as f32, a.y as f32, a.z as f32, w]
}

fn m4(m: DMat4) -> [f32; 16] {
    m.as_mat4().to_cols_array()
}

impl FrameUniforms {
    /// Pure: computes the uniforms for `s` (unit-tested without a GPU).
    pub fn new(s: &RenderSettings, v: &VolumeInfo) -> FrameUniforms {
        let cam = &s.camera;
        let model = v.tex_to_world(s);
        let linear = DMat3::from_mat4(model);
        let to_tex = linear.inverse();
        let tex_to_clip = cam.projection(aspect(s)).as_dmat4() * cam.view().as_dmat4() * model;
        let CameraRays {
            forward,
            right,
            up,
            tan,
            aspect,
            fan,
            spread,
        } = CameraRays::of(s);
        let eye_tex = model.inverse().transform_point3(cam.eye.as_dvec3());
        let dims = DVec3::from_array(v.dims.map(f64::from));
        let index_to_world = v.index_to_world(s);
        // The step in voxels of level 0; the opacity of a segment follows its length in voxels of the source.
        let step_length = v.step_length(s);
        let h = step_length * v.smallest_voxel(s) as f32;
        let shading = s.lighting.shading.unwrap_or_default();
        let surfaces = s.isosurfaces();
        let (iso_values, iso_colors) = iso_tables(&surfaces);
        let [part_origin, part_lo, part_hi] = PartInfo::uniforms(v.part, v.dims);
        let (marched_width, marched_height) = s.marched_size();
        FrameUniforms {
            tex_to_clip: m4(tex_to_clip),
            tex_to_world: m4(model),
            gradient_to_world: m4(DMat4::from_mat3(index_to_world.inverse().transpose())),
            eye_tex: v4(eye_tex, 1.0),
            ray_forward: v4(to_tex * forward, cam.near),
            ray_right: v4(to_tex * (right * (fan * tan * aspect)), 0.0),
            // NDC y grows downwards (row 0 is the top of the image).
            ray_down: v4(to_tex * (-up * (fan * tan)), 0.0),
            origin_dx: v4(to_tex * (right * (spread * tan * aspect)), 0.0),
            origin_dy: v4(to_tex * (-up * (spread * tan)), 0.0),
            slab_lo: v4(s.cut.slab_lo.as_dvec3(), 0.0),
            slab_hi: v4(s.cut.slab_hi.as_dvec3(), 0.0),
            extent: [0.0, 0.0, 0.0, h],
            value_map: [v.scale_bias.0, v.scale_bias.1, s.colour.window[0], s.colour.window[1]],
            alpha: [
                s.colour.step_alpha,
                step_length * v.source_voxels,
                s.compositing.early_termination,
                if s.colour.multiplied_alpha { 1.0 } else { 0.0 },
            ],
            background: [
                srgb_to_linear(s.background.x),
                srgb_to_linear(s.background.y),
                srgb_to_linear(s.background.z),
                1.0,
            ],
            viewport: [
                marched_width as f32,
                marched_height as f32,
                max_steps(linear, h),
                s.pipeline.count_samples as u32 as f32,
            ],
            texel: v4(1.0 / dims, 0.0),
            voxel_world: [
                s.lighting.shading_fade * (s.colour.window[1] - s.colour.window[0]),
                s.layers.iter().filter(|l| l.kind == LayerKind::Overlay).count() as f32,
                s.layers.iter().filter(|l| l.kind == LayerKind::Labels).count() as f32,
                s.lighting.gradient_opacity.unwrap_or(0.0),
            ],
            shading: [shading.ambient, shading.diffuse, shading.specular, shading.shininess],
            mode_params: [
                s.compositing.iso_value,
                s.compositing.density,
                s.looks_up_bricks() as u32 as f32,
                surfaces.len().min(4) as f32,
            ],
            brick: v4(DVec3::splat(f64::from(skip::BRICK << v.held)) / dims, 0.0),
            dims: [v.dims[0] as f32, v.dims[1] as f32, v.dims[2] as f32, 0.0],
            flags: [
                s.compositing.mode.index(),
                s.sampling.jitter.is_some() as u32,
                s.sampling.jitter.unwrap_or(0),
                s.lighting.shading.is_some() as u32,
            ],
            iso_values,
            iso_colors,
            light_dir: light_dir(s),
            light_color: light_color(s),
            light_grid: light_grid(s, v),
            clip_plane: v.clip_plane(s),
            pool_inv: v4(DVec3::from_array(v.pool.texels.map(|t| 1.0 / f64::from(t))), 0.0),
            pool_brick: {
                let [x, y, z] = v.pool.brick.map(|b| b as f32);
                [x, y, z, super::pool::BORDER as f32]
            },
            pool_slot: v4(
                DVec3::from_array(v.pool.brick.map(|b| f64::from(super::pool::slot_side(b)))),
                0.0,
            ),
            pool_grid: v4(
                DVec3::from_array([0, 1, 2].map(|a| f64::from(v.dims[a].div_ceil(v.pool.brick[a].max(1))))),
                v.step_level as f32,
            ),
            part_origin,
            part_lo,
            part_hi,
        }
    }
}
