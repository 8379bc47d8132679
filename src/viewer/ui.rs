//! The viewer's state and its egui panel. `ViewerState` is plain data; [`ViewerState::render_settings`] is the one
//! place it turns into renderer parameters (unit-tested). The panel edits the state and returns [`UiAction`]s
//! for what needs the GPU or a thread (loading, screenshots).

use super::controls::{gizmo_axes, look_along, pick_axis, OrbitView, RotationAnimation};
use super::time_control::TimeControl;
use crate::camera::{edge_labels, Camera, ViewPreset};
use crate::quality::{Gradients, Quality};
use crate::render::PassTimings;
use crate::settings::{CompositeMode, PositionFormat, RaySetup, RenderSettings, Shading};
use crate::transfer::Colormap;
use crate::volume::geometry::index_axis_names;
use crate::volume::{parse_scivis_name, Geometry, RawOptions, VoxelType, BUILTIN_NAMES};
use egui::{Color32, Pos2, Stroke};
use glam::{Mat4, Vec2, Vec3};
use std::path::PathBuf;

/// Everything the user can change, and what the panel shows.
#[derive(Clone, Debug)]
pub struct ViewerState {
    /// Transfer function, slicing, ray setup...: a RenderSettings whose camera and size are filled per frame.
    pub look: RenderSettings,
    pub orbit: OrbitView,
    pub show_boxes: bool,
    pub auto_rotate: bool,
    pub panel_visible: bool,
    pub vsync: bool,
    /// Slab (position, width) per axis, as the sliders show them.
    pub slabs: [(f32, f32); 3],
    /// Box side lengths of the volume on screen.
    pub extent: Vec3,
    /// Where the volume's voxels are (its affine, and whether it is anatomical) and its grid.
    pub geometry: Geometry,
    pub dims: [u32; 3],
    pub volume_label: String,
    pub load_path: String,
    pub raw_dims: [u32; 3],
    pub raw_type: VoxelType,
    pub raw_spacing: [f32; 3],
    /// Last load error, shown in the panel until the next load.
    pub error: Option<String>,
    pub status: Option<String>,
    pub loading: Option<(String, f32)>,
    pub frame_ms: f64,
    pub gpu: Option<PassTimings>,
    pub animation: Option<RotationAnimation>,
    /// Where the volume view is in the window (points), as laid out by the last UI pass.
    pub view_rect: Option<egui::Rect>,
    /// Value histogram of the volume (256 bins over the normalised range) and its data range, for the editor.
    pub histogram: Vec<u64>,
    pub range: [f64; 2],
    pub tf_dragging: Option<usize>,
    pub ortho: bool,
    /// Sampling quality of still frames, as `render --quality` (the step resolved per frame from the transfer
    /// function); `None`: the step slider's step.
    pub quality: Option<Quality>,
    /// Shaded frames may take the volume's gradient texture (`render --gradients auto`): the viewer kept the
    /// volume to make it. Not for series, whose steps would each need one.
    pub gradient_texture: bool,
    /// Interactive level of detail: while the view moves, lower resolution and the draft quality's step (with a
    /// custom step, double it), then a full frame.
    pub lod: bool,
    /// The user moved the view in this UI pass (drag or wheel).
    pub interacting: bool,
    /// GPU time of the last full-quality frame, for choosing the level of detail.
    pub full_frame_ms: Option<f64>,
    /// A series' step slider and playback.
    pub time: TimeControl,
    /// Keep the transfer function and value window when another volume loads (else they reset: a CT's
    /// Hounsfield-unit function would leave an MRI invisible).
    pub tf_locked: bool,
}

/// What the panel asks the viewer to do.
#[derive(Clone, Debug)]
pub enum UiAction {
    LoadFile(PathBuf, RawOptions),
    LoadBuiltin(String),
    Screenshot,
    VsyncChanged,
    /// Show the platform's file dialog (off the render thread).
    OpenDialog,
}

/// Degrees per second of auto-rotation.
pub const AUTO_ROTATE_DEG_PER_S: f32 = 30.0;

