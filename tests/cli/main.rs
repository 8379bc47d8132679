//! The `volcast` binary end to end, as a user runs it: every command and option through the built binary, GPU
//! commands under `--validate` with zero messages. One test binary (not one per file) so the library is linked
//! once for all of them.

// Public: this binary's tests use only part of what the tests share, and rustc counts a crate's public items as
// used, so the rest is not dead code here (tests/common/mod.rs).
#[path = "../common/mod.rs"]
pub mod common;

mod bench;
mod bricks;
mod clip;
mod colorbar;
mod convert;
mod help;
mod info_notes;
mod layers;
mod movie;
mod options;
mod render_and_errors;
mod scale;
mod series;
mod state;
mod tools;
mod units;
mod zarr;
