//! The reference's rule 13 (`volcast::scene::layers`), written from the rule: each layer placed by its own
//! affine, overlays sampled trilinearly in data units and classified by the colormap's control points, label maps
//! at the nearest voxel, opacity per layer voxel corrected to the step, and the mix at a sample. Nothing here
//! reads the GPU's tables.

use super::classify::{colormap_srgb, linear};
use super::reference::{shade, Lamp};
use glam::{DMat3, DMat4, DVec3};
use volcast::scene::layers::{Blend, LayerKind, LayerStyle};
use volcast::scene::settings::Shading;
use volcast::volume::Volume;

/// Rule 5's lighting of label maps, where shading is on: the unit direction towards the eye (world), the shading
/// and lamp, and the base's millimetres per world unit (`d mm / d world`), which takes a gradient to the world.
pub struct Lit<'a> {
    pub view: DVec3,
    pub shading: &'a Shading,
    pub lamp: Lamp,
    pub mm_per_world: DMat3,
}

/// One layer as the reference holds it.
pub struct RefLayer {
    dims: [usize; 3],
    /// Overlays: values in data units; label maps: ids.
    values: Vec<f64>,
    /// Millimetres to the layer's voxel index.
    from_mm: DMat4,
    smallest_mm: f64,
    /// Label maps: the sRGB colour and opacity (0–255) of an id.
    colours: Option<Box<dyn Fn(u32) -> [u8; 4] + Send + Sync>>,
}

impl RefLayer {
    pub fn overlay(volume: &Volume) -> RefLayer {
        RefLayer::of(volume, None)
    }

    /// A label map whose id i looks like `colours(i)`.
    pub fn labels(volume: &Volume, colours: impl Fn(u32) -> [u8; 4] + Send + Sync + 'static) -> RefLayer {
        RefLayer::of(volume, Some(Box::new(colours)))
    }

