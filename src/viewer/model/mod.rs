//! The viewer's model: everything it shows and the user edits, as plain data, and the pure logic over it. No
//! window, no GPU and no egui context or textures: egui appears only through its value types (`Rect`, `Pos2`),
//! so every rule here is unit-tested without a display. Widgets edit a [`Model`]; the app turns it into renderer
//! parameters once a frame ([`Model::frame_settings`]).
//!
//! `Model` is `Clone`, and cheaply: its one sizeable part, the value histogram, is shared. An undo stack can keep
//! snapshots of it (or of the parts an edit touches: `look` for the transfer function and the clipping plane,
//! `camera.orbit` for the view).

pub mod actions;
pub mod chooser;
pub mod export;
pub mod files;
pub mod framing;
pub mod history;
pub mod layers;
pub mod measurements;
pub mod orbit;
pub mod recent;
pub mod session;
pub mod settings;
pub mod slices;
pub mod tf;
pub mod time;

use crate::render::PassTimings;
use crate::scene::camera::{Camera, ViewPreset};
use crate::scene::quality::{Gradients, Quality};
use crate::scene::settings::RenderSettings;
use crate::volume::{Geometry, Volume};
use files::FileFields;
use glam::{Mat4, Vec3};
use history::History;
use orbit::{OrbitView, RotationAnimation};
use slices::SliceViews;
use std::sync::Arc;
use tf::TfEditorState;
use time::TimeControl;

/// Everything the user can change, and what the panel shows.
#[derive(Clone, Debug)]
pub struct Model {
    /// Transfer function, value window, mode, shading, light, clipping plane, ray setup...: a RenderSettings whose
    /// camera, size and slabs are filled per frame.
    pub look: RenderSettings,
    /// Slab (position, width) per axis, as the sliders show them.
    pub slabs: [(f32, f32); 3],
    pub camera: OrbitCamera,
    /// Where the volume's voxels are (its affine, and whether it is anatomical).
    pub geometry: Geometry,
    /// The volume's grid.
    pub dims: [u32; 3],
    pub volume: VolumeInfo,
    pub sampling: Sampling,
    /// The transfer-function editor's own state (drag, save/load path, the volume's facts for "auto", the lock).
    pub tf_editor: TfEditorState,
    /// The three slice views (four-up layout), their crosshair and window/level.
    pub slices: SliceViews,
    /// The layers shown with the volume (their looks; the app holds their voxels).
    pub layers: layers::LayerList,
    /// A series' step slider and playback.
    pub time: TimeControl,
    pub display: Display,
    pub files: FileFields,
    /// The files opened last (the panel's Recent menu).
    pub recent: recent::RecentFiles,
    pub messages: Messages,
    pub stats: FrameStats,
    /// The shown volume is streamed through a pool of bricks (it is over the GPU budget whole).
    pub streaming: Option<Streaming>,
    pub interaction: Interaction,
    /// The "Export figure" section's fields.
    pub export: export::FigureExport,
    /// Undo and redo of transfer-function, clipping-plane and camera edits.
    pub history: History,
}

/// The 3D view's camera and its motion.
#[derive(Clone, Copy, Debug)]
pub struct OrbitCamera {
    pub orbit: OrbitView,
    pub ortho: bool,
    /// A fly-to (gizmo click, "look along") in progress.
    pub animation: Option<RotationAnimation>,
    pub auto_rotate: bool,
}

/// What the shown volume is, beyond its box: its description and its values.
#[derive(Clone, Debug)]
pub struct VolumeInfo {
    /// "name — dims type, spacing", or "loading…".
    pub label: String,
    /// Box side lengths of the volume on screen.
    pub extent: Vec3,
    /// Value histogram ([`crate::transfer::auto::AUTO_BINS`] bins over the normalised range): the editor draws it,
    /// the automatic transfer function and the slices' window/level read it.
    pub histogram: Arc<[u64]>,
    /// The data range the normalised values span.
    pub range: [f64; 2],
    /// The unit of the values, for the probe and the colour bar ("HU" for CT; empty when unknown).
    pub unit: String,
    /// The series of the DICOM folder shown, if it holds several (the panel's chooser); empty otherwise.
    pub series: Vec<crate::volume::SeriesInfo>,
}

/// How finely frames are sampled.
#[derive(Clone, Copy, Debug)]
pub struct Sampling {
    /// Sampling quality of still frames, as `render --quality` (the step resolved per frame from the transfer
    /// function); `None`: the step slider's step.
    pub quality: Option<Quality>,
    /// Interactive level of detail: while the view moves, lower resolution and the draft quality's step (with a
    /// custom step, double it), then a full frame.
    pub lod: bool,
    /// Shaded frames may take the volume's gradient texture (`render --gradients auto`): the viewer kept the
    /// volume to make it. Not for series, whose steps would each need one.
    pub gradient_texture: bool,
}

