//! volcast: a volume ray caster on raw Vulkan. The binary (`src/main.rs`, `src/cli/`) and the tests drive this
//! library, so both exercise one render path. ARCHITECTURE.md draws the map of these rooms.
//!
//! Pure rooms (no Vulkan): `volume` (the in-memory model: voxels, placement, time steps, value ranges), `pyramid`
//! (the resolution pyramid: level sizes, the reduction from one level to the next, bricks across levels, the level
//! that fits the budgets), `formats` (files to a `Volume`: one reader per format, and the entry point that picks
//! one), `convert` (volumes to OME-Zarr stores), `scale` (volumes within memory budgets: reading a level, the
//! preview, the pyramid cache), `transfer` (values to colour and opacity), `scene` (what a frame shows, as plain
//! data). Rooms that drive the GPU: `gpu` (the Vulkan layer), `render` (the passes and the headless path), `measure`
//! (compare, fidelity, bench, playback), `movie` and `viewer`. `cli` holds the command line's options and subcommand
//! bodies, here so that the Python module (`python/`) parses the same options and renders through the same steps as
//! `volcast render`.

pub mod cli;
pub mod convert;
pub mod distributed;
pub mod formats;
pub mod gpu;
pub mod measure;
pub mod movie;
pub mod pyramid;
pub mod render;
pub mod scale;
pub mod scene;
pub mod transfer;
pub mod viewer;
pub mod volume;