impl ViewerState {
    pub fn new(extent: Vec3, volume_label: String) -> ViewerState {
        let look = RenderSettings::new(1, 1, extent);
        ViewerState {
            orbit: OrbitView::from_camera(&look.camera),
            look,
            show_boxes: true,
            auto_rotate: false,
            panel_visible: true,
            vsync: true,
            slabs: [(0.5, 1.0); 3],
            extent,
            geometry: Geometry::from_spacing([1.0; 3]),
            dims: [1; 3],
            volume_label,
            load_path: String::new(),
            raw_dims: [256, 256, 256],
            raw_type: VoxelType::U8,
            raw_spacing: [1.0; 3],
            error: None,
            status: None,
            loading: None,
            frame_ms: 0.0,
            gpu: None,
            animation: None,
            view_rect: None,
            histogram: Vec::new(),
            range: [0.0, 1.0],
            tf_dragging: None,
            ortho: false,
            quality: Some(Quality::Normal),
            gradient_texture: false,
            lod: true,
            interacting: false,
            full_frame_ms: None,
            time: TimeControl::new(1, 0),
            tf_locked: false,
        }
    }

    /// Whether the view is of patient space (an anatomical volume, not shown in voxel axes).
    pub fn anatomical(&self) -> bool {
        self.geometry.anatomical && !self.look.voxel_axes
    }

    /// The default view: what `volcast render` shows without camera options (an anatomical volume from the
    /// front, head up).
    pub fn reset_view(&mut self) {
        let defaults = RenderSettings::new(1, 1, self.extent);
        let camera = if self.anatomical() {
            ViewPreset::Anterior.camera(defaults.camera.eye.length(), Vec3::ZERO)
        } else {
            defaults.camera
        };
        self.orbit = OrbitView::from_camera(&camera);
        self.animation = None;
    }

    /// Turns the view to look from `preset`'s side, at the same distance.
    pub fn look_from(&mut self, preset: ViewPreset) {
        let distance = self.orbit.camera().eye.distance(self.orbit.camera().target);
        let target = self.orbit.camera().target;
        self.orbit = OrbitView::from_camera(&preset.camera(distance, target));
        self.animation = None;
    }

    /// The raw fields (dims, type, scale) describe the volume shown, so a raw reload starts from them.
    pub fn describe_raw(&mut self, dims: [u32; 3], voxel_type: VoxelType, spacing: [f32; 3]) {
        self.raw_dims = dims;
        self.raw_type = voxel_type;
        self.raw_spacing = spacing;
    }

    /// A new volume: its box, placement and a default view; the classification (transfer function and value
    /// window) resets to the simple model unless locked; slicing stays.
    pub fn set_volume(&mut self, extent: Vec3, geometry: Geometry, dims: [u32; 3], label: String) {
        if !self.tf_locked {
            self.look.transfer_function = None;
            self.look.window = crate::settings::DEFAULT_WINDOW;
        }
        self.extent = extent;
        self.geometry = geometry;
        self.dims = dims;
        self.volume_label = label;
        self.reset_view();
    }

    /// Texture space to the render world for what the view shows.
    pub fn tex_to_world(&self) -> Mat4 {
        self.geometry.tex_to_world(self.dims, self.look.voxel_axes).as_mat4()
    }

    /// The renderer's parameters for a `width`×`height` frame.
    pub fn render_settings(&self, width: u32, height: u32) -> RenderSettings {
        let mut s = self.look.clone();
        s.width = width.max(1);
        s.height = height.max(1);
        s.camera = self.orbit.camera();
        s.camera.ortho = self.ortho;
        for (axis, &(pos, width)) in self.slabs.iter().enumerate() {
            s.set_slab(axis, pos, width);
            // A slab thinner than the slider's resolution would be empty: keep a sliver.
            if s.slab_hi[axis] <= s.slab_lo[axis] {
                s.slab_hi[axis] = (s.slab_lo[axis] + 1e-3).min(1.0);
                s.slab_lo[axis] = s.slab_hi[axis] - 1e-3;
            }
        }
        if s.window[0] >= s.window[1] {
            s.window[1] = (s.window[0] + 1e-3).min(1.0);
            s.window[0] = s.window[1] - 1e-3;
        }
        if let Some(q) = self.quality {
            q.apply(&mut s, self.range);
        }
        let gradients = if self.gradient_texture {
            Gradients::Auto
        } else {
            Gradients::Samples
        };
        gradients.apply(&mut s, self.dims.iter().map(|&d| u64::from(d)).product());
        s
    }

