//! Rule 9's light grid (`RenderSettings` docs): shadows as transmittance towards the light, swept slice by slice
//! away from it (Behrens and Ratering 1998), and ambient occlusion from 14 short rays per cell, computed on the GPU
//! by shaders/light.comp when the transfer function, the light or the volume changes, and read by the march with
//! one filtered fetch per lit sample (two with occlusion).

use super::march_key::Sampling;
use super::{FrameUniforms, Renderer, VolumeInfo, LIGHT_SHADERS};
use crate::gpu::pipeline::compute_pipeline;
use crate::gpu::resources::{Buffer, Image, ImageDesc};
use crate::gpu::sync::{image_barrier, memory_barrier, Access};
use crate::gpu::{Gpu, GpuError};
use crate::scene::settings::{CompositeMode, RenderSettings};
use crate::transfer::function::{Classification, LUT_SIZE};
use ash::vk;
use glam::{DMat3, DVec3};
use gpu_allocator::MemoryLocation;

/// The grid's longest side, in cells, for volumes larger than this (rule 9's `f`).
pub const MAX_CELLS: u32 = 128;

/// Extinction per voxel length of an opaque material (rule 6's cap).
const OPAQUE: f32 = 32.0;

/// The light grid's geometry for a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightGrid {
    pub cells: [u32; 3],
    /// The sweep axis.
    pub axis: usize,
    /// The step towards the light, in cells (its `axis` component ±1; zero without a light).
    pub delta: DVec3,
    /// The step's world length in voxels.
    pub step_voxels: f64,
    /// The smallest voxel side in world units (lengths in voxels are of it).
    pub voxel: f64,
    /// Whether the sweep runs (a light to cast shadows from) and whether the occlusion is computed.
    pub shadows: bool,
    pub occlusion: bool,
}

impl LightGrid {
    /// The grid for a volume of `dims` placed by `linear` (texture space to world) with smallest voxel side
    /// `voxel` (world units), lit from unit world direction `light` (None: no shadow sweep), with occlusion or
    /// without.
    pub fn new(dims: [u32; 3], linear: DMat3, voxel: f64, light: Option<DVec3>, occlusion: bool) -> LightGrid {
        let largest = dims.iter().copied().max().unwrap_or(1);
        let f = largest.div_ceil(MAX_CELLS).max(1);
        let cells = dims.map(|d| d.div_ceil(f).max(2));
        let n = DVec3::from_array(cells.map(f64::from));
        let Some(light) = light else {
            return LightGrid {
                cells,
                axis: 0,
                delta: DVec3::ZERO,
                step_voxels: 0.0,
                voxel,
                shadows: false,
                occlusion,
            };
        };
        let d = n * (linear.inverse() * light);
        let a = d.abs();
        let axis = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let delta = d / a[axis];
        LightGrid {
            cells,
            axis,
            delta,
            step_voxels: (linear * (delta / n)).length() / voxel,
            voxel,
            shadows: true,
            occlusion,
        }
    }

    /// The shadow read's offset from a lit point, in texture space: 1.5 steps towards the light.
    pub fn read_offset(&self) -> DVec3 {
        1.5 * self.delta / DVec3::from_array(self.cells.map(f64::from))
    }

    /// The slices of the sweep in order, from the one nearest the light.
    fn slices(&self) -> Vec<u32> {
        let n = self.cells[self.axis];
        if self.delta[self.axis] > 0.0 {
            (0..n).rev().collect()
        } else {
            (0..n).collect()
        }
    }
}

