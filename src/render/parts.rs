//! The parts a [`Renderer`](super::Renderer) is made of, by how long they live: the layouts, pipelines, descriptor
//! sets and samplers made once with it; the classification table it bakes for each frame's settings; and the
//! targets it makes for the frame size. Each part destroys its own handles.

use super::light_volume::LightPass;
use super::march_key::MarchKey;
use super::positions::PositionTargets;
use super::spacing::SpacedTarget;
use crate::gpu::resources::Buffer;
use crate::gpu::Gpu;
use crate::scene::settings::RenderSettings;
use crate::transfer::function::Classification;
use ash::vk;

/// The descriptor-set layouts (frame, volume, positions, storage) and the pipeline layouts built from them.
#[derive(Default)]
pub(super) struct Layouts {
    pub frame_set: vk::DescriptorSetLayout,
    pub volume_set: vk::DescriptorSetLayout,
    pub positions_set: vk::DescriptorSetLayout,
    pub storage_set: vk::DescriptorSetLayout,
    pub faces: vk::PipelineLayout,
    pub march_faces: vk::PipelineLayout,
    pub march_analytic: vk::PipelineLayout,
    pub march_compute: vk::PipelineLayout,
}

impl Layouts {
    pub fn destroy(&self, gpu: &Gpu) {
        let d = &gpu.device;
        // SAFETY: the pipelines made from these layouts are destroyed first, and no frame is in flight; null
        // handles are ignored by Vulkan.
        unsafe {
            d.destroy_pipeline_layout(self.march_compute, None);
            d.destroy_descriptor_set_layout(self.storage_set, None);
            d.destroy_pipeline_layout(self.faces, None);
            d.destroy_pipeline_layout(self.march_faces, None);
            d.destroy_pipeline_layout(self.march_analytic, None);
            d.destroy_descriptor_set_layout(self.frame_set, None);
            d.destroy_descriptor_set_layout(self.volume_set, None);
            d.destroy_descriptor_set_layout(self.positions_set, None);
        }
    }
}

/// The pipelines: the box faces', the march's (made when first needed) and rule 9's light grid pass.
pub(super) struct Pipelines {
    /// Entry and exit pipelines per position format: [Rgba32f, Rgba16f] × [entry, exit].
    pub position: [[vk::Pipeline; 2]; 2],
    /// March pipelines by `MarchKey::index`, created when first needed.
    pub march: [vk::Pipeline; MarchKey::COUNT],
    /// Rule 9's light grid pass (None only while the renderer is being made).
    pub light: Option<LightPass>,
}

impl Default for Pipelines {
    fn default() -> Pipelines {
        Pipelines {
            position: [[vk::Pipeline::null(); 2]; 2],
            march: [vk::Pipeline::null(); MarchKey::COUNT],
            light: None,
        }
    }
}

impl Pipelines {
    pub fn destroy(&mut self, gpu: &Gpu) {
        // SAFETY: no frame is in flight; null handles (pipelines never made) are ignored by Vulkan.
        unsafe {
            for p in self.position.iter().flatten().chain(&self.march) {
                gpu.device.destroy_pipeline(*p, None);
            }
        }
        if let Some(pass) = self.light.take() {
            pass.destroy(gpu);
        }
    }
}

/// The descriptor pool and the sets every frame shares (the frame slots hold their own).
#[derive(Default)]
pub(super) struct Descriptors {
    pub pool: vk::DescriptorPool,
    pub volume_set: vk::DescriptorSet,
    pub positions_set: vk::DescriptorSet,
}

#[derive(Default)]
pub(super) struct Samplers {
    pub linear: vk::Sampler,
    pub point: vk::Sampler,
}

impl Samplers {
    pub fn destroy(&self, gpu: &Gpu) {
        // SAFETY: no frame is in flight and no set written with them is used again.
        unsafe {
            gpu.device.destroy_sampler(self.linear, None);
            gpu.device.destroy_sampler(self.point, None);
        }
    }
}

/// Rule 4's classification as the march reads it, baked for the settings of the frames being drawn.
pub(super) struct Table {
    /// The baked table (shaders/volume.glsl `Lut`): `LUT_ROWS` rows of `LUT_SIZE` entries.
    pub lut: Buffer,
    /// Its integral functions (shaders/volume.glsl `Integrals`, a uniform buffer of `LUT_SIZE` vec4).
    pub integrals: Buffer,
    /// What the table holds: classification, window, data range and step rule it was baked for, and row 0
    /// itself (the brick occupancy is computed from it).
    pub baked: Option<(Classification, [f32; 2], [f64; 2], StepRule)>,
    pub entries: Vec<[f32; 4]>,
}

impl Table {
    pub fn destroy(self, gpu: &Gpu) {
        self.integrals.destroy(gpu);
        self.lut.destroy(gpu);
    }
}

/// The targets made for the frame size: the entry/exit positions (faces setup) and, where rays are spaced (rule
/// 12), the march's smaller image.
#[derive(Default)]
pub(super) struct Targets {
    pub positions: Option<PositionTargets>,
    pub spaced: Option<SpacedTarget>,
}

impl Targets {
    pub fn destroy(&mut self, gpu: &Gpu) {
        if let Some(p) = self.positions.take() {
            p.destroy(gpu);
        }
        if let Some(t) = self.spaced.take() {
            t.destroy(gpu);
        }
    }
}

/// What the integral table (`preintegrate::integral_table`) depends on beyond the classification and window:
/// for the density model, its density factor (the emission model's extinction does not depend on the step).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct StepRule {
    pub density: Option<f32>,
}

impl StepRule {
    pub fn of(s: &RenderSettings) -> StepRule {
        StepRule {
            density: (s.compositing.mode == crate::scene::settings::CompositeMode::Density)
                .then_some(s.compositing.density),
        }
    }
}