    /// What a frame of `width`×`height` renders: full quality, or — while the view moves, with `lod` on — a
    /// fraction of the resolution (upscaled when shown; see [`ViewerState::lod_divisor`]), the draft quality's
    /// step (at least the still frame's; with a custom step, twice it) and at least its brick strides.
    pub fn frame_settings(&self, width: u32, height: u32, moving: bool) -> RenderSettings {
        let mut s = self.render_settings(width, height);
        if self.lod && moving {
            let f = self.lod_divisor();
            s.width = width.div_ceil(f).max(1);
            s.height = height.div_ceil(f).max(1);
            s.step_length = match self.quality {
                Some(_) => s.step_length.max(Quality::Draft.step_length(&s, self.range)),
                None => (s.step_length * 2.0).min(64.0),
            };
            s.max_stride = s.max_stride.max(Quality::Draft.max_stride());
        }
        s
    }

    /// How much to shrink each side while moving: aims the reduced frame (which also takes half the steps) at
    /// ~12 ms of GPU time from the last full-quality frame's, between 2 and 6. Measured on lavapipe at 512²:
    /// halving gave 68 ms per frame for the helix (15 fps), quartering 27 ms (37 fps).
    pub fn lod_divisor(&self) -> u32 {
        let full_ms = self.full_frame_ms.unwrap_or(100.0);
        ((full_ms / 2.0 / 12.0).sqrt().ceil() as u32).clamp(2, 6)
    }

    /// Advances animations by `dt` seconds; true while something is still moving.
    pub fn animate(&mut self, dt: f32) -> bool {
        let mut moving = false;
        if let Some(anim) = &mut self.animation {
            let (q, done) = anim.step(dt);
            self.orbit.rotation = q;
            if done {
                self.animation = None;
            }
            moving = true;
        }
        if self.auto_rotate && self.animation.is_none() {
            self.orbit.turn(AUTO_ROTATE_DEG_PER_S.to_radians() * dt);
            moving = true;
        }
        moving
    }

    /// Fills dims and type from an open-scivis file name, if it matches.
    pub fn take_dims_from_name(&mut self) {
        if let Some((_, dims, ty)) = parse_scivis_name(&self.load_path) {
            self.raw_dims = dims;
            self.raw_type = ty;
        }
    }

    fn raw_options(&self) -> RawOptions {
        RawOptions {
            dims: Some(self.raw_dims),
            voxel_type: Some(self.raw_type),
            spacing: Some(self.raw_spacing),
        }
    }

    /// A load of `path` with dims/type from its name when it matches, else from the panel's fields.
    pub fn load_action(&mut self, path: PathBuf) -> UiAction {
        self.load_path = path.display().to_string();
        let named = parse_scivis_name(&self.load_path).is_some();
        self.take_dims_from_name();
        let mut opts = self.raw_options();
        if named {
            opts.dims = None;
            opts.voxel_type = None;
        }
        UiAction::LoadFile(path.clone(), raw_only(&path, opts))
    }
}

/// The panel's dims/type/scale describe raw files; other formats carry their own (and the scale would override
/// their spacing), so they get none.
fn raw_only(path: &std::path::Path, opts: RawOptions) -> RawOptions {
    match crate::volume::detect_format(path) {
        Ok(crate::volume::Format::Raw) | Err(_) => opts,
        Ok(_) => RawOptions::default(),
    }
}

fn color_of(rgba: [u8; 4]) -> Color32 {
    Color32::from_rgb(rgba[0], rgba[1], rgba[2])
}