/// Rule 9's extinction per voxel length at the table's 4096 values, from the baked table `lut` (rule 4's opacity
/// per voxel step): emission `−ln(1 − a)`, density `a·density` (at most 32), zero outside the window;
/// iso-surfaces 32 at and above the lowest opaque surface.
pub fn extinction_table(s: &RenderSettings, lut: &[[f32; 4]]) -> Vec<f32> {
    let last = (LUT_SIZE - 1) as f32;
    match s.compositing.mode {
        CompositeMode::Isosurface => {
            let wall = s
                .isosurfaces()
                .iter()
                .filter(|x| x.opacity >= 1.0)
                .map(|x| x.value)
                .fold(f32::INFINITY, f32::min);
            (0..LUT_SIZE)
                .map(|i| if i as f32 / last >= wall { OPAQUE } else { 0.0 })
                .collect()
        }
        // The table holds the window's edge beyond it (tf::bake); outside the window nothing absorbs.
        _ => lut
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let v = i as f32 / last;
                if v < s.colour.window[0] || v > s.colour.window[1] {
                    return 0.0;
                }
                if s.compositing.mode == CompositeMode::Density {
                    return (e[3] * s.compositing.density).min(OPAQUE);
                }
                let a = f64::from(e[3]).clamp(0.0, 1.0);
                ((-(1.0 - a).ln()) as f32).min(OPAQUE)
            })
            .collect(),
    }
}

/// The light the shadow sweep runs from (None without shadows: occlusion needs no direction).
fn sweep_light(s: &RenderSettings) -> Option<glam::Vec3> {
    s.light_direction().filter(|_| s.lighting.shadows)
}

/// What a light grid was computed for: it is recomputed when any of this changes.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct LightKey {
    classification: Classification,
    window: [f32; 2],
    mode: CompositeMode,
    density: f32,
    surfaces: Vec<(f32, f32)>,
    light: Option<[f32; 3]>,
    shadows: bool,
    occlusion: bool,
}

impl LightKey {
    pub(super) fn of(s: &RenderSettings) -> LightKey {
        LightKey {
            classification: s.classification(),
            window: s.colour.window,
            mode: s.compositing.mode,
            density: s.compositing.density,
            surfaces: if s.compositing.mode == CompositeMode::Isosurface {
                s.isosurfaces().iter().map(|x| (x.value, x.opacity)).collect()
            } else {
                Vec::new()
            },
            light: sweep_light(s).map(|d| d.to_array()),
            shadows: s.lighting.shadows,
            occlusion: s.lighting.ambient_occlusion,
        }
    }
}

/// The grid's image and what it holds.
pub(super) struct LightImage {
    pub(super) image: Image,
    pub(super) key: LightKey,
}

/// The compute pass that fills light grids: its layouts, a pipeline per volume layout (made when first needed),
/// its descriptor set and the extinction table.
pub(super) struct LightPass {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    /// By `Sampling::index`.
    pipelines: [vk::Pipeline; Sampling::ALL.len()],
    pub(super) set: vk::DescriptorSet,
    extinction: Buffer,
}

/// The push constants of shaders/light.comp.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    info: [i32; 4],
    delta: [f32; 4],
    grid: [f32; 4],
}

