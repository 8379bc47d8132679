//! Layers: further volumes shown with the base volume in the one march, each on its own grid and placement, and
//! each with its own look. The renderer holds their voxels (`Renderer::set_layers`); a frame's
//! [`RenderSettings::layers`](super::settings::RenderSettings) says how each looks, in the same order.
//!
//! **Rule 13, layers** (the shaders, `shaders/layers.glsl`, and the CPU reference, `tests/common/layers.rs`,
//! follow it):
//! - **Placement.** A layer's voxel index at a point is its own affine's inverse of the point's millimetres (the
//!   base's affine of the base's index): no layer is resampled onto another's grid. A point outside the layer's
//!   box (index < −½ or > dim − ½ on an axis) shows nothing of the layer.
//! - **Overlays** are sampled trilinearly (rule 3, clamped to the edge inside the box) in data units. A value v is
//!   shown where it is finite and, with a threshold T, `v ≥ T` (or `|v| ≥ T` for a signed overlay), else where
//!   it lies in the window [lo, hi]. It takes the colour at `clamp((v − lo)/(hi − lo), 0, 1)` of the colormap, or
//!   of its tint's ramp from black (sRGB, decoded to linear light), and the layer's `opacity`.
//! - **Label maps** are sampled at the nearest voxel (`floor(index + ½)`), never interpolated across ids. Id 0
//!   shows nothing; any other id takes its table colour (or `labels::default_colour`), with the table's opacity
//!   times the layer's `opacity`; hidden ids show nothing.
//! - **Label surfaces.** With shading on (rule 5), a label's colour is lit as a surface: its normal is the gradient
//!   of the trilinear interpolant (clamped as an overlay's) of the indicator "the voxel holds this id" over the
//!   cell around the point, taken to the world through the layer's own affine; two-sided, unfaded. That normal
//!   turns smoothly across each cell, where the ids' voxel faces would light a staircase. Overlays are not lit.
//! - **Opacity** `a` is per voxel of the layer's own grid: over a march step of h world units it is
//!   `α = 1 − (1 − a)^(h/d)`, d the layer's smallest voxel side in world units.
//! - **Mixing at a step.** At each sample (rule 2's points, not the ray's end), the base's segment (rule 6: colour
//!   c₀, opacity α₀) and each layer's (cᵢ, αᵢ) make one: `α = 1 − Π(1 − αᵢ)`, `c = Σαᵢcᵢ / Σαᵢ` (nothing where
//!   Σαᵢ = 0), composited by rule 7. So depth order is right by construction: what is nearer on the ray is
//!   composited first, whichever volume holds it. The base alone (no layer shown there) is rule 6 unchanged.
//! - **Strides and skipping** (rule 2) near a layer: each layer is cut into blocks of 4³ of its voxels; a block
//!   *may show* where a label there (its voxels and a one-voxel apron) is shown, or an overlay's value range there
//!   meets its threshold (`max ≥ T`, `max |v| ≥ T` signed) or window. The base's bricks that the box of such a block
//!   (index `4b − 1` to `min(4b + 4, dim)` per axis, mapped by its corners into the base's index space) touches take
//!   every sample and are never empty; elsewhere rule 2 holds as for the base alone, since no layer shows anything
//!   there (`render/layer_bricks.rs`).
//! - **Blends.** An overlay's `blend` says how it meets the rest (`Blend`); label maps always mix in depth. At each
//!   sample, with T the ray's transmittance before it (1 − the opacity composited so far) and (cᵢ, αᵢ) the layer's
//!   step as above: `Composite` mixes in as above; `Add` adds `T·αᵢ·cᵢ` to the ray's colour and nothing to its
//!   opacity (light without absorption, as fluorescence); `Max` keeps, per colour channel, the largest
//!   `T·a·cᵢ` over the ray's samples (a its opacity per voxel, so no step length enters: a projection, dimmed by
//!   what lies in front). At the ray's end the added light and every maximum are added to its colour.
//! - Layers mix in emission and density modes; other modes refuse layers.

use crate::transfer::colormap::Colormap;
use crate::transfer::function::srgb_to_linear;

/// What a layer's voxels are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LayerKind {
    /// A continuous map (an fMRI statistic, a second modality, a channel), sampled trilinearly.
    #[default]
    Overlay,
    /// Integer ids, sampled at the nearest voxel, coloured per id.
    Labels,
}

/// How an overlay meets the volume and the other layers along a ray (rule 13).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Blend {
    /// Composited in depth with the rest, sample by sample: what is nearer hides what is behind.
    #[default]
    Composite,
    /// Its largest light along the ray (per colour channel), dimmed by what lies in front: a projection.
    Max,
    /// Light without absorption, added along the ray and dimmed by what lies in front: fluorescence.
    Add,
}

impl Blend {
    pub const ALL: [Blend; 3] = [Blend::Composite, Blend::Max, Blend::Add];

    pub fn name(self) -> &'static str {
        match self {
            Blend::Composite => "composite",
            Blend::Max => "max",
            Blend::Add => "add",
        }
    }

    pub fn parse(s: &str) -> Option<Blend> {
        Blend::ALL.into_iter().find(|b| b.name() == s)
    }
}

