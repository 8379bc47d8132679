//! Figures: a render with the colour bar of its classification beside it and a scale bar on it, as `volcast
//! render --colorbar --scale-bar` writes and the viewer's "Export figure" saves.

use crate::scene::settings::RenderSettings;
use crate::transfer::auto::VolumeFacts;
use crate::transfer::colorbar::{append_colorbar, colorbar, ColorbarSpec};
use crate::volume::Volume;
use image::RgbaImage;

/// `image` with the colour bar of `s`'s classification appended (unit "HU" for CT): it grows by the bar's width.
pub fn with_colorbar(image: &RgbaImage, s: &RenderSettings, volume: &Volume) -> RgbaImage {
    let classification = s.classification();
    append_colorbar(image, &spec(&classification, s, volume))
}

/// `image`, a render of `s` of `volume`, with the scale bar drawn on it and the colour bar appended where asked.
pub fn annotated(image: RgbaImage, s: &RenderSettings, volume: &Volume, colorbar: bool, scale_bar: bool) -> RgbaImage {
    let image = if scale_bar {
        with_scale_bar(image, s, volume)
    } else {
        image
    };
    if colorbar {
        with_colorbar(&image, s, volume)
    } else {
        image
    }
}

/// Draws the scale bar of `s` onto `image`, a render of `volume` (`render/scale_bar.rs`).
pub fn with_scale_bar(mut image: RgbaImage, s: &RenderSettings, volume: &Volume) -> RgbaImage {
    crate::render::scale_bar::draw(&mut image, s, volume.geometry.world_per_mm(volume.dims));
    image
}

/// The width of the colour bar that [`with_colorbar`] appends to an image `height` pixels high (it does not
/// depend on the image's width): a figure of a given width renders that much narrower.
pub fn colorbar_width(s: &RenderSettings, volume: &Volume, height: u32) -> u32 {
    let classification = s.classification();
    colorbar(&spec(&classification, s, volume), height).width()
}

fn spec<'a>(
    classification: &'a crate::transfer::function::Classification,
    s: &RenderSettings,
    volume: &Volume,
) -> ColorbarSpec<'a> {
    let to_u8 = |c: f32| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
    ColorbarSpec {
        classification,
        window: s.colour.window,
        range: volume.range,
        unit: VolumeFacts::of(volume).kind().unit(),
        background: [to_u8(s.background.x), to_u8(s.background.y), to_u8(s.background.z)],
    }
}