impl LightPass {
    /// Layouts and the table; `frame` and `volume` are the march's set layouts (sets 0 and 1).
    pub(super) fn new(
        gpu: &Gpu,
        frame: vk::DescriptorSetLayout,
        volume: vk::DescriptorSetLayout,
    ) -> Result<LightPass, GpuError> {
        let extinction = Buffer::new(
            gpu,
            (LUT_SIZE * 4) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::CpuToGpu,
            "light extinction table",
        )?;
        let mut pass = LightPass {
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            pipelines: [vk::Pipeline::null(); Sampling::ALL.len()],
            set: vk::DescriptorSet::null(),
            extinction,
        };
        let bindings = [vk::DescriptorType::STORAGE_IMAGE, vk::DescriptorType::STORAGE_BUFFER].map(|ty| {
            vk::DescriptorSetLayoutBinding::default()
                .descriptor_type(ty)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::COMPUTE)
        });
        let bindings = [bindings[0].binding(0), bindings[1].binding(1)];
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: valid create info on a live device.
        match unsafe { gpu.device.create_descriptor_set_layout(&info, None) } {
            Ok(l) => pass.set_layout = l,
            Err(e) => {
                pass.destroy(gpu);
                return Err(GpuError::vk("vkCreateDescriptorSetLayout", e));
            }
        }
        let sets = [frame, volume, pass.set_layout];
        let range = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(std::mem::size_of::<Push>() as u32)];
        let info = vk::PipelineLayoutCreateInfo::default()
            .set_layouts(&sets)
            .push_constant_ranges(&range);
        // SAFETY: the set layouts are live.
        match unsafe { gpu.device.create_pipeline_layout(&info, None) } {
            Ok(l) => pass.layout = l,
            Err(e) => {
                pass.destroy(gpu);
                return Err(GpuError::vk("vkCreatePipelineLayout", e));
            }
        }
        Ok(pass)
    }

    pub(super) fn set_layout(&self) -> vk::DescriptorSetLayout {
        self.set_layout
    }

    /// Fills `image` with the grid `grid` (ready for sampling afterwards) from the table `extinction`
    /// ([`extinction_table`]): pass 0 writes (1, O) everywhere, then with shadows one pass per slice sweeps T away
    /// from the light. `sets` are the frame's (its uniforms) and the volume's.
    pub(super) fn fill(
        &mut self,
        gpu: &Gpu,
        sampling: Sampling,
        extinction: &[f32],
        grid: &LightGrid,
        image: &Image,
        sets: [vk::DescriptorSet; 2],
    ) -> Result<(), GpuError> {
        let li = sampling.index();
        if self.pipelines[li] == vk::Pipeline::null() {
            self.pipelines[li] = compute_pipeline(gpu, &LIGHT_SHADERS[li], self.layout)?;
        }
        self.bind(gpu, extinction, image)?;
        let pipeline = self.pipelines[li];
        gpu.submit_and_wait(|cb| self.record(&gpu.device, cb, pipeline, grid, image, sets))
    }

    /// Points the pass's own set at `image` and at the table `extinction`, written into its buffer.
    fn bind(&mut self, gpu: &Gpu, extinction: &[f32], image: &Image) -> Result<(), GpuError> {
        self.extinction.write(bytemuck::cast_slice(extinction))?;
        let image_info = [vk::DescriptorImageInfo::default()
            .image_view(image.view)
            .image_layout(vk::ImageLayout::GENERAL)];
        let buffer_info = [vk::DescriptorBufferInfo {
            buffer: self.extinction.raw,
            offset: 0,
            range: vk::WHOLE_SIZE,
        }];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                .image_info(&image_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&buffer_info),
        ];
        // SAFETY: no submitted work uses the set (Renderer::prepare's contract).
        unsafe { gpu.device.update_descriptor_sets(&writes, &[]) };
        Ok(())
    }

    /// Records [`Self::fill`]'s passes into `cb`.
    fn record(
        &self,
        d: &ash::Device,
        cb: vk::CommandBuffer,
        pipeline: vk::Pipeline,
        grid: &LightGrid,
        image: &Image,
        sets: [vk::DescriptorSet; 2],
    ) {
        let n = grid.cells;
        let grid_push = [n[0] as f32, n[1] as f32, n[2] as f32, grid.voxel as f32];
        let delta = [
            grid.delta.x as f32,
            grid.delta.y as f32,
            grid.delta.z as f32,
            grid.step_voxels as f32,
        ];
        let (o1, o2) = match grid.axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let all_sets = [sets[0], sets[1], self.set];
        let push = |cb, p: Push| {
            // SAFETY: `cb` is recording with this layout bound; the range matches the layout's.
            unsafe {
                d.cmd_push_constants(
                    cb,
                    self.layout,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    bytemuck::bytes_of(&p),
                )
            };
        };
        image_barrier(d, cb, image.raw, Access::Undefined, Access::ComputeReadWrite);
        // SAFETY: `cb` is recording; pipeline, layout and sets are live and compatible.
        unsafe {
            d.cmd_bind_pipeline(cb, vk::PipelineBindPoint::COMPUTE, pipeline);
            d.cmd_bind_descriptor_sets(cb, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &all_sets, &[]);
        }
        push(
            cb,
            Push {
                info: [0, 0, 0, i32::from(grid.occlusion)],
                delta,
                grid: grid_push,
            },
        );
        // SAFETY: as above; the shader bounds-checks the rounded-up groups.
        unsafe { d.cmd_dispatch(cb, n[0].div_ceil(8), n[1].div_ceil(8), n[2]) };
        if grid.shadows {
            for (i, slice) in grid.slices().into_iter().enumerate() {
                memory_barrier(d, cb, Access::ComputeReadWrite, Access::ComputeReadWrite);
                push(
                    cb,
                    Push {
                        info: [1, slice as i32, grid.axis as i32, i32::from(i == 0)],
                        delta,
                        grid: grid_push,
                    },
                );
                // SAFETY: as above.
                unsafe { d.cmd_dispatch(cb, n[o1].div_ceil(8), n[o2].div_ceil(8), 1) };
            }
        }
        image_barrier(d, cb, image.raw, Access::ComputeReadWrite, Access::FragmentSampled);
    }

    pub(super) fn destroy(self, gpu: &Gpu) {
        // SAFETY: no submitted work uses these (the renderer's destroy waits for the device); null handles are
        // ignored.
        unsafe {
            for p in self.pipelines {
                gpu.device.destroy_pipeline(p, None);
            }
            gpu.device.destroy_pipeline_layout(self.layout, None);
            gpu.device.destroy_descriptor_set_layout(self.set_layout, None);
        }
        self.extinction.destroy(gpu);
    }
}

