//! How `FrameArgs` become `RenderSettings`: whole (every option, defaults included, over the volume's default
//! view), or as overrides of a saved view (`render --state`: only the options the command line gave, each over
//! the view's own value). One function per group of options (`frame.rs`); each applies an option where `wants` says
//! so.

use super::frame::{
    CameraArgs, ColourArgs, CompositingArgs, CutArgs, FrameArgs, Given, LightingArgs, OutputArgs, SamplingArgs,
};
use super::parse::IsoColor;
use super::UsageError;
use crate::scene::camera::Camera;
use crate::scene::lighting::IsoSurface;
use crate::scene::quality::{Gradients, Quality};
use crate::scene::settings::{PositionFormat, RenderSettings, DEFAULT_WINDOW};
use crate::scene::values::{fraction_note, DataValue};
use crate::transfer::function::TransferFunction;
use crate::volume::Volume;
use anyhow::{bail, Context, Result};
use glam::Vec3;

/// Whether the settings are made whole or override a saved view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scope {
    Whole,
    Overrides,
}

/// The options that choose the classification's model: given any, a file keeps the simple colormap model (or the
/// function named) instead of the automatic transfer function.
pub const CLASSIFICATION: &[&str] = &["preset", "tf", "colormap", "step_alpha", "multiplied_alpha"];
const CAMERA: &[&str] = &["azimuth", "elevation", "distance", "eye", "look_at", "view_dir", "view"];
const LIGHTING: &[&str] = &[
    "shading",
    "lighting",
    "light",
    "light_color",
    "light_intensity",
    "shadows",
    "ambient_occlusion",
];
/// Options whose change changes the step a quality level resolves to.
const STEP_INPUTS: &[&str] = &[
    "preset",
    "tf",
    "colormap",
    "window",
    "step_alpha",
    "multiplied_alpha",
    "mode",
    "density",
];

/// Whether an option is applied: every option when the settings are made whole, over a saved view only those given.
struct Wants<'a> {
    scope: Scope,
    given: &'a Given,
}

impl Wants<'_> {
    fn id(&self, id: &str) -> bool {
        self.scope == Scope::Whole || self.given.has(id)
    }

    fn whole(&self) -> bool {
        self.scope == Scope::Whole
    }
}

impl FrameArgs {
    /// Settings for `volume` from every option (the defaults of those not given). Values that make no valid frame
    /// are a [`UsageError`]: only the command line is to blame.
    pub fn settings(&self, volume: &Volume) -> Result<RenderSettings> {
        let (width, height) = self.output.size;
        let mut s = RenderSettings::new(width, height, volume.extent());
        self.apply(&mut s, volume, Scope::Whole, None)?;
        Ok(s)
    }

    /// A saved view's settings `s` with the options the command line gave applied over it; `quality` is the view's
    /// quality level (re-resolved when an option changes what the step depends on).
    pub fn override_view(&self, s: &mut RenderSettings, volume: &Volume, quality: Option<Quality>) -> Result<()> {
        self.apply(s, volume, Scope::Overrides, quality)
    }

    fn apply(&self, s: &mut RenderSettings, volume: &Volume, scope: Scope, quality: Option<Quality>) -> Result<()> {
        let wants = Wants {
            scope,
            given: &self.given,
        };
        self.output.apply(s, &wants);
        self.camera.apply(s, volume, &wants)?;
        self.colour.apply(s, volume, &wants)?;
        self.compositing.apply(s, volume, &wants);
        self.lighting.apply(s, &wants);
        self.cut.apply(s, &wants);
        // The quality's step depends on the classification, so it is resolved last, from valid settings.
        let invalid = |m: String| match scope {
            Scope::Whole => anyhow::Error::new(UsageError(m)),
            // A saved view's own values may be what is wrong.
            Scope::Overrides => anyhow::Error::msg(m),
        };
        s.validate().map_err(invalid)?;
        self.sampling.apply(s, volume, &wants, quality);
        s.validate().map_err(invalid)
    }
}

