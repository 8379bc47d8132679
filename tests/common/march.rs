//! The reference's march of one pixel (rules 1–8 of `RenderSettings`): its ray, the samples along it, and each
//! compositing mode (emission/density with pre-integrated segments and brick strides, MIP/MinIP/average, the
//! isosurface with its bisection), in f64. `Reference` (reference.rs) holds the volume it samples.

use super::classify::{encode, jitter_offset, linear, Classifier};
use super::layers::{mix, Glow, Lit};
use super::rays::{ray_segment, CameraBasis};
use super::reference::{shade, Lamp, PixelTrace, Placement, Reference, Segment};
use super::segments::Segments;
use super::strides::{BrickRanges, Strides};
use glam::DVec3;
use volcast::scene::settings::{CompositeMode, RenderSettings, Shading};

/// Everything per-frame that `trace` needs, computed once.
pub(crate) struct Frame<'a> {
    volume: &'a Reference,
    camera: CameraBasis,
    placement: Placement,
    /// Rule 10's clipping plane in the world: unit normal n and offset, kept where `p·n ≥ offset` (the world's
    /// origin is the box's centre, and its scale uniform, so the millimetre offset just scales).
    clip: Option<(DVec3, f64)>,
    /// The slab box, texture space.
    box_lo: DVec3,
    box_hi: DVec3,
    step: f64,
    classifier: Classifier,
    /// Rule 6's segment integrals (emission and density modes).
    segments: Option<Segments>,
    window: [f64; 2],
    /// Exponent of rule 6's opacity correction (and factor of the density model).
    step_length: f64,
    mode: CompositeMode,
    /// Rule 7's surfaces by value: value, linear colour (None: the classification's), opacity.
    surfaces: Vec<(f64, Option<DVec3>, f64)>,
    lamp: Lamp,
    /// Rule 9's light grid, where it applies.
    light_grid: Option<super::light::LightGridRef>,
    /// Rule 5's lighting where it applies: `shading` in emission/density modes, `shading` or its defaults in
    /// isosurface mode.
    shading: Option<Shading>,
    gradient_opacity: Option<f64>,
    /// Rule 5's shading fade (0: off).
    shading_fade: f64,
    /// `gradient_texture`: shade from the grid gradients instead of central differences of the interpolant.
    grid_gradients: bool,
    jitter: Option<u32>,
    /// Rule 2's brick strides (None: every sample).
    strides: Option<Strides>,
    /// The finest level a cut shows (rule 2's level strides).
    finest: u32,
    early_termination: f64,
    /// Rule 13's layer styles and the world's scale.
    layers: Vec<volcast::scene::layers::LayerStyle>,
    world_per_mm: f64,
    /// Linear light.
    background: DVec3,
}

/// The result of one mode's march: colour and opacity before rule 8.
struct Composite {
    color: DVec3,
    alpha: f64,
}