    fn of(volume: &Volume, colours: Option<Box<dyn Fn(u32) -> [u8; 4] + Send + Sync>>) -> RefLayer {
        let [nx, ny, nz] = volume.dims;
        let mut values = Vec::with_capacity(volume.voxel_count());
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    values.push(volume.value(x, y, z));
                }
            }
        }
        let a = volume.geometry.affine;
        let sides = [a.x_axis, a.y_axis, a.z_axis].map(|c| c.truncate().length());
        RefLayer {
            dims: volume.dims.map(|d| d as usize),
            values,
            from_mm: a.inverse(),
            smallest_mm: sides.into_iter().fold(f64::INFINITY, f64::min),
            colours,
        }
    }

    fn at(&self, x: usize, y: usize, z: usize) -> f64 {
        self.values[x + self.dims[0] * (y + self.dims[1] * z)]
    }

    /// Trilinear at voxel index `i` (centres at integers), clamped to the edge.
    fn trilinear(&self, i: DVec3) -> f64 {
        let mut lo = [0usize; 3];
        let mut f = [0f64; 3];
        for a in 0..3 {
            let c = i[a].clamp(0.0, (self.dims[a] - 1) as f64);
            lo[a] = (c.floor() as usize).min(self.dims[a].saturating_sub(2));
            f[a] = c - lo[a] as f64;
        }
        let hi = [0, 1, 2].map(|a| (lo[a] + 1).min(self.dims[a] - 1));
        let mut v = 0.0;
        for (cz, wz) in [(lo[2], 1.0 - f[2]), (hi[2], f[2])] {
            for (cy, wy) in [(lo[1], 1.0 - f[1]), (hi[1], f[1])] {
                for (cx, wx) in [(lo[0], 1.0 - f[0]), (hi[0], f[0])] {
                    let w = wx * wy * wz;
                    if w != 0.0 {
                        v += w * self.at(cx, cy, cz);
                    }
                }
            }
        }
        v
    }

    /// Rule 13's normal of label `id` at voxel index `i`, per layer voxel: at each corner of the cell around `i`
    /// the central difference of the indicator "the voxel holds `id`" (indices clamped to the edge), interpolated
    /// trilinearly (the cell clamped as `trilinear`'s).
    pub fn label_gradient(&self, i: DVec3, id: u32) -> DVec3 {
        let mut lo = [0usize; 3];
        let mut f = [0f64; 3];
        for a in 0..3 {
            let c = i[a].clamp(0.0, (self.dims[a] - 1) as f64);
            lo[a] = (c.floor() as usize).min(self.dims[a].saturating_sub(2));
            f[a] = c - lo[a] as f64;
        }
        let holds = |v: [i64; 3]| {
            let [x, y, z] = [0, 1, 2].map(|a| v[a].clamp(0, self.dims[a] as i64 - 1) as usize);
            f64::from(u8::from(self.at(x, y, z) as u32 == id))
        };
        let mut g = DVec3::ZERO;
        for corner in 0..8 {
            let at = [0, 1, 2].map(|a| (lo[a] + (corner >> a & 1)).min(self.dims[a] - 1) as i64);
            let w: f64 = (0..3)
                .map(|a| if corner >> a & 1 == 1 { f[a] } else { 1.0 - f[a] })
                .product();
            for a in 0..3 {
                let (mut up, mut down) = (at, at);
                up[a] += 1;
                down[a] -= 1;
                g[a] += w * (holds(up) - holds(down)) / 2.0;
            }
        }
        g
    }

    /// Rule 13's look at millimetre point `mm`: linear colour and opacity per layer voxel (None: nothing shown);
    /// a label's colour lit along `label_gradient` where `lit` is given.
    fn look(&self, mm: DVec3, style: &LayerStyle, lit: Option<&Lit>) -> Option<(DVec3, f64)> {
        let i = self.from_mm.transform_point3(mm);
        let n = DVec3::new(self.dims[0] as f64, self.dims[1] as f64, self.dims[2] as f64);
        if i.cmplt(DVec3::splat(-0.5)).any() || i.cmpgt(n - 0.5).any() {
            return None;
        }
        let opacity = if style.visible { f64::from(style.opacity) } else { 0.0 };
        if style.kind == LayerKind::Labels {
            let v = (i + 0.5).floor().clamp(DVec3::ZERO, n - 1.0);
            let id = self.at(v.x as usize, v.y as usize, v.z as usize) as u32;
            if id == 0 {
                return None;
            }
            let c = self.colours.as_ref().map_or([0; 4], |f| f(id));
            let mut rgb = linear(DVec3::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2])) / 255.0);
            if let Some(lit) = lit {
                // Per voxel -> per millimetre -> per world unit: the transposed Jacobians, in turn.
                let per_mm = DMat3::from_mat4(self.from_mm).transpose() * self.label_gradient(i, id);
                let world = lit.mm_per_world.transpose() * per_mm;
                rgb = shade(rgb, world, lit.view, lit.shading, &lit.lamp, 1.0);
            }
            return Some((rgb, f64::from(c[3]) / 255.0 * opacity));
        }
        let v = self.trilinear(i);
        let [lo, hi] = style.window;
        let shown = match style.threshold {
            Some(t) if style.signed => v.abs() >= t,
            Some(t) => v >= t,
            None => v >= lo && v <= hi,
        };
        if v.is_nan() || !shown {
            return None;
        }
        let c = ((v - lo) / (hi - lo)).clamp(0.0, 1.0);
        let srgb = match style.tint {
            Some([r, g, b]) => DVec3::new(f64::from(r), f64::from(g), f64::from(b)) / 255.0 * c,
            None => colormap_srgb(style.colormap, c),
        };
        Some((linear(srgb), opacity))
    }
}

/// Rule 13's blocks for strides and skipping: 4³ of a layer's voxels.
const BLOCK: usize = 4;

impl RefLayer {
    /// Rule 13's strides near a layer: per block that may show something (a shown label, or an overlay value range
    /// meeting the threshold or window, over the block's voxels and a one-voxel apron), the 8 corners in
    /// millimetres of its box `4b − 1 … min(4b + 4, dim)` of index space.
    pub fn showing_boxes_mm(&self, style: &LayerStyle) -> Vec<[DVec3; 8]> {
        if !style.visible || style.opacity <= 0.0 {
            return Vec::new();
        }
        let to_mm = self.from_mm.inverse();
        let blocks = self.dims.map(|d| d.div_ceil(BLOCK));
        let mut boxes = Vec::new();
        for bz in 0..blocks[2] {
            for by in 0..blocks[1] {
                for bx in 0..blocks[0] {
                    let b = [bx, by, bz];
                    let reach =
                        |a: usize| (b[a] * BLOCK).saturating_sub(1)..=((b[a] + 1) * BLOCK).min(self.dims[a] - 1);
                    let mut values = Vec::new();
                    for z in reach(2) {
                        for y in reach(1) {
                            for x in reach(0) {
                                values.push(self.at(x, y, z));
                            }
                        }
                    }
                    if !self.block_may_show(&values, style) {
                        continue;
                    }
                    let lo = DVec3::from_array(b.map(|k| (k * BLOCK) as f64 - 1.0));
                    let n = DVec3::from_array(self.dims.map(|d| d as f64));
                    let hi = (lo + (BLOCK + 1) as f64).min(n);
                    boxes.push(std::array::from_fn(|c| {
                        let pick = |bit: usize, a: usize| if c & bit == 0 { lo[a] } else { hi[a] };
                        to_mm.transform_point3(DVec3::new(pick(1, 0), pick(2, 1), pick(4, 2)))
                    }));
                }
            }
        }
        boxes
    }

