//! The viewer's state: everything the user can change, as plain data. [`ViewerState::render_settings`] is the one
//! place it turns into renderer parameters (unit-tested).

use crate::render::PassTimings;
use crate::scene::camera::ViewPreset;
use crate::scene::quality::{Gradients, Quality};
use crate::scene::settings::RenderSettings;
use crate::viewer::controls::{OrbitView, RotationAnimation};
use crate::viewer::slice_views::SliceViews;
use crate::viewer::time_control::TimeControl;
use crate::volume::{parse_scivis_name, Geometry, RawOptions, VoxelType};
use glam::{Mat4, Vec3};
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
    /// Value histogram of the volume ([`crate::transfer::auto::AUTO_BINS`] bins over the normalised range): the
    /// editor draws it, the automatic transfer function and the slices' window/level read it.
    pub histogram: Vec<u64>,
    pub range: [f64; 2],
    /// The transfer-function editor's own state (drag, save/load path, the volume's facts for "auto").
    pub tf_editor: crate::viewer::tf_editor::TfEditorState,
    /// Draw the colour bar over the 3D view.
    pub show_colorbar: bool,
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
    /// The three slice views (four-up layout), their crosshair and window/level.
    pub slices: SliceViews,
    /// The unit of the volume's values, for the probe and the colour bar ("HU" for CT; empty when unknown).
    pub value_unit: String,
    /// Where Ctrl+S and "Save session" write, and "Open session" reads.
    pub session_path: String,
    /// What a drag on the clipping plane's widget does, while one lasts.
    pub clip_grab: Option<crate::viewer::clip_widget::ClipGrab>,
    /// The GIF being recorded (F9 or the panel's Record), shown in the panel.
    pub recording: Option<String>,
}

/// What the panel asks the viewer to do.
#[derive(Clone, Debug)]
pub enum UiAction {
    LoadFile(PathBuf, RawOptions),
    LoadBuiltin(String),
    /// Write the session to `ViewerState::session_path`.
    SaveSession,
    /// Restore a session file (loading its volume if another is shown).
    OpenSession(PathBuf),
    Screenshot,
    /// Start recording the 3D view into a GIF, or stop and write it.
    ToggleRecording,
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
            tf_editor: Default::default(),
            show_colorbar: false,
            ortho: false,
            quality: Some(Quality::Normal),
            gradient_texture: false,
            lod: true,
            interacting: false,
            full_frame_ms: None,
            time: TimeControl::new(1, 0),
            tf_locked: false,
            slices: SliceViews::default(),
            value_unit: String::new(),
            session_path: "volcast-session.json".into(),
            clip_grab: None,
            recording: None,
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
            self.look.window = crate::scene::settings::DEFAULT_WINDOW;
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

    /// The camera the 3D view renders with.
    pub fn camera(&self) -> crate::scene::camera::Camera {
        let mut camera = self.orbit.camera();
        camera.ortho = self.ortho;
        camera
    }

    /// The render world to clip space for the 3D view `rect`: what overlays project their shapes with.
    pub fn view_projection(&self, rect: egui::Rect) -> Mat4 {
        let camera = self.camera();
        camera.projection(rect.width() / rect.height().max(1.0)) * camera.view()
    }

    /// The renderer's parameters for a `width`×`height` frame.
    pub fn render_settings(&self, width: u32, height: u32) -> RenderSettings {
        let mut s = self.look.clone();
        s.width = width.max(1);
        s.height = height.max(1);
        s.camera = self.camera();
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

    pub(super) fn raw_options(&self) -> RawOptions {
        RawOptions {
            dims: Some(self.raw_dims),
            voxel_type: Some(self.raw_type),
            spacing: Some(self.raw_spacing),
        }
    }

    /// A load of `path` with dims/type from its name when it matches, else from the panel's fields.
    pub fn load_action(&mut self, path: PathBuf) -> UiAction {
        if crate::viewer::session::is_session_file(&path) {
            return UiAction::OpenSession(path);
        }
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
pub(super) fn raw_only(path: &std::path::Path, opts: RawOptions) -> RawOptions {
    match crate::volume::detect_format(path) {
        Ok(crate::volume::Format::Raw) | Err(_) => opts,
        Ok(_) => RawOptions::default(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::edge_labels;
    use crate::viewer::ui::next_lower;

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
        state.look.shading = Some(crate::scene::settings::Shading::default());
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
    fn a_new_volume_resets_the_classification_unless_locked() {
        // A CT's Hounsfield-unit function left a newly loaded MRI invisible.
        let mut state = ViewerState::new(Vec3::ONE, "x".into());
        let g = Geometry::from_spacing([1.0; 3]);
        state.look.transfer_function = crate::transfer::function::TransferFunction::preset("ct-bone").ok();
        state.look.window = [0.0, 1.0];
        state.set_volume(Vec3::ONE, g, [10, 10, 10], "mri".into());
        assert!(state.look.transfer_function.is_none());
        assert_eq!(state.look.window, crate::scene::settings::DEFAULT_WINDOW);
        state.look.transfer_function = crate::transfer::function::TransferFunction::preset("ct-bone").ok();
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
