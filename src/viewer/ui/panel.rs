//! The settings panel: egui widgets that edit the [`ViewerState`] and return [`UiAction`]s for what needs the GPU or a
//! thread (loading, screenshots).

use super::state::{raw_only, UiAction, ViewerState};
use super::tf_panel::transfer_function_section;
use crate::scene::camera::ViewPreset;
use crate::scene::clip::ClipPlane;
use crate::scene::settings::{CompositeMode, PositionFormat, RaySetup, Shading};
use crate::viewer::clip_widget;
use crate::viewer::controls::{look_along, RotationAnimation};
use crate::volume::geometry::index_axis_names;
use crate::volume::{parse_scivis_name, VoxelType, BUILTIN_NAMES};
use egui::Color32;
use std::path::PathBuf;

/// The settings panel. Returns what the viewer must do beyond editing `state`.
pub fn settings_panel(ui: &mut egui::Ui, state: &mut ViewerState) -> Vec<UiAction> {
    let mut actions = Vec::new();
    ui.heading("volcast");
    ui.label(&state.volume_label);
    if let Some((label, progress)) = &state.loading {
        ui.horizontal(|ui| {
            ui.spinner();
            ui.label(format!("loading {label}"));
        });
        ui.add(egui::ProgressBar::new(*progress).show_percentage());
    }
    if let Some(err) = &state.error {
        ui.colored_label(Color32::from_rgb(255, 110, 110), err);
    }
    if let Some(status) = &state.status {
        ui.label(status);
    }
    state.time.panel(ui);
    ui.separator();

    transfer_function_section(ui, state);
    rendering_section(ui, state);
    crate::viewer::lighting_panel::lighting_section(ui, &mut state.look);
    slicing_section(ui, state);
    view_section(ui, state, &mut actions);
    volume_section(ui, state, &mut actions);
    session_section(ui, state, &mut actions);
    performance_section(ui, state);
    actions
}

/// Mode, shading and camera projection.
fn rendering_section(ui: &mut egui::Ui, state: &mut ViewerState) {
    egui::CollapsingHeader::new("Rendering")
        .default_open(true)
        .show(ui, |ui| {
            let look = &mut state.look;
            egui::ComboBox::from_label("mode")
                .selected_text(look.mode.name())
                .show_ui(ui, |ui| {
                    for m in CompositeMode::ALL {
                        ui.selectable_value(&mut look.mode, m, m.name());
                    }
                });
            match look.mode {
                CompositeMode::Isosurface => {
                    ui.add(egui::Slider::new(&mut look.iso_value, 0.0..=1.0).text("iso value"));
                }
                CompositeMode::Density => {
                    ui.add(egui::Slider::new(&mut look.density, 0.0..=20.0).text("density factor"));
                }
                _ => {}
            }
            let mut shading = look.shading.is_some();
            if ui.checkbox(&mut shading, "gradient shading (S)").changed() {
                look.shading = shading.then(Shading::default);
            }
            if let Some(sh) = &mut look.shading {
                ui.add(egui::Slider::new(&mut sh.ambient, 0.0..=1.0).text("ambient"));
                ui.add(egui::Slider::new(&mut sh.diffuse, 0.0..=1.0).text("diffuse"));
                ui.add(egui::Slider::new(&mut sh.specular, 0.0..=1.0).text("specular"));
                ui.add(egui::Slider::new(&mut sh.shininess, 1.0..=100.0).text("shininess"));
            }
            let mut grad = look.gradient_opacity.is_some();
            if ui.checkbox(&mut grad, "gradient-modulated opacity").changed() {
                look.gradient_opacity = grad.then_some(0.05);
            }
            if let Some(r) = &mut look.gradient_opacity {
                ui.add(
                    egui::Slider::new(r, 0.005..=0.5)
                        .logarithmic(true)
                        .text("full at |grad v|"),
                );
            }
            let mut jitter = look.jitter.is_some();
            if ui.checkbox(&mut jitter, "jittered ray start").changed() {
                look.jitter = jitter.then_some(0);
            }
            ui.checkbox(&mut state.ortho, "orthographic");
            ui.checkbox(&mut state.lod, "lower detail while moving");
            ui.horizontal_wrapped(|ui| {
                ui.label("look along");
                for (axis, name) in ["X", "Y", "Z"].iter().enumerate() {
                    for (positive, sign) in [(true, "+"), (false, "-")] {
                        if ui.small_button(format!("{sign}{name}")).clicked() {
                            state.animation =
                                Some(RotationAnimation::new(state.orbit.rotation, look_along(axis, positive)));
                        }
                    }
                }
            });
        });
}

