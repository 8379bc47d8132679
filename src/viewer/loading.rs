//! Loading volumes: a file or built-in read on a background thread (with progress) while the window keeps
//! drawing, then installed on the GPU; a series' steps uploaded as the time controls ask, one ahead while playing.

use super::model::time::TimeControl;
use super::{Running, ViewerError, VolumeSource};
use crate::gpu::GpuError;
use crate::gpu::VkContext;
use crate::volume::{self, Volume};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::sync::Arc;

pub(super) struct Loading {
    pub(super) label: String,
    /// What is loading (recorded for the view state once shown).
    pub(super) source: VolumeSource,
    pub(super) progress: Arc<AtomicU32>,
    pub(super) rx: Receiver<Result<(Volume, Vec<u64>), String>>,
}

/// The viewer's histogram of normalised values, over every step of a series (as its range is): the automatic
/// transfer function's bins, so that the viewer opens a file with the function `render --preset auto` gives.
pub(super) fn value_histogram(v: &Volume) -> Vec<u64> {
    crate::transfer::auto::value_histogram(v, crate::transfer::auto::AUTO_BINS)
}

/// Loads any format `volume::open` reads (raw with the given options); a volume larger than `max_dim` (the
/// device's 3D texture limit) is downsampled with a warning rather than refused.
pub(super) fn open_source(
    source: &VolumeSource,
    max_dim: u32,
    progress: &mut dyn FnMut(f32),
) -> Result<Volume, String> {
    match source {
        VolumeSource::Builtin(name, size) => volume::builtin(name, *size).map_err(|e| e.to_string()),
        VolumeSource::File(path, raw) => {
            let opts = volume::OpenOptions {
                raw: raw.clone(),
                max_dim: Some(max_dim),
                ..Default::default()
            };
            volume::open_with_progress(path, &opts, progress).map_err(|e| e.to_string())
        }
    }
}

pub(super) fn load_in_background(source: VolumeSource, max_dim: u32) -> Loading {
    let label = match &source {
        VolumeSource::Builtin(name, _) => name.clone(),
        VolumeSource::File(path, _) => path.display().to_string(),
    };
    let progress = Arc::new(AtomicU32::new(0));
    let (tx, rx) = std::sync::mpsc::channel();
    let p = progress.clone();
    let recorded = source.clone();
    std::thread::spawn(move || {
        // Reading is 90% of the bar, the histogram the rest.
        let result = open_source(&source, max_dim, &mut |f| {
            p.store((0.9 * f).to_bits(), Ordering::Relaxed)
        });
        p.store(0.9f32.to_bits(), Ordering::Relaxed);
        let analysed: Result<(Volume, Vec<u64>), String> = result.map(|v| {
            let h = value_histogram(&v);
            (v, h)
        });
        p.store(1.0f32.to_bits(), Ordering::Relaxed);
        let _ = tx.send(analysed);
    });
    Loading {
        label,
        source: recorded,
        progress,
        rx,
    }
}

impl Running {
    /// `--time`: the step to show first; an error where the volume has no such step.
    pub(super) fn apply_time(&mut self, time: Option<u32>) -> Result<(), ViewerError> {
        if let Some(t) = time {
            let steps = self.state.time.steps;
            if t >= steps {
                return Err(ViewerError::Other(format!(
                    "time step {t} does not exist: the volume has {steps} (0 to {})",
                    steps - 1
                )));
            }
            self.state.time.wanted = t;
        }
        Ok(())
    }

