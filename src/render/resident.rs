//! Changing which bricks the pool holds: a [`Cut`] (levels.rs) becomes a new pool of its bricks, its page table,
//! and skip ranges that hold for every level shown; `Renderer::show_levels` and `show_cut`.

use super::gpu_volume::{upload_pool, GpuVolume, Levels};
use super::levels::{self, Cut};
use super::pool::Pool;
use super::skip;
use super::Renderer;
use crate::gpu::{Gpu, GpuError};
use crate::scene::settings::RenderSettings;
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
        levels::extend_pyramid(volume, &mut self.pyramid, top as u32)
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
        let (image, corners, directory) = upload_pool(gpu, self.layout, &Levels::of(volume, &self.pyramid), &pool)?;
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
        self.info.pool = pool.info();
        self.pool = pool;
        self.cut = cut.clone();
        // A sample of level L reads voxels of level L: the skip ranges take every level up to the coarsest shown.
        self.bricks = skip::BrickGrid::new(volume).with_levels(&self.pyramid[..top]);
        self.occupancy_key = None;
        Ok(true)
    }
}

impl Renderer {
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
        let top = levels::top_level(volume.dims, brick);
        let grid = vol.pool.grid;
        let cut = match choice {
            levels::LevelChoice::Finest => levels::Cut::uniform(grid, 0),
            levels::LevelChoice::Forced(l) => levels::Cut::uniform(grid, l.min(top)),
            levels::LevelChoice::Screen { factor, bricks } => {
                let view = levels::View::of(&vol.info, s);
                levels::screen_cut(volume.dims, brick, top, &view, factor, bricks)
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
