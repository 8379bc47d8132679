//! The GPU path on lavapipe under the Khronos validation layer: images against the independent CPU reference
//! (tests/common), the two ray setups against each other, the default quality against the converged image, and
//! the validation plumbing itself.

// Public: this binary's tests use only part of what the tests share, and rustc counts a crate's public items as
// used, so the rest is not dead code here (tests/common/mod.rs).
#[path = "../common/mod.rs"]
pub mod common;

mod clip;
mod features;
mod finer;
mod layers;
mod levels;
mod lighting;
mod methods_agree;
mod pool;
mod quality;
mod refinable;
mod spacing;
mod stand_in;
mod stream;
mod validation_canary;
mod vs_reference;