impl OutputArgs {
    fn apply(&self, s: &mut RenderSettings, wants: &Wants) {
        if wants.id("size") {
            (s.width, s.height) = self.size;
        }
        if wants.id("background") {
            s.background = self.background;
        }
    }
}

impl CameraArgs {
    /// The camera: `--eye`, `--view-dir`, `--view` or the orbit. Over a saved view, the angles and distance not
    /// given are the view's own.
    fn apply(&self, s: &mut RenderSettings, volume: &Volume, wants: &Wants) -> Result<()> {
        if wants.id("voxel_axes") {
            s.voxel_axes = self.voxel_axes;
        }
        let fov = if wants.id("fov") { self.fov } else { s.camera.fov_y_deg };
        if wants.whole() || wants.given.any(CAMERA) {
            s.camera = self.camera(s, volume, wants.scope, fov)?;
        }
        s.camera.fov_y_deg = fov;
        if wants.id("ortho") {
            s.camera.ortho = self.ortho;
        }
        Ok(())
    }

    fn camera(&self, s: &RenderSettings, volume: &Volume, scope: Scope, fov: f32) -> Result<Camera> {
        let extent = volume.extent();
        let old = &s.camera;
        let target = match (self.look_at, scope) {
            (Some(t), _) => t,
            (None, Scope::Whole) => Vec3::ZERO,
            (None, Scope::Overrides) => old.target,
        };
        let distance = match (self.distance, scope) {
            (Some(d), _) => d,
            (None, Scope::Whole) => Camera::fit_distance(extent.length() * 0.5, fov),
            (None, Scope::Overrides) => old.eye.distance(old.target),
        };
        let anatomical = volume.geometry.anatomical && !self.voxel_axes;
        let view = match self.view {
            Some(v) => Some(v),
            None if scope == Scope::Whole && anatomical && self.azimuth.is_none() && self.elevation.is_none() => {
                Some(crate::scene::camera::ViewPreset::Anterior)
            }
            None => None,
        };
        // Over a saved view, the direction it looks from (as orbit angles) stands in for angles not given.
        let (az, el) = match scope {
            Scope::Whole => (if anatomical { 0.0 } else { 35.0 }, if anatomical { 0.0 } else { 25.0 }),
            Scope::Overrides => orbit_angles(old),
        };
        Ok(match (self.eye, self.view_dir, view) {
            (Some(eye), _, _) => Camera::looking_at(eye, target),
            (None, Some(dir), _) => {
                if !(dir.is_finite() && dir.length() > 1e-6) {
                    bail!(UsageError(format!("--view-dir {dir} must be a non-zero direction")));
                }
                Camera::looking_at(target - dir.normalize() * distance, target)
            }
            (None, None, Some(view)) => view.camera(distance, target),
            (None, None, None) => Camera::orbit(
                self.azimuth.unwrap_or(az),
                self.elevation.unwrap_or(el),
                distance,
                target,
            ),
        })
    }
}

impl ColourArgs {
    /// The classification: a transfer function (`--preset`, `--tf`, or for a file given none of the
    /// classification options the automatic one), else the colormap model; the value window.
    fn apply(&self, s: &mut RenderSettings, volume: &Volume, wants: &Wants) -> Result<()> {
        let (given, scope) = (wants.given, wants.scope);
        let named = self.transfer_function(volume)?;
        let automatic = scope == Scope::Whole && named.is_none() && given.from_file && !given.any(CLASSIFICATION);
        let tf = if automatic {
            Some(crate::transfer::auto::auto_for_volume(volume))
        } else {
            named
        };
        let new_function = tf.is_some() && (automatic || wants.id("preset") || wants.id("tf"));
        // Over a saved view, --colormap alone leaves its transfer function for the colormap model, whose window
        // the function's [0, 1] is not.
        let to_colormap = scope == Scope::Overrides && given.has("colormap") && s.colour.transfer_function.is_some();
        if wants.id("colormap") {
            s.colour.colormap = self.colormap;
        }
        if new_function || scope == Scope::Whole || given.has("colormap") {
            s.colour.transfer_function = tf;
        }
        s.colour.window = match (self.window, scope) {
            (Some((lo, hi)), _) => {
                if let Some(note) = fraction_note("--window", &[lo, hi], volume.range) {
                    eprintln!("note: {note}");
                }
                [lo.fraction(volume.range), hi.fraction(volume.range)]
            }
            _ if new_function => [0.0, 1.0],
            (None, Scope::Whole) => DEFAULT_WINDOW,
            (None, Scope::Overrides) if to_colormap && !new_function => DEFAULT_WINDOW,
            (None, Scope::Overrides) => s.colour.window,
        };
        if wants.id("step_alpha") {
            s.colour.step_alpha = self.step_alpha;
        }
        if wants.id("multiplied_alpha") {
            s.colour.multiplied_alpha = self.multiplied_alpha;
        }
        if let (Some(path), Some(tf)) = (&self.save_tf, &s.colour.transfer_function) {
            std::fs::write(path, tf.to_json()).with_context(|| format!("writing {}", path.display()))?;
        }
        Ok(())
    }

