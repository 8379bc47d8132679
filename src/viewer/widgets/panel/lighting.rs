//! The panel's lighting section: the light (headlight or a direction by azimuth and elevation, colour,
//! intensity), shadows and ambient occlusion, and the iso-surfaces' materials and extra layers.

use crate::scene::lighting::{IsoSurface, Light, MAX_ISOSURFACES, NEUTRAL};
use crate::scene::settings::{CompositeMode, RenderSettings};
use glam::Vec3;

/// Azimuth and elevation (degrees, as `Light::from_angles`) of unit direction `d`.
pub fn angles(d: Vec3) -> (f32, f32) {
    let d = d.normalize();
    ((-d.x).atan2(d.y).to_degrees(), d.z.clamp(-1.0, 1.0).asin().to_degrees())
}

fn color_edit(ui: &mut egui::Ui, color: &mut Vec3) {
    let mut rgb = color.to_array();
    ui.color_edit_button_rgb(&mut rgb);
    *color = Vec3::from_array(rgb);
}

/// A surface's material: the colormap's colour at its value (None), or a colour of its own.
fn material_edit(ui: &mut egui::Ui, color: &mut Option<Vec3>) {
    let mut by_colormap = color.is_none();
    if ui.checkbox(&mut by_colormap, "colormap colour").changed() {
        *color = (!by_colormap).then_some(NEUTRAL);
    }
    if let Some(c) = color {
        color_edit(ui, c);
    }
}

/// The lighting section for `look`.
pub fn lighting_section(ui: &mut egui::Ui, look: &mut RenderSettings) {
    egui::CollapsingHeader::new("Lighting")
        .default_open(false)
        .show(ui, |ui| {
            let lit = look.compositing.mode == CompositeMode::Isosurface || look.lighting.shading.is_some();
            if !lit {
                ui.label("Turn on gradient shading (S) or the iso-surface mode to light the volume.");
            }
            let mut directional = look.lighting.light.direction.is_some();
            if ui
                .checkbox(&mut directional, "directional light (drag the sun disc in the view)")
                .changed()
            {
                look.lighting.light.direction =
                    directional.then(|| Light::from_angles(-45.0, 35.0).direction.unwrap_or(Vec3::Z));
            }
            if let Some(d) = look.lighting.light.direction {
                let (mut az, mut el) = angles(d);
                let a = ui.add(egui::Slider::new(&mut az, -180.0..=180.0).text("light azimuth°"));
                let e = ui.add(egui::Slider::new(&mut el, -90.0..=90.0).text("light elevation°"));
                if a.changed() || e.changed() {
                    look.lighting.light.direction = Light::from_angles(az, el).direction;
                }
            }
            ui.horizontal(|ui| {
                color_edit(ui, &mut look.lighting.light.color);
                ui.add(egui::Slider::new(&mut look.lighting.light.intensity, 0.0..=4.0).text("intensity"));
            });
            let projection = look.compositing.mode.is_projection();
            ui.add_enabled_ui(!projection, |ui| {
                ui.checkbox(&mut look.lighting.shadows, "shadows")
                    .on_hover_text("Light attenuated through the volume; a headlight casts them from a key light");
                ui.checkbox(&mut look.lighting.ambient_occlusion, "ambient occlusion");
            });
            if projection {
                ui.label("MIP, MinIP and average are not lit: no shadows or occlusion.");
            }
            if look.compositing.mode == CompositeMode::Isosurface {
                ui.separator();
                iso_surfaces(ui, look);
            }
        });
}

/// The first surface's material and the extra layers.
fn iso_surfaces(ui: &mut egui::Ui, look: &mut RenderSettings) {
    ui.label("Iso-surfaces (composited in the order a ray meets them)");
    ui.horizontal(|ui| material_edit(ui, &mut look.compositing.iso_color));
    ui.add(egui::Slider::new(&mut look.compositing.iso_opacity, 0.01..=1.0).text("opacity"));
    let mut remove = None;
    for (i, extra) in look.compositing.extra_isosurfaces.iter_mut().enumerate() {
        ui.separator();
        ui.add(egui::Slider::new(&mut extra.value, 0.0..=1.0).text(format!("surface {} value", i + 2)));
        ui.horizontal(|ui| {
            material_edit(ui, &mut extra.color);
            if ui.button("remove").clicked() {
                remove = Some(i);
            }
        });
        ui.add(egui::Slider::new(&mut extra.opacity, 0.01..=1.0).text("opacity"));
    }
    if let Some(i) = remove {
        look.compositing.extra_isosurfaces.remove(i);
    }
    if look.compositing.extra_isosurfaces.len() + 1 < MAX_ISOSURFACES && ui.button("add a surface").clicked() {
        // A translucent layer below the first: skin over bone.
        look.compositing.extra_isosurfaces.push(IsoSurface {
            value: (look.compositing.iso_value * 0.5).clamp(0.0, 1.0),
            color: Some(Vec3::new(0.9, 0.65, 0.55)),
            opacity: 0.3,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_invert_from_angles() {
        for (az, el) in [(0.0, 0.0), (-45.0, 35.0), (120.0, -20.0), (-170.0, 80.0)] {
            let d = Light::from_angles(az, el).direction.unwrap();
            let (a, e) = angles(d);
            assert!((a - az).abs() < 1e-3 && (e - el).abs() < 1e-3, "{az},{el} -> {a},{e}");
        }
    }
}