/// The axis slabs.
fn slicing_section(ui: &mut egui::Ui, state: &mut ViewerState) {
    egui::CollapsingHeader::new("Slicing")
        .default_open(true)
        .show(ui, |ui| {
            let names = if state.anatomical() {
                index_axis_names(&state.geometry)
            } else {
                ["x", "y", "z"].map(String::from)
            };
            for (axis, name) in names.iter().enumerate() {
                let (pos, width) = &mut state.slabs[axis];
                ui.add(egui::Slider::new(pos, 0.0..=1.0).text(format!("{name} position")));
                ui.add(egui::Slider::new(width, 0.0..=1.0).text(format!("{name} width")));
            }
            if ui.button("Reset slices").clicked() {
                state.slabs = [(0.5, 1.0); 3];
            }
            ui.separator();
            clip_plane_controls(ui, state);
        });
}

/// The arbitrary clipping plane: on/off, offset, flip, face the camera (dragged in the 3D view).
fn clip_plane_controls(ui: &mut egui::Ui, state: &mut ViewerState) {
    let mut on = state.look.clip_plane.is_some();
    if ui.checkbox(&mut on, "clip plane (C)").changed() {
        state.look.clip_plane = on.then(|| clip_widget::facing_away(state));
    }
    let Some(plane) = state.look.clip_plane else {
        return;
    };
    let reach = clip_widget::half_diagonal_mm(state);
    let mut offset = plane.offset();
    if ui
        .add(egui::Slider::new(&mut offset, -reach..=reach).text("offset (mm)"))
        .changed()
    {
        state.look.clip_plane = plane.with_offset(offset).ok().or(Some(plane));
    }
    ui.horizontal(|ui| {
        if ui.button("Flip (F)").clicked() {
            state.look.clip_plane = Some(plane.flipped());
        }
        if ui.button("Face the camera").clicked() {
            let forward = state.orbit.camera().forward();
            state.look.clip_plane = ClipPlane::through(forward, plane.point()).ok().or(Some(plane));
        }
    });
    let n = plane.normal();
    let frame = if state.anatomical() { "RAS" } else { "xyz" };
    ui.label(format!("normal {frame} {:.2} {:.2} {:.2}", n.x, n.y, n.z));
    ui.weak("Drag its handle to slide it, its ring to turn it.");
}

/// View presets, boxes, ray setup, reset and screenshot.
fn view_section(ui: &mut egui::Ui, state: &mut ViewerState, actions: &mut Vec<UiAction>) {
    egui::CollapsingHeader::new("View").default_open(true).show(ui, |ui| {
        ui.horizontal(|ui| {
            ui.label("from");
            for preset in ViewPreset::ALL {
                let name = preset.name();
                let letter = name[..1].to_ascii_uppercase();
                if ui.button(letter).on_hover_text(name).clicked() {
                    state.look_from(preset);
                }
            }
        });
        if state.geometry.anatomical {
            let voxel_axes = state.look.voxel_axes;
            ui.checkbox(&mut state.look.voxel_axes, "voxel axes (ignore the file's orientation)");
            if voxel_axes != state.look.voxel_axes {
                state.reset_view();
            }
        }
        ui.checkbox(&mut state.slices.shown, "slice views, four-up (L)");
        ui.checkbox(&mut state.show_boxes, "draw bounding box");
        ui.checkbox(&mut state.show_colorbar, "colour bar (data units)");
        ui.checkbox(&mut state.auto_rotate, "auto-rotate (Space)");
        if ui.checkbox(&mut state.vsync, "vsync").changed() {
            actions.push(UiAction::VsyncChanged);
        }
        ui.horizontal(|ui| {
            ui.label("ray setup");
            ui.selectable_value(&mut state.look.ray_setup, RaySetup::Faces, "faces");
            ui.selectable_value(&mut state.look.ray_setup, RaySetup::Analytic, "analytic");
        });
        if state.look.ray_setup == RaySetup::Faces {
            ui.horizontal(|ui| {
                ui.label("positions");
                ui.selectable_value(&mut state.look.position_format, PositionFormat::Rgba32f, "rgba32f");
                ui.selectable_value(&mut state.look.position_format, PositionFormat::Rgba16f, "rgba16f");
            });
        }
        ui.horizontal(|ui| {
            if ui.button("Reset view (R)").clicked() {
                state.reset_view();
            }
            if ui.button("Screenshot (F12)").clicked() {
                actions.push(UiAction::Screenshot);
            }
        });
        let record = if state.recording.is_some() {
            "Stop recording (F9)"
        } else {
            "Record GIF (F9)"
        };
        if ui.button(record).clicked() {
            actions.push(UiAction::ToggleRecording);
        }
        if let Some(path) = &state.recording {
            ui.colored_label(Color32::from_rgb(255, 110, 110), format!("recording {path}"));
        }
        ui.label("Hide this panel: Tab");
    });
}

