//! The passes. `Renderer::record` writes one frame into a colour target: for the entry/exit method pass 1 (front
//! faces → entry positions), pass 2 (back faces → exit positions) and pass 3 (march); for the analytic method
//! the march alone. The same code serves headless rendering and (later) the window.

mod brick_upload;
pub mod figure;
mod finer_cells;
mod gpu_volume;
pub mod gradients;
pub mod headless;
pub mod info;
mod init;
mod layer_bricks;
pub mod layers;
pub mod levels;
pub mod light_volume;
pub mod march_key;
mod part;
mod parts;
pub mod placement;
pub mod pool;
mod positions;
mod record;
pub mod refinable;
mod resident;
pub mod save;
pub mod scale_bar;
pub mod skip;
mod spacing;
pub mod stream;
mod texels;
mod uniforms;

pub use part::{GHOST_ABOVE, GHOST_BELOW};
pub use uniforms::{mirrors, FrameUniforms, PartInfo, PoolInfo, VolumeInfo};

use crate::gpu::upload::upload_image_with;
use gpu_volume::{image_3d_once, upload_3d, GpuVolume};
pub use gpu_volume::{VolumeLayout, AUTO_LIMIT};

use crate::gpu::pipeline::{compute_pipeline, graphics_pipeline, shader, GraphicsDesc, ShaderCode};
use crate::gpu::resources::{Buffer, Filling};
pub use crate::gpu::TexelPolicy;
use crate::gpu::{Gpu, GpuError};
use crate::scene::settings::{RaySetup, RenderSettings};
use crate::transfer::function::{bake, Classification};
use crate::transfer::preintegrate::integral_table;
use crate::volume::Volume;
use ash::vk;
use march_key::{Family, LayerKinds, Lighting, MarchKey, Sampling, Setup};
pub use positions::position_bytes_per_pixel;
use positions::PositionTargets;

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
    mode: crate::scene::settings::CompositeMode,
    iso: f32,
    skip_empty: bool,
    /// Rule 13's layers: a layered frame skips only where they show nothing too.
    layers: Vec<crate::scene::layers::LayerStyle>,
    /// Rule 2's strides: the longest stride (1 where strides do not apply), the step, the density factor, the
    /// depth bound (which shading changes) and the spread bound (both scaled by the tolerance).
    strides: (u32, u32, u32, u64, u64),
}

impl OccupancyKey {
    fn of(s: &RenderSettings) -> OccupancyKey {
        OccupancyKey {
            classification: s.classification(),
            window: s.colour.window,
            mode: s.compositing.mode,
            iso: s.compositing.iso_value,
            skip_empty: s.sampling.skip_empty,
            layers: s.layers.clone(),
            strides: if s.sampling.max_stride > 1 {
                (
                    s.sampling.max_stride,
                    s.sampling.step_length.to_bits(),
                    s.compositing.density.to_bits(),
                    s.stride_depth().to_bits(),
                    s.stride_spread().to_bits(),
                )
            } else {
                (1, 0, 0, 0, 0)
            },
        }
    }
}

/// Rows of the table buffer: the baked classification (opacity per voxel-length step, f32 RGBA), which the
/// projection and isosurface marches read.
const LUT_ROWS: usize = 1;

include!(concat!(env!("OUT_DIR"), "/march_shaders.rs"));

const QUERIES: u32 = 4;