/// The colormap as a strip, with the value window marked.
fn colormap_strip(ui: &mut egui::Ui, colormap: Colormap, window: [f32; 2]) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(ui.available_width(), 16.0), egui::Sense::hover());
    let lut = colormap.lut();
    let painter = ui.painter();
    let n = 64;
    for i in 0..n {
        let t0 = i as f32 / n as f32;
        let t1 = (i + 1) as f32 / n as f32;
        // The strip spans the value range; inside the window the colormap is stretched over it.
        let c = ((t0 - window[0]) / (window[1] - window[0]).max(1e-6)).clamp(0.0, 1.0);
        let inside = t0 >= window[0] && t0 <= window[1];
        let color = if inside {
            color_of(lut[(c * 255.0) as usize])
        } else {
            Color32::from_gray(30)
        };
        let r = egui::Rect::from_min_max(
            Pos2::new(egui::lerp(rect.left()..=rect.right(), t0), rect.top()),
            Pos2::new(egui::lerp(rect.left()..=rect.right(), t1), rect.bottom()),
        );
        painter.rect_filled(r, 0.0, color);
    }
}

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

    egui::CollapsingHeader::new("Transfer function")
        .default_open(true)
        .show(ui, |ui| {
            let look = &mut state.look;
            let current = look
                .transfer_function
                .as_ref()
                .map(|t| t.name.clone())
                .unwrap_or_else(|| "simple (Qt)".into());
            egui::ComboBox::from_label("preset")
                .selected_text(&current)
                .show_ui(ui, |ui| {
                    if ui
                        .selectable_label(look.transfer_function.is_none(), "simple (Qt)")
                        .clicked()
                    {
                        look.transfer_function = None;
                        look.window = crate::settings::DEFAULT_WINDOW;
                    }
                    for name in crate::tf::PRESET_NAMES {
                        if ui.selectable_label(current == *name, *name).clicked() {
                            look.transfer_function = crate::tf::TransferFunction::preset(name).ok();
                            look.window = [0.0, 1.0];
                        }
                    }
                });
            ui.checkbox(&mut state.tf_locked, "keep when another volume loads");
            let look = &mut state.look;
            ui.label("Visible value range");
            ui.add(egui::Slider::new(&mut look.window[0], 0.0..=1.0).text("min"));
            ui.add(egui::Slider::new(&mut look.window[1], 0.0..=1.0).text("max"));
            if look.window[0] > look.window[1] {
                look.window.swap(0, 1);
            }
            if let Some(tf) = &mut look.transfer_function {
                ui.label("Opacity (click: add, drag: move, right-click: delete)");
                super::tf_editor::editor(
                    ui,
                    tf,
                    look.window,
                    state.range,
                    &state.histogram,
                    &mut state.tf_dragging,
                );
                if tf.colors.is_empty() {
                    egui::ComboBox::from_label("Colormap")
                        .selected_text(tf.colormap.name())
                        .show_ui(ui, |ui| {
                            for c in Colormap::ALL {
                                ui.selectable_value(&mut tf.colormap, c, c.name());
                            }
                        });
                }
            } else {
                colormap_strip(ui, look.colormap, look.window);
                egui::ComboBox::from_label("Colormap")
                    .selected_text(look.colormap.name())
                    .show_ui(ui, |ui| {
                        for c in Colormap::ALL {
                            ui.selectable_value(&mut look.colormap, c, c.name());
                        }
                    });
                ui.add(egui::Slider::new(&mut look.step_alpha, 0.0..=1.0).text("step alpha"));
                ui.checkbox(&mut look.multiplied_alpha, "multiplied alpha");
            }
            let name = |q: Option<Quality>| q.map_or("custom step", Quality::name);
            egui::ComboBox::from_label("quality (Q)")
                .selected_text(name(state.quality))
                .show_ui(ui, |ui| {
                    for q in Quality::ALL.into_iter().map(Some).chain([None]) {
                        ui.selectable_value(&mut state.quality, q, name(q));
                    }
                });
            ui.add_enabled(
                state.quality.is_none(),
                egui::Slider::new(&mut state.look.step_length, 0.1..=4.0)
                    .logarithmic(true)
                    .text("step length (voxels)"),
            );
        });

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

    super::lighting_panel::lighting_section(ui, &mut state.look);

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
        });

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
        ui.checkbox(&mut state.show_boxes, "draw bounding box");
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
        ui.label("Hide this panel: Tab");
    });

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
    actions
}

/// World-space corners of the texture-space box [lo, hi] of a volume placed by `tex_to_world`.
pub fn box_corners(tex_to_world: Mat4, lo: Vec3, hi: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        let t = Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
        tex_to_world.transform_point3(lo + (hi - lo) * t)
    })
}

