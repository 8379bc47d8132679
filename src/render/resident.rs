//! Changing which bricks the pool holds: a [`Cut`] (levels.rs) becomes a new pool of its bricks, its page table,
//! and skip ranges that hold for every level shown (`Renderer::show_levels` and `show_cut`); or the pool is
//! streamed: a fixed number of slots filled brick by brick as the view needs them (stream.rs,
//! `Renderer::start_stream` and `stream_step`).

use super::gpu_volume::{
    corners_format, image_3d, layout_for, occupancy_image, upload_pool, GpuVolume, PoolImages, VolumeLayout,
};
use super::levels::{self, Cut};
use super::pool::{slot_side, Pool, TILED_BRICK};
use super::skip;
use super::stream::{Step, Stream};
use super::texels::Levels;
use super::Renderer;
use crate::gpu::{Gpu, GpuError, TexelPolicy};
use crate::pyramid::bricks::{grid_at, top_level};
use crate::pyramid::in_memory::extend_pyramid;
use crate::scene::settings::RenderSettings;
use crate::volume::cells::CellRanges;
use crate::volume::Volume;

impl GpuVolume {
    /// Shows `cut` of `volume` (the volume this was made from): builds the pyramid up to its coarsest level once,
    /// uploads a pool of its bricks and its page table, and replaces the current ones. The gradient texture is
    /// dropped (the caller makes it again). No frame may still be using this volume. Returns whether anything
    /// changed.
    pub(super) fn show_cut(&mut self, gpu: &Gpu, volume: &Volume, cut: &Cut) -> Result<bool, GpuError> {
        if *cut == self.cut {
            return Ok(false);
        }
        let top = cut.level.iter().copied().max().unwrap_or(0) as usize;
        extend_pyramid(volume, &mut self.pyramid, top as u32)
            .map_err(|e| GpuError::TooLarge(format!("pyramid of {}: {e}", volume.name)))?;
        let limit = gpu.properties.limits.max_image_dimension3_d;
        let pool = Pool::with_cut(volume.dims, self.pool.brick, limit, cut).map_err(GpuError::TooLarge)?;
        let needed = pool.texel_count() * self.layout.bytes_per_voxel();
        if needed > gpu.device_local_bytes / 2 {
            return Err(GpuError::TooLarge(format!(
                "a pool of {} bricks needs {} MiB on the GPU as {} (plus as much again to upload) but the device has {} MiB",
                cut.shown().len(),
                needed >> 20,
                self.layout.name(),
                gpu.device_local_bytes >> 20
            )));
        }
        let images = upload_pool(gpu, self.layout, &Levels::of(volume, &self.pyramid), &pool)?;
        self.replace_pool(gpu, images, pool);
        self.cut = cut.clone();
        self.info.step_level = step_level(cut);
        self.stream = None;
        self.skip_follows_cut();
        Ok(true)
    }
}

impl GpuVolume {
    /// The cut shown changed: the skip grid follows it when a frame next needs it ([`skip_grid`](Self::skip_grid)),
    /// not on every step of a stream, and the occupancy is computed again.
    fn skip_follows_cut(&mut self) {
        self.skip_stale = true;
        self.occupancy_key = None;
    }

    /// The skip grid for the cut shown: a sample of level L reads voxels of level L, so each skip brick takes the
    /// ranges of the levels shown where it lies (`levels::cut_ranges`, over each level's grid, made once).
    pub(super) fn skip_grid(&mut self) -> &skip::BrickGrid {
        if self.skip_stale {
            if self.skip_levels.is_empty() {
                // Until the first cut, `bricks` is level 0's own grid (replaced below).
                self.skip_levels.push(std::mem::take(&mut self.bricks));
            }
            while self.skip_levels.len() <= self.pyramid.len() {
                let level = &self.pyramid[self.skip_levels.len() - 1];
                self.skip_levels.push(skip::BrickGrid::new(level));
            }
            let held = (self.info.held, &self.finer_ranges);
            self.bricks = levels::cut_ranges(&self.skip_levels, &self.cut, self.pool.brick, held);
            self.skip_stale = false;
        }
        &self.bricks
    }

