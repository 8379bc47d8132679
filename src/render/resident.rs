//! Changing which bricks the pool holds: a [`Cut`] (levels.rs) becomes a new pool of its bricks, its page table,
//! and skip ranges that hold for every level shown.

use super::gpu_volume::{upload_directory, upload_layout, GpuVolume, Levels};
use super::levels::{self, Cut};
use super::pool::Pool;
use super::skip;
use super::uniforms::PoolInfo;
use crate::gpu::{Gpu, GpuError};
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
        if self.pyramid.len() < top {
            self.pyramid = levels::pyramid(volume, top as u32)
                .map_err(|e| GpuError::TooLarge(format!("pyramid of {}: {e}", volume.name)))?;
        }
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
        let (image, corners) = upload_layout(gpu, self.layout, &Levels::of(volume, &self.pyramid), &pool)?;
        let directory = match upload_directory(gpu, &pool) {
            Ok(d) => d,
            Err(e) => {
                for i in [image, corners].into_iter().flatten() {
                    i.destroy(gpu);
                }
                return Err(e);
            }
        };
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
        self.info.pool = PoolInfo {
            brick: pool.brick,
            texels: pool.texels(),
        };
        self.pool = pool;
        self.cut = cut.clone();
        // A sample of level L reads voxels of level L: the skip ranges take every level up to the coarsest shown.
        self.bricks = skip::BrickGrid::new(volume).with_levels(&self.pyramid[..top]);
        self.occupancy_key = None;
        Ok(true)
    }
}