pub struct Renderer {
    output_format: vk::Format,
    layouts: parts::Layouts,
    pipelines: parts::Pipelines,
    descriptors: parts::Descriptors,
    samplers: parts::Samplers,
    /// What each frame in flight needs of its own.
    slots: Vec<FrameSlot>,
    table: parts::Table,
    targets: parts::Targets,
    volume: Option<GpuVolume>,
    /// Rule 13's layers (one-voxel stand-ins when there are none, so their bindings are always valid).
    layers: Option<layers::GpuLayers>,
    /// How the next `set_volume` stores voxels (see [`TexelPolicy`]); starts as the GPU's option.
    pub texel_policy: TexelPolicy,
    /// The brick side volumes are cut into (render/pool.rs; None: one brick where it fits).
    pub brick_side: Option<u32>,
    /// How long the last light grid took to fill (wall clock, submission to completion).
    light_ms: Option<f64>,
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

impl Renderer {
    /// Bakes the table for `s` on data of value range `range` into the (host-visible) table buffer; no frame
    /// may be in flight (prepare's contract).
    fn upload_lut(&mut self, s: &RenderSettings, range: [f64; 2]) -> Result<(), GpuError> {
        let classification = s.classification();
        let rule = parts::StepRule::of(s);
        let lut = bake(&classification, s.colour.window, range);
        let rows: Vec<[u32; 4]> = lut.iter().map(|e| e.map(f32::to_bits)).collect();
        self.table.lut.write(bytemuck::cast_slice(&rows))?;
        let integrals = integral_table(&lut, rule.density);
        self.table.integrals.write(bytemuck::cast_slice(&integrals))?;
        self.table.baked = Some((classification, s.colour.window, range, rule));
        self.table.entries = lut;
        Ok(())
    }

