//! The volume's pass: the same [`Renderer`] as `volcast render`, marching into an offscreen view image, and the
//! volume on the GPU — installed, switched to another step of a series, the next step uploaded ahead while a
//! series plays, the gradient texture made on the first frame that reads it. A frame whose view has not changed
//! does not march ([`ViewContent`]).

use super::reuse::ViewContent;
use crate::gpu::resources::{Image, ImageDesc};
use crate::gpu::sync::Access;
use crate::gpu::{Gpu, GpuError, VkContext};
use crate::pyramid::budget::Budgets;
use crate::render::headless::OUTPUT_FORMAT;
use crate::render::levels::Cut;
use crate::render::placement::{Placed, Progress};
use crate::render::{PassTimings, PreparedVolume, Renderer};
use crate::scene::settings::RenderSettings;
use crate::volume::Volume;
use ash::vk;

#[derive(Default)]
pub(super) struct VolumePass {
    renderer: Option<Renderer>,
    /// What the march draws into; blitted to the swapchain image. Sized to the frame's settings.
    view: Option<Image>,
    /// The step after the shown one while a series plays, uploaded ahead of display.
    ahead: Option<(u32, PreparedVolume)>,
    /// A volume streamed through a pool: the cut its view last reached (nothing to do until the view wants
    /// another), and how far it came.
    stream: Option<Reached>,
    /// What the view image holds: a frame that would march it again shows it instead.
    content: ViewContent,
    /// Per frame slot: whether the frame last recorded there marched (else it wrote no GPU times).
    slot_marched: Vec<bool>,
}

#[derive(Default)]
struct Reached {
    cut: Option<Cut>,
    progress: Option<Progress>,
}

fn wait_idle(gpu: &Gpu) -> Result<(), GpuError> {
    // SAFETY: plain wait on a live device.
    unsafe { gpu.device.device_wait_idle() }.ctx("vkDeviceWaitIdle")
}

impl VolumePass {
    pub(super) fn new(gpu: &Gpu, frames_in_flight: usize) -> Result<VolumePass, GpuError> {
        Ok(VolumePass {
            renderer: Some(Renderer::new(gpu, OUTPUT_FORMAT, frames_in_flight)?),
            view: None,
            ahead: None,
            stream: None,
            content: ViewContent::default(),
            slot_marched: vec![false; frames_in_flight],
        })
    }

