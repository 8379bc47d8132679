//! The desktop viewer in a real window, each test under its own Xvfb and driven by real X input (xdotool through
//! XTEST), read back with `xwd`. The X tests share this binary but run one at a time: the X session helper
//! (`common::x11::xvfb`) hands out one turn at a time, held until the test's Xvfb is dropped.

// Public: this binary's tests use only part of what the tests share, and rustc counts a crate's public items as
// used, so the rest is not dead code here (tests/common/mod.rs).
#[path = "../common/mod.rs"]
pub mod common;

mod captures;
mod clip;
mod export;
mod formats;
mod history;
mod idle;
mod keys;
mod large;
mod layers;
mod lighting;
mod panel;
mod recent;
mod series;
mod shortcut_overlay;
mod slice_tools;
mod slices;
mod small_window;
mod spaced;
mod tf;
mod time;
mod turns;
mod window;
mod zarr;
