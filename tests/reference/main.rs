//! The independent CPU reference (tests/common) proven against closed forms and published values, rule by rule,
//! so that a GPU test failing against it points at the GPU. The rules are numbered in `RenderSettings`'s docs:
//!
//! | module | rules |
//! |---|---|
//! | `rays` | 0 placement, 1 rays |
//! | `samples` | 2 samples, 3 values |
//! | `classify` | 4 classification |
//! | `shading` | 5 shading |
//! | `compositing` | 6 segments, 7 compositing, 8 output |
//! | `isosurfaces` | 7's iso-surfaces, with 5's directional light |
//! | `light` | 9 shadows and ambient occlusion |
//! | `layers` | 13 layers: label surfaces |
//! | `clip` | 10 clipping plane |
//! | `spacing` | 12 ray spacing |
//! | `harness` | the image comparison the GPU tests judge by, and the reference's speed |
//!
//! `scenes` holds what they share. Nothing here needs a GPU.

// Public: this binary's tests use only part of what the tests share, and rustc counts a crate's public items as
// used, so the rest is not dead code here (tests/common/mod.rs).
#[path = "../common/mod.rs"]
pub mod common;

mod classify;
mod clip;
mod compositing;
mod harness;
mod isosurfaces;
mod layers;
mod light;
mod rays;
mod samples;
mod scenes;
mod shading;
mod spacing;
