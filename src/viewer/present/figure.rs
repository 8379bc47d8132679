//! The "Export figure" render: the session's view at any size through the headless path (`volcast render`'s),
//! on the viewer's device, with a renderer and volume of its own for the one frame.

use super::Presenter;
use crate::gpu::GpuError;
use crate::pyramid::budget::Budgets;
use crate::render::headless::Headless;
use crate::scene::settings::RenderSettings;
use crate::volume::Volume;

impl Presenter {
    /// Renders `volume` with `s` offscreen and reads it back (blocks until the device is done). The volume is
    /// uploaded again for this frame (streamed until refined for the figure's view where it is over `budgets`' GPU
    /// budget whole), so the window's own frames in flight are untouched.
    pub fn render_offscreen(
        &self,
        volume: &Volume,
        s: &RenderSettings,
        budgets: &Budgets,
    ) -> Result<image::RgbaImage, GpuError> {
        let gpu = &self.gpu;
        let mut headless = Headless::new(gpu)?;
        let mut render = || -> Result<image::RgbaImage, GpuError> {
            headless.renderer.place_volume(gpu, volume, budgets)?;
            headless.renderer.refine(gpu, volume, s)?;
            if s.lighting.gradient_texture {
                headless.renderer.enable_gradient_texture(gpu, volume)?;
            }
            Ok(headless.render(gpu, s)?.image)
        };
        let image = render();
        headless.destroy(gpu);
        image
    }
}
