//! The Vulkan layer: context, resources, barriers, pipelines. Everything here may touch Vulkan; nothing outside
//! `gpu/` and `render/` does.

pub mod context;
pub mod pipeline;
pub mod resources;
pub mod swapchain;
pub mod sync;
pub mod upload;

pub use context::{default_device, list_devices, DeviceInfo, Gpu, GpuOptions, ValidationLog, ValidationMessage};

use ash::vk;

/// How a volume's voxels are stored on the GPU (`--texture`; see `render::VolumeLayout`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TexelPolicy {
    /// On CPU devices (lavapipe) the fastest layout that fits in [`crate::render::AUTO_LIMIT`]: a corner texture
    /// for 8/16-bit data, else a float texture, else native; on GPUs the native texture.
    #[default]
    Auto,
    /// A texture in the data's own format: R8_UNORM, R16_UNORM or R32_SFLOAT (the least memory).
    Native,
    /// An R32_SFLOAT texture (4 bytes per voxel).
    Float,
    /// A corner texture for 8- and 16-bit data (4 or 8 bytes per voxel); float data keeps its texture.
    Corners,
}

/// What can go wrong on the GPU side, with messages a user can act on.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No loader or no driver: volcast can't run at all (exit code 2).
    #[error("no Vulkan available: {0}. Install a Vulkan driver, e.g. `apt-get install mesa-vulkan-drivers` (lavapipe, a software Vulkan that needs no GPU)")]
    NoVulkan(String),
    #[error("no usable Vulkan device: {0}. Install a Vulkan 1.3 driver, e.g. `apt-get install mesa-vulkan-drivers`, or pick another with --device (see `volcast devices`)")]
    NoDevice(String),
    #[error("validation was requested but the Khronos validation layer is not installed: `apt-get install vulkan-validationlayers`")]
    NoValidationLayer,
    #[error("{what} failed: {result}")]
    Vk { what: &'static str, result: vk::Result },
    #[error("GPU memory allocation failed: {0}")]
    Alloc(#[from] gpu_allocator::AllocationError),
    #[error("{0}")]
    TooLarge(String),
    /// A streamed pool's budget holds not even one brick.
    #[error("{0}")]
    NoRoom(String),
    /// Reading a brick from the volume's file failed (it changed or went away since it was opened).
    #[error("{0}")]
    Source(String),
    #[error("invalid render settings: {0}")]
    InvalidSettings(String),
    #[error("internal GPU state lost: {0}")]
    Lost(&'static str),
}

impl GpuError {
    pub fn vk(what: &'static str, result: vk::Result) -> GpuError {
        GpuError::Vk { what, result }
    }

    /// True when there is no Vulkan to run on at all (exit code 2 in the CLI).
    pub fn is_unavailable(&self) -> bool {
        matches!(
            self,
            GpuError::NoVulkan(_) | GpuError::NoDevice(_) | GpuError::NoValidationLayer
        )
    }
}

/// Adds a call name to a raw `VkResult`.
pub trait VkContext<T> {
    fn ctx(self, what: &'static str) -> Result<T, GpuError>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    fn ctx(self, what: &'static str) -> Result<T, GpuError> {
        self.map_err(|e| GpuError::vk(what, e))
    }
}

impl Gpu {
    /// The budgets a volume is shown within on this device, from `--host-budget` and `--gpu-budget` (`None`: a
    /// quarter of the machine's memory, the device's largest heap), with its 3-D texture side limit. Every command
    /// and the viewer map the two flags through here.
    pub fn budgets(&self, host: Option<u64>, device: Option<u64>) -> crate::pyramid::budget::Budgets {
        crate::pyramid::budget::Budgets::host(host).with_gpu(crate::pyramid::budget::GpuBudget {
            bytes: device.unwrap_or(self.device_local_bytes),
            max_dim: self.properties.limits.max_image_dimension3_d,
        })
    }
}