    fn block_may_show(&self, values: &[f64], style: &LayerStyle) -> bool {
        if style.kind == LayerKind::Labels {
            return values
                .iter()
                .any(|&id| id != 0.0 && self.colours.as_ref().is_some_and(|f| f(id as u32)[3] > 0));
        }
        let finite: Vec<f64> = values.iter().copied().filter(|v| !v.is_nan()).collect();
        let (lo, hi) = finite
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
        let top = finite.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        match style.threshold {
            _ if finite.is_empty() => false,
            Some(t) if style.signed => top >= t,
            Some(t) => hi >= t,
            None => hi >= style.window[0] && lo <= style.window[1],
        }
    }
}

/// Rule 13's opacity `a` per voxel of `layer`'s grid over a march step of `step` world units.
fn step_alpha(a: f64, layer: &RefLayer, step: f64, world_per_mm: f64) -> f64 {
    1.0 - (1.0 - a).max(0.0).powf(step / (layer.smallest_mm * world_per_mm))
}

/// Rule 13's mix at a sample: the base's segment `(rgb, alpha)` and each layer's step at millimetre point `mm`
/// that is composited in depth, for a march step of `step` world units (`world_per_mm` world units per
/// millimetre); label maps lit by `lit` where shading is on.
pub fn mix(
    base: (DVec3, f64),
    layers: &[RefLayer],
    styles: &[LayerStyle],
    mm: DVec3,
    (step, world_per_mm): (f64, f64),
    lit: Option<&Lit>,
) -> (DVec3, f64) {
    let (mut keep, mut sum, mut weight) = (1.0 - base.1, base.1 * base.0, base.1);
    for (layer, style) in layers.iter().zip(styles) {
        let Some((rgb, a)) = layer.look(mm, style, lit).filter(|_| style.blend == Blend::Composite) else {
            continue;
        };
        let alpha = step_alpha(a, layer, step, world_per_mm);
        keep *= 1.0 - alpha;
        sum += alpha * rgb;
        weight += alpha;
    }
    if weight > 0.0 {
        (sum / weight, 1.0 - keep)
    } else {
        (DVec3::ZERO, 0.0)
    }
}

/// Rule 13's other blends along one ray: the light added, and each layer's largest light.
pub struct Glow {
    added: DVec3,
    peaks: Vec<DVec3>,
}

impl Glow {
    pub fn new(layers: usize) -> Glow {
        Glow {
            added: DVec3::ZERO,
            peaks: vec![DVec3::ZERO; layers],
        }
    }

    /// The steps at `mm` of the layers blended by addition or maximum, seen through transmittance `front`.
    pub fn gather(&mut self, layers: &[RefLayer], styles: &[LayerStyle], mm: DVec3, step: (f64, f64), front: f64) {
        for (i, (layer, style)) in layers.iter().zip(styles).enumerate() {
            let Some((rgb, a)) = layer.look(mm, style, None) else {
                continue;
            };
            match style.blend {
                Blend::Composite => {}
                Blend::Add => self.added += front * step_alpha(a, layer, step.0, step.1) * rgb,
                Blend::Max => self.peaks[i] = self.peaks[i].max(front * a * rgb),
            }
        }
    }

    /// What is added to the ray's colour at its end.
    pub fn total(&self) -> DVec3 {
        self.peaks.iter().fold(self.added, |sum, &p| sum + p)
    }
}

/// The base's texture point `tex` in millimetres (its affine of its voxel index).
pub fn base_mm(affine: DMat4, dims: [usize; 3], tex: DVec3) -> DVec3 {
    let n = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64);
    affine.transform_point3(tex * n - 0.5)
}
