//! The panel's Rendering section: compositing mode, shading, opacity modulation, ray jitter, projection, level
//! of detail and the "look along" buttons.

use crate::scene::settings::{CompositeMode, Shading};
use crate::viewer::model::orbit::{look_along, RotationAnimation};
use crate::viewer::model::Model;

/// Mode, shading and camera projection.
pub fn rendering_section(ui: &mut egui::Ui, model: &mut Model) {
    egui::CollapsingHeader::new("Rendering")
        .default_open(true)
        .show(ui, |ui| {
            let look = &mut model.look;
            egui::ComboBox::from_label("mode")
                .selected_text(look.compositing.mode.name())
                .show_ui(ui, |ui| {
                    for m in CompositeMode::ALL {
                        ui.selectable_value(&mut look.compositing.mode, m, m.name());
                    }
                });
            match look.compositing.mode {
                CompositeMode::Isosurface => {
                    let iso = egui::Slider::new(&mut look.compositing.iso_value, 0.0..=1.0).text("iso value");
                    ui.add(super::in_data_units(iso, model.volume.range));
                }
                CompositeMode::Density => {
                    ui.add(egui::Slider::new(&mut look.compositing.density, 0.0..=20.0).text("density factor"));
                }
                _ => {}
            }
            let mut shading = look.lighting.shading.is_some();
            if ui.checkbox(&mut shading, "gradient shading (S)").changed() {
                look.lighting.shading = shading.then(Shading::default);
            }
            if let Some(sh) = &mut look.lighting.shading {
                ui.add(egui::Slider::new(&mut sh.ambient, 0.0..=1.0).text("ambient"));
                ui.add(egui::Slider::new(&mut sh.diffuse, 0.0..=1.0).text("diffuse"));
                ui.add(egui::Slider::new(&mut sh.specular, 0.0..=1.0).text("specular"));
                ui.add(egui::Slider::new(&mut sh.shininess, 1.0..=100.0).text("shininess"));
            }
            let mut grad = look.lighting.gradient_opacity.is_some();
            if ui.checkbox(&mut grad, "gradient-modulated opacity").changed() {
                look.lighting.gradient_opacity = grad.then_some(0.05);
            }
            if let Some(r) = &mut look.lighting.gradient_opacity {
                ui.add(
                    egui::Slider::new(r, 0.005..=0.5)
                        .logarithmic(true)
                        .text("full at |grad v|"),
                );
            }
            let mut jitter = look.sampling.jitter.is_some();
            if ui.checkbox(&mut jitter, "jittered ray start").changed() {
                look.sampling.jitter = jitter.then_some(0);
            }
            ui.checkbox(&mut model.camera.ortho, "orthographic");
            ui.checkbox(&mut model.sampling.lod, "lower detail while moving");
            ui.horizontal_wrapped(|ui| {
                ui.label("look along");
                for (axis, name) in ["X", "Y", "Z"].iter().enumerate() {
                    for (positive, sign) in [(true, "+"), (false, "-")] {
                        if ui.small_button(format!("{sign}{name}")).clicked() {
                            model.camera.animation = Some(RotationAnimation::new(
                                model.camera.orbit.rotation,
                                look_along(axis, positive),
                            ));
                        }
                    }
                }
            });
        });
}