const BOX_EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// Screen position (points) of a world point, or None behind the near plane.
pub fn project(view_proj: Mat4, p: Vec3, rect: egui::Rect) -> Option<Pos2> {
    let c = view_proj * p.extend(1.0);
    if c.w <= 1e-6 || c.z < 0.0 {
        return None;
    }
    let ndc = c.truncate() / c.w;
    Some(Pos2::new(
        rect.left() + (ndc.x * 0.5 + 0.5) * rect.width(),
        rect.top() + (ndc.y * 0.5 + 0.5) * rect.height(),
    ))
}

/// Bounding box, slab box and origin gizmo over the volume view; handles camera input on it.
pub fn view_overlay(ui: &mut egui::Ui, state: &mut ViewerState) {
    let rect = ui.max_rect();
    state.view_rect = Some(rect);
    let response = ui.interact(rect, ui.id().with("volume view"), egui::Sense::click_and_drag());
    let viewport = Vec2::new(rect.width(), rect.height());
    let gizmo_center = Vec2::new(rect.right() - 60.0, rect.bottom() - 60.0);
    let gizmo_radius = 40.0;
    state.interacting = response.dragged();
    // A drag that starts on the light gizmo moves the light, not the camera.
    let moving_light = super::light_gizmo::light_gizmo(ui, state, rect, &response);

    if let Some(pos) = response.interact_pointer_pos() {
        let p = Vec2::new(pos.x - rect.left(), pos.y - rect.top());
        let d = response.drag_delta();
        if response.dragged_by(egui::PointerButton::Primary) && d != egui::Vec2::ZERO && !moving_light {
            state.animation = None;
            state.orbit.arcball(p - Vec2::new(d.x, d.y), p, viewport);
        }
        if response.dragged_by(egui::PointerButton::Secondary) || response.dragged_by(egui::PointerButton::Middle) {
            state.orbit.pan(Vec2::new(d.x, d.y), viewport);
        }
    }
    if response.clicked() {
        if let Some(pos) = response.interact_pointer_pos() {
            let axes = gizmo_axes(state.orbit.rotation);
            if let Some(a) = pick_axis(Vec2::new(pos.x, pos.y), gizmo_center, gizmo_radius, 10.0, &axes) {
                state.animation = Some(RotationAnimation::new(
                    state.orbit.rotation,
                    look_along(a.axis, a.positive),
                ));
            }
        }
    }
    if response.hovered() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            state.orbit.zoom(scroll / 50.0);
            state.interacting = true;
        }
    }

    let painter = ui.painter_at(rect);
    if state.show_boxes {
        let s = state.render_settings(rect.width() as u32, rect.height() as u32);
        let cam: Camera = s.camera;
        let vp = cam.projection(rect.width() / rect.height().max(1.0)) * cam.view();
        let model = state.tex_to_world();
        let draw_box = |lo: Vec3, hi: Vec3, color: Color32| {
            let corners = box_corners(model, lo, hi).map(|c| project(vp, c, rect));
            for (a, b) in BOX_EDGES {
                if let (Some(pa), Some(pb)) = (corners[a], corners[b]) {
                    painter.line_segment([pa, pb], Stroke::new(1.0, color));
                }
            }
        };
        draw_box(Vec3::ZERO, Vec3::ONE, Color32::from_gray(160));
        if s.slab_lo != Vec3::ZERO || s.slab_hi != Vec3::ONE {
            draw_box(s.slab_lo, s.slab_hi, Color32::from_rgb(255, 200, 60));
        }
    }

    let colors = [
        Color32::from_rgb(230, 70, 70),
        Color32::from_rgb(90, 200, 90),
        Color32::from_rgb(80, 130, 240),
    ];
    let c = Pos2::new(gizmo_center.x, gizmo_center.y);
    painter.circle_filled(c, gizmo_radius + 12.0, Color32::from_black_alpha(90));
    for a in gizmo_axes(state.orbit.rotation) {
        let end = Pos2::new(c.x + a.screen.x * gizmo_radius, c.y + a.screen.y * gizmo_radius);
        let color = if a.positive {
            colors[a.axis]
        } else {
            colors[a.axis].gamma_multiply(0.45)
        };
        if a.positive {
            painter.line_segment([c, end], Stroke::new(2.0, color));
        }
        painter.circle_filled(end, 8.0, color);
        // In patient space every end is named (R/L, A/P, S/I); otherwise the positive ends X, Y, Z.
        let label = if state.anatomical() {
            Some([['L', 'R'], ['P', 'A'], ['I', 'S']][a.axis][usize::from(a.positive)])
        } else {
            a.positive.then_some(['X', 'Y', 'Z'][a.axis])
        };
        if let Some(label) = label {
            painter.text(
                end,
                egui::Align2::CENTER_CENTER,
                label,
                egui::FontId::proportional(11.0),
                Color32::BLACK,
            );
        }
    }
    if state.anatomical() {
        // Which side of the patient each edge of the view faces.
        let [left, right, top, bottom] = edge_labels(&state.orbit.camera());
        let font = egui::FontId::proportional(16.0);
        let color = Color32::from_rgb(255, 220, 120);
        let mid = rect.center();
        for (text, pos, align) in [
            (left, Pos2::new(rect.left() + 8.0, mid.y), egui::Align2::LEFT_CENTER),
            (right, Pos2::new(rect.right() - 8.0, mid.y), egui::Align2::RIGHT_CENTER),
            (top, Pos2::new(mid.x, rect.top() + 8.0), egui::Align2::CENTER_TOP),
            (
                bottom,
                Pos2::new(mid.x, rect.bottom() - 8.0),
                egui::Align2::CENTER_BOTTOM,
            ),
        ] {
            painter.text(pos, align, text, font.clone(), color);
        }
    }
}

