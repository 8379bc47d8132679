//! What a frame shows, as plain data: the render settings, the camera, the clipping plane, the light and the
//! iso-surfaces, the quality levels, slice geometry and the saved view state. Pure code: the renderer and the
//! viewer read these; nothing here touches the GPU.

pub mod camera;
pub mod clip;
pub mod groups;
pub mod layer_set;
pub mod layers;
pub mod lighting;
pub mod quality;
pub mod settings;
pub mod slice;
pub mod slice_layers;
pub mod values;
pub mod view_state;
