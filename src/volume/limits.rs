//! What volcast holds as one volume. A file of its own so that the rooms below `volume`'s loaders (the pyramid's
//! budgets) can name the limits without importing the loaders.

/// Largest dimension accepted at load; the device's own limit is checked later at upload.
pub const MAX_DIM: u32 = 16384;

/// Most voxels accepted at load (2^36, 64 Gi): a bound on what a header may claim. What is actually held is set
/// by the budgets (`pyramid::budget`): the host holds the finest level within its budget, and the GPU streams
/// bricks of it through a pool within its own (render/stream.rs).
pub const MAX_VOXELS: u64 = 1 << 36;