/// Removes the presses of Tab (without modifiers) from `input` and returns how many there were: the viewer handles
/// Tab itself (panel on/off) and egui must not move its focus with it.
pub fn take_tab_presses(input: &mut egui::RawInput) -> usize {
    let is_tab =
        |e: &egui::Event| matches!(e, egui::Event::Key { key: egui::Key::Tab, modifiers, .. } if modifiers.is_none());
    let presses = input
        .events
        .iter()
        .filter(|e| {
            is_tab(e)
                && matches!(
                    e,
                    egui::Event::Key {
                        pressed: true,
                        repeat: false,
                        ..
                    }
                )
        })
        .count();
    input.events.retain(|e| !is_tab(e));
    presses
}

/// Keyboard shortcuts: R reset, Space auto-rotate, Tab panel (scripted keys; a real Tab is taken before egui,
/// `take_tab_presses`), F12 screenshot.
pub fn shortcuts(ctx: &egui::Context, state: &mut ViewerState) -> Vec<UiAction> {
    let mut actions = Vec::new();
    if ctx.egui_wants_keyboard_input() {
        return actions;
    }
    ctx.input(|i| {
        if i.key_pressed(egui::Key::R) {
            state.reset_view();
        }
        if i.key_pressed(egui::Key::Space) {
            state.auto_rotate = !state.auto_rotate;
        }
        if i.key_pressed(egui::Key::Tab) {
            state.panel_visible = !state.panel_visible;
        }
        if i.key_pressed(egui::Key::F12) {
            actions.push(UiAction::Screenshot);
        }
        if i.key_pressed(egui::Key::P) {
            state.time.toggle_play();
        }
        if i.key_pressed(egui::Key::Q) {
            state.quality = Some(next_lower(state.quality));
        }
        if i.key_pressed(egui::Key::S) {
            state.look.shading = match state.look.shading {
                Some(_) => None,
                None => Some(Shading::default()),
            };
        }
    });
    actions
}