/// How one layer looks (rule 13).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct LayerStyle {
    pub kind: LayerKind,
    /// Overlays: the values (data units) the colormap spans.
    pub window: [f64; 2],
    /// Overlays: shown where `v ≥ threshold` (`|v|` when `signed`); None: where v is in the window.
    pub threshold: Option<f64>,
    pub signed: bool,
    pub colormap: Colormap,
    /// Overlays: in place of the colormap, a ramp from black to this sRGB colour over the window (a channel's own
    /// colour, as napari and OMERO show channels).
    pub tint: Option<[u8; 3]>,
    /// Opacity per voxel of the layer's own grid.
    pub opacity: f32,
    pub visible: bool,
    /// Overlays: how it meets the rest along the ray.
    pub blend: Blend,
}

impl Default for LayerStyle {
    fn default() -> LayerStyle {
        LayerStyle {
            kind: LayerKind::Overlay,
            window: [0.0, 1.0],
            threshold: None,
            signed: false,
            colormap: Colormap::Plasma,
            tint: None,
            opacity: 0.5,
            visible: true,
            blend: Blend::Composite,
        }
    }
}

/// Entries of an overlay's colour table (`overlay_table`).
pub const OVERLAY_ENTRIES: usize = 256;

impl LayerStyle {
    /// An overlay of values in `range` (data units): a signed map (values both sides of 0) gets a window
    /// symmetric about 0 and the diverging cool-warm map, so 0 is its middle; others the range and plasma.
    pub fn overlay(range: [f64; 2], threshold: Option<f64>) -> LayerStyle {
        let signed = range[0] < 0.0 && range[1] > 0.0;
        let m = range[0].abs().max(range[1].abs());
        LayerStyle {
            window: if signed {
                [-m, m]
            } else {
                [threshold.unwrap_or(range[0]).min(range[1]), range[1]]
            },
            threshold,
            signed,
            colormap: if signed { Colormap::CoolWarm } else { Colormap::Plasma },
            opacity: 0.6,
            ..LayerStyle::default()
        }
    }

    /// A channel's look, as napari and OMERO show channels: a ramp from black to `tint` (sRGB) over `window`,
    /// shown from `threshold`, blended by maximum at full opacity.
    pub fn channel(window: [f64; 2], tint: [u8; 3], threshold: f64) -> LayerStyle {
        LayerStyle {
            window,
            threshold: Some(threshold),
            tint: Some(tint),
            colormap: Colormap::Grayscale,
            blend: Blend::Max,
            opacity: 1.0,
            ..LayerStyle::default()
        }
    }

    /// A label map's look: its table's colours at half opacity per voxel.
    pub fn labels() -> LayerStyle {
        LayerStyle {
            kind: LayerKind::Labels,
            opacity: 0.5,
            ..LayerStyle::default()
        }
    }

    /// The overlay's colours at positions `i/(N − 1)` of its window, in linear light, with its opacity: the
    /// table the GPU interpolates linearly (the reference evaluates the colormap itself).
    pub fn overlay_table(&self) -> Vec<[f32; 4]> {
        (0..OVERLAY_ENTRIES)
            .map(|i| {
                let c = i as f64 / (OVERLAY_ENTRIES - 1) as f64;
                let [r, g, b] = self.srgb(c).map(|x| srgb_to_linear(x as f32));
                [r, g, b, self.opacity]
            })
            .collect()
    }

    /// The sRGB colour at position `c` (0–1) of the window: the tint's ramp, else the colormap.
    pub fn srgb(&self, c: f64) -> [f64; 3] {
        match self.tint {
            Some(t) => t.map(|x| f64::from(x) / 255.0 * c),
            None => self.colormap.srgb(c),
        }
    }

    /// Whether an overlay shows value `v` (rule 13): finite, and over its threshold (`|v|` for a signed one), else
    /// in its window.
    pub fn shows(&self, v: f64) -> bool {
        v.is_finite()
            && match (self.threshold, self.signed) {
                (Some(t), true) => v.abs() >= t,
                (Some(t), false) => v >= t,
                (None, _) => v >= self.window[0] && v <= self.window[1],
            }
    }

    /// Where `v` lies in the window (0–1, clamped): the position of its colour.
    pub fn position(&self, v: f64) -> f64 {
        ((v - self.window[0]) / (self.window[1] - self.window[0])).clamp(0.0, 1.0)
    }

    /// A check of the values a user gave: a message naming the bad one.
    pub fn check(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.opacity) {
            return Err(format!("layer opacity {} is outside 0..1", self.opacity));
        }
        let ordered = self.window[0] < self.window[1];
        if self.kind == LayerKind::Overlay && (!ordered || self.window.iter().any(|w| !w.is_finite())) {
            return Err(format!(
                "overlay window {:?} must be two finite values, low < high",
                self.window
            ));
        }
        if self.kind == LayerKind::Labels && self.blend != Blend::Composite {
            return Err("label maps are composited in depth; only overlays take another blend".into());
        }
        if self.threshold.is_some_and(|t| !t.is_finite()) {
            return Err("the overlay threshold must be finite".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_signed_map_is_centred_on_zero_and_a_positive_one_starts_at_its_threshold() {
        let z = LayerStyle::overlay([-7.9, 6.0], Some(3.0));
        assert!(z.signed);
        assert_eq!(z.window, [-7.9, 7.9]);
        assert_eq!(z.colormap, Colormap::CoolWarm);
        let p = LayerStyle::overlay([0.0, 10.0], Some(2.0));
        assert!(!p.signed);
        assert_eq!(p.window, [2.0, 10.0]);
        assert_eq!(p.overlay_table().len(), OVERLAY_ENTRIES);
        assert!(LayerStyle { opacity: 2.0, ..p }.check().is_err());
    }
}