    /// The function `--preset` or `--tf` names, if any.
    fn transfer_function(&self, volume: &Volume) -> Result<Option<TransferFunction>> {
        Ok(match (&self.preset, &self.tf) {
            (Some(name), _) if name == "auto" => Some(crate::transfer::auto::auto_for_volume(volume)),
            (Some(name), _) => Some(TransferFunction::preset(name)?),
            (None, Some(path)) => Some(TransferFunction::load(path)?),
            (None, None) => self.tf_value.clone(),
        })
    }
}

impl CompositingArgs {
    fn apply(&self, s: &mut RenderSettings, volume: &Volume, wants: &Wants) {
        if wants.id("mode") {
            s.compositing.mode = self.mode;
        }
        if wants.id("iso") {
            if let Some(note) = fraction_note("--iso", &[self.iso], volume.range) {
                eprintln!("note: {note}");
            }
            s.compositing.iso_value = self.iso.fraction(volume.range);
        }
        if wants.id("iso_color") {
            match self.iso_color {
                Some(IsoColor::Colormap) => s.compositing.iso_color = None,
                Some(IsoColor::Rgb(c)) => s.compositing.iso_color = Some(c),
                None => {}
            }
        }
        if wants.id("iso_opacity") {
            s.compositing.iso_opacity = self.iso_opacity;
        }
        if wants.id("surfaces") {
            let placed = |(v, surface): &(DataValue, IsoSurface)| IsoSurface {
                value: v.fraction(volume.range),
                ..*surface
            };
            s.compositing.extra_isosurfaces = self.surfaces.iter().map(placed).collect();
        }
        if wants.id("density") {
            s.compositing.density = self.density;
        }
        if wants.id("early_termination") {
            s.compositing.early_termination = self.early_termination;
        }
    }
}

impl LightingArgs {
    /// Shading and the light, and what the gradient does to a frame.
    fn apply(&self, s: &mut RenderSettings, wants: &Wants) {
        if wants.id("gradient_opacity") {
            s.lighting.gradient_opacity = self.gradient_opacity;
        }
        if wants.id("shading_fade") {
            s.lighting.shading_fade = self.shading_fade.unwrap_or(0.0);
        }
        if wants.whole() || wants.given.any(LIGHTING) {
            self.apply_light(s, wants);
        }
    }

    /// A light option, shadows or occlusion turn shading on; over a saved view shading stays as it was unless such
    /// an option is given.
    fn apply_light(&self, s: &mut RenderSettings, wants: &Wants) {
        let lit = self.light.is_some()
            || self.light_color.is_some()
            || self.light_intensity.is_some()
            || self.shadows
            || self.ambient_occlusion;
        if wants.id("shadows") {
            s.lighting.shadows = self.shadows;
        }
        if wants.id("ambient_occlusion") {
            s.lighting.ambient_occlusion = self.ambient_occlusion;
        }
        if (s.lighting.shadows || s.lighting.ambient_occlusion) && s.compositing.mode.is_projection() {
            eprintln!(
                "note: {} is not lit: shadows and ambient occlusion do not apply",
                s.compositing.mode.name()
            );
        }
        let was_on = !wants.whole() && s.lighting.shading.is_some();
        let coefficients = match s.lighting.shading {
            Some(c) if !wants.id("lighting") => c,
            _ => self.lighting,
        };
        s.lighting.shading = (self.shading || lit || was_on).then_some(coefficients);
        if wants.id("light") {
            s.lighting.light.direction = self.light.and_then(|l| l.0);
        }
        if wants.id("light_color") {
            s.lighting.light.color = self.light_color.unwrap_or(Vec3::ONE);
        }
        if wants.id("light_intensity") {
            s.lighting.light.intensity = self.light_intensity.unwrap_or(1.0);
        }
    }
}