impl<'a> Frame<'a> {
    pub(crate) fn new(volume: &'a Reference, s: &RenderSettings) -> Frame<'a> {
        let stepped = volume.stepped(s);
        let s = &stepped;
        let placement = volume.placement(s);
        let world_per_mm = placement.world_per_mm();
        let shading = match s.compositing.mode {
            CompositeMode::Isosurface => Some(s.lighting.shading.unwrap_or_default()),
            _ => s.lighting.shading,
        };
        let segments = match s.compositing.mode {
            CompositeMode::Emission => Some(Segments::new(
                volume.classifier(s),
                s.colour.window.map(f64::from),
                None,
            )),
            CompositeMode::Density => Some(Segments::new(
                volume.classifier(s),
                s.colour.window.map(f64::from),
                Some(f64::from(s.compositing.density)),
            )),
            _ => None,
        };
        let mut strides = segments.as_ref().and_then(|segments| {
            let ranges = volume
                .brick_ranges
                .get_or_init(|| BrickRanges::new(&volume.values, volume.dims));
            Strides::new(ranges, volume.dims, s, segments)
        });
        // Rule 13: every sample is taken where a layer may show something.
        if let Some(strides) = &mut strides {
            for (layer, style) in volume.layers.iter().zip(&s.layers) {
                for corners in layer.showing_boxes_mm(style) {
                    strides.take_every_sample(&corners.map(|mm| volume.mm_to_index(mm)));
                }
            }
        }
        let mut frame = Frame {
            volume,
            camera: CameraBasis::new(s),
            step: f64::from(s.sampling.step_length) * placement.voxel_sides().min_element(),
            placement,
            clip: s
                .cut
                .clip_plane
                .map(|p| (p.normal().as_dvec3().normalize(), f64::from(p.offset()) * world_per_mm)),
            box_lo: s.cut.slab_lo.as_dvec3(),
            box_hi: s.cut.slab_hi.as_dvec3(),
            classifier: volume.classifier(s),
            segments,
            window: s.colour.window.map(f64::from),
            // A segment's opacity counts the source's voxels it crosses (rule 6: a stand-in keeps its optical depth).
            step_length: f64::from(s.sampling.step_length) * volume.source_voxels,
            mode: s.compositing.mode,
            surfaces: {
                let mut v: Vec<(f64, Option<DVec3>, f64)> = std::iter::once((
                    s.compositing.iso_value,
                    s.compositing.iso_color,
                    s.compositing.iso_opacity,
                ))
                .chain(
                    s.compositing
                        .extra_isosurfaces
                        .iter()
                        .map(|x| (x.value, x.color, x.opacity)),
                )
                .map(|(value, color, opacity)| {
                    (
                        f64::from(value),
                        color.map(|c| linear(c.as_dvec3())),
                        f64::from(opacity),
                    )
                })
                .collect();
                v.sort_by(|a, b| a.0.total_cmp(&b.0));
                v
            },
            lamp: Lamp::new(&s.lighting.light, super::light::light_direction(s)),
            // Made below, from the frame's own classifier and placement.
            light_grid: None,
            shading,
            gradient_opacity: s.lighting.gradient_opacity.map(f64::from),
            shading_fade: f64::from(s.lighting.shading_fade),
            grid_gradients: s.lighting.gradient_texture,
            jitter: s.sampling.jitter,
            strides,
            finest: volume.finest_level(),
            early_termination: f64::from(s.compositing.early_termination),
            layers: s.layers.clone(),
            world_per_mm,
            background: linear(s.background.as_dvec3()),
        };
        if super::light::applies(s) {
            frame.light_grid = Some(super::light::LightGridRef::new(
                volume,
                s,
                &frame.classifier,
                &frame.placement,
            ));
        }
        frame
    }

    /// The lamp at texture point `p`: rule 9's shadow and occlusion applied.
    fn lamp_at(&self, p: DVec3) -> Lamp {
        match &self.light_grid {
            Some(g) => self.lamp.at(g.shadow(p), g.occlusion(p)),
            None => self.lamp,
        }
    }

    /// Rule 3's visibility test (every mode but isosurface).
    fn visible(&self, v: f64) -> bool {
        !v.is_nan() && v >= self.window[0] && v <= self.window[1]
    }

    fn gradient(&self, tex: DVec3) -> DVec3 {
        if self.grid_gradients {
            self.volume.grid_gradient(tex)
        } else {
            self.volume.gradient(tex)
        }
    }

    pub(crate) fn trace(&self, x: u32, y: u32) -> PixelTrace {
        let (origin, dir, t_near) = self.camera.ray(x, y);
        let offset = self.jitter.map_or(0.5, |seed| jitter_offset(x, y, seed));
        let background = self.background.clamp(DVec3::ZERO, DVec3::ONE);
        let mut trace = PixelTrace {
            segment: None,
            offset,
            samples: 0,
            composited: 0,
            value: None,
            hit: None,
            color: DVec3::ZERO,
            alpha: 0.0,
            terminated_early: false,
            linear: background,
            output: encode(background),
        };
        // The slab box is a box in texture space: intersect there, with t still in world units along `dir`.
        let (origin_tex, dir_tex) = (self.placement.to_tex(origin), self.placement.dir_to_tex(dir));
        let Some((t_start, t_end)) = ray_segment(origin_tex, dir_tex, self.box_lo, self.box_hi, t_near) else {
            return trace;
        };
        let Some((t_start, t_end, clipped_start)) = self.clip_to_plane(origin, dir, t_start, t_end) else {
            return trace;
        };
        let segment = Segment {
            origin,
            dir,
            t_start,
            t_end,
            clipped_start,
        };
        trace.segment = Some(segment);
        let result = match self.mode {
            CompositeMode::Emission | CompositeMode::Density => self.absorb(&segment, &mut trace),
            CompositeMode::Mip | CompositeMode::MinIp | CompositeMode::Average => self.extremum(&segment, &mut trace),
            CompositeMode::Isosurface => self.isosurface(&segment, &mut trace),
        };
        trace.color = result.color;
        trace.alpha = result.alpha;
        trace.linear = (result.color + (1.0 - result.alpha) * self.background).clamp(DVec3::ZERO, DVec3::ONE);
        trace.output = encode(trace.linear);
        trace
    }

    /// Rule 10: the part of `[t_start, t_end]` of the ray `origin + t·dir` (world) that the clipping plane keeps,
    /// and whether the plane moved its start; None when nothing (or one point) is left.
    fn clip_to_plane(&self, origin: DVec3, dir: DVec3, t_start: f64, t_end: f64) -> Option<(f64, f64, bool)> {
        let Some((n, offset)) = self.clip else {
            return Some((t_start, t_end, false));
        };
        // (origin + t·dir)·n − offset = f0 + t·slope ≥ 0.
        let (f0, slope) = (origin.dot(n) - offset, dir.dot(n));
        let (mut t0, mut t1, mut moved) = (t_start, t_end, false);
        if slope == 0.0 {
            if f0 < 0.0 {
                return None;
            }
        } else {
            let t = -f0 / slope;
            if slope > 0.0 && t > t0 {
                (t0, moved) = (t, true);
            } else if slope < 0.0 {
                t1 = t1.min(t);
            }
        }
        (t0 < t1).then_some((t0, t1, moved))
    }

    /// Rule 2's sample distances from the segment's start: `(k + o)·h` while below the segment's length.
    fn sample_offsets(&self, segment: &Segment, offset: f64) -> impl Iterator<Item = f64> + '_ {
        let (length, step) = (segment.length(), self.step);
        (0u32..)
            .map(move |k| (f64::from(k) + offset) * step)
            .take_while(move |&t| t < length)
    }

