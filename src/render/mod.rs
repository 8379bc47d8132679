//! The passes. `Renderer::record` writes one frame into a colour target: for the entry/exit method pass 1 (front
//! faces → entry positions), pass 2 (back faces → exit positions) and pass 3 (march); for the analytic method
//! the march alone. The same code serves headless rendering and (later) the window.

mod gpu_volume;
pub mod skip;

use gpu_volume::{image_3d, upload_3d, GpuVolume};
pub use gpu_volume::{VolumeLayout, AUTO_LIMIT};

use crate::gpu::pipeline::{compute_pipeline, graphics_pipeline, shader, GraphicsDesc, ShaderCode};
use crate::gpu::resources::{Buffer, Image, ImageDesc};
use crate::gpu::sync::{image_barriers, Access, ImageTransition};
pub use crate::gpu::TexelPolicy;
use crate::gpu::{Gpu, GpuError, VkContext};
use crate::settings::{PositionFormat, RaySetup, RenderSettings};
use crate::tf::{bake, half_pairs, srgb_to_linear, step_table, Classification, LUT_SIZE};
use crate::volume::{Geometry, Volume};
use ash::vk;
use glam::{DMat3, DMat4, DVec3};
use gpu_allocator::MemoryLocation;

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
}

impl VolumeInfo {
    /// Texture space to the render world for `s` (the volume's placement, or its voxel axes).
    pub fn tex_to_world(&self, s: &RenderSettings) -> DMat4 {
        self.geometry.tex_to_world(self.dims, s.voxel_axes)
    }
}

/// Whether a texture-to-world transform mirrors: its box's faces then wind the other way on screen, so the
/// entry pass must cull front faces and the exit pass back faces.
pub fn mirrors(tex_to_world: DMat4) -> bool {
    DMat3::from_mat4(tex_to_world).determinant() < 0.0
}

impl FrameUniforms {
    /// Pure: computes the uniforms for `s` (unit-tested without a GPU).
    pub fn new(s: &RenderSettings, v: &VolumeInfo) -> FrameUniforms {
        let aspect = s.width as f32 / s.height as f32;
        let cam = &s.camera;
        let model = v.tex_to_world(s);
        let linear = DMat3::from_mat4(model);
        let to_tex = linear.inverse();
        let tex_to_clip = cam.projection(aspect).as_dmat4() * cam.view().as_dmat4() * model;
        let forward = cam.forward().as_dvec3();
        let right = forward.cross(cam.up.as_dvec3()).normalize();
        let up = right.cross(forward);
        let tan = f64::from((cam.fov_y_deg.to_radians() * 0.5).tan());
        let eye_tex = model.inverse().transform_point3(cam.eye.as_dvec3());
        // Perspective rays fan out from the eye; orthographic rays start spread over the eye's plane.
        let (fan, spread) = if cam.ortho {
            (0.0, f64::from((cam.eye - cam.target).length()))
        } else {
            (1.0, 0.0)
        };
        let aspect = f64::from(aspect);
        let dims = DVec3::from_array(v.dims.map(f64::from));
        // A voxel's step along each index axis, in world units: the columns of L·diag(1/dims).
        let index_to_world = linear * DMat3::from_diagonal(1.0 / dims);
        let voxel = [0, 1, 2].map(|i| index_to_world.col(i).length());
        let h = s.step_length * voxel.iter().copied().fold(f64::INFINITY, f64::min) as f32;
        // The longest path through the box: its longest diagonal.
        let diagonal = [
            DVec3::ONE,
            DVec3::new(-1.0, 1.0, 1.0),
            DVec3::new(1.0, -1.0, 1.0),
            DVec3::new(1.0, 1.0, -1.0),
        ]
        .iter()
        .map(|d| (linear * *d).length())
        .fold(0.0, f64::max) as f32;
        let max_steps = (diagonal / h).ceil() + 2.0;
        let v4 = |a: DVec3, w: f32| [a.x as f32, a.y as f32, a.z as f32, w];
        let m4 = |m: DMat4| m.as_mat4().to_cols_array();
        let shading = s.shading.unwrap_or_default();
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
            slab_lo: v4(s.slab_lo.as_dvec3(), 0.0),
            slab_hi: v4(s.slab_hi.as_dvec3(), 0.0),
            extent: [0.0, 0.0, 0.0, h],
            value_map: [v.scale_bias.0, v.scale_bias.1, s.window[0], s.window[1]],
            alpha: [
                s.step_alpha,
                s.step_length,
                s.early_termination,
                if s.multiplied_alpha { 1.0 } else { 0.0 },
            ],
            background: [
                srgb_to_linear(s.background.x),
                srgb_to_linear(s.background.y),
                srgb_to_linear(s.background.z),
                1.0,
            ],
            viewport: [
                s.width as f32,
                s.height as f32,
                max_steps,
                s.count_samples as u32 as f32,
            ],
            texel: v4(1.0 / dims, 0.0),
            voxel_world: [0.0, 0.0, 0.0, s.gradient_opacity.unwrap_or(0.0)],
            shading: [shading.ambient, shading.diffuse, shading.specular, shading.shininess],
            mode_params: [s.iso_value, s.density, s.skip_empty as u32 as f32, 0.0],
            brick: v4(DVec3::splat(f64::from(skip::BRICK)) / dims, 0.0),
            dims: [v.dims[0] as f32, v.dims[1] as f32, v.dims[2] as f32, 0.0],
            flags: [
                s.mode.index(),
                s.jitter.is_some() as u32,
                s.jitter.unwrap_or(0),
                s.shading.is_some() as u32,
            ],
        }
    }
}

