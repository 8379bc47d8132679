//! Where a volume goes on the GPU within the budgets: whole (one texture, or a pool of all its level-0 bricks)
//! when it fits the GPU budget so, else streamed brick by brick through a pool of half the GPU budget
//! (resident.rs, stream.rs). `render`, the viewer, its figure export and movies all place a volume this way, and
//! refine a stream with [`Renderer::refine`].

use super::levels::Cut;
use super::stream::Step;
use super::Renderer;
use crate::gpu::{Gpu, GpuError};
use crate::pyramid::budget::{misfit, Budgets, Shape};
use crate::scene::settings::RenderSettings;
use crate::volume::Volume;

/// Bytes of bricks uploaded per stream step (Voreen's bound per frame): a step never stalls a frame on a large
/// upload.
pub const UPLOAD_PER_STEP: u64 = 32 << 20;

/// One step of `volume` (its shown step) fits `budgets`' GPU budget whole; a volume already held is not measured
/// against the host budget again.
pub fn fits_gpu_whole(volume: &Volume, budgets: &Budgets) -> bool {
    if volume.finer.is_some() {
        // Its finer levels are in the file: only a pool can show them.
        return false;
    }
    let shape = Shape {
        dims: volume.dims,
        voxel_type: volume.source_type,
        steps: 1,
    };
    let gpu_only = Budgets {
        host: u64::MAX,
        ..*budgets
    };
    misfit(&shape, 0, &gpu_only).is_none()
}

/// Why `volume` is streamed, as the notes say it after its name: over the GPU budget whole (`gpu_budget` bytes),
/// or holding a coarser level of its file whose finer levels' bricks are read from the file (or from where
/// [`FinerLevels::origin`](crate::volume::FinerLevels::origin) says).
pub fn streamed_because(volume: &Volume, gpu_budget: u64) -> String {
    match &volume.finer {
        Some(f) => {
            let [x, y, z] = f.dims();
            format!(
                "holds level {} of its {x}x{y}x{z} voxels; the finer levels' bricks are read from {} as the view \
                 needs them",
                f.held(),
                f.origin()
            )
        }
        None => format!(
            "is over the GPU budget whole ({})",
            crate::pyramid::budget::show(gpu_budget)
        ),
    }
}

/// How a volume was placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placed {
    Whole,
    /// Through a pool of this many slots.
    Streamed {
        capacity: usize,
    },
}

/// How far a stream has come towards the cut its view wants.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Progress {
    /// Bricks of the wanted cut resident at their level, of all it has.
    pub resident: usize,
    pub wanted: usize,
    /// Steps taken since the stream started.
    pub steps: u64,
    /// Every wanted brick is resident (or no more can be uploaded).
    pub done: bool,
    /// How many level-0 bricks show each level now.
    pub per_level: Vec<usize>,
}

impl Progress {
    fn of(step: &Step, steps: u64) -> Progress {
        let wanted = step.wanted.shown().len();
        let top = step.shown.level.iter().copied().max().unwrap_or(0) as usize;
        let mut per_level = vec![0usize; top + 1];
        for &l in &step.shown.level {
            per_level[l as usize] += 1;
        }
        Progress {
            resident: wanted - step.missing.min(wanted),
            wanted,
            steps,
            done: step.missing == 0 || step.uploads.is_empty(),
            per_level,
        }
    }

    /// "level 0 in 12, level 1 in 500" (of the level-0 bricks).
    pub fn levels_shown(&self) -> String {
        let levels: Vec<String> = (self.per_level.iter().enumerate())
            .filter(|(_, &n)| n > 0)
            .map(|(l, n)| format!("level {l} in {n}"))
            .collect();
        levels.join(", ")
    }
}

impl Renderer {
    /// Shows `volume` whole if one step of it fits `budgets` whole, else streamed through a pool of half the GPU
    /// budget (the rest for targets and the other textures), which [`refine`](Self::refine) fills. A pool without
    /// room for one brick is [`GpuError::NoRoom`]: the caller shows a coarser whole level instead.
    pub fn place_volume(&mut self, gpu: &Gpu, volume: &Volume, budgets: &Budgets) -> Result<Placed, GpuError> {
        if fits_gpu_whole(volume, budgets) {
            self.set_volume(gpu, volume)?;
            return Ok(Placed::Whole);
        }
        let gpu_budget = budgets.gpu.map_or(gpu.device_local_bytes, |g| g.bytes);
        self.set_volume_streamed(gpu, volume, gpu_budget / 2)?;
        let capacity = self.stream().map_or(0, |s| s.capacity());
        Ok(Placed::Streamed { capacity })
    }

    /// The cut the screen rule wants for the view `s` (one level coarser per doubling of `factor`) within the
    /// streamed pool; `None` when the volume is not streamed.
    pub fn stream_wanted(&mut self, volume: &Volume, s: &RenderSettings, factor: f64) -> Option<Cut> {
        let vol = self.volume.as_mut()?;
        let (top, bound) = vol.stream.as_ref().map(|st| (st.top, st.cut_bound()))?;
        let view = super::levels::View::of(&vol.info, s);
        let (dims, brick) = (vol.pool.dims, vol.pool.brick);
        let classes = vol.refine_classes(volume, s, top);
        let may_refine = |l, b| classes.is_none_or(|c| c.may_refine(l, b));
        Some(super::levels::screen_cut(
            dims,
            brick,
            top,
            (&view, factor),
            bound,
            &may_refine,
        ))
    }

    /// One step of the stream towards `wanted`, at most [`UPLOAD_PER_STEP`] of uploads; says how far it has come.
    /// Call between frames.
    pub fn refine_towards(&mut self, gpu: &Gpu, volume: &Volume, wanted: &Cut) -> Result<Progress, GpuError> {
        let per_step = self.stream_uploads_within(UPLOAD_PER_STEP);
        let step = self.stream_to(gpu, volume, wanted, per_step)?;
        let steps = self.stream().map_or(0, |s| s.steps());
        Ok(Progress::of(&step, steps))
    }

    /// Steps the stream until `wanted` is resident (or nothing more can be uploaded).
    pub fn refine_to(&mut self, gpu: &Gpu, volume: &Volume, wanted: &Cut) -> Result<Progress, GpuError> {
        loop {
            let progress = self.refine_towards(gpu, volume, wanted)?;
            if progress.done {
                return Ok(progress);
            }
        }
    }

    /// Steps the stream until the screen rule's cut for `s` is resident (headless: a movie frame, a figure, a
    /// render). `None` when the volume is not streamed.
    pub fn refine(&mut self, gpu: &Gpu, volume: &Volume, s: &RenderSettings) -> Result<Option<Progress>, GpuError> {
        match self.stream_wanted(volume, s, 1.0) {
            Some(wanted) => self.refine_to(gpu, volume, &wanted).map(Some),
            None => Ok(None),
        }
    }
}