    /// Texture coordinate of the point at distance `t` from the segment's start.
    fn tex_at(&self, segment: &Segment, t: f64) -> DVec3 {
        self.placement.to_tex(segment.at(segment.t_start + t))
    }

    /// Rules 5–7 for emission–absorption and the density model: the ray is composited segment by segment
    /// between consecutive points — its start, the samples, its end — each segment pre-integrated (segments.rs).
    fn absorb(&self, segment: &Segment, trace: &mut PixelTrace) -> Composite {
        let (mut color, mut alpha) = (DVec3::ZERO, 0.0f64);
        let light = -segment.dir;
        let (mut t_prev, mut v_prev) = (0.0, self.volume.sample(self.tex_at(segment, 0.0)));
        // Rule 2's strides: sample k only where k is a multiple of its brick's stride times its level stride.
        let samples: Vec<f64> = self
            .sample_offsets(segment, trace.offset)
            .enumerate()
            .filter(|&(k, t)| {
                let tex = self.tex_at(segment, t);
                let stride =
                    self.strides.as_ref().map_or(1, |b| b.at(tex)) * self.volume.level_stride(tex, self.finest);
                (k as u64).is_multiple_of(stride)
            })
            .map(|(_, t)| t)
            .collect();
        let mut glow = Glow::new(self.layers.len());
        let ends = samples
            .iter()
            .map(|&t| (t, true))
            .chain(std::iter::once((segment.length(), false)));
        for (t, is_sample) in ends {
            if is_sample {
                trace.samples += 1;
            }
            let tex = self.tex_at(segment, t);
            let v = self.volume.sample(tex);
            let (vp, t_mid_prev, length) = (v_prev, t_prev, (t - t_prev) / self.step * self.step_length);
            (t_prev, v_prev) = (t, v);
            let mut seg = self.base_segment(segment, (vp, v), (t_mid_prev, t), length, light);
            if is_sample && !self.layers.is_empty() {
                let mm = self.volume.mm_at(tex);
                let step = (self.step, self.world_per_mm);
                glow.gather(&self.volume.layers, &self.layers, mm, step, 1.0 - alpha);
                let base = seg.unwrap_or((DVec3::ZERO, 0.0));
                let lit = self.shading.as_ref().map(|shading| Lit {
                    view: light,
                    shading,
                    lamp: self.lamp_at(tex),
                    mm_per_world: self.volume.mm_per_world(&self.placement),
                });
                let mixed = mix(base, &self.volume.layers, &self.layers, mm, step, lit.as_ref());
                seg = seg.or((mixed.1 > 0.0).then_some(mixed)).map(|_| mixed);
            }
            let Some((rgb, a_step)) = seg else { continue };
            color += (1.0 - alpha) * a_step * rgb;
            alpha += (1.0 - alpha) * a_step;
            trace.composited += 1;
            if alpha >= self.early_termination {
                trace.terminated_early = true;
                break;
            }
        }
        // Rule 13: the other blends' light, added at the ray's end.
        color += glow.total();
        Composite { color, alpha }
    }

