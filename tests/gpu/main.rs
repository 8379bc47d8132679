//! The GPU path on lavapipe under the Khronos validation layer: images against the independent CPU reference
//! (tests/common), the two ray setups against each other, the default quality against the converged image, and
//! the validation plumbing itself.

mod clip;
mod features;
mod lighting;
mod methods_agree;
mod quality;
mod validation_canary;
mod vs_reference;
