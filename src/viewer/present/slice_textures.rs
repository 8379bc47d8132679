//! The slice views' images as egui textures: one per view, resampled from the volume (`slice::render`) and
//! uploaded only when what it shows changed. egui owns the textures; its renderer uploads them with the frame's
//! texture changes.

use crate::scene::slice;
use crate::viewer::model::slices::SliceImage;
use crate::volume::Volume;

/// Each view's texture and what it shows.
#[derive(Default)]
pub struct SliceTextures([Option<(SliceImage, egui::TextureHandle)>; 3]);

impl SliceTextures {
    /// The texture showing `image`, made again from `volume` when it shows something else; without a volume, the
    /// last one made (if any).
    pub fn texture(
        &mut self,
        ctx: &egui::Context,
        image: &SliceImage,
        volume: Option<&Volume>,
    ) -> Option<egui::TextureId> {
        let slot = image.slot();
        let cached = &mut self.0[slot];
        if let Some(volume) = volume.filter(|_| cached.as_ref().is_none_or(|(shown, _)| shown != image)) {
            let frame = &image.frame;
            let rgba = slice::render(volume, image.mm_from_index, frame, image.wl);
            let pixels = egui::ColorImage::from_rgba_unmultiplied([frame.width as usize, frame.height as usize], &rgba);
            match cached {
                Some((shown, texture)) => {
                    texture.set(pixels, egui::TextureOptions::LINEAR);
                    *shown = *image;
                }
                None => {
                    let texture = ctx.load_texture(format!("slice {slot}"), pixels, egui::TextureOptions::LINEAR);
                    *cached = Some((*image, texture));
                }
            }
        }
        cached.as_ref().map(|(_, texture)| texture.id())
    }
}
