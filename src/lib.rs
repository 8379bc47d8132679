//! volcast: a volume ray caster on raw Vulkan. The binary (`src/main.rs`, `src/cli/`) and the tests drive this
//! library, so both exercise one render path.

pub mod bench;
pub mod camera;
pub mod clip;
pub mod colorbar;
pub mod compare;
pub mod fidelity;
pub mod gpu;
pub mod headless;
pub mod huge_pages;
pub mod image_out;
pub mod info;
pub mod lighting;
pub mod movie;
pub mod playback;
pub mod preintegrate;
pub mod quality;
pub mod render;
pub mod settings;
pub mod slice;
pub mod tf;
pub mod tf_auto;
pub mod transfer;
pub mod view_state;
pub mod viewer;
pub mod volume;