/// The Q key's cycle: one level lower, from draft to converged (a custom step goes to normal).
pub fn next_lower(q: Option<Quality>) -> Quality {
    match q {
        Some(Quality::Converged) | None => Quality::Normal,
        Some(Quality::Normal) => Quality::Fast,
        Some(Quality::Fast) => Quality::Draft,
        Some(Quality::Draft) => Quality::Converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn initial_state_renders_what_render_renders() {
        let extent = Vec3::new(1.0, 1.0, 0.5);
        let state = ViewerState::new(extent, "x".into());
        let viewer = state.render_settings(320, 200);
        let mut cli = RenderSettings::new(320, 200, extent);
        assert!((viewer.camera.eye - cli.camera.eye).length() < 1e-5);
        assert!(
            viewer.camera.view().abs_diff_eq(cli.camera.view(), 1e-5),
            "same view matrix"
        );
        cli.camera = viewer.camera;
        // `render`'s default quality, resolved on the same value range.
        Quality::Normal.apply(&mut cli, state.range);
        assert_eq!(viewer, cli);
    }

    #[test]
    fn sliders_map_to_slabs_and_degenerate_values_stay_valid() {
        let mut state = ViewerState::new(Vec3::ONE, "x".into());
        state.slabs[0] = (0.25, 0.3);
        state.slabs[2] = (0.9, 0.0);
        state.look.window = [0.6, 0.6];
        let s = state.render_settings(10, 10);
        assert!((s.slab_lo.x - 0.1).abs() < 1e-6 && (s.slab_hi.x - 0.4).abs() < 1e-6);
        assert!(s.slab_hi.z > s.slab_lo.z, "zero width keeps a sliver");
        s.validate().expect("always valid");
    }

    #[test]
    fn quality_sets_the_still_step_and_draft_the_moving_one() {
        let mut state = ViewerState::new(Vec3::ONE, "x".into());
        state.full_frame_ms = Some(40.0);
        let plain = state.render_settings(401, 300);
        let mut cli = state.render_settings(401, 300);
        for q in Quality::ALL {
            state.quality = Some(q);
            Quality::apply(q, &mut cli, state.range);
            assert_eq!(
                state.frame_settings(401, 300, false).step_length,
                cli.step_length,
                "{q:?}"
            );
            let moving = state.frame_settings(401, 300, true).step_length;
            assert_eq!(moving, cli.step_length.max(2.0), "{q:?} while moving: draft's 2 voxels");
        }
        // Strong opacity shortens every level's step, the draft's while moving too (to a quarter at most).
        state.look.step_alpha = 1.0;
        state.quality = Some(Quality::Normal);
        let moving = state.frame_settings(401, 300, true).step_length;
        assert!((0.5..2.0).contains(&moving), "{moving}");
        assert!(state.frame_settings(401, 300, false).step_length < 0.4);
        // Q walks down the levels and wraps; a custom step keeps the slider's.
        assert_eq!(next_lower(Some(Quality::Normal)), Quality::Fast);
        assert_eq!(next_lower(Some(Quality::Draft)), Quality::Converged);
        assert_eq!(next_lower(None), Quality::Normal);
        state.quality = None;
        state.look.step_length = 0.7;
        assert_eq!(state.frame_settings(401, 300, false).step_length, 0.7);
        assert_eq!(plain.step_length, Quality::Normal.step_length(&plain, [0.0, 1.0]));
        // Shaded frames take the gradient texture where the viewer kept the volume for it.
        state.look.shading = Some(crate::settings::Shading::default());
        assert!(!state.render_settings(8, 8).gradient_texture);
        state.gradient_texture = true;
        assert!(state.render_settings(8, 8).gradient_texture);
        state.look.shading = None;
        assert!(
            !state.render_settings(8, 8).gradient_texture,
            "unshaded frames read no gradient"
        );
    }

    #[test]
    fn level_of_detail_while_moving() {
        let mut state = ViewerState::new(Vec3::ONE, "x".into());
        state.quality = None;
        let still = state.frame_settings(401, 300, false);
        assert_eq!((still.width, still.height, still.step_length), (401, 300, 1.0));
        state.full_frame_ms = Some(40.0);
        let moving = state.frame_settings(401, 300, true);
        assert_eq!((moving.width, moving.height, moving.step_length), (201, 150, 2.0));
        state.full_frame_ms = Some(400.0);
        assert_eq!(state.lod_divisor(), 5, "slow frames shrink more");
        state.full_frame_ms = Some(10_000.0);
        assert_eq!(state.lod_divisor(), 6);
        assert_eq!(moving.camera, still.camera);
        state.lod = false;
        assert_eq!(state.frame_settings(401, 300, true), still);
    }

    #[test]
    fn auto_rotate_and_animation_advance() {
        let mut state = ViewerState::new(Vec3::ONE, "x".into());
        assert!(!state.animate(0.1));
        state.auto_rotate = true;
        let before = state.orbit.camera().eye;
        assert!(state.animate(1.0));
        let after = state.orbit.camera().eye;
        let turned = before.truncate().angle_to(after.truncate()).to_degrees();
        assert!((turned - AUTO_ROTATE_DEG_PER_S).abs() < 0.1, "{turned}");
    }

    #[test]
    fn dropped_scivis_file_fills_dims_and_type() {
        let mut state = ViewerState::new(Vec3::ONE, "x".into());
        let action = state.load_action(PathBuf::from("/data/skull_64x32x16_int16.raw"));
        assert_eq!(state.raw_dims, [64, 32, 16]);
        assert_eq!(state.raw_type, VoxelType::I16);
        match action {
            UiAction::LoadFile(p, opts) => {
                assert_eq!(p, PathBuf::from("/data/skull_64x32x16_int16.raw"));
                assert_eq!(opts.dims, None, "the loader reads them from the name");
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn projected_box_corners_land_in_the_view() {
        let state = ViewerState::new(Vec3::ONE, "x".into());
        let s = state.render_settings(100, 100);
        let vp = s.camera.projection(1.0) * s.camera.view();
        let rect = egui::Rect::from_min_size(Pos2::ZERO, egui::vec2(100.0, 100.0));
        for c in box_corners(state.tex_to_world(), Vec3::ZERO, Vec3::ONE) {
            let p = project(vp, c, rect).expect("in front of the camera");
            assert!(rect.contains(p), "{p:?}");
        }
    }

    #[test]
    fn tab_presses_are_taken_from_egui() {
        let key = |key, pressed| egui::Event::Key {
            key,
            physical_key: None,
            pressed,
            repeat: false,
            modifiers: Default::default(),
        };
        let mut input = egui::RawInput {
            events: vec![
                key(egui::Key::Tab, true),
                key(egui::Key::Tab, false),
                key(egui::Key::R, true),
            ],
            ..Default::default()
        };
        assert_eq!(take_tab_presses(&mut input), 1);
        assert_eq!(input.events.len(), 1, "R stays for the shortcuts");
    }

    #[test]
    fn a_new_volume_resets_the_classification_unless_locked() {
        // A CT's Hounsfield-unit function left a newly loaded MRI invisible.
        let mut state = ViewerState::new(Vec3::ONE, "x".into());
        let g = Geometry::from_spacing([1.0; 3]);
        state.look.transfer_function = crate::tf::TransferFunction::preset("ct-bone").ok();
        state.look.window = [0.0, 1.0];
        state.set_volume(Vec3::ONE, g, [10, 10, 10], "mri".into());
        assert!(state.look.transfer_function.is_none());
        assert_eq!(state.look.window, crate::settings::DEFAULT_WINDOW);
        state.look.transfer_function = crate::tf::TransferFunction::preset("ct-bone").ok();
        state.tf_locked = true;
        state.set_volume(Vec3::ONE, g, [10, 10, 10], "ct".into());
        assert!(state.look.transfer_function.is_some(), "locked: kept");
    }

    #[test]
    fn an_anatomical_volume_starts_from_the_front_and_names_its_axes() {
        let mut state = ViewerState::new(Vec3::ONE, "x".into());
        let las = Geometry::anatomical(glam::DMat4::from_diagonal(glam::DVec4::new(-2.0, 2.0, 2.0, 1.0)));
        state.set_volume(Vec3::ONE, las, [10, 10, 10], "las".into());
        assert!(state.anatomical());
        let cam = state.orbit.camera();
        assert!(
            cam.eye.y > 0.0 && cam.eye.x.abs() < 1e-4 && cam.eye.z.abs() < 1e-4,
            "in front: {cam:?}"
        );
        assert_eq!(edge_labels(&cam), ['R', 'L', 'S', 'I']);
        // Mirrored storage: texture x = 0 (voxel i = 0) is on the patient's right (+x).
        assert!(state.tex_to_world().transform_point3(Vec3::ZERO).x > 0.0);
        state.look_from(ViewPreset::Left);
        assert!(state.orbit.camera().eye.x < 0.0);
        state.look.voxel_axes = true;
        assert!(!state.anatomical());
        assert!(
            state.tex_to_world().transform_point3(Vec3::ZERO).x < 0.0,
            "voxel axes: as stored"
        );
    }
}
