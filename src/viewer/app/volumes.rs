//! The volumes the app keeps on the CPU and shows on the GPU: installing one (in the presenter and the model),
//! showing the step of a series the time controls ask for, and uploading the next one ahead while it plays.

use crate::gpu::GpuError;
use crate::pyramid::budget::Budgets;
use crate::render::placement::Placed;
use crate::viewer::model::{Model, Streaming};
use crate::viewer::present::Presenter;
use crate::viewer::VolumeSource;
use crate::volume::Volume;

/// The shown volume on the CPU, and where it came from.
#[derive(Default)]
pub(super) struct Shown {
    /// A time series' every step, kept to upload the one the time controls ask for; `None` for a 3-D volume.
    series: Option<Volume>,
    /// A 3-D volume, kept whatever its size: the slice views resample it, and the gradient texture is made from
    /// it on the first frame that reads gradients. `None` for a series.
    kept: Option<Volume>,
    /// Where the shown volume came from (for sessions and screenshots' view states).
    pub(super) source: Option<VolumeSource>,
    /// The layers shown with it (their voxels; the model holds their looks).
    pub(super) layers: crate::scene::layer_set::Layers,
}

impl Shown {
    /// What the slice views resample: the shown step of a series, or the kept volume.
    pub(super) fn for_slices(&self) -> Option<&Volume> {
        self.series.as_ref().or(self.kept.as_ref())
    }

    /// The 3-D volume kept for its gradient texture.
    pub(super) fn kept(&self) -> Option<&Volume> {
        self.kept.as_ref()
    }

    /// The shown step of a series; `None` for a 3-D volume.
    pub(super) fn series_step(&self) -> Option<u32> {
        self.series.as_ref().map(Volume::shown_step)
    }

    /// Shows `v` in place of the volume shown: on the GPU (whole, or streamed where one step is over `budgets`'
    /// GPU budget whole; a GPU budget without room for one brick shows the finest whole level that fits it), in the
    /// model (resetting what depends on the volume), and kept here.
    pub(super) fn install(
        &mut self,
        presenter: &mut Presenter,
        model: &mut Model,
        (mut v, histogram): (Volume, Vec<u64>),
        from_file: bool,
        budgets: &Budgets,
    ) -> Result<(), GpuError> {
        let placed = match presenter.set_volume(&v, budgets) {
            Err(GpuError::NoRoom(why)) => {
                eprintln!(
                    "note: {}: no brick fits the GPU budget's pool ({why}); shown whole",
                    v.name
                );
                v = crate::scale::fit(v, budgets, false).map_err(|e| GpuError::TooLarge(e.to_string()))?;
                presenter.set_volume(&v, budgets)?
            }
            placed => placed?,
        };
        model.show_volume(&v, histogram.into(), from_file);
        model.streaming = match placed {
            Placed::Whole => None,
            Placed::Streamed { capacity } => {
                eprintln!(
                    "note: {} {}; streamed through a pool of {capacity} bricks",
                    v.name,
                    crate::render::placement::streamed_because(&v, budgets.gpu.map_or(0, |g| g.bytes))
                );
                // Central differences: a gradient texture of the pool (8 bytes a texel) would be made again
                // after every step that uploads.
                model.sampling.gradient_texture = false;
                Some(Streaming {
                    capacity,
                    progress: None,
                })
            }
        };
        (self.series, self.kept) = if v.timesteps() > 1 {
            (Some(v), None)
        } else {
            (None, Some(v))
        };
        Ok(())
    }

    /// Uploads the step the time controls ask for, if it is not the one on the GPU.
    pub(super) fn show_wanted_step(&mut self, presenter: &mut Presenter, model: &mut Model) -> Result<(), GpuError> {
        let wanted = model.time.wanted;
        let Some(series) = self.series.as_mut().filter(|s| s.shown_step() != wanted) else {
            return Ok(());
        };
        if series.show_step(wanted).is_err() {
            return Ok(());
        }
        model.slices.generation += 1;
        presenter.show_step(series, wanted)
    }

    /// While a series plays, uploads the step after the shown one, so that when its time comes it is shown without
    /// waiting for an upload. Called after a frame is submitted: the volume's conversion and brick grid are made on
    /// the CPU while the device renders that frame (on a GPU in parallel; on lavapipe the two share the cores).
    pub(super) fn upload_ahead(&mut self, presenter: &mut Presenter, model: &Model) -> Result<(), GpuError> {
        let time = &model.time;
        let Some(series) = self.series.as_mut().filter(|_| time.playing && time.steps > 1) else {
            return Ok(());
        };
        let next = (time.wanted + 1) % time.steps;
        if presenter.holds_ahead(next) {
            return Ok(());
        }
        presenter.drop_ahead();
        let shown = series.shown_step();
        if series.show_step(next).is_err() {
            return Ok(());
        }
        let uploaded = presenter.upload_ahead(next, series);
        // Moving the step's voxels back costs nothing: show_step swaps vectors.
        let _ = series.show_step(shown);
        uploaded
    }
}