/// What is drawn besides the volume, and how the window presents.
#[derive(Clone, Copy, Debug)]
pub struct Display {
    pub panel_visible: bool,
    pub show_boxes: bool,
    /// Draw the colour bar over the 3D view.
    pub show_colorbar: bool,
    pub vsync: bool,
    /// The list of keyboard and mouse shortcuts over the window (F1 or ?).
    pub show_shortcuts: bool,
}

/// What the panel tells the user.
#[derive(Clone, Debug, Default)]
pub struct Messages {
    /// Last error (a load, a screenshot...), shown until the next load.
    pub error: Option<String>,
    pub status: Option<String>,
    /// A background load: what, and how far (0 to 1).
    pub loading: Option<(String, f32)>,
    /// The GIF being recorded (F9 or the panel's Record).
    pub recording: Option<String>,
    /// What `error` and `status` are about: the panel shows them beside the controls of that action.
    pub about: Topic,
}

/// Which action's controls a message shows beside.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Topic {
    /// Loads (the Volume section, under *Load volume*).
    #[default]
    Volume,
    /// Saving and opening sessions (the Session section).
    Session,
    /// Screenshots and recordings (the View section, under their buttons).
    Capture,
    /// The ruler's measurements (the Slicing section, under their buttons).
    Measurements,
    /// Adding and removing layers (the Layers section).
    Layers,
}

/// A volume streamed through a pool: its slots, and how far the view has refined towards the level each brick
/// wants.
#[derive(Clone, Debug, Default)]
pub struct Streaming {
    pub capacity: usize,
    pub progress: Option<crate::render::placement::Progress>,
}

impl Streaming {
    /// Still refining: some brick the view wants is not resident yet.
    pub fn refining(&self) -> bool {
        self.progress.as_ref().is_none_or(|p| !p.done)
    }
}

/// What the last frames measured.
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameStats {
    pub frame_ms: f64,
    pub gpu: Option<PassTimings>,
    /// GPU time of the last full-quality frame, for choosing the level of detail.
    pub full_frame_ms: Option<f64>,
    /// Frames presented since the start, and how many of them marched the view (the rest showed it unchanged).
    pub drawn: u64,
    pub marched: u64,
}

/// What the pointer is doing in the 3D view, as the last UI pass saw it.
#[derive(Clone, Copy, Debug, Default)]
pub struct Interaction {
    /// Where the volume view is in the window (points).
    pub view_rect: Option<egui::Rect>,
    /// The user moved the view in this UI pass (drag or wheel).
    pub interacting: bool,
    /// What a drag on the clipping plane's widget does, while one lasts.
    pub clip_grab: Option<ClipGrab>,
}

/// What a drag that started on the clipping plane's widget does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClipGrab {
    Slide,
    Turn,
}

/// Degrees per second of auto-rotation.
pub const AUTO_ROTATE_DEG_PER_S: f32 = 30.0;

impl Model {
    pub fn new(extent: Vec3, volume_label: String) -> Model {
        let look = RenderSettings::new(1, 1, extent);
        Model {
            camera: OrbitCamera {
                orbit: OrbitView::from_camera(&look.camera),
                ortho: false,
                animation: None,
                auto_rotate: false,
            },
            look,
            slabs: [(0.5, 1.0); 3],
            geometry: Geometry::from_spacing([1.0; 3]),
            dims: [1; 3],
            volume: VolumeInfo {
                label: volume_label,
                extent,
                histogram: Arc::from([]),
                range: [0.0, 1.0],
                unit: String::new(),
                series: Vec::new(),
            },
            sampling: Sampling {
                quality: Some(Quality::Normal),
                lod: true,
                gradient_texture: false,
            },
            tf_editor: TfEditorState::default(),
            slices: SliceViews::default(),
            layers: layers::LayerList::default(),
            time: TimeControl::new(1, 0),
            display: Display {
                panel_visible: true,
                show_boxes: true,
                show_colorbar: false,
                vsync: true,
                show_shortcuts: false,
            },
            files: FileFields::default(),
            recent: recent::RecentFiles::default(),
            messages: Messages::default(),
            stats: FrameStats::default(),
            streaming: None,
            interaction: Interaction::default(),
            export: Default::default(),
            history: History::default(),
        }
    }

    /// Whether the view is of patient space (an anatomical volume, not shown in voxel axes).
    pub fn anatomical(&self) -> bool {
        self.geometry.anatomical && !self.look.voxel_axes
    }

    /// The default view: what `volcast render` shows without camera options (an anatomical volume from the
    /// front, head up).
    pub fn reset_view(&mut self) {
        let defaults = RenderSettings::new(1, 1, self.volume.extent);
        let camera = if self.anatomical() {
            ViewPreset::Anterior.camera(defaults.camera.eye.length(), Vec3::ZERO)
        } else {
            defaults.camera
        };
        self.camera.orbit = OrbitView::from_camera(&camera);
        self.camera.animation = None;
    }