    /// Puts `images` (the pool's texture or corners, and page table) and `pool` in place of the current ones,
    /// destroying those and what was filled from them (the gradient texture, the light grid). No frame may still use
    /// them.
    fn replace_pool(&mut self, gpu: &Gpu, (image, corners, directory): PoolImages, pool: Pool) {
        for old in [
            std::mem::replace(&mut self.image, image),
            std::mem::replace(&mut self.corners, corners),
            self.gradient.take(),
        ]
        .into_iter()
        .flatten()
        {
            old.destroy(gpu);
        }
        std::mem::replace(&mut self.directory, directory).destroy(gpu);
        self.drop_light(gpu);
        self.info.pool = pool.info();
        self.pool = pool;
    }

    /// Drops the light grid (it was filled from bricks no longer shown); the next frame that needs it fills it.
    fn drop_light(&mut self, gpu: &Gpu) {
        if let Some(l) = self.light.take() {
            l.image.destroy(gpu);
        }
    }

    /// `volume` streamed through a pool of at most `pool_bytes` on the device, in bricks of `brick` voxels: as many
    /// slots as fit (no more than the pyramid has bricks), in the native texel format unless `policy` names another
    /// (a wider layout would hold fewer bricks). Nothing is shown until the first step.
    pub(super) fn streamed(
        gpu: &Gpu,
        policy: TexelPolicy,
        volume: &Volume,
        brick: u32,
        pool_bytes: u64,
    ) -> Result<GpuVolume, GpuError> {
        let (dims, _) = level0(volume);
        let brick3 = dims.map(|d| brick.clamp(1, d));
        let policy = match policy {
            TexelPolicy::Auto => TexelPolicy::Native,
            p => p,
        };
        let slot_texels = brick3.iter().map(|&b| u64::from(slot_side(b))).product::<u64>();
        let layout = layout_for(gpu, policy, volume, slot_texels);
        let top = top_level(dims, brick3);
        let bricks_in_pyramid = (0..=top)
            .map(|l| grid_at(dims, brick3, l).iter().map(|&g| g as u64).product::<u64>())
            .sum::<u64>();
        let limit = gpu.properties.limits.max_image_dimension3_d;
        let fit = pool_bytes / (slot_texels * layout.bytes_per_voxel());
        // Every brick of the pyramid where the budget takes their arrangement; else as many as it takes.
        let capacity = super::pool::slots_holding(bricks_in_pyramid, brick3, limit)
            .filter(|&n| n <= fit)
            .unwrap_or_else(|| super::pool::slots_within(fit.min(bricks_in_pyramid), brick3, limit));
        if capacity == 0 {
            return Err(GpuError::NoRoom(format!(
                "a brick of {}x{}x{} needs {} KiB on the GPU as {} and the pool may take {} KiB",
                brick3[0],
                brick3[1],
                brick3[2],
                (slot_texels * layout.bytes_per_voxel()) >> 10,
                layout.name(),
                pool_bytes >> 10
            )));
        }
        let bricks = skip::BrickGrid::new(volume);
        let occupancy = occupancy_image(gpu, &bricks)?;
        let directory = match image_3d(gpu, ash::vk::Format::R32G32_UINT, [1, 1, 1], "page table") {
            Ok(d) => d,
            Err(e) => {
                occupancy.destroy(gpu);
                return Err(e);
            }
        };
        let pool = Pool::with_capacity(dims, brick3, limit, 1, 0).map_err(GpuError::TooLarge)?;
        let mut v = GpuVolume::assemble(volume, layout, (None, None, directory), pool, bricks, occupancy);
        if let Err(e) = v.start_stream(gpu, volume, brick, capacity as usize) {
            v.destroy(gpu);
            return Err(e);
        }
        Ok(v)
    }

