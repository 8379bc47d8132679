//! The running viewer: the window, the presenter, egui, the model and what the app keeps beside them. Made when
//! the window opens (the first volume shown, or loading), torn down when it closes.

use super::capture::Capture;
use super::gui::Gui;
use super::loading::{open_source, value_histogram, Arrived, Limits, Loader};
use super::pacing::{Activity, Pacing};
use super::script::Script;
use super::title;
use super::volumes::Shown;
use crate::scale::cache::PyramidCache;
use crate::viewer::model::history::Snapshot;
use crate::viewer::model::Model;
use crate::viewer::present::Presenter;
use crate::viewer::{ViewerError, ViewerOptions, VolumeSource};
use crate::volume::{Volume, VoxelData, VoxelType};
use winit::event_loop::{ActiveEventLoop, EventLoopProxy};
use winit::window::Window;

pub(super) struct Running {
    pub(super) window: Window,
    /// The GPU side; destroyed before the window (its surface is the window's).
    pub(super) presenter: Presenter,
    pub(super) gui: Gui,
    pub(super) model: Model,
    pub(super) shown: Shown,
    pub(super) loader: Loader,
    pub(super) capture: Capture,
    pub(super) script: Option<Script>,
    pub(super) pacing: Pacing,
    /// How layers added in the panel look.
    pub(super) layer_looks: crate::scene::layer_set::Looks,
}

impl Running {
    pub(super) fn new(
        event_loop: &ActiveEventLoop,
        opts: &ViewerOptions,
        layers: crate::scene::layer_set::Layers,
        waker: EventLoopProxy<()>,
    ) -> Result<Running, ViewerError> {
        let attributes = Window::default_attributes()
            .with_title("volcast")
            .with_inner_size(winit::dpi::PhysicalSize::new(opts.size.0, opts.size.1));
        let window = event_loop
            .create_window(attributes)
            .map_err(|e| ViewerError::NoDisplay(format!("creating a window: {e}")))?;
        let model = initial_model(opts);
        let presenter = Presenter::new(&window, &opts.gpu, model.display.vsync)?;
        let mut r = Running {
            gui: Gui::new(&window, presenter.max_texture_side()),
            loader: Loader::new(
                Limits {
                    budgets: presenter.budgets(opts.host_budget, opts.gpu_budget),
                    max_dim: opts.max_dim,
                    cache: (!opts.no_cache).then(|| PyramidCache::new(opts.cache_dir.clone())),
                },
                opts.restore.clone(),
                waker.clone(),
            ),
            window,
            presenter,
            model,
            shown: Shown::default(),
            capture: Capture::default(),
            script: (!opts.script.is_empty()).then(|| Script::new(&opts.script, waker)),
            pacing: Pacing::new(),
            layer_looks: opts.layer_looks.clone(),
        };
        // On error `r` is torn down properly before the error is returned.
        match r.set_layers(layers).and_then(|()| r.show_first_volume(opts)) {
            Ok(()) => Ok(r),
            Err(e) => {
                r.destroy();
                Err(e)
            }
        }
    }