    /// Turns the view to look from `preset`'s side, at the same distance.
    pub fn look_from(&mut self, preset: ViewPreset) {
        let now = self.camera.orbit.camera();
        let distance = now.eye.distance(now.target);
        self.camera.orbit = OrbitView::from_camera(&preset.camera(distance, now.target));
        self.camera.animation = None;
    }

    /// A new volume: its box, placement and a default view; the classification (transfer function and value
    /// window) resets to the simple model unless locked; slicing stays.
    pub fn set_volume(&mut self, extent: Vec3, geometry: Geometry, dims: [u32; 3], label: String) {
        if !self.tf_editor.locked {
            self.look.colour.transfer_function = None;
            self.look.colour.window = crate::scene::settings::DEFAULT_WINDOW;
        }
        self.volume.extent = extent;
        self.geometry = geometry;
        self.dims = dims;
        self.volume.label = label;
        self.reset_view();
    }

    /// `v` is shown: its box, placement and description, its values (`histogram` over the normalised range, the
    /// unit), the slices centred on it, the transfer-function editor's facts, the time controls for its steps. A
    /// file's volume gets the transfer function its modality calls for (CT in HU, others by percentiles) unless
    /// the user locked theirs; the built-ins (synthetic, no modality) keep the simple model.
    pub fn show_volume(&mut self, v: &Volume, histogram: Arc<[u64]>, from_file: bool) {
        let spacing = v.spacing();
        let [sx, sy, sz] = v.geometry.spacing().map(crate::volume::geometry::shortest);
        let label = format!(
            "{} — {}×{}×{} {}, spacing {sx}×{sy}×{sz}",
            v.name, v.dims[0], v.dims[1], v.dims[2], v.source_type
        );
        self.set_volume(v.extent(), v.geometry, v.dims, label);
        self.files.describe_raw(v.dims, v.source_type, spacing);
        self.slices.reset(v.dims, &histogram, v.range);
        self.volume.histogram = histogram.clone();
        self.volume.range = v.range;
        self.volume.series = v.series.clone();
        self.tf_editor.set_volume(v, histogram);
        self.volume.unit = self.tf_editor.unit().unwrap_or_default().to_string();
        if !self.tf_editor.locked && from_file {
            if let Some(tf) = self.tf_editor.auto() {
                self.look.colour.transfer_function = Some(tf);
                self.look.colour.window = [0.0, 1.0];
            }
        }
        self.time = TimeControl::new(v.timesteps(), v.shown_step());
        // The gradient texture is made from the kept volume: not for a series, whose steps would each need one.
        self.sampling.gradient_texture = v.timesteps() == 1 && Gradients::texture_fits(v.voxel_count() as u64);
    }

    /// Texture space to the render world for what the view shows.
    pub fn tex_to_world(&self) -> Mat4 {
        self.geometry.tex_to_world(self.dims, self.look.voxel_axes).as_mat4()
    }

    /// The camera the 3D view renders with.
    pub fn view_camera(&self, width: f32, height: f32) -> Camera {
        let mut orbit = self.camera.orbit;
        orbit.distance *= self.fit_factor(width, height);
        let mut camera = orbit.camera();
        camera.ortho = self.camera.ortho;
        camera
    }

    /// How much farther the camera stands in a `width`×`height` view than the orbit says
    /// ([`framing::fit_factor`]): the 3D view's (its shape in points, with the gizmo), or an image of another
    /// shape (an exported figure: no gizmo).
    pub fn fit_factor(&self, width: f32, height: f32) -> f32 {
        let fov = self.camera.orbit.fov_y_deg;
        let aspect = width / height.max(1.0);
        match self.interaction.view_rect {
            Some(r) if (r.width() / r.height().max(1.0) - aspect).abs() < 0.02 => {
                framing::fit_factor(r.width(), r.height(), true, fov, self.camera.ortho)
            }
            Some(_) => framing::fit_factor(width, height, false, fov, self.camera.ortho),
            None => framing::fit_factor(width, height, true, fov, self.camera.ortho),
        }
    }

    /// The render world to clip space for the 3D view `rect`: what overlays project their shapes with.
    pub fn view_projection(&self, rect: egui::Rect) -> Mat4 {
        let camera = self.view_camera(rect.width(), rect.height());
        camera.projection(rect.width() / rect.height().max(1.0)) * camera.view()
    }

