//! The independent CPU reference (tests/common) proven against closed forms and published values, so that a GPU
//! test failing against it points at the GPU. Nothing here needs a GPU.

mod classify;
mod clip;
mod light;
mod selftest;
