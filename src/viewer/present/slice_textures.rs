//! The slice views' images as egui textures: one per view, resampled from the volume (`slice::render`) and
//! uploaded only when what it shows changed. egui owns the textures; its renderer uploads them with the frame's
//! texture changes.

use crate::scene::slice;
use crate::scene::slice_layers;
use crate::viewer::model::slices::{SliceImage, SliceSource};

/// Each view's texture and what it shows.
#[derive(Default)]
pub struct SliceTextures([Option<(SliceImage, egui::TextureHandle)>; 3]);

impl SliceTextures {
    /// The texture showing `image`, made again from `source` (the volume, with its layers over it) when it shows
    /// something else; without a source, the last one made (if any).
    pub fn texture(
        &mut self,
        ctx: &egui::Context,
        image: &SliceImage,
        source: Option<SliceSource>,
    ) -> Option<egui::TextureId> {
        let slot = image.slot();
        let cached = &mut self.0[slot];
        if let Some(source) = source.filter(|_| cached.as_ref().is_none_or(|(shown, _)| shown != image)) {
            let frame = &image.frame;
            let mut rgba = slice::render(source.volume, image.mm_from_index, frame, image.wl);
            let (base, mm) = (&source.volume.geometry, image.mm_from_index);
            slice_layers::paint(&mut rgba, base, mm, frame, source.layers, source.styles);
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