/// GPU time per pass of the last frame, from timestamp queries.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct PassTimings {
    /// Entry and exit passes (entry/exit method only).
    pub entry_ms: Option<f64>,
    pub exit_ms: Option<f64>,
    pub march_ms: f64,
    pub total_ms: f64,
}

/// A volume uploaded by [`Renderer::prepare_volume`] and not yet shown. Give it to
/// [`Renderer::install_volume`], or [`destroy`](Self::destroy) it.
pub struct PreparedVolume(GpuVolume);

impl PreparedVolume {
    pub fn destroy(self, gpu: &Gpu) {
        self.0.destroy(gpu);
    }
}

/// Everything the brick occupancy depends on besides the volume.
#[derive(Clone, Debug, PartialEq)]
struct OccupancyKey {
    classification: Classification,
    window: [f32; 2],
    mode: crate::settings::CompositeMode,
    iso: f32,
    adaptive: bool,
}

impl OccupancyKey {
    fn of(s: &RenderSettings) -> OccupancyKey {
        OccupancyKey {
            classification: s.classification(),
            window: s.window,
            mode: s.mode,
            iso: s.iso_value,
            adaptive: s.adaptive_step,
        }
    }
}

struct PositionTargets {
    entry: Image,
    exit: Image,
    format: PositionFormat,
}

impl PositionTargets {
    fn vk_format(format: PositionFormat) -> vk::Format {
        match format {
            PositionFormat::Rgba32f => vk::Format::R32G32B32A32_SFLOAT,
            PositionFormat::Rgba16f => vk::Format::R16G16B16A16_SFLOAT,
        }
    }

    fn destroy(self, gpu: &Gpu) {
        self.exit.destroy(gpu);
        self.entry.destroy(gpu);
    }
}

/// Rows of the table buffer: 0 the baked classification (opacity per voxel-length step, f32 RGBA); 1 and 2 the
/// same corrected for one and for two march steps and premultiplied (`tf::step_table`), which the unshaded
/// emission/density march reads instead of computing a power per sample (2: faint bricks, adaptive step),
/// stored as `tf::half_pairs` (each entry with its successor, as f16: one load per sample).
const LUT_ROWS: usize = 3;

/// What rows 1 and 2 of the table depend on beyond the classification: the step length in voxels and, for the
/// density model, its density factor.
#[derive(Clone, Copy, Debug, PartialEq)]
struct StepRule {
    steps: f32,
    density: Option<f32>,
}

impl StepRule {
    fn of(s: &RenderSettings) -> StepRule {
        StepRule {
            steps: s.step_length,
            density: (s.mode == crate::settings::CompositeMode::Density).then_some(s.density),
        }
    }
}

/// Which march pipeline family `s` uses: 0 entry/exit faces, 1 analytic (fragment), 2 analytic (compute).
fn setup_index(s: &RenderSettings) -> usize {
    match s.ray_setup {
        RaySetup::Faces => 0,
        RaySetup::Analytic if s.compute => 2,
        RaySetup::Analytic => 1,
    }
}

/// Which compiled variant of the march `s` needs (build.rs MARCH_VARIANTS): 0 emission/density, 1 the same with
/// gradients (shading or gradient-modulated opacity), 2 MIP/MinIP/average, 3 isosurface, 4 gradients from the
/// gradient texture.
pub fn march_variant(s: &RenderSettings) -> usize {
    use crate::settings::CompositeMode as M;
    match s.mode {
        M::Emission | M::Density if (s.shading.is_some() || s.gradient_opacity.is_some()) && s.gradient_texture => 4,
        M::Emission | M::Density if s.shading.is_some() || s.gradient_opacity.is_some() => 1,
        M::Emission | M::Density => 0,
        M::Mip | M::MinIp | M::Average => 2,
        M::Isosurface => 3,
    }
}

include!(concat!(env!("OUT_DIR"), "/march_shaders.rs"));

/// Bytes per pixel that the entry/exit method needs beyond the output image (both position targets).
pub fn position_bytes_per_pixel(format: PositionFormat) -> u64 {
    match format {
        PositionFormat::Rgba32f => 32,
        PositionFormat::Rgba16f => 16,
    }
}

const QUERIES: u32 = 4;

pub struct Renderer {
    output_format: vk::Format,
    frame_set_layout: vk::DescriptorSetLayout,
    volume_set_layout: vk::DescriptorSetLayout,
    positions_set_layout: vk::DescriptorSetLayout,
    faces_layout: vk::PipelineLayout,
    march_faces_layout: vk::PipelineLayout,
    march_analytic_layout: vk::PipelineLayout,
    storage_set_layout: vk::DescriptorSetLayout,
    march_compute_layout: vk::PipelineLayout,
    /// Entry and exit pipelines per position format: [Rgba32f, Rgba16f] × [entry, exit].
    position_pipelines: [[vk::Pipeline; 2]; 2],
    /// March pipelines per `setup_index` × shader variant × volume layout, created when first needed (see
    /// `march_variant`, `VolumeLayout::index`).
    march_pipelines: [[[vk::Pipeline; 3]; 5]; 3],
    descriptor_pool: vk::DescriptorPool,
    volume_set: vk::DescriptorSet,
    positions_set: vk::DescriptorSet,
    slots: Vec<FrameSlot>,
    linear_sampler: vk::Sampler,
    point_sampler: vk::Sampler,
    /// The baked table (shaders/march.glsl `Lut`): [`LUT_ROWS`] rows of [`LUT_SIZE`] entries.
    lut: Buffer,
    /// What the table holds: classification, window, data range and step rule it was baked for, and row 0
    /// itself (the brick occupancy is computed from it).
    baked: Option<(Classification, [f32; 2], [f64; 2], StepRule)>,
    lut_table: Vec<[f32; 4]>,
    volume: Option<GpuVolume>,
    /// How the next `set_volume` stores voxels (see [`TexelPolicy`]); starts as the GPU's option.
    pub texel_policy: TexelPolicy,
    positions: Option<PositionTargets>,
    timestamp_period_ns: f64,
}