    /// Rules 5 and 6: the segment between values `vp` and `v` at distances `ts`, `length` voxels long: its colour
    /// and opacity (None where an end is NaN or it is transparent).
    fn base_segment(
        &self,
        segment: &Segment,
        (vp, v): (f64, f64),
        ts: (f64, f64),
        length: f64,
        light: DVec3,
    ) -> Option<(DVec3, f64)> {
        let segments = self.segments.as_ref().expect("segments for emission and density");
        let (t_mid_prev, t) = ts;
        {
            if v.is_nan() || vp.is_nan() {
                return None;
            }
            let (mut sigma, mut rgb) = segments.mean(vp, v);
            if sigma <= 0.0 {
                return None;
            }
            if self.shading.is_some() || self.gradient_opacity.is_some() {
                let grad = self.gradient(self.tex_at(segment, 0.5 * (t + t_mid_prev)));
                if let Some(reference) = self.gradient_opacity {
                    sigma *= (grad.length() / reference).min(1.0);
                }
                if let Some(shading) = &self.shading {
                    let p = self.tex_at(segment, 0.5 * (t + t_mid_prev));
                    let fade = super::reference::gradient_fade(grad, self.shading_fade, self.window);
                    rgb = shade(rgb, self.placement.normal(grad), light, shading, &self.lamp_at(p), fade);
                }
            }
            let a_step = match self.mode {
                CompositeMode::Density => (sigma * length).min(1.0),
                _ => 1.0 - (-sigma * length).exp(),
            };
            Some((rgb, a_step))
        }
    }

    /// Rule 7 for MIP, MinIP and average: the colour of the max/min/mean of the visible samples.
    fn extremum(&self, segment: &Segment, trace: &mut PixelTrace) -> Composite {
        let mut visible = Vec::new();
        for t in self.sample_offsets(segment, trace.offset) {
            trace.samples += 1;
            let v = self.volume.sample(self.tex_at(segment, t));
            if self.visible(v) {
                visible.push(v);
            }
        }
        trace.composited = visible.len() as u32;
        if visible.is_empty() {
            return Composite {
                color: DVec3::ZERO,
                alpha: 0.0,
            };
        }
        let m = match self.mode {
            CompositeMode::Mip => visible.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            CompositeMode::MinIp => visible.iter().copied().fold(f64::INFINITY, f64::min),
            _ => visible.iter().sum::<f64>() / visible.len() as f64,
        };
        trace.value = Some(m);
        Composite {
            color: self.classifier.rgb(m),
            alpha: 1.0,
        }
    }

    /// Rule 7 for iso-surfaces: where the samples cross the surfaces (a NaN sample below every one), each crossing
    /// placed by 8 bisection steps, coloured, shaded and composited front to back in the order met.
    fn isosurface(&self, segment: &Segment, trace: &mut PixelTrace) -> Composite {
        let value_at = |t: f64| {
            let v = self.volume.sample(self.tex_at(segment, t));
            if v.is_nan() {
                f64::NEG_INFINITY
            } else {
                v
            }
        };
        let shading = self.shading.unwrap_or_default();
        let (mut color, mut alpha) = (DVec3::ZERO, 0.0);
        let mut previous: Option<(f64, f64)> = None;
        for t in self.sample_offsets(segment, trace.offset) {
            trace.samples += 1;
            let v = value_at(t);
            let v_prev = previous.map_or(f64::NEG_INFINITY, |p| p.1);
            let mut met: Vec<&(f64, Option<DVec3>, f64)> = self
                .surfaces
                .iter()
                .filter(|(iso, _, _)| (v_prev < *iso) != (v < *iso))
                .collect();
            if previous.is_none() || v < v_prev {
                met.reverse();
            }
            // Rule 10: on the clipping plane the first sample meets nothing (surfaces are cut, not capped).
            if previous.is_none() && segment.clipped_start {
                met.clear();
            }
            for (iso, material, opacity) in met {
                let t_hit = match previous {
                    None => t,
                    Some((t_prev, _)) => {
                        let below_before = v_prev < *iso;
                        let (mut lo, mut hi) = (t_prev, t);
                        for _ in 0..8 {
                            let mid = (lo + hi) / 2.0;
                            if (value_at(mid) < *iso) == below_before {
                                lo = mid;
                            } else {
                                hi = mid;
                            }
                        }
                        (lo + hi) / 2.0
                    }
                };
                trace.composited += 1;
                trace.hit.get_or_insert(segment.t_start + t_hit);
                let grad = self.gradient(self.tex_at(segment, t_hit));
                let rgb = material.unwrap_or_else(|| self.classifier.iso_rgb(*iso));
                let p = self.tex_at(segment, t_hit);
                let lit = shade(
                    rgb,
                    self.placement.normal(grad),
                    -segment.dir,
                    &shading,
                    &self.lamp_at(p),
                    1.0,
                );
                color += (1.0 - alpha) * opacity * lit;
                alpha += (1.0 - alpha) * opacity;
                if alpha >= self.early_termination {
                    break;
                }
            }
            if alpha >= self.early_termination {
                trace.terminated_early = alpha < 1.0;
                break;
            }
            previous = Some((t, v));
        }
        Composite { color, alpha }
    }
}