/// A grid image of `grid`'s size: RGBA16F (storage and filtered sampling are required of every device for it).
pub(super) fn light_image(gpu: &Gpu, grid: &LightGrid) -> Result<Image, GpuError> {
    let [width, height, depth] = grid.cells;
    Image::new(
        gpu,
        ImageDesc {
            format: vk::Format::R16G16B16A16_SFLOAT,
            extent: vk::Extent3D { width, height, depth },
            usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED,
        },
        "light grid",
    )
}

/// The grid for frame `s` on volume `v`.
pub fn grid_for(s: &RenderSettings, v: &VolumeInfo) -> LightGrid {
    let linear = DMat3::from_mat4(v.tex_to_world(s));
    let light = sweep_light(s).map(|d| d.as_dvec3());
    LightGrid::new(v.dims, linear, v.smallest_voxel(s), light, s.lighting.ambient_occlusion)
}

impl Renderer {
    /// How long the last light grid (rule 9) took to fill, in ms; None before the first.
    pub fn light_grid_ms(&self) -> Option<f64> {
        self.light_ms
    }

    pub(super) fn light_is_current(&self, s: &RenderSettings) -> bool {
        !s.uses_light_volume()
            || self
                .volume
                .as_ref()
                .is_none_or(|v| v.light.as_ref().is_some_and(|l| l.key == LightKey::of(s)))
    }

    /// Fills rule 9's light grid for `s` where it does not hold `s`'s yet (the table must be current). The
    /// frame's uniforms go to the first slot's buffer, which no frame in flight reads (prepare's contract).
    pub(super) fn prepare_light(&mut self, gpu: &Gpu, s: &RenderSettings) -> Result<(), GpuError> {
        if self.light_is_current(s) {
            return Ok(());
        }
        let sampling = self.sampling();
        let (Some(vol), Some(pass), Some(slot)) = (&mut self.volume, &mut self.pipelines.light, self.slots.first_mut())
        else {
            return Ok(());
        };
        let grid = grid_for(s, &vol.info);
        // Before any image is taken out of the volume, so that an error leaves nothing unowned.
        slot.uniforms
            .write(bytemuck::bytes_of(&FrameUniforms::new(s, &vol.info)))?;
        if vol.light.as_ref().is_some_and(|l| {
            let e = l.image.desc.extent;
            [e.width, e.height, e.depth] != grid.cells
        }) {
            if let Some(old) = vol.light.take() {
                old.image.destroy(gpu);
            }
        }
        let image = match vol.light.take() {
            Some(l) => l.image,
            None => light_image(gpu, &grid)?,
        };
        let extinction = extinction_table(s, &self.table.entries);
        let started = std::time::Instant::now();
        let filled = pass.fill(
            gpu,
            sampling,
            &extinction,
            &grid,
            &image,
            [slot.set, self.descriptors.volume_set],
        );
        self.light_ms = Some(started.elapsed().as_secs_f64() * 1e3);
        if let Err(e) = filled {
            image.destroy(gpu);
            self.write_volume_set(gpu);
            return Err(e);
        }
        vol.light = Some(LightImage {
            image,
            key: LightKey::of(s),
        });
        self.write_volume_set(gpu);
        Ok(())
    }
}
