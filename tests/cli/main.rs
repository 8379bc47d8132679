//! The `volcast` binary end to end, as a user runs it: every command and option through the built binary, GPU
//! commands under `--validate` with zero messages. One test binary (not one per file) so the library is linked
//! once for all of them.

mod bench;
mod clip;
mod colorbar;
mod movie;
mod options;
mod render_and_errors;
mod tools;