    fn write_volume_set(&self, gpu: &Gpu) {
        let Some(vol) = &self.volume else { return };
        // With a corner texture there is no volume texture; the occupancy texture holds the binding (the corner
        // variants never read it).
        let volume_view = vol.image.as_ref().map_or(vol.occupancy.view, |i| i.view);
        let volume_info = [vk::DescriptorImageInfo::default()
            .image_view(volume_view)
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        let sampler_info = [vk::DescriptorImageInfo::default().sampler(self.samplers.linear)];
        let lut_info = [vk::DescriptorBufferInfo {
            buffer: self.table.lut.raw,
            offset: 0,
            range: vk::WHOLE_SIZE,
        }];
        let integrals_info = [vk::DescriptorBufferInfo {
            buffer: self.table.integrals.raw,
            offset: 0,
            range: vk::WHOLE_SIZE,
        }];
        // Without a corner texture the binding holds the volume: only the corner variants read it.
        let corners_info = [vk::DescriptorImageInfo::default()
            .image_view(vol.corners.as_ref().map_or(volume_view, |c| c.view))
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        let occupancy_info = [vk::DescriptorImageInfo::default()
            .image_view(vol.occupancy.view)
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        // Without a gradient texture the binding holds the volume: only the gradient-texture variant reads it.
        let gradient_info = [vk::DescriptorImageInfo::default()
            .image_view(vol.gradient.as_ref().map_or(volume_view, |g| g.view))
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        // Likewise the light grid: only the light-grid variants read it.
        let light_info = [vk::DescriptorImageInfo::default()
            .image_view(vol.light.as_ref().map_or(volume_view, |l| l.image.view))
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        let directory_info = [vk::DescriptorImageInfo::default()
            .image_view(vol.directory.view)
            .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(self.descriptors.volume_set)
                .dst_binding(4)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&gradient_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.descriptors.volume_set)
                .dst_binding(3)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&occupancy_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.descriptors.volume_set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&volume_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.descriptors.volume_set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::SAMPLER)
                .image_info(&sampler_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.descriptors.volume_set)
                .dst_binding(2)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&lut_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.descriptors.volume_set)
                .dst_binding(5)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&corners_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.descriptors.volume_set)
                .dst_binding(6)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .buffer_info(&integrals_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.descriptors.volume_set)
                .dst_binding(7)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&light_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.descriptors.volume_set)
                .dst_binding(8)
                .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                .image_info(&directory_info),
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
        GpuVolume::new(gpu, self.texel_policy, volume, self.brick_side).map(PreparedVolume)
    }

    /// Shows `prepared`, destroying the current volume. No frame in flight may still use the current volume.
    pub fn install_volume(&mut self, gpu: &Gpu, prepared: PreparedVolume) {
        if let Some(old) = self.volume.replace(prepared.0) {
            old.destroy(gpu);
        }
        self.write_volume_set(gpu);
    }

    /// Precomputes `volume`'s gradients (its [`gradients::GradientFilter`] on the voxel grid, RGBA16 SNORM, 8 bytes
    /// per voxel) for frames with `gradient_texture`: the alternative to six extra samples per gradient, and the
    /// smoothed gradient rule 5 prefers. `volume` must be the one last given to `set_volume`. A volume whose finer
    /// levels are read from its file has no texture (its finest voxels are not held): its frames take gradients by
    /// central differences whatever `gradient_texture` says.
    pub fn enable_gradient_texture(&mut self, gpu: &Gpu, volume: &Volume) -> Result<(), GpuError> {
        let Some(vol) = &mut self.volume else {
            return Err(GpuError::Lost("no volume loaded"));
        };
        if vol.gradient.is_some() || vol.info.held > 0 {
            return Ok(());
        }
        // Slab by slab: the gradients of the slices of each level the slab's slots hold, on that level's voxel
        // grid, then gathered into the slots like the values (borders included). A volume kept as one brick
        // computes each slice once or twice (the border), and no whole copy of the gradients is held.
        let top = vol.pool.levels.len() - 1;
        let levels: Vec<&Volume> = std::iter::once(volume).chain(&vol.pyramid[..top]).collect();
        let filter = gradients::GradientFilter::for_volume(volume);
        let pool = &vol.pool;
        let mut image = image_3d_once(gpu, vk::Format::R16G16B16A16_SNORM, pool.texels(), "gradients")?;
        let filled = upload_image_with(gpu, &mut image, pool.texel_count() * 8, |range, dst| {
            let (first, count) = (range.start / 8, dst.len() / 8);
            // Per level: the index of its first slice computed, and those slices' gradients.
            let slabs: Vec<(usize, Vec<[i16; 4]>)> = pool
                .source_slices(first, count)
                .into_iter()
                .zip(&levels)
                .map(|(span, v)| {
                    let Some((z0, z1)) = span else { return (0, Vec::new()) };
                    let plane = v.dims[0] as usize * v.dims[1] as usize;
                    let mut grid = vec![[0i16; 4]; (z1 - z0 + 1) * plane];
                    gradients::fill_gradient_slices(v, filter, z0, &mut grid);
                    (z0 * plane, grid)
                })
                .collect();
            pool.fill(first, bytemuck::cast_slice_mut(dst), false, |r, x| {
                r.this[x].map_or([0; 4], |(l, i)| {
                    let (start, grid) = &slabs[l as usize];
                    grid[i - start]
                })
            })
        });
        if let Err(e) = filled {
            image.destroy(gpu);
            return Err(e);
        }
        vol.gradient = Some(image);
        self.write_volume_set(gpu);
        Ok(())
    }

    /// Whether the loaded volume's gradient texture is made (`enable_gradient_texture`).
    pub fn has_gradient_texture(&self) -> bool {
        self.volume.as_ref().is_some_and(|v| v.gradient.is_some())
    }

    /// Where the loaded volume's bricks lie in the pool (None: no volume).
    pub fn pool(&self) -> Option<&pool::Pool> {
        self.volume.as_ref().map(|v| &v.pool)
    }

    /// How the loaded volume is stored on the GPU (None: no volume).
    pub fn volume_layout(&self) -> Option<VolumeLayout> {
        self.volume.as_ref().map(|v| v.layout)
    }

    /// Whether the volume's texture (or corner texture) was written in place by the host rather than uploaded
    /// through a staging buffer (`gpu_volume::image_3d_once`).
    pub fn volume_is_host_written(&self) -> bool {
        self.volume
            .as_ref()
            .and_then(|v| v.image.as_ref().or(v.corners.as_ref()))
            .is_some_and(|i| !matches!(i.filling, Filling::Transfer))
    }

    /// Bytes the volume (texture or corner texture) takes on the device.
    pub fn volume_bytes(&self) -> u64 {
        self.volume.as_ref().map_or(0, |v| {
            v.image.as_ref().map_or(0, |i| i.allocated_bytes()) + v.corners.as_ref().map_or(0, |c| c.allocated_bytes())
        })
    }

    /// How the shaders read the loaded volume (as a texture without one).
    fn sampling(&self) -> Sampling {
        self.volume.as_ref().map_or(Sampling::Texture, |v| v.sampling())
    }

    /// The march variant frame `s` needs on the loaded volume.
    fn march_key(&self, s: &RenderSettings) -> MarchKey {
        use crate::scene::settings::CompositeMode as M;
        let setup = match s.pipeline.ray_setup {
            RaySetup::Faces => Setup::Faces,
            RaySetup::Analytic if s.pipeline.compute => Setup::Compute,
            RaySetup::Analytic => Setup::Analytic,
        };
        let from_file = self.volume.as_ref().is_some_and(|v| v.info.held > 0);
        let lighting = Lighting::new(s.lighting.gradient_texture && !from_file, s.uses_light_volume());
        let shaded = s.lighting.shading.is_some() || s.lighting.gradient_opacity.is_some();
        let family = match s.compositing.mode {
            M::Emission | M::Density if !s.layers.is_empty() => {
                use crate::scene::layers::{Blend, LayerKind};
                let labels = s.layers.iter().filter(|l| l.kind == LayerKind::Labels).count();
                let blended = s.layers.iter().any(|l| l.blend != Blend::Composite);
                let kinds = LayerKinds::of(s.layers.len() - labels, labels, blended);
                Family::Layers(kinds, shaded.then_some(Lighting::new(lighting.gradient_texture, false)))
            }
            M::Emission | M::Density if s.lighting.shading.is_some() || s.lighting.gradient_opacity.is_some() => {
                Family::EmissionShaded(lighting)
            }
            M::Emission | M::Density => Family::Emission,
            M::Mip | M::MinIp | M::Average => Family::Projection,
            M::Isosurface => Family::Isosurface(lighting),
        };
        MarchKey {
            setup,
            family,
            sampling: self.sampling(),
        }
    }

    /// Whether [`Renderer::prepare`] has work to do for `s` (callers wait for in-flight frames only then).
    pub fn needs_prepare(&self, s: &RenderSettings) -> bool {
        let targets_fit = match s.pipeline.ray_setup {
            RaySetup::Faces => self.positions_fit(s),
            RaySetup::Analytic => self.targets.positions.is_none(),
        };
        !targets_fit
            || !spacing::fits(&self.targets.spaced, s)
            || !self.lut_is_current(s)
            || !self.occupancy_is_current(s)
            || self.pipelines.march[self.march_key(s).index()] == vk::Pipeline::null()
            || !self.light_is_current(s)
            || !self.layers_are_current(s)
    }

    fn occupancy_is_current(&self, s: &RenderSettings) -> bool {
        !s.looks_up_bricks()
            || self
                .volume
                .as_ref()
                .is_none_or(|v| v.occupancy_key.as_ref() == Some(&OccupancyKey::of(s)))
    }

    fn positions_fit(&self, s: &RenderSettings) -> bool {
        self.targets.positions.as_ref().is_some_and(|p| p.fit(s))
    }

    /// The loaded volume's value range (what data-unit transfer functions are baked against).
    fn volume_range(&self) -> [f64; 2] {
        self.volume.as_ref().map(|v| v.info.range).unwrap_or([0.0, 1.0])
    }

    fn lut_is_current(&self, s: &RenderSettings) -> bool {
        let range = self.volume_range();
        self.table.baked.as_ref().is_some_and(|(c, w, r, rule)| {
            *w == s.colour.window && *r == range && *rule == parts::StepRule::of(s) && *c == s.classification()
        })
    }

    /// Creates (or re-creates) what `settings` needs that depends on more than the frame: colormap, targets.
    /// Must be called while no submitted frame is in flight.
    pub fn prepare(&mut self, gpu: &Gpu, s: &RenderSettings) -> Result<(), GpuError> {
        self.prepare_layers(gpu, s)?;
        let key = self.march_key(s);
        let reads_gradients = key.family.lighting().is_some_and(|l| l.gradient_texture);
        if reads_gradients && self.volume.as_ref().is_some_and(|v| v.gradient.is_none()) {
            return Err(GpuError::InvalidSettings(
                "gradient_texture needs enable_gradient_texture() first".into(),
            ));
        }
        if self.pipelines.march[key.index()] == vk::Pipeline::null() {
            self.pipelines.march[key.index()] = self.march_pipeline(gpu, key)?;
        }
        if !self.lut_is_current(s) {
            self.upload_lut(s, self.volume_range())?;
        }
        if !self.occupancy_is_current(s) {
            // The table is current now (above), so the occupancy follows from it.
            if let Some(vol) = &mut self.volume {
                // Strides follow the step the march takes (the finest level shown), and none is taken where a
                // skip brick holds fewer than 8 of its samples.
                let stepped = vol.info.stepped(s);
                let (dims, geometry, brick) = (vol.info.dims, vol.info.geometry, skip::BRICK << vol.info.held);
                let grid = vol.skip_grid();
                let mut levels = grid.classify(&self.table.entries, &stepped);
                // Rule 13: where a layer may show something, every sample is taken.
                if let (Some(layers), false) = (&self.layers, s.layers.is_empty()) {
                    layers.mark(&s.layers, &mut levels, grid.bricks, brick, (&geometry, dims));
                }
                let (occupancy, depth) = (skip::encode_reach(&levels, grid.bricks), grid.bricks[2]);
                upload_3d(gpu, &mut vol.occupancy, &occupancy, depth)?;
                vol.occupancy_key = Some(OccupancyKey::of(s));
            }
        }
        if s.uses_light_volume() {
            self.prepare_light(gpu, s)?;
        }
        spacing::prepare(gpu, &mut self.targets.spaced, self.output_format, s)?;
        if s.pipeline.ray_setup == RaySetup::Faces {
            if !self.positions_fit(s) {
                if let Some(old) = self.targets.positions.take() {
                    old.destroy(gpu);
                }
                self.targets.positions = Some(PositionTargets::new(
                    gpu,
                    s,
                    self.samplers.point,
                    self.descriptors.positions_set,
                )?);
            }
        } else if let Some(old) = self.targets.positions.take() {
            // The analytic method needs no position targets: free their memory.
            old.destroy(gpu);
        }
        Ok(())
    }

    fn march_pipeline(&self, gpu: &Gpu, key: MarchKey) -> Result<vk::Pipeline, GpuError> {
        let code = &MARCH_SHADERS[key.index()];
        let layout = match key.setup {
            Setup::Faces => self.layouts.march_faces,
            Setup::Analytic => self.layouts.march_analytic,
            Setup::Compute => return compute_pipeline(gpu, code, self.layouts.march_compute),
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
        )
    }

    /// Bytes the current ray setup needs on the GPU for extra targets at `width`×`height`: the position targets
    /// and, where rays are spaced, the march's own (4 bytes a pixel), all at the marched size.
    pub fn extra_target_bytes(s: &RenderSettings) -> u64 {
        let (w, h) = s.marched_size();
        let pixels = u64::from(w) * u64::from(h);
        let spaced = if s.spacing() > 1 { 4 * pixels } else { 0 };
        spaced
            + match s.pipeline.ray_setup {
                RaySetup::Faces => position_bytes_per_pixel(s.pipeline.position_format) * pixels,
                RaySetup::Analytic => 0,
            }
    }

    pub fn destroy(mut self, gpu: &Gpu) {
        let d = &gpu.device;
        // SAFETY: callers destroy the renderer after its last frame completed; null handles are ignored by Vulkan.
        unsafe {
            let _ = d.device_wait_idle();
            for slot in self.slots.drain(..) {
                d.destroy_query_pool(slot.query_pool, None);
                slot.uniforms.destroy(gpu);
            }
        }
        self.targets.destroy(gpu);
        if let Some(v) = self.volume.take() {
            v.destroy(gpu);
        }
        if let Some(l) = self.layers.take() {
            l.destroy(gpu);
        }
        // SAFETY: as above; the sets it holds are not used again.
        unsafe { d.destroy_descriptor_pool(self.descriptors.pool, None) };
        self.pipelines.destroy(gpu);
        self.layouts.destroy(gpu);
        self.samplers.destroy(gpu);
        self.table.destroy(gpu);
    }
}