/// Built-ins, a path or dialog, and the raw fields.
fn volume_section(ui: &mut egui::Ui, state: &mut ViewerState, actions: &mut Vec<UiAction>) {
    egui::CollapsingHeader::new("Volume").default_open(true).show(ui, |ui| {
        ui.horizontal_wrapped(|ui| {
            for name in BUILTIN_NAMES {
                if ui.button(*name).clicked() {
                    actions.push(UiAction::LoadBuiltin(name.to_string()));
                }
            }
        });
        ui.horizontal(|ui| {
            if ui.button("Open…").clicked() {
                actions.push(UiAction::OpenDialog);
            }
            ui.label("or a path (or drop a file on the window):");
        });
        // A fixed width: a long path scrolls inside the field instead of widening the panel for good.
        let path_field =
            egui::TextEdit::singleline(&mut state.load_path).desired_width(ui.available_width().min(250.0));
        if ui.add(path_field).changed() {
            state.take_dims_from_name();
        }
        egui::Grid::new("raw").num_columns(2).show(ui, |ui| {
            ui.label("dims");
            ui.horizontal(|ui| {
                for d in &mut state.raw_dims {
                    ui.add(egui::DragValue::new(d).range(1..=crate::volume::MAX_DIM));
                }
            });
            ui.end_row();
            ui.label("type");
            egui::ComboBox::from_id_salt("raw type")
                .selected_text(state.raw_type.name())
                .show_ui(ui, |ui| {
                    for t in VoxelType::ALL {
                        ui.selectable_value(&mut state.raw_type, t, t.name());
                    }
                });
            ui.end_row();
            ui.label("scale");
            ui.horizontal(|ui| {
                for s in &mut state.raw_spacing {
                    ui.add(egui::DragValue::new(s).speed(0.01).range(0.001..=1000.0));
                }
            });
            ui.end_row();
        });
        let can_load = !state.load_path.trim().is_empty() && state.loading.is_none();
        if ui.add_enabled(can_load, egui::Button::new("Load volume")).clicked() {
            let path = PathBuf::from(state.load_path.trim());
            let mut opts = state.raw_options();
            if parse_scivis_name(&state.load_path).is_some() {
                // The name carries dims and type; the fields were filled from it but may have been edited.
                opts.dims = Some(state.raw_dims);
                opts.voxel_type = Some(state.raw_type);
            }
            actions.push(UiAction::LoadFile(path.clone(), raw_only(&path, opts)));
        }
        // A load's error beside the button that caused it (it also shows at the top of the panel).
        if let Some(err) = &state.error {
            ui.colored_label(Color32::from_rgb(255, 110, 110), err);
        }
    });
}

/// Frame and GPU times.
fn performance_section(ui: &mut egui::Ui, state: &mut ViewerState) {
    egui::CollapsingHeader::new("Performance")
        .default_open(true)
        .show(ui, |ui| {
            ui.label(format!("frame {:.1} ms", state.frame_ms));
            if let Some(t) = state.gpu {
                match (t.entry_ms, t.exit_ms) {
                    (Some(a), Some(b)) => {
                        ui.label(format!("GPU entry {a:.2} + exit {b:.2} + march {:.2} ms", t.march_ms));
                    }
                    _ => {
                        ui.label(format!("GPU march {:.2} ms", t.march_ms));
                    }
                }
            }
        });
}

/// Save and open sessions (the whole viewer state as JSON).
fn session_section(ui: &mut egui::Ui, state: &mut ViewerState, actions: &mut Vec<UiAction>) {
    egui::CollapsingHeader::new("Session")
        .default_open(true)
        .show(ui, |ui| {
            let field =
                egui::TextEdit::singleline(&mut state.session_path).desired_width(ui.available_width().min(250.0));
            ui.add(field);
            ui.horizontal(|ui| {
                let named = !state.session_path.trim().is_empty();
                if ui
                    .add_enabled(named, egui::Button::new("Save session (Ctrl+S)"))
                    .clicked()
                {
                    actions.push(UiAction::SaveSession);
                }
                if ui.add_enabled(named, egui::Button::new("Open session")).clicked() {
                    actions.push(UiAction::OpenSession(PathBuf::from(state.session_path.trim())));
                }
            });
        });
}