/// What each frame in flight needs of its own: the host writes its uniforms and reads its timestamps while
/// other frames may still run on the GPU.
struct FrameSlot {
    uniforms: Buffer,
    set: vk::DescriptorSet,
    query_pool: vk::QueryPool,
    /// The output image as a storage image, for the compute march (written when a frame is recorded).
    storage_set: vk::DescriptorSet,
    /// The ray setup of the last frame recorded in this slot (None: nothing recorded yet).
    recorded: Option<RaySetup>,
}

fn set_layout(
    gpu: &Gpu,
    bindings: &[(vk::DescriptorType, vk::ShaderStageFlags)],
) -> Result<vk::DescriptorSetLayout, GpuError> {
    let b: Vec<vk::DescriptorSetLayoutBinding> = bindings
        .iter()
        .enumerate()
        .map(|(i, &(ty, stages))| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(i as u32)
                .descriptor_type(ty)
                .descriptor_count(1)
                .stage_flags(stages)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&b);
    // SAFETY: valid create info on a live device.
    unsafe { gpu.device.create_descriptor_set_layout(&info, None) }.ctx("vkCreateDescriptorSetLayout")
}

fn pipeline_layout(gpu: &Gpu, sets: &[vk::DescriptorSetLayout]) -> Result<vk::PipelineLayout, GpuError> {
    let info = vk::PipelineLayoutCreateInfo::default().set_layouts(sets);
    // SAFETY: the set layouts are live.
    unsafe { gpu.device.create_pipeline_layout(&info, None) }.ctx("vkCreatePipelineLayout")
}

fn sampler(gpu: &Gpu, filter: vk::Filter) -> Result<vk::Sampler, GpuError> {
    let info = vk::SamplerCreateInfo::default()
        .mag_filter(filter)
        .min_filter(filter)
        .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
        .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .max_lod(0.0);
    // SAFETY: valid create info on a live device.
    unsafe { gpu.device.create_sampler(&info, None) }.ctx("vkCreateSampler")
}

