//! Values to colour and opacity, all pure code: the colormaps, the transfer function (presets, JSON, the baked
//! lookup table), the automatic function chosen by modality, pre-integration's tables and the colour bar.

pub mod auto;
pub mod colorbar;
pub mod colormap;
pub mod function;
pub mod preintegrate;

pub use colormap::Colormap;
