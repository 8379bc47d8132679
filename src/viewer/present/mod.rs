//! The GPU side of the viewer.

pub mod slice_textures;