    /// Replaces the pool with an empty one of `capacity` slots of `brick`-voxel bricks for streaming `volume`,
    /// whose pyramid is made up to its top level (one brick). Nothing is shown until the first step.
    fn start_stream(&mut self, gpu: &Gpu, volume: &Volume, brick: u32, capacity: usize) -> Result<(), GpuError> {
        let (dims, held) = level0(volume);
        let brick = dims.map(|d| brick.clamp(1, d));
        let top = top_level(dims, brick);
        extend_pyramid(volume, &mut self.pyramid, top.saturating_sub(held))
            .map_err(|e| GpuError::TooLarge(format!("pyramid of {}: {e}", volume.name)))?;
        let limit = gpu.properties.limits.max_image_dimension3_d;
        let pool = Pool::with_capacity(dims, brick, limit, capacity, top).map_err(GpuError::TooLarge)?;
        let format = match self.layout {
            VolumeLayout::Texture(f) => f,
            corners => corners_format(corners),
        };
        let image = image_3d(gpu, format, pool.texels(), "streamed pool")?;
        let directory = match image_3d(gpu, ash::vk::Format::R32G32_UINT, pool.grid, "page table") {
            Ok(d) => d,
            Err(e) => {
                image.destroy(gpu);
                return Err(e);
            }
        };
        let (image, corners) = match self.layout {
            VolumeLayout::Texture(_) => (Some(image), None),
            _ => (None, Some(image)),
        };
        self.stream = Some(Stream::new(pool.capacity(), top));
        self.cut = levels::Cut::uniform(pool.grid, top);
        self.replace_pool(gpu, (image, corners, directory), pool);
        if let Some(f) = &volume.finer {
            // The pool's level 0 is the file's; the volume is its level `held`.
            (self.info.dims, self.info.geometry) = (f.dims(), f.geometry());
            self.info.source_voxels = 1.0;
        }
        self.info.held = held;
        self.info.step_level = step_level(&self.cut);
        (self.refinable, self.refine_classes) = (None, None);
        self.skip_follows_cut();
        Ok(())
    }

    /// Which bricks of levels 1..=`top` of the pool's pyramid frame `s` may refine (refinable.rs), or None where
    /// that is not known: a series, or a file's finer levels without level 0's ranges.
    pub(super) fn refine_classes(
        &mut self,
        volume: &Volume,
        s: &RenderSettings,
        top: u32,
    ) -> Option<&super::refinable::Classes> {
        let key = super::OccupancyKey::of(s);
        if self.refine_classes.as_ref().is_none_or(|(k, _)| *k != key) {
            if self.refinable.is_none() {
                let made;
                let cells = match &volume.finer {
                    Some(f) => volume.cells.as_deref().filter(|c| c.dims == f.dims())?,
                    None if volume.timesteps() == 1 => {
                        made = CellRanges::of(volume);
                        &made
                    }
                    None => return None,
                };
                self.refinable = Some(super::refinable::Refinable::new(cells, volume, self.pool.brick, top));
            }
            let lut = crate::transfer::function::bake(&s.classification(), s.colour.window, self.info.range);
            let classes = self.refinable.as_ref()?.classes(&lut, s);
            self.refine_classes = Some((key, classes));
        }
        self.refine_classes.as_ref().map(|(_, c)| c)
    }

