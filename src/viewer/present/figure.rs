//! The "Export figure" render: the session's view at any size through the headless path (`volcast render`'s),
//! on the viewer's device, with a renderer and volume of its own for the one frame.

use super::Presenter;
use crate::gpu::GpuError;
use crate::render::headless::Headless;
use crate::scene::settings::RenderSettings;
use crate::volume::Volume;

impl Presenter {
    /// Renders `volume` with `s` offscreen and reads it back (blocks until the device is done). The volume is
    /// uploaded again for this frame, so the window's own frames in flight are untouched.
    pub fn render_offscreen(&self, volume: &Volume, s: &RenderSettings) -> Result<image::RgbaImage, GpuError> {
        let gpu = &self.gpu;
        let mut headless = Headless::new(gpu)?;
        let mut render = || -> Result<image::RgbaImage, GpuError> {
            headless.set_volume(gpu, volume)?;
            if s.gradient_texture {
                headless.renderer.enable_gradient_texture(gpu, volume)?;
            }
            Ok(headless.render(gpu, s)?.image)
        };
        let image = render();
        headless.destroy(gpu);
        image
    }
}