impl Renderer {
    /// Creates pipelines and fixed resources. `output_format` is the colour target's format (RGBA8 headless);
    /// `frames_in_flight` slots let that many recorded frames be pending at once (see [`Renderer::record`]).
    /// On error everything created so far is destroyed again.
    pub fn new(gpu: &Gpu, output_format: vk::Format, frames_in_flight: usize) -> Result<Renderer, GpuError> {
        let all = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT | vk::ShaderStageFlags::COMPUTE;
        let frag = vk::ShaderStageFlags::FRAGMENT | vk::ShaderStageFlags::COMPUTE;
        let lut = Buffer::new(
            gpu,
            (LUT_ROWS * LUT_SIZE * std::mem::size_of::<[f32; 4]>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
            "transfer function table",
        )?;
        let mut r = Renderer {
            output_format,
            frame_set_layout: vk::DescriptorSetLayout::null(),
            volume_set_layout: vk::DescriptorSetLayout::null(),
            positions_set_layout: vk::DescriptorSetLayout::null(),
            faces_layout: vk::PipelineLayout::null(),
            march_faces_layout: vk::PipelineLayout::null(),
            march_analytic_layout: vk::PipelineLayout::null(),
            storage_set_layout: vk::DescriptorSetLayout::null(),
            march_compute_layout: vk::PipelineLayout::null(),
            position_pipelines: [[vk::Pipeline::null(); 2]; 2],
            march_pipelines: [[[vk::Pipeline::null(); 3]; 5]; 3],
            descriptor_pool: vk::DescriptorPool::null(),
            volume_set: vk::DescriptorSet::null(),
            positions_set: vk::DescriptorSet::null(),
            slots: Vec::new(),
            linear_sampler: vk::Sampler::null(),
            point_sampler: vk::Sampler::null(),
            lut,
            baked: None,
            lut_table: Vec::new(),
            volume: None,
            texel_policy: gpu.texel_policy,
            positions: None,
            timestamp_period_ns: gpu.properties.limits.timestamp_period as f64,
        };
        match r.init(gpu, all, frag, frames_in_flight.max(1)) {
            Ok(()) => Ok(r),
            Err(e) => {
                r.destroy(gpu);
                Err(e)
            }
        }
    }

    fn init(
        &mut self,
        gpu: &Gpu,
        all: vk::ShaderStageFlags,
        frag: vk::ShaderStageFlags,
        slots: usize,
    ) -> Result<(), GpuError> {
        use vk::DescriptorType as D;
        self.frame_set_layout = set_layout(gpu, &[(D::UNIFORM_BUFFER, all)])?;
        self.volume_set_layout = set_layout(
            gpu,
            &[
                (D::SAMPLED_IMAGE, frag),
                (D::SAMPLER, frag),
                (D::STORAGE_BUFFER, frag),
                (D::SAMPLED_IMAGE, frag),
                (D::SAMPLED_IMAGE, frag),
                (D::STORAGE_BUFFER, frag),
            ],
        )?;
        self.positions_set_layout = set_layout(
            gpu,
            &[(D::SAMPLED_IMAGE, frag), (D::SAMPLED_IMAGE, frag), (D::SAMPLER, frag)],
        )?;
        self.faces_layout = pipeline_layout(gpu, &[self.frame_set_layout])?;
        self.march_faces_layout = pipeline_layout(
            gpu,
            &[self.frame_set_layout, self.volume_set_layout, self.positions_set_layout],
        )?;
        self.march_analytic_layout = pipeline_layout(gpu, &[self.frame_set_layout, self.volume_set_layout])?;
        self.storage_set_layout = set_layout(gpu, &[(D::STORAGE_IMAGE, vk::ShaderStageFlags::COMPUTE)])?;
        self.march_compute_layout = pipeline_layout(
            gpu,
            &[self.frame_set_layout, self.volume_set_layout, self.storage_set_layout],
        )?;
        self.linear_sampler = sampler(gpu, vk::Filter::LINEAR)?;
        self.point_sampler = sampler(gpu, vk::Filter::NEAREST)?;

        let faces_vert = shader!("faces.vert");
        let faces_frag = shader!("faces.frag");
        for (i, format) in [PositionFormat::Rgba32f, PositionFormat::Rgba16f]
            .into_iter()
            .enumerate()
        {
            for (j, cull) in [vk::CullModeFlags::BACK, vk::CullModeFlags::FRONT]
                .into_iter()
                .enumerate()
            {
                self.position_pipelines[i][j] = graphics_pipeline(
                    gpu,
                    &GraphicsDesc {
                        vertex: &faces_vert,
                        fragment: &faces_frag,
                        layout: self.faces_layout,
                        color_format: PositionTargets::vk_format(format),
                        cull,
                    },
                )?;
            }
        }
        let n = slots as u32;
        let sizes = [
            vk::DescriptorPoolSize {
                ty: D::UNIFORM_BUFFER,
                descriptor_count: n,
            },
            vk::DescriptorPoolSize {
                ty: D::SAMPLED_IMAGE,
                descriptor_count: 6,
            },
            vk::DescriptorPoolSize {
                ty: D::SAMPLER,
                descriptor_count: 2,
            },
            vk::DescriptorPoolSize {
                ty: D::STORAGE_IMAGE,
                descriptor_count: n,
            },
            vk::DescriptorPoolSize {
                ty: D::STORAGE_BUFFER,
                descriptor_count: 2,
            },
        ];
        let pool_info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(2 + 2 * n)
            .pool_sizes(&sizes);
        // SAFETY: valid create info on a live device.
        self.descriptor_pool =
            unsafe { gpu.device.create_descriptor_pool(&pool_info, None) }.ctx("vkCreateDescriptorPool")?;
        let mut layouts = vec![self.volume_set_layout, self.positions_set_layout];
        layouts.extend(std::iter::repeat_n(self.frame_set_layout, slots));
        layouts.extend(std::iter::repeat_n(self.storage_set_layout, slots));
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.descriptor_pool)
            .set_layouts(&layouts);
        // SAFETY: the pool has room for exactly these sets.
        let sets = unsafe { gpu.device.allocate_descriptor_sets(&alloc) }.ctx("vkAllocateDescriptorSets")?;
        (self.volume_set, self.positions_set) = (sets[0], sets[1]);
        for (&set, &storage_set) in sets[2..2 + slots].iter().zip(&sets[2 + slots..]) {
            let uniforms = Buffer::new(
                gpu,
                std::mem::size_of::<FrameUniforms>() as u64,
                vk::BufferUsageFlags::UNIFORM_BUFFER,
                MemoryLocation::CpuToGpu,
                "frame uniforms",
            )?;
            let query_info = vk::QueryPoolCreateInfo::default()
                .query_type(vk::QueryType::TIMESTAMP)
                .query_count(QUERIES);
            // SAFETY: valid create info on a live device.
            let query_pool = match unsafe { gpu.device.create_query_pool(&query_info, None) } {
                Ok(q) => q,
                Err(e) => {
                    uniforms.destroy(gpu);
                    return Err(GpuError::vk("vkCreateQueryPool", e));
                }
            };
            let buffer_info = [vk::DescriptorBufferInfo {
                buffer: uniforms.raw,
                offset: 0,
                range: vk::WHOLE_SIZE,
            }];
            let write = vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(0)
                .descriptor_type(D::UNIFORM_BUFFER)
                .buffer_info(&buffer_info);
            // SAFETY: the set is not in use by any command buffer.
            unsafe { gpu.device.update_descriptor_sets(&[write], &[]) };
            self.slots.push(FrameSlot {
                uniforms,
                set,
                query_pool,
                storage_set,
                recorded: None,
            });
        }
        let initial = RenderSettings::default();
        self.upload_lut(&initial, [0.0, 1.0])?;
        Ok(())
    }

    /// Bakes the table for `s` on data of value range `range` into the (host-visible) table buffer; no frame
    /// may be in flight (prepare's contract).
    fn upload_lut(&mut self, s: &RenderSettings, range: [f64; 2]) -> Result<(), GpuError> {
        let classification = s.classification();
        let rule = StepRule::of(s);
        let lut = bake(&classification, s.window, range);
        let mut rows: Vec<[u32; 4]> = lut.iter().map(|e| e.map(f32::to_bits)).collect();
        rows.extend(half_pairs(&step_table(&lut, rule.steps, rule.density)));
        rows.extend(half_pairs(&step_table(&lut, 2.0 * rule.steps, rule.density)));
        self.lut.write(bytemuck::cast_slice(&rows))?;
        self.baked = Some((classification, s.window, range, rule));
        self.lut_table = lut;
        Ok(())
    }