    fn renderer(&mut self) -> Result<&mut Renderer, GpuError> {
        self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))
    }

    pub(super) fn view(&self) -> Result<&Image, GpuError> {
        self.view.as_ref().ok_or(GpuError::Lost("view image"))
    }

    /// Shows `volume` (waiting for in-flight frames: their descriptors are rewritten): a series whole (the loader
    /// read it within the GPU budget), one step whole if it fits `budgets` so, else streamed through a pool
    /// ([`refine`](Self::refine) fills it).
    pub(super) fn set_volume(&mut self, gpu: &Gpu, volume: &Volume, budgets: &Budgets) -> Result<Placed, GpuError> {
        wait_idle(gpu)?;
        if let Some((_, old)) = self.ahead.take() {
            old.destroy(gpu);
        }
        self.stream = None;
        self.content.changed();
        let renderer = self.renderer()?;
        let placed = if volume.timesteps() > 1 {
            renderer.set_volume(gpu, volume)?;
            Placed::Whole
        } else {
            renderer.place_volume(gpu, volume, budgets)?
        };
        if let Placed::Streamed { .. } = placed {
            self.stream = Some(Reached::default());
        }
        Ok(placed)
    }

    /// Shows `layers` with the volume (waiting for in-flight frames: the layers' bindings are rewritten).
    pub(super) fn set_layers(&mut self, gpu: &Gpu, layers: &crate::scene::layer_set::Layers) -> Result<(), GpuError> {
        wait_idle(gpu)?;
        self.content.changed();
        self.renderer()?.show_layers(gpu, layers)
    }

    /// One step of a streamed volume towards the cut the still view `s` wants (one level coarser while `moving`),
    /// unless that cut is resident already: how far it has come, and whether it reached the cut just now. `None`
    /// for a volume shown whole. `volume` is the one given to `set_volume`.
    pub(super) fn refine(
        &mut self,
        gpu: &Gpu,
        s: &RenderSettings,
        moving: bool,
        volume: &Volume,
    ) -> Result<Option<(Progress, bool)>, GpuError> {
        let (Some(reached), Some(renderer), content) =
            (self.stream.as_mut(), self.renderer.as_mut(), &mut self.content)
        else {
            return Ok(None);
        };
        let factor = if moving { 2.0 } else { 1.0 };
        let Some(wanted) = renderer.stream_wanted(volume, s, factor) else {
            return Ok(None);
        };
        if reached.cut.as_ref() == Some(&wanted) {
            return Ok(reached.progress.clone().map(|p| (p, false)));
        }
        // The page table, and the pool's slots uploaded, are read by the frames in flight.
        wait_idle(gpu)?;
        content.changed();
        let progress = renderer.refine_towards(gpu, volume, &wanted)?;
        if progress.done {
            reached.cut = Some(wanted);
        }
        reached.progress = Some(progress.clone());
        Ok(Some((progress.clone(), progress.done)))
    }

    /// Shows step `step` of `series` (whose voxels are that step's now): a descriptor update when it was uploaded
    /// ahead, else an upload.
    pub(super) fn show_step(&mut self, gpu: &Gpu, series: &Volume, step: u32) -> Result<(), GpuError> {
        // The volume replaced is one that in-flight frames use.
        wait_idle(gpu)?;
        self.content.changed();
        let ahead = self.ahead.take();
        let renderer = self.renderer()?;
        match ahead {
            Some((ahead_step, prepared)) if ahead_step == step => {
                renderer.install_volume(gpu, prepared);
                Ok(())
            }
            other => {
                if let Some((_, stale)) = other {
                    stale.destroy(gpu);
                }
                renderer.set_volume(gpu, series)
            }
        }
    }

    /// Whether step `step` is the one uploaded ahead.
    pub(super) fn holds_ahead(&self, step: u32) -> bool {
        self.ahead.as_ref().is_some_and(|(s, _)| *s == step)
    }

    /// Forgets the step uploaded ahead.
    pub(super) fn drop_ahead(&mut self, gpu: &Gpu) {
        if let Some((_, stale)) = self.ahead.take() {
            stale.destroy(gpu);
        }
    }

    /// Uploads `volume` (showing step `step`) to be shown later. A step that cannot be uploaded now (memory for
    /// two volumes) is uploaded when it is due instead, where a failure is reported.
    pub(super) fn upload_ahead(&mut self, gpu: &Gpu, step: u32, volume: &Volume) -> Result<(), GpuError> {
        let renderer = self.renderer.as_ref().ok_or(GpuError::Lost("renderer"))?;
        self.ahead = renderer.prepare_volume(gpu, volume).ok().map(|p| (step, p));
        Ok(())
    }

    /// Creates what `settings` needs beyond the frame (the gradient texture from `kept`, position targets,
    /// colormap, the view image) after waiting for in-flight frames, only when something changed.
    pub(super) fn prepare(
        &mut self,
        gpu: &Gpu,
        settings: &RenderSettings,
        kept: Option<&Volume>,
    ) -> Result<(), GpuError> {
        let view_fits = self
            .view
            .as_ref()
            .is_some_and(|v| (v.desc.extent.width, v.desc.extent.height) == (settings.width, settings.height));
        // The gradient texture on the first frame that reads gradients (the volume was kept for it).
        if settings.lighting.gradient_texture && self.renderer.as_ref().is_some_and(|r| !r.has_gradient_texture()) {
            let volume = kept.ok_or(GpuError::Lost("no volume kept for gradients"))?;
            wait_idle(gpu)?;
            self.content.changed();
            self.renderer()?.enable_gradient_texture(gpu, volume)?;
        }
        if view_fits && !self.renderer()?.needs_prepare(settings) {
            return Ok(());
        }
        wait_idle(gpu)?;
        self.content.changed();
        if !view_fits {
            if let Some(old) = self.view.take() {
                old.destroy(gpu);
            }
            // TRANSFER_DST: a frame of spaced rays (rule 12, `draft`) is blitted into it.
            let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::TRANSFER_DST;
            self.view = Some(Image::new(
                gpu,
                ImageDesc::d2(OUTPUT_FORMAT, settings.width, settings.height, usage),
                "view",
            )?);
        }
        self.renderer()?.prepare(gpu, settings)
    }

    /// The GPU times of the frame last recorded in `slot` (its fence waited); `None` where it did not march.
    pub(super) fn timings(&self, gpu: &Gpu, slot: usize) -> Result<Option<PassTimings>, GpuError> {
        if !self.slot_marched.get(slot).copied().unwrap_or(false) {
            return Ok(None);
        }
        let renderer = self.renderer.as_ref().ok_or(GpuError::Lost("renderer"))?;
        renderer.timings(gpu, slot)
    }

    /// Records the march into the view image unless it holds this frame already. Returns how the view image is
    /// left for the blit: written as a colour attachment (marched), or still as the last frame's transfers read it.
    pub(super) fn record(
        &mut self,
        gpu: &Gpu,
        cb: vk::CommandBuffer,
        slot: usize,
        settings: &RenderSettings,
    ) -> Result<Access, GpuError> {
        let marches = self.content.stale(settings);
        if let Some(m) = self.slot_marched.get_mut(slot) {
            *m = marches;
        }
        if !marches {
            return Ok(Access::TransferRead);
        }
        self.content.marched(None);
        let view = self.view.as_ref().ok_or(GpuError::Lost("view image"))?;
        let target = (view.raw, view.view);
        let renderer = self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))?;
        renderer.record(gpu, cb, slot, target, Access::TransferRead, settings)?;
        self.content.marched(Some(settings));
        Ok(Access::ColorAttachmentWrite)
    }

    /// Destroys the volume uploaded ahead, the renderer and the view image. The device must be idle.
    pub(super) fn destroy(mut self, gpu: &Gpu) {
        self.drop_ahead(gpu);
        if let Some(r) = self.renderer.take() {
            r.destroy(gpu);
        }
        if let Some(v) = self.view.take() {
            v.destroy(gpu);
        }
    }
}