    /// One step of the stream towards `wanted`: its uploads into their slots and the page table of what is shown.
    fn stream_step(&mut self, gpu: &Gpu, volume: &Volume, wanted: &Cut, max_uploads: usize) -> Result<Step, GpuError> {
        let stream = self.stream.as_mut().ok_or(GpuError::Lost("the pool is not streamed"))?;
        let step = stream.step(wanted, max_uploads);
        let fresh = stream.uploaded == step.uploads.len() as u64;
        stream.write(&mut self.pool, &step.shown);
        if !step.uploads.is_empty() {
            let slots: Vec<u32> = step.uploads.iter().map(|&(slot, _)| slot).collect();
            let image = self
                .image
                .as_ref()
                .or(self.corners.as_ref())
                .ok_or(GpuError::Lost("the pool has no image"))?;
            let levels = Levels::held(volume, &self.pyramid, self.info.held);
            let finer = volume.finer.as_deref();
            let read = super::brick_upload::upload_bricks(
                gpu,
                image,
                self.layout,
                (&levels, finer),
                &self.pool,
                &slots,
                fresh,
            )?;
            for (r, cells) in read {
                let normal = cells.map(|range| volume.normalize_range(range));
                self.finer_ranges.insert((r.level, r.brick), normal);
            }
            if let Some(g) = self.gradient.take() {
                g.destroy(gpu);
            }
            self.drop_light(gpu);
        }
        let table = self.pool.table();
        super::gpu_volume::upload_3d(
            gpu,
            &mut self.directory,
            bytemuck::cast_slice(&table),
            self.pool.grid[2],
        )?;
        if self.cut != step.shown {
            self.cut = step.shown.clone();
            self.skip_follows_cut();
            self.info.step_level = step_level(&self.cut);
        }
        Ok(step)
    }
}

/// Level 0's size of `volume` (its file's, where it holds a coarser level with finer ones in the file) and the
/// level it holds.
fn level0(volume: &Volume) -> ([u32; 3], u32) {
    volume.finer.as_ref().map_or((volume.dims, 0), |f| (f.dims(), f.held()))
}

/// The march's step level for `cut`: the finest level shown (`VolumeInfo::step_level`). A sample of level L
/// resolves no more than one of its voxels, so a cut of coarser levels takes longer steps.
pub fn step_level(cut: &Cut) -> u32 {
    cut.level.iter().copied().min().unwrap_or(0)
}

impl Renderer {
    /// Streams `volume` (the one last given to `set_volume`) through a pool of `capacity` slots of bricks of
    /// `--brick-size` (default [`TILED_BRICK`]) voxels: the pool starts empty, and [`stream_step`](Self::stream_step)
    /// fills it. Call between frames.
    pub fn start_stream(&mut self, gpu: &Gpu, volume: &Volume, capacity: usize) -> Result<(), GpuError> {
        let brick = self.brick_side.unwrap_or(TILED_BRICK);
        let Some(vol) = &mut self.volume else {
            return Err(GpuError::Lost("no volume loaded"));
        };
        vol.start_stream(gpu, volume, brick, capacity)?;
        self.write_volume_set(gpu);
        Ok(())
    }

    /// One step of the stream: the screen rule's cut for the view `s` (with `factor`, within the pool less the
    /// top's slot), at most `max_uploads` bricks uploaded (coarsest first), the rest shown from the finest resident
    /// coarser brick. Call between frames; the step says how many wanted bricks are still missing.
    pub fn stream_step(
        &mut self,
        gpu: &Gpu,
        volume: &Volume,
        s: &RenderSettings,
        factor: f64,
        max_uploads: usize,
    ) -> Result<Step, GpuError> {
        let wanted = self
            .stream_wanted(volume, s, factor)
            .ok_or(GpuError::Lost("the pool is not streamed (start_stream first)"))?;
        self.stream_to(gpu, volume, &wanted, max_uploads)
    }

    /// One step of the stream towards `wanted` (a cut of the streamed pool's grid within its bound).
    pub fn stream_to(
        &mut self,
        gpu: &Gpu,
        volume: &Volume,
        wanted: &Cut,
        max_uploads: usize,
    ) -> Result<Step, GpuError> {
        let Some(vol) = &mut self.volume else {
            return Err(GpuError::Lost("no volume loaded"));
        };
        if wanted.grid != vol.pool.grid {
            return Err(GpuError::Lost("a cut for another brick grid"));
        }
        let step = vol.stream_step(gpu, volume, wanted, max_uploads)?;
        if !step.uploads.is_empty() {
            self.write_volume_set(gpu);
        }
        Ok(step)
    }