    /// The volume the command line names. A file loads in the background, so the window shows its progress at
    /// once (a 1 GiB volume took 20 s with no window at all): until it is there an empty placeholder (all below
    /// the value window) stands in, and a script waits for it.
    fn show_first_volume(&mut self, opts: &ViewerOptions) -> Result<(), ViewerError> {
        if let VolumeSource::File(path, _) = &opts.source {
            // The path field names the file, so that a failed load can be corrected and loaded again.
            self.model.files.load_path = path.display().to_string();
            self.model.files.path_edited();
            let placeholder = Volume::new("loading", [2; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(vec![0; 8]))
                .map_err(|e| ViewerError::Other(e.to_string()))?;
            self.install((placeholder, Vec::new()), false)?;
            self.model.volume.label = "loading…".into();
            self.loader.channel = opts.channel;
            (self.loader).start_series(opts.source.clone(), opts.series.clone(), &mut self.model.messages);
            self.loader.initial = Some(opts.time);
            if let Some(script) = &mut self.script {
                script.waiting_for_load = true;
            }
            return Ok(());
        }
        let opened = open_source(&opts.source, self.loader.limits(), None, opts.channel, &mut |_| {})
            .map_err(ViewerError::Other)?;
        let first = match opened.keep {
            Some(keep) => keep.write(opened.volume),
            None => opened.volume,
        };
        let histogram = value_histogram(&first);
        // An array from Python is data, as a file is: it opens with the automatic transfer function.
        let data = matches!(opts.source, VolumeSource::Memory(_));
        self.install((first, histogram), data)?;
        self.shown.source = Some(opts.source.clone());
        self.window.set_title(&title::window_title(self.shown.source.as_ref()));
        self.start_at(opts.time)?;
        if let Some(session) = self.loader.pending_restore.take() {
            self.model.restore(&session);
        }
        Ok(())
    }

    /// Installs a volume that finished loading; the command line's: `--time` applies, and a failure to show it
    /// ends the session. A session waiting for it is restored.
    pub(super) fn install_arrived(&mut self, arrived: Arrived) -> Result<(), ViewerError> {
        let Arrived {
            volume,
            histogram,
            source,
            label,
            initial,
            preview,
        } = arrived;
        let from_file = matches!(source, VolumeSource::File(..) | VolumeSource::Memory(_));
        // A multiscale image (OME-Zarr) says which of its levels it shows, and why not a finer one; so does a volume
        // shown at a coarser level than its file's, and a preview.
        let level = volume
            .notes
            .iter()
            .find(|n| {
                (n.starts_with("level ") && n.contains(" of "))
                    || n.starts_with("pyramid level")
                    || n.starts_with("a preview")
            })
            .cloned();
        if preview {
            return self.install_preview(volume, histogram, &label, level);
        }
        // After a preview, the volume replaces it in the view the user has: the camera and clipping plane, and the
        // transfer function if they changed it (else the volume's own automatic one, from its full histogram).
        let after_preview = self.loader.preview_tf.is_some();
        let edited = self.loader.preview_edited(&self.model.look.colour.transfer_function);
        let before = after_preview.then(|| Snapshot::of(&self.model));
        let from_file = from_file && !edited;
        let dims = volume.dims;
        let installed = self.install((volume, histogram), from_file);
        // Logged too: a load from the panel or a drop has no other trace outside the window.
        if let Err(e) = installed {
            eprintln!("could not show {label}: {e}");
            self.model.messages.error = Some(format!("{label}: {e}"));
            return match initial {
                Some(_) => Err(e.into()),
                None => Ok(()),
            };
        }
        if let Some(mut view) = before {
            if !edited {
                let look = &self.model.look;
                (view.transfer_function, view.window, view.colormap) = (
                    look.colour.transfer_function.clone(),
                    look.colour.window,
                    look.colour.colormap,
                );
            }
            view.restore(&mut self.model);
        }
        eprintln!("loaded {label}");
        eprintln!("holds {}x{}x{} voxels", dims[0], dims[1], dims[2]);
        self.model.messages.status = Some(format!("loaded {label}"));
        if let Some(level) = level {
            eprintln!("showing {level}");
            self.model.messages.status = Some(format!("loaded {label}: {level}"));
        }
        if let VolumeSource::File(path, _) = &source {
            self.model.recent.remember(path);
        }
        self.shown.source = Some(source);
        self.window.set_title(&title::window_title(self.shown.source.as_ref()));
        if let Some(time) = initial {
            self.start_at(time)?;
        }
        if let Some(session) = self.loader.pending_restore.take() {
            self.model.restore(&session);
        }
        Ok(())
    }

    /// Shows `volume` within the loader's budgets (`Shown::install`: whole, or streamed over the GPU budget).
    fn install(&mut self, volume: (Volume, Vec<u64>), from_file: bool) -> Result<(), crate::gpu::GpuError> {
        let budgets = self.loader.limits().budgets;
        (self.shown).install(&mut self.presenter, &mut self.model, volume, from_file, &budgets)
    }

    /// Shows a strided preview while its volume is read; the load goes on, and a script waiting for it waits on.
    fn install_preview(
        &mut self,
        volume: Volume,
        histogram: Vec<u64>,
        label: &str,
        note: Option<String>,
    ) -> Result<(), ViewerError> {
        let installed = self.install((volume, histogram), true);
        if let Err(e) = installed {
            // The volume itself may still fit where its preview did not: say so and wait for it.
            eprintln!("could not show a preview of {label}: {e}");
            return Ok(());
        }
        self.loader.preview_tf = Some(self.model.look.colour.transfer_function.clone());
        let note = note.unwrap_or_default();
        eprintln!("previewing {label}: {note}");
        self.model.messages.status = Some(format!("refining {label}: {note}"));
        Ok(())
    }

    /// `--time`: the step to show first; an error where the volume has no such step.
    fn start_at(&mut self, time: Option<u32>) -> Result<(), ViewerError> {
        match time {
            Some(t) => self.model.time.start_at(t).map_err(ViewerError::Other),
            None => Ok(()),
        }
    }

    /// What keeps the viewer drawing now (see `pacing`).
    pub(super) fn activity(&self) -> Activity {
        Activity {
            loading: self.loader.busy(),
            dialog: self.loader.dialog_open(),
            camera_moving: self.model.camera_moving(),
            playing: self.model.time.playing,
            script: self.script.as_ref().is_some_and(|s| s.waiting_until().is_none()),
            refining: self.pacing.refine_pending || self.model.streaming.as_ref().is_some_and(|s| s.refining()),
            held_input: self.gui.holds_input(),
        }
    }

    pub(super) fn destroy(mut self) {
        // A recording still running is written, as if stopped.
        self.capture.stop_recording(&mut self.model.messages);
        self.presenter.destroy();
        // The window drops after the presenter: the surface was made on it.
    }
}

/// The model before the first volume: the command line's quality, layout and transfer function.
fn initial_model(opts: &ViewerOptions) -> Model {
    let mut model = Model::new(glam::Vec3::ONE, "loading…".into());
    model.sampling.quality = Some(opts.quality);
    model.slices.shown = opts.slices;
    model.recent = crate::viewer::model::recent::RecentFiles::from_env();
    if let Some(tf) = &opts.transfer_function {
        // Locked, so that loading the volume does not replace it with the automatic one.
        model.look.colour.transfer_function = Some(tf.clone());
        model.look.colour.window = [0.0, 1.0];
        model.tf_editor.locked = true;
    }
    model
}