impl CutArgs {
    /// The slabs and the clipping plane.
    fn apply(&self, s: &mut RenderSettings, wants: &Wants) {
        for &(axis, pos, width) in &self.slices {
            s.cut.set_slab(axis, pos, width);
        }
        if wants.id("clip_plane") {
            s.cut.clip_plane = self.clip_plane;
        }
    }
}

impl SamplingArgs {
    /// The step and strides (the quality level's, or `--step-length`), where gradients come from, jitter, skipping
    /// and the position targets' format. Over a saved
    /// view, its own quality level is resolved again where an option changed what the step depends on.
    fn apply(&self, s: &mut RenderSettings, volume: &Volume, wants: &Wants, saved: Option<Quality>) {
        let given = wants.given;
        let level = match wants.scope {
            Scope::Whole => Some(self.quality),
            Scope::Overrides if given.has("quality") => Some(self.quality),
            Scope::Overrides => saved.filter(|_| given.any(STEP_INPUTS)),
        };
        if let Some(q) = level {
            q.apply(s, volume.range);
        }
        if let Some(step) = self.step_length {
            s.sampling.step_length = step;
            s.sampling.max_stride = 1;
        }
        if let Some(stride) = self.max_stride {
            s.sampling.max_stride = stride;
        }
        if let Some(k) = self.ray_spacing {
            s.sampling.ray_spacing = k;
        }
        let reads_gradients = given.any(LIGHTING) || given.any(&["mode", "gradient_opacity"]);
        if wants.id("gradients") || wants.id("gradient_texture") || reads_gradients {
            let gradients = if self.gradient_texture {
                Gradients::Texture
            } else {
                self.gradients
            };
            gradients.apply(s, volume.voxel_count() as u64);
        }
        if wants.id("no_jitter") || wants.id("jitter_seed") {
            s.sampling.jitter = (!self.no_jitter).then_some(self.jitter_seed);
        }
        if wants.id("no_skip") {
            s.sampling.skip_empty = !self.no_skip;
        }
        if wants.id("positions") {
            s.pipeline.position_format = if self.positions == "rgba16f" {
                PositionFormat::Rgba16f
            } else {
                PositionFormat::Rgba32f
            };
        }
    }
}

/// The orbit angles (azimuth about +z from +y, elevation) `camera` looks from, as `Camera::orbit` takes them.
fn orbit_angles(camera: &Camera) -> (f32, f32) {
    let dir = (camera.eye - camera.target).normalize_or_zero();
    let elevation = dir.z.clamp(-1.0, 1.0).asin().to_degrees();
    let azimuth = (-dir.x).atan2(dir.y).to_degrees();
    (azimuth, elevation)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orbit_angles_invert_the_orbit() {
        for (az, el) in [(35.0, 25.0), (-120.0, -40.0), (0.0, 0.0), (170.0, 60.0)] {
            let c = Camera::orbit(az, el, 3.0, Vec3::new(0.1, -0.2, 0.3));
            let (a, e) = orbit_angles(&c);
            assert!((a - az).abs() < 1e-3 && (e - el).abs() < 1e-3, "{az},{el} -> {a},{e}");
        }
    }

    #[test]
    fn given_ids_are_what_the_command_line_named() {
        let g = super::super::frame::Given::for_test(&["size", "window"], true);
        assert!(g.has("size") && g.any(&["tf", "window"]) && !g.has("mode"));
    }
}