    /// Replaces the current volume with `volume` streamed through a pool of at most `pool_bytes` of device memory
    /// in bricks of `--brick-size` (default [`TILED_BRICK`]); [`stream_step`](Self::stream_step) fills it.
    pub fn set_volume_streamed(&mut self, gpu: &Gpu, volume: &Volume, pool_bytes: u64) -> Result<(), GpuError> {
        let brick = self.brick_side.unwrap_or(TILED_BRICK);
        let v = GpuVolume::streamed(gpu, self.texel_policy, volume, brick, pool_bytes)?;
        if let Some(old) = self.volume.replace(v) {
            old.destroy(gpu);
        }
        self.write_volume_set(gpu);
        Ok(())
    }

    /// How many of the streamed pool's bricks `bytes` of uploads hold (at least one).
    pub fn stream_uploads_within(&self, bytes: u64) -> usize {
        self.volume.as_ref().map_or(1, |v| {
            let texels = v.pool.brick.iter().map(|&b| u64::from(slot_side(b))).product::<u64>();
            (bytes / (texels * v.layout.bytes_per_voxel())).max(1) as usize
        })
    }

    /// The stream's state (None: not streaming).
    pub fn stream(&self) -> Option<&Stream> {
        self.volume.as_ref().and_then(|v| v.stream.as_ref())
    }
    /// Shows the levels `choice` gives the view `s` of `volume` (the one last given to `set_volume`): a pool of the
    /// bricks of that cut and its page table (levels.rs has the rule). A gradient texture is made again for the new
    /// pool. Call between frames. Returns the cut shown.
    pub fn show_levels(
        &mut self,
        gpu: &Gpu,
        volume: &Volume,
        s: &RenderSettings,
        choice: levels::LevelChoice,
    ) -> Result<levels::Cut, GpuError> {
        let Some(vol) = &mut self.volume else {
            return Err(GpuError::Lost("no volume loaded"));
        };
        let brick = vol.pool.brick;
        let top = top_level(volume.dims, brick);
        let grid = vol.pool.grid;
        let cut = match choice {
            levels::LevelChoice::Finest => levels::Cut::uniform(grid, 0),
            levels::LevelChoice::Forced(l) => levels::Cut::uniform(grid, l.min(top)),
            levels::LevelChoice::Screen { factor, bricks } => {
                let view = levels::View::of(&vol.info, s);
                let classes = vol.refine_classes(volume, s, top);
                let may_refine = |l, b| classes.is_none_or(|c| c.may_refine(l, b));
                levels::screen_cut(volume.dims, brick, top, (&view, factor), bricks, &may_refine)
            }
        };
        self.show_cut(gpu, volume, &cut)?;
        Ok(cut)
    }

    /// Shows `cut` of `volume` (the one last given to `set_volume`; `cut.grid` must be its pool's grid), as
    /// [`show_levels`](Self::show_levels) does for the cut it chooses.
    pub fn show_cut(&mut self, gpu: &Gpu, volume: &Volume, cut: &levels::Cut) -> Result<(), GpuError> {
        let Some(vol) = &mut self.volume else {
            return Err(GpuError::Lost("no volume loaded"));
        };
        if cut.grid != vol.pool.grid || cut.level.len() != vol.pool.directory.len() {
            return Err(GpuError::Lost("a cut for another brick grid"));
        }
        let had_gradients = vol.gradient.is_some();
        if vol.show_cut(gpu, volume, cut)? {
            self.write_volume_set(gpu);
            if had_gradients {
                self.enable_gradient_texture(gpu, volume)?;
            }
        }
        Ok(())
    }
}