    pub(super) fn install_volume(&mut self, v: Volume, histogram: Vec<u64>, from_file: bool) -> Result<(), GpuError> {
        // SAFETY: plain wait on a live device; set_volume rewrites descriptors that in-flight frames use.
        unsafe { self.gpu.device.device_wait_idle() }.ctx("vkDeviceWaitIdle")?;
        if let Some((_, old)) = self.ahead.take() {
            old.destroy(&self.gpu);
        }
        let renderer = self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))?;
        renderer.set_volume(&self.gpu, &v)?;
        let spacing = v.spacing();
        let label = format!(
            "{} — {}×{}×{} {}, spacing {}×{}×{}",
            v.name, v.dims[0], v.dims[1], v.dims[2], v.source_type, spacing[0], spacing[1], spacing[2]
        );
        self.state.set_volume(v.extent(), v.geometry, v.dims, label);
        self.state.files.describe_raw(v.dims, v.source_type, spacing);
        self.state.slices.reset(v.dims, &histogram, v.range);
        let histogram: std::sync::Arc<[u64]> = histogram.into();
        self.state.volume.histogram = histogram.clone();
        self.state.volume.range = v.range;
        self.state.tf_editor.set_volume(&v, histogram);
        self.state.volume.unit = self.state.tf_editor.unit().unwrap_or_default().to_string();
        // A file's volume gets the transfer function its modality calls for (CT in HU, others by percentiles)
        // unless the user locked theirs; the built-ins (synthetic, no modality) keep the simple model.
        if !self.state.tf_editor.locked && from_file {
            if let Some(tf) = self.state.tf_editor.auto() {
                self.state.look.transfer_function = Some(tf);
                self.state.look.window = [0.0, 1.0];
            }
        }
        self.state.time = TimeControl::new(v.timesteps(), v.shown_step());
        let keep = v.timesteps() == 1 && crate::scene::quality::Gradients::texture_fits(v.voxel_count() as u64);
        self.state.sampling.gradient_texture = keep;
        (self.series, self.kept) = if v.timesteps() > 1 {
            (Some(v), None)
        } else {
            // Kept whatever its size: the slice views resample it (and the gradient texture is made from it).
            (None, Some(v))
        };
        self.has_volume = true;
        Ok(())
    }

    /// Uploads the step the time controls ask for, if it is not the one on the GPU.
    pub(super) fn show_wanted_step(&mut self) -> Result<(), GpuError> {
        let wanted = self.state.time.wanted;
        let Some(series) = self.series.as_mut().filter(|s| s.shown_step() != wanted) else {
            return Ok(());
        };
        if series.show_step(wanted).is_err() {
            return Ok(());
        }
        self.state.slices.generation += 1;
        // SAFETY: plain wait on a live device; the volume replaced is one that in-flight frames use.
        unsafe { self.gpu.device.device_wait_idle() }.ctx("vkDeviceWaitIdle")?;
        let renderer = self.renderer.as_mut().ok_or(GpuError::Lost("renderer"))?;
        match self.ahead.take() {
            // Uploaded ahead: showing it is a descriptor update.
            Some((step, prepared)) if step == wanted => {
                renderer.install_volume(&self.gpu, prepared);
                Ok(())
            }
            other => {
                if let Some((_, stale)) = other {
                    stale.destroy(&self.gpu);
                }
                renderer.set_volume(&self.gpu, series)
            }
        }
    }

    /// While a series plays, uploads the step after the shown one, so that when its time comes it is shown without
    /// waiting for an upload. Called after a frame is submitted: the volume's conversion and brick grid are made on
    /// the CPU while the device renders that frame (on a GPU in parallel; on lavapipe the two share the cores).
    pub(super) fn upload_ahead(&mut self) -> Result<(), GpuError> {
        let time = &self.state.time;
        let Some(series) = self.series.as_mut().filter(|_| time.playing && time.steps > 1) else {
            return Ok(());
        };
        let next = (time.wanted + 1) % time.steps;
        if self.ahead.as_ref().is_some_and(|(step, _)| *step == next) {
            return Ok(());
        }
        if let Some((_, stale)) = self.ahead.take() {
            stale.destroy(&self.gpu);
        }
        let shown = series.shown_step();
        if series.show_step(next).is_err() {
            return Ok(());
        }
        let renderer = self.renderer.as_ref().ok_or(GpuError::Lost("renderer"))?;
        let prepared = renderer.prepare_volume(&self.gpu, series);
        // Moving the step's voxels back costs nothing: show_step swaps vectors.
        let _ = series.show_step(shown);
        // A step that cannot be uploaded now (memory for two volumes) is uploaded when it is due instead, where
        // a failure is reported.
        self.ahead = prepared.ok().map(|p| (next, p));
        Ok(())
    }

    pub(super) fn start_load(&mut self, source: VolumeSource) {
        if self.loading.is_some() {
            self.state.messages.status = Some("a volume is already loading".into());
            return;
        }
        self.state.messages.error = None;
        self.loading = Some(load_in_background(
            source,
            self.gpu.properties.limits.max_image_dimension3_d,
        ));
    }

    /// Takes a finished background load, keeping the old volume on error.
    pub(super) fn poll_loading(&mut self) -> Result<(), ViewerError> {
        let Some(loading) = &self.loading else { return Ok(()) };
        match loading.rx.try_recv() {
            Ok(Ok((volume, histogram))) => {
                let label = loading.label.clone();
                let source = loading.source.clone();
                self.loading = None;
                self.state.messages.loading = None;
                // Logged too: a load from the panel or a drop has no other trace outside the window.
                let from_file = matches!(source, VolumeSource::File(..));
                if let Err(e) = self.install_volume(volume, histogram, from_file) {
                    eprintln!("could not show {label}: {e}");
                    self.state.messages.error = Some(format!("{label}: {e}"));
                    if self.initial_load.take().is_some() {
                        return Err(e.into());
                    }
                } else {
                    eprintln!("loaded {label}");
                    self.state.messages.status = Some(format!("loaded {label}"));
                    self.shown_source = Some(source);
                    if let Some(time) = self.initial_load.take() {
                        self.apply_time(time)?;
                    }
                    if let Some(session) = self.pending_restore.take() {
                        self.state.restore(&session);
                    }
                }
            }
            Ok(Err(e)) => {
                self.pending_restore = None;
                if self.initial_load.take().is_some() {
                    // The command line's volume: nothing else to show, so the session ends with its error.
                    return Err(ViewerError::Other(e));
                }
                eprintln!("could not load {}: {e}", loading.label);
                self.state.messages.error = Some(format!("{}: {e}", loading.label));
                self.loading = None;
                self.state.messages.loading = None;
            }
            Err(TryRecvError::Empty) => {
                let p = f32::from_bits(loading.progress.load(Ordering::Relaxed));
                self.state.messages.loading = Some((loading.label.clone(), p));
            }
            Err(TryRecvError::Disconnected) => {
                self.state.messages.error = Some(format!("{}: the loader stopped unexpectedly", loading.label));
                self.loading = None;
                self.state.messages.loading = None;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewer::model::tf::TfEditorState;

    #[test]
    fn the_viewer_opens_with_the_automatic_function_render_gives() {
        // Percentile ramps (volumes without CT units) depend on the histogram's bins: the viewer's must be
        // the one `render --preset auto` takes, or the two open the same file differently.
        for &name in crate::volume::BUILTIN_NAMES {
            let v = crate::volume::builtin(name, Some(48)).unwrap();
            let mut editor = TfEditorState::default();
            editor.set_volume(&v, value_histogram(&v).into());
            assert_eq!(
                editor.auto(),
                Some(crate::transfer::auto::auto_for_volume(&v)),
                "{name}"
            );
        }
    }
}
