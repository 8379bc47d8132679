//! The resolution pyramid, in one place: which levels a volume has and where they lie ([`geometry`], the halving
//! rule), how a level is made from the one below ([`reduce`], over the element types of [`sample`]; [`in_memory`]
//! for a volume held whole; [`max_dim`] for the axes over `--max-dim`), how bricks nest across levels ([`bricks`]), and which level fits the memory budgets
//! ([`budget`]). Pure code, no Vulkan: `formats`, `convert`, `scale` and `render` ask it, and none of them
//! computes a level's size itself. It names only `volume`'s model (voxel types, geometry, `Volume`), never a room
//! that uses it. docs/large-volumes.md states the rules.

pub mod bricks;
pub mod budget;
pub mod geometry;
pub mod in_memory;
pub mod max_dim;
pub mod reduce;
pub mod sample;
