//! The measuring tools: the pure image differences every comparison uses, `compare` (the two ray setups side by
//! side), fidelity (a frame's error against its converged image), `bench` and time-series playback.

pub mod bench;
pub mod compare;
pub mod fidelity;
pub mod image_diff;
pub mod playback;
pub mod scale_bench;
