//! The layers over a slice view's image, and their values under the cursor: rule 13's placement and each layer's
//! look in two dimensions, as 3D Slicer draws layers over its slices. Layers go over the image in their order;
//! hidden layers and hidden ids show nothing.
//! - An **overlay** is sampled trilinearly at the pixel's point (by its own affine). Where it shows (rule 13: finite,
//!   its threshold or else its window), its colour goes over the pixel with its opacity (`composite`), is added
//!   times its opacity (`add`), or is kept per channel where brighter (`max`), as napari blends channels.
//! - A **label map** is sampled at the nearest voxel. A labelled pixel takes its id's colour at the id's opacity
//!   times the layer's; a pixel on the edge of its label (a neighbour left, right, above or below holds another id)
//!   takes it at the id's opacity alone: the outline, which stays visible at a low fill.

use super::layer_set::Layers;
use super::layers::{Blend, LayerKind, LayerStyle};
use super::slice::{sample, SliceFrame};
use crate::volume::Geometry;
use glam::{DMat4, DVec2, DVec3};

/// Paints `layers`, looking as `styles` say, over `rgba` (the slice image of `frame`, sRGB, over the volume of
/// geometry `base` whose voxel index `mm_from_index` maps to the slice's millimetres).
pub fn paint(
    rgba: &mut [u8],
    base: &Geometry,
    mm_from_index: DMat4,
    frame: &SliceFrame,
    layers: &Layers,
    styles: &[LayerStyle],
) {
    for (i, style) in styles.iter().enumerate().take(layers.len()) {
        if !style.visible || style.opacity <= 0.0 {
            continue;
        }
        let to_layer = index_from_slice(base, mm_from_index, &layers.volumes[i].geometry);
        match (&layers.labels[i], style.kind) {
            (Some((map, colours)), LayerKind::Labels) => {
                let ids = dense_ids(frame, to_layer, layers.volumes[i].dims, &map.index);
                paint_labels(rgba, frame, &ids, colours, style.opacity);
            }
            _ => paint_overlay(rgba, frame, to_layer, &layers.volumes[i], style),
        }
    }
}

/// The matrix from the slice's millimetres to a layer's voxel index: back to the volume's index, into the world by
/// its affine, and into the layer's index by the inverse of the layer's.
fn index_from_slice(base: &Geometry, mm_from_index: DMat4, layer: &Geometry) -> DMat4 {
    layer.affine.inverse() * base.affine * mm_from_index.inverse()
}

/// The pixel's centre in the slice's millimetres.
fn pixel_point(frame: &SliceFrame, x: u32, y: u32) -> DVec3 {
    frame.world(DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5))
}

fn paint_overlay(rgba: &mut [u8], frame: &SliceFrame, to_layer: DMat4, v: &crate::volume::Volume, style: &LayerStyle) {
    let a = f64::from(style.opacity);
    for y in 0..frame.height {
        for x in 0..frame.width {
            let Some(value) = sample(v, to_layer, pixel_point(frame, x, y)).filter(|&s| style.shows(s)) else {
                continue;
            };
            let colour = style.srgb(style.position(value));
            let i = (y as usize * frame.width as usize + x as usize) * 4;
            for c in 0..3 {
                let under = f64::from(rgba[i + c]) / 255.0;
                let over = colour[c];
                let mixed = match style.blend {
                    Blend::Composite => under * (1.0 - a) + over * a,
                    Blend::Add => under + over * a,
                    Blend::Max => under.max(over * a),
                };
                rgba[i + c] = (mixed.clamp(0.0, 1.0) * 255.0).round() as u8;
            }
            rgba[i + 3] = 255;
        }
    }
}

/// Each pixel's dense label index (0: none) at its nearest voxel of a label map of `dims`.
fn dense_ids(frame: &SliceFrame, to_layer: DMat4, dims: [u32; 3], index: &[u32]) -> Vec<u32> {
    let mut ids = vec![0u32; frame.width as usize * frame.height as usize];
    for y in 0..frame.height {
        for x in 0..frame.width {
            if let Some(voxel) = nearest(to_layer.transform_point3(pixel_point(frame, x, y)), dims) {
                ids[y as usize * frame.width as usize + x as usize] = index[voxel];
            }
        }
    }
    ids
}

/// The voxel at `floor(c + ½)` (rule 13's nearest), as an index into the voxels; None outside the box.
fn nearest(c: DVec3, dims: [u32; 3]) -> Option<usize> {
    let mut v = [0usize; 3];
    for a in 0..3 {
        let r = (c[a] + 0.5).floor();
        if !(r >= 0.0 && r < f64::from(dims[a])) {
            return None;
        }
        v[a] = r as usize;
    }
    Some(v[0] + dims[0] as usize * (v[1] + dims[1] as usize * v[2]))
}

fn paint_labels(rgba: &mut [u8], frame: &SliceFrame, ids: &[u32], colours: &[[u8; 4]], opacity: f32) {
    let (w, h) = (frame.width as usize, frame.height as usize);
    for y in 0..h {
        for x in 0..w {
            let id = ids[y * w + x];
            let Some(&[r, g, b, alpha]) = colours.get(id as usize).filter(|c| id != 0 && c[3] > 0) else {
                continue;
            };
            let differs = |nx: usize, ny: usize| ids[ny * w + nx] != id;
            let edge = x == 0
                || y == 0
                || x + 1 == w
                || y + 1 == h
                || differs(x - 1, y)
                || differs(x + 1, y)
                || differs(x, y - 1)
                || differs(x, y + 1);
            let table = f32::from(alpha) / 255.0;
            let a = if edge { table } else { table * opacity };
            let i = (y * w + x) * 4;
            for (c, over) in [r, g, b].into_iter().enumerate() {
                let mixed = f32::from(rgba[i + c]) * (1.0 - a) + f32::from(over) * a;
                rgba[i + c] = mixed.round().clamp(0.0, 255.0) as u8;
            }
            rgba[i + 3] = 255;
        }
    }
}

/// Each layer's value at the slice point `w` (millimetres of the slice, as `paint`'s), as the cursor's probe
/// names it: `name: value` for an overlay, `name: id Label` for a label map; nothing outside a layer's box.
pub fn values_at(base: &Geometry, mm_from_index: DMat4, w: DVec3, layers: &Layers) -> Vec<String> {
    let mut out = Vec::new();
    for i in 0..layers.len() {
        let v = &layers.volumes[i];
        let to_layer = index_from_slice(base, mm_from_index, &v.geometry);
        let name = super::layer_set::short_name(&layers.names[i]);
        match &layers.labels[i] {
            Some((map, _)) => {
                if let Some(voxel) = nearest(to_layer.transform_point3(w), v.dims) {
                    let id = map.ids[map.index[voxel] as usize];
                    let label = if id == 0 {
                        "none".to_string()
                    } else {
                        layers.tables[i].name(id)
                    };
                    out.push(format!("{name}: {id} {label}"));
                }
            }
            None => {
                if let Some(value) = sample(v, to_layer, w) {
                    out.push(format!("{name}: {value:.3}"));
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests;