    /// Advances animations by `dt` seconds; true while something is still moving.
    pub fn animate(&mut self, dt: f32) -> bool {
        let camera = &mut self.camera;
        let mut moving = false;
        if let Some(anim) = &mut camera.animation {
            let (q, done) = anim.step(dt);
            camera.orbit.rotation = q;
            if done {
                camera.animation = None;
            }
            moving = true;
        }
        if camera.auto_rotate && camera.animation.is_none() {
            camera.orbit.turn(AUTO_ROTATE_DEG_PER_S.to_radians() * dt);
            moving = true;
        }
        moving
    }

    /// Whether the view is moving by itself (a fly-to or auto-rotation).
    pub fn camera_moving(&self) -> bool {
        self.camera.animation.is_some() || self.camera.auto_rotate
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::edge_labels;

    #[test]
    fn auto_rotate_and_animation_advance() {
        let mut model = Model::new(Vec3::ONE, "x".into());
        assert!(!model.animate(0.1));
        model.camera.auto_rotate = true;
        let before = model.camera.orbit.camera().eye;
        assert!(model.animate(1.0));
        let after = model.camera.orbit.camera().eye;
        let turned = before.truncate().angle_to(after.truncate()).to_degrees();
        assert!((turned - AUTO_ROTATE_DEG_PER_S).abs() < 0.1, "{turned}");
    }

    #[test]
    fn a_new_volume_resets_the_classification_unless_locked() {
        // A CT's Hounsfield-unit function left a newly loaded MRI invisible.
        let mut model = Model::new(Vec3::ONE, "x".into());
        let g = Geometry::from_spacing([1.0; 3]);
        model.look.colour.transfer_function = crate::transfer::function::TransferFunction::preset("ct-bone").ok();
        model.look.colour.window = [0.0, 1.0];
        model.set_volume(Vec3::ONE, g, [10, 10, 10], "mri".into());
        assert!(model.look.colour.transfer_function.is_none());
        assert_eq!(model.look.colour.window, crate::scene::settings::DEFAULT_WINDOW);
        model.look.colour.transfer_function = crate::transfer::function::TransferFunction::preset("ct-bone").ok();
        model.tf_editor.locked = true;
        model.set_volume(Vec3::ONE, g, [10, 10, 10], "ct".into());
        assert!(model.look.colour.transfer_function.is_some(), "locked: kept");
    }

    #[test]
    fn an_anatomical_volume_starts_from_the_front_and_names_its_axes() {
        let mut model = Model::new(Vec3::ONE, "x".into());
        let las = Geometry::anatomical(glam::DMat4::from_diagonal(glam::DVec4::new(-2.0, 2.0, 2.0, 1.0)));
        model.set_volume(Vec3::ONE, las, [10, 10, 10], "las".into());
        assert!(model.anatomical());
        let cam = model.camera.orbit.camera();
        assert!(
            cam.eye.y > 0.0 && cam.eye.x.abs() < 1e-4 && cam.eye.z.abs() < 1e-4,
            "in front: {cam:?}"
        );
        assert_eq!(edge_labels(&cam), ['R', 'L', 'S', 'I']);
        // Mirrored storage: texture x = 0 (voxel i = 0) is on the patient's right (+x).
        assert!(model.tex_to_world().transform_point3(Vec3::ZERO).x > 0.0);
        model.look_from(ViewPreset::Left);
        assert!(model.camera.orbit.camera().eye.x < 0.0);
        model.look.voxel_axes = true;
        assert!(!model.anatomical());
        assert!(
            model.tex_to_world().transform_point3(Vec3::ZERO).x < 0.0,
            "voxel axes: as stored"
        );
    }

    #[test]
    fn a_shown_volume_resets_what_depends_on_it() {
        let mut model = Model::new(Vec3::ONE, "x".into());
        let v = crate::volume::builtin("helix", Some(16)).unwrap();
        let histogram: Arc<[u64]> = vec![1; 1024].into();
        model.show_volume(&v, histogram.clone(), false);
        assert_eq!(model.dims, v.dims);
        assert!(model.volume.label.starts_with(&v.name), "{}", model.volume.label);
        assert!(Arc::ptr_eq(&model.volume.histogram, &histogram));
        assert_eq!((model.time.steps, model.slices.generation), (1, 1));
        assert!(
            model.look.colour.transfer_function.is_none(),
            "a built-in keeps the simple model"
        );
        model.show_volume(&v, histogram, true);
        assert!(
            model.look.colour.transfer_function.is_some(),
            "a file's volume gets the automatic function"
        );
        assert_eq!(
            model.files.raw_dims, v.dims,
            "a raw reload starts from the shown volume"
        );
    }

    #[test]
    fn a_model_is_a_cheap_snapshot() {
        // An undo stack keeps clones: the histogram is shared, not copied.
        let mut model = Model::new(Vec3::ONE, "x".into());
        model.volume.histogram = vec![1; 1024].into();
        let snapshot = model.clone();
        assert!(Arc::ptr_eq(&snapshot.volume.histogram, &model.volume.histogram));
    }
}