    fn write_volume_set(&self, gpu: &Gpu) {
        let Some(vol) = &self.volume else { return };
        // With a corner buffer there is no volume texture; the occupancy texture holds the binding (the corner
        // variants never read it).
        let volume_view = vol.image.as_ref().map_or(vol.occupancy.view, |i| i.view);
        let volume_info = [vk::DescriptorImageInfo::default()
            .image_view(volume_view)
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        let sampler_info = [vk::DescriptorImageInfo::default().sampler(self.linear_sampler)];
        let lut_info = [vk::DescriptorBufferInfo {
            buffer: self.lut.raw,
            offset: 0,
            range: vk::WHOLE_SIZE,
        }];
        // Without a corner buffer the binding holds the table: only the corner variants read it.
        let corners_info = [vk::DescriptorBufferInfo {
            buffer: vol.corners.as_ref().map_or(self.lut.raw, |c| c.raw),
            offset: 0,
            range: vk::WHOLE_SIZE,
        }];
        let occupancy_info = [vk::DescriptorImageInfo::default()
            .image_view(vol.occupancy.view)
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        // Without a gradient texture the binding holds the volume: only the gradient-texture variant reads it.
        let gradient_info = [vk::DescriptorImageInfo::default()
            .image_view(vol.gradient.as_ref().map_or(volume_view, |g| g.view))
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(self.volume_set)
                .dst_binding(4)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&gradient_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.volume_set)
                .dst_binding(3)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&occupancy_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.volume_set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&volume_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.volume_set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::SAMPLER)
                .image_info(&sampler_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.volume_set)
                .dst_binding(2)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&lut_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.volume_set)
                .dst_binding(5)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&corners_info),
        ];
        // SAFETY: callers only update descriptors while no submitted work uses them (headless waits per frame).
        unsafe { gpu.device.update_descriptor_sets(&writes, &[]) };
    }

    /// Uploads `volume` in the layout the texel policy gives it, replacing the current one. The size is checked
    /// against the device's 3D image limit and memory before anything is allocated.
    pub fn set_volume(&mut self, gpu: &Gpu, volume: &Volume) -> Result<(), GpuError> {
        let prepared = self.prepare_volume(gpu, volume)?;
        self.install_volume(gpu, prepared);
        Ok(())
    }

    /// Uploads `volume` without showing it: the frames keep the current volume until
    /// [`install_volume`](Self::install_volume). A series' next step is uploaded this way while its current one
    /// is shown.
    pub fn prepare_volume(&self, gpu: &Gpu, volume: &Volume) -> Result<PreparedVolume, GpuError> {
        GpuVolume::new(gpu, self.texel_policy, volume).map(PreparedVolume)
    }

    /// Shows `prepared`, destroying the current volume. No frame in flight may still use the current volume.
    pub fn install_volume(&mut self, gpu: &Gpu, prepared: PreparedVolume) {
        if let Some(old) = self.volume.replace(prepared.0) {
            old.destroy(gpu);
        }
        self.write_volume_set(gpu);
    }

    /// Precomputes `volume`'s gradients (central differences on the voxel grid, RGBA16 SNORM, 8 bytes per voxel)
    /// for frames with `gradient_texture`: the alternative to six extra samples per shaded sample. `volume` must
    /// be the one last given to `set_volume`.
    pub fn enable_gradient_texture(&mut self, gpu: &Gpu, volume: &Volume) -> Result<(), GpuError> {
        let Some(vol) = &mut self.volume else {
            return Err(GpuError::Lost("no volume loaded"));
        };
        if vol.gradient.is_some() {
            return Ok(());
        }
        let [w, h, d] = volume.dims;
        let at = |x: i64, y: i64, z: i64| {
            let c = |v: i64, n: u32| v.clamp(0, n as i64 - 1) as u32;
            let v = volume.normalized(c(x, w), c(y, h), c(z, d));
            if v.is_nan() {
                0.0
            } else {
                v
            }
        };
        let mut texels: Vec<i16> = Vec::with_capacity(volume.voxel_count() * 4);
        for z in 0..d as i64 {
            for y in 0..h as i64 {
                for x in 0..w as i64 {
                    // Stored as 2g so the range of g, [-0.5, 0.5], fills SNORM's [-1, 1].
                    let g = [
                        at(x + 1, y, z) - at(x - 1, y, z),
                        at(x, y + 1, z) - at(x, y - 1, z),
                        at(x, y, z + 1) - at(x, y, z - 1),
                    ];
                    texels.extend(g.map(|v| (v.clamp(-1.0, 1.0) * 32767.0).round() as i16));
                    texels.push(0);
                }
            }
        }
        let image = image_3d(gpu, vk::Format::R16G16B16A16_SNORM, volume.dims, "gradients")?;
        if let Err(e) = upload_3d(gpu, &image, bytemuck::cast_slice(&texels), d) {
            image.destroy(gpu);
            return Err(e);
        }
        vol.gradient = Some(image);
        self.write_volume_set(gpu);
        Ok(())
    }

    /// How the loaded volume is stored on the GPU (None: no volume).
    pub fn volume_layout(&self) -> Option<VolumeLayout> {
        self.volume.as_ref().map(|v| v.layout)
    }

    /// Bytes the volume (texture or corner buffer) takes on the device.
    pub fn volume_bytes(&self) -> u64 {
        self.volume.as_ref().map_or(0, |v| {
            v.image.as_ref().map_or(0, |i| i.allocated_bytes()) + v.corners.as_ref().map_or(0, |c| c.size)
        })
    }

    /// The sampling index of the march shaders for the loaded volume (0 without one).
    fn layout_index(&self) -> usize {
        self.volume.as_ref().map_or(0, |v| v.layout.index())
    }

    /// Whether [`Renderer::prepare`] has work to do for `s` (callers wait for in-flight frames only then).
    pub fn needs_prepare(&self, s: &RenderSettings) -> bool {
        let targets_fit = match s.ray_setup {
            RaySetup::Faces => self.positions_fit(s),
            RaySetup::Analytic => self.positions.is_none(),
        };
        !targets_fit
            || !self.lut_is_current(s)
            || !self.occupancy_is_current(s)
            || self.march_pipelines[setup_index(s)][march_variant(s)][self.layout_index()] == vk::Pipeline::null()
    }

    fn occupancy_is_current(&self, s: &RenderSettings) -> bool {
        !s.skip_empty
            || self
                .volume
                .as_ref()
                .is_none_or(|v| v.occupancy_key.as_ref() == Some(&OccupancyKey::of(s)))
    }

    fn positions_fit(&self, s: &RenderSettings) -> bool {
        self.positions.as_ref().is_some_and(|p| {
            p.format == s.position_format
                && p.entry.desc.extent.width == s.width
                && p.entry.desc.extent.height == s.height
        })
    }

    /// The loaded volume's value range (what data-unit transfer functions are baked against).
    fn volume_range(&self) -> [f64; 2] {
        self.volume.as_ref().map(|v| v.info.range).unwrap_or([0.0, 1.0])
    }

    fn lut_is_current(&self, s: &RenderSettings) -> bool {
        let range = self.volume_range();
        self.baked.as_ref().is_some_and(|(c, w, r, rule)| {
            *w == s.window && *r == range && *rule == StepRule::of(s) && *c == s.classification()
        })
    }

    /// Creates (or re-creates) what `settings` needs that depends on more than the frame: colormap, targets.
    /// Must be called while no submitted frame is in flight.
    pub fn prepare(&mut self, gpu: &Gpu, s: &RenderSettings) -> Result<(), GpuError> {
        let (si, vi) = (setup_index(s), march_variant(s));
        if vi == 4 && self.volume.as_ref().is_some_and(|v| v.gradient.is_none()) {
            return Err(GpuError::InvalidSettings(
                "gradient_texture needs enable_gradient_texture() first".into(),
            ));
        }
        let li = self.layout_index();
        if self.march_pipelines[si][vi][li] == vk::Pipeline::null() {
            let code = &MARCH_SHADERS[si][vi][li];
            self.march_pipelines[si][vi][li] = if si == 2 {
                compute_pipeline(gpu, code, self.march_compute_layout)?
            } else {
                let layout = match s.ray_setup {
                    RaySetup::Faces => self.march_faces_layout,
                    RaySetup::Analytic => self.march_analytic_layout,
                };
                graphics_pipeline(
                    gpu,
                    &GraphicsDesc {
                        vertex: &shader!("fullscreen.vert"),
                        fragment: code,
                        layout,
                        color_format: self.output_format,
                        cull: vk::CullModeFlags::NONE,
                    },
                )?
            };
        }
        if !self.lut_is_current(s) {
            self.upload_lut(s, self.volume_range())?;
        }
        if !self.occupancy_is_current(s) {
            // The table is current now (above), so the occupancy follows from it.
            if let Some(vol) = &mut self.volume {
                let levels = vol
                    .bricks
                    .classify(&self.lut_table, s.mode, s.window, s.iso_value, s.adaptive_step);
                let occupancy = skip::encode_reach(&levels, vol.bricks.bricks);
                upload_3d(gpu, &vol.occupancy, &occupancy, vol.bricks.bricks[2])?;
                vol.occupancy_key = Some(OccupancyKey::of(s));
            }
        }
        if s.ray_setup == RaySetup::Faces {
            if !self.positions_fit(s) {
                if let Some(old) = self.positions.take() {
                    old.destroy(gpu);
                }
                let format = PositionTargets::vk_format(s.position_format);
                let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
                let entry = Image::new(gpu, ImageDesc::d2(format, s.width, s.height, usage), "entry positions")?;
                let exit = match Image::new(gpu, ImageDesc::d2(format, s.width, s.height, usage), "exit positions") {
                    Ok(i) => i,
                    Err(e) => {
                        entry.destroy(gpu);
                        return Err(e);
                    }
                };
                let targets = PositionTargets {
                    entry,
                    exit,
                    format: s.position_format,
                };
                let infos = [targets.entry.view, targets.exit.view].map(|v| {
                    [vk::DescriptorImageInfo::default()
                        .image_view(v)
                        .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)]
                });
                let sampler_info = [vk::DescriptorImageInfo::default().sampler(self.point_sampler)];
                let writes = [
                    vk::WriteDescriptorSet::default()
                        .dst_set(self.positions_set)
                        .dst_binding(0)
                        .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                        .image_info(&infos[0]),
                    vk::WriteDescriptorSet::default()
                        .dst_set(self.positions_set)
                        .dst_binding(1)
                        .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                        .image_info(&infos[1]),
                    vk::WriteDescriptorSet::default()
                        .dst_set(self.positions_set)
                        .dst_binding(2)
                        .descriptor_type(vk::DescriptorType::SAMPLER)
                        .image_info(&sampler_info),
                ];
                // SAFETY: no submitted work uses the set (prepare's contract).
                unsafe { gpu.device.update_descriptor_sets(&writes, &[]) };
                self.positions = Some(targets);
            }
        } else if let Some(old) = self.positions.take() {
            // The analytic method needs no position targets: free their memory.
            old.destroy(gpu);
        }
        Ok(())
    }

    /// Records one frame into `output` (a `width`×`height` colour image of `output_format`, last used as `from`;
    /// its old contents are discarded). `output` ends in `Access::ColorAttachmentWrite`.
    /// Call [`Renderer::prepare`] with the same settings first. `slot` (< frames in flight) must not be used by a
    /// frame that is still pending on the GPU: its uniforms are written now, by the host.
    pub fn record(
        &mut self,
        gpu: &Gpu,
        cb: vk::CommandBuffer,
        slot: usize,
        output: (vk::Image, vk::ImageView),
        from: Access,
        s: &RenderSettings,
    ) -> Result<(), GpuError> {
        let vol = self.volume.as_ref().ok_or(GpuError::Lost("no volume loaded"))?;
        let uniforms = FrameUniforms::new(s, &vol.info);
        let slot = self
            .slots
            .get_mut(slot)
            .ok_or(GpuError::Lost("frame slot out of range"))?;
        slot.uniforms.write(bytemuck::bytes_of(&uniforms))?;
        slot.recorded = Some(s.ray_setup);
        let (frame_set, query_pool, storage_set) = (slot.set, slot.query_pool, slot.storage_set);
        let march_pipeline = self.march_pipelines[setup_index(s)][march_variant(s)][self.layout_index()];
        if march_pipeline == vk::Pipeline::null() {
            return Err(GpuError::Lost("prepare() was not called for these settings"));
        }
        let dev = &gpu.device;
        let extent = vk::Extent2D {
            width: s.width,
            height: s.height,
        };
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: s.width as f32,
            height: s.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let scissor = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent,
        };
        let ts = |cb, i| {
            // SAFETY: the query was reset at the start of this command buffer.
            unsafe { dev.cmd_write_timestamp2(cb, vk::PipelineStageFlags2::ALL_COMMANDS, query_pool, i) }
        };
        // SAFETY: `cb` is recording, outside any rendering scope.
        unsafe { dev.cmd_reset_query_pool(cb, query_pool, 0, QUERIES) };
        ts(cb, 0);
        let begin = |view: vk::ImageView, load: vk::AttachmentLoadOp| {
            let attachment = [vk::RenderingAttachmentInfo::default()
                .image_view(view)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(load)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue {
                    color: vk::ClearColorValue { float32: [0.0; 4] },
                })];
            let info = vk::RenderingInfo::default()
                .render_area(scissor)
                .layer_count(1)
                .color_attachments(&attachment);
            // SAFETY: `view`'s image is in COLOR_ATTACHMENT_OPTIMAL (barriers above) and matches `extent`.
            unsafe {
                dev.cmd_begin_rendering(cb, &info);
                dev.cmd_set_viewport(cb, 0, &[viewport]);
                dev.cmd_set_scissor(cb, 0, &[scissor]);
            }
        };
        let output_to_attachment = ImageTransition {
            image: output.0,
            from,
            to: Access::ColorAttachmentWrite,
            discard: true,
        };
        match s.ray_setup {
            RaySetup::Faces => {
                let p = self
                    .positions
                    .as_ref()
                    .ok_or(GpuError::Lost("prepare() was not called"))?;
                let pi = match p.format {
                    PositionFormat::Rgba32f => 0,
                    PositionFormat::Rgba16f => 1,
                };
                // Last frame's march read both targets; wait for that before overwriting them.
                let discard = |image| ImageTransition {
                    image,
                    from: Access::FragmentSampled,
                    to: Access::ColorAttachmentWrite,
                    discard: true,
                };
                image_barriers(
                    dev,
                    cb,
                    &[discard(p.entry.raw), discard(p.exit.raw), output_to_attachment],
                );
                // Pipeline 0 culls back faces, 1 front faces; a mirroring placement swaps which is which.
                let flip = usize::from(self.volume.as_ref().is_some_and(|v| mirrors(v.info.tex_to_world(s))));
                for (j, target) in [&p.entry, &p.exit].into_iter().enumerate() {
                    begin(target.view, vk::AttachmentLoadOp::CLEAR);
                    // SAFETY: rendering has begun; the pipeline and set match the faces layout.
                    unsafe {
                        dev.cmd_bind_pipeline(
                            cb,
                            vk::PipelineBindPoint::GRAPHICS,
                            self.position_pipelines[pi][j ^ flip],
                        );
                        dev.cmd_bind_descriptor_sets(
                            cb,
                            vk::PipelineBindPoint::GRAPHICS,
                            self.faces_layout,
                            0,
                            &[frame_set],
                            &[],
                        );
                        dev.cmd_draw(cb, 36, 1, 0, 0);
                        dev.cmd_end_rendering(cb);
                    }
                    ts(cb, 1 + j as u32);
                }
                let to_sampled = |image| ImageTransition {
                    image,
                    from: Access::ColorAttachmentWrite,
                    to: Access::FragmentSampled,
                    discard: false,
                };
                image_barriers(dev, cb, &[to_sampled(p.entry.raw), to_sampled(p.exit.raw)]);
                // The march writes every pixel, so the old contents need not be loaded.
                begin(output.1, vk::AttachmentLoadOp::DONT_CARE);
                // SAFETY: rendering has begun; the sets match the march-faces layout and hold live resources.
                unsafe {
                    dev.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, march_pipeline);
                    dev.cmd_bind_descriptor_sets(
                        cb,
                        vk::PipelineBindPoint::GRAPHICS,
                        self.march_faces_layout,
                        0,
                        &[frame_set, self.volume_set, self.positions_set],
                        &[],
                    );
                    dev.cmd_draw(cb, 3, 1, 0, 0);
                    dev.cmd_end_rendering(cb);
                }
                ts(cb, 3);
            }
            RaySetup::Analytic if s.compute => {
                let image_info = [vk::DescriptorImageInfo::default()
                    .image_view(output.1)
                    .image_layout(vk::ImageLayout::GENERAL)];
                let write = vk::WriteDescriptorSet::default()
                    .dst_set(storage_set)
                    .dst_binding(0)
                    .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                    .image_info(&image_info);
                // SAFETY: the slot's last frame has completed (record's contract), so nothing uses the set.
                unsafe { dev.update_descriptor_sets(&[write], &[]) };
                image_barriers(
                    dev,
                    cb,
                    &[ImageTransition {
                        to: Access::ComputeWrite,
                        ..output_to_attachment
                    }],
                );
                // SAFETY: the sets match the march-compute layout and hold live resources; `output` is in GENERAL.
                unsafe {
                    dev.cmd_bind_pipeline(cb, vk::PipelineBindPoint::COMPUTE, march_pipeline);
                    dev.cmd_bind_descriptor_sets(
                        cb,
                        vk::PipelineBindPoint::COMPUTE,
                        self.march_compute_layout,
                        0,
                        &[frame_set, self.volume_set, storage_set],
                        &[],
                    );
                    dev.cmd_dispatch(cb, s.width.div_ceil(8), s.height.div_ceil(8), 1);
                }
                ts(cb, 1);
                // record's contract: the output ends as a colour attachment, whichever pass wrote it.
                image_barriers(
                    dev,
                    cb,
                    &[ImageTransition {
                        image: output.0,
                        from: Access::ComputeWrite,
                        to: Access::ColorAttachmentWrite,
                        discard: false,
                    }],
                );
            }
            RaySetup::Analytic => {
                image_barriers(dev, cb, &[output_to_attachment]);
                begin(output.1, vk::AttachmentLoadOp::DONT_CARE);
                // SAFETY: rendering has begun; the sets match the march-analytic layout and hold live resources.
                unsafe {
                    dev.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, march_pipeline);
                    dev.cmd_bind_descriptor_sets(
                        cb,
                        vk::PipelineBindPoint::GRAPHICS,
                        self.march_analytic_layout,
                        0,
                        &[frame_set, self.volume_set],
                        &[],
                    );
                    dev.cmd_draw(cb, 3, 1, 0, 0);
                    dev.cmd_end_rendering(cb);
                }
                ts(cb, 1);
            }
        }
        Ok(())
    }

    /// GPU times of the last frame recorded in `slot`; call after its submission has completed.
    pub fn timings(&self, gpu: &Gpu, slot: usize) -> Result<Option<PassTimings>, GpuError> {
        let Some(slot) = self.slots.get(slot) else {
            return Ok(None);
        };
        let Some(setup) = slot.recorded else { return Ok(None) };
        let count = match setup {
            RaySetup::Faces => 4,
            RaySetup::Analytic => 2,
        };
        let mut ticks = [0u64; QUERIES as usize];
        // SAFETY: the queries were written by a completed submission; WAIT is not needed but harmless.
        unsafe {
            gpu.device.get_query_pool_results(
                slot.query_pool,
                0,
                &mut ticks[..count],
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .ctx("vkGetQueryPoolResults")?;
        let ms = |a: usize, b: usize| ticks[b].saturating_sub(ticks[a]) as f64 * self.timestamp_period_ns * 1e-6;
        Ok(Some(match setup {
            RaySetup::Faces => PassTimings {
                entry_ms: Some(ms(0, 1)),
                exit_ms: Some(ms(1, 2)),
                march_ms: ms(2, 3),
                total_ms: ms(0, 3),
            },
            RaySetup::Analytic => PassTimings {
                entry_ms: None,
                exit_ms: None,
                march_ms: ms(0, 1),
                total_ms: ms(0, 1),
            },
        }))
    }

    /// Bytes the current ray setup needs on the GPU for extra targets at `width`×`height`.
    pub fn extra_target_bytes(s: &RenderSettings) -> u64 {
        match s.ray_setup {
            RaySetup::Faces => position_bytes_per_pixel(s.position_format) * s.width as u64 * s.height as u64,
            RaySetup::Analytic => 0,
        }
    }

    pub fn destroy(mut self, gpu: &Gpu) {
        // SAFETY: callers destroy the renderer after its last frame completed; null handles are ignored by Vulkan.
        unsafe {
            let d = &gpu.device;
            let _ = d.device_wait_idle();
            for slot in self.slots.drain(..) {
                d.destroy_query_pool(slot.query_pool, None);
                slot.uniforms.destroy(gpu);
            }
            if let Some(p) = self.positions.take() {
                p.destroy(gpu);
            }
            if let Some(v) = self.volume.take() {
                v.destroy(gpu);
            }
            d.destroy_descriptor_pool(self.descriptor_pool, None);
            for p in self.position_pipelines.iter().flatten() {
                d.destroy_pipeline(*p, None);
            }
            for p in self.march_pipelines.iter().flatten().flatten() {
                d.destroy_pipeline(*p, None);
            }
            d.destroy_pipeline_layout(self.march_compute_layout, None);
            d.destroy_descriptor_set_layout(self.storage_set_layout, None);
            d.destroy_pipeline_layout(self.faces_layout, None);
            d.destroy_pipeline_layout(self.march_faces_layout, None);
            d.destroy_pipeline_layout(self.march_analytic_layout, None);
            d.destroy_descriptor_set_layout(self.frame_set_layout, None);
            d.destroy_descriptor_set_layout(self.volume_set_layout, None);
            d.destroy_descriptor_set_layout(self.positions_set_layout, None);
            d.destroy_sampler(self.linear_sampler, None);
            d.destroy_sampler(self.point_sampler, None);
        }
        self.lut.destroy(gpu);
    }
}
