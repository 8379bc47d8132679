//! Loading volumes: a file or built-in read on a background thread (with progress) while the window keeps
//! drawing, and the platform's file dialog on a thread of its own. What arrives is installed by the app
//! (`volumes`).

use crate::formats;
use crate::scene::view_state::ViewState;
use crate::viewer::model::chooser::FileChooser;
use crate::viewer::model::{Messages, Model, Topic};
use crate::viewer::VolumeSource;
use crate::volume::{self, Volume};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::event_loop::EventLoopProxy;

/// No file from the desktop's dialog this soon after *Open…*: no dialog was shown (rfd found no xdg-desktop-portal
/// and no zenity, as under Xvfb, and says so only in its log), so the viewer's own chooser opens instead. A person
/// who cancels a real dialog this fast gets the chooser too, and can cancel it as well.
const NO_DIALOG_WITHIN: Duration = Duration::from_millis(1000);

/// A load under way.
struct Loading {
    label: String,
    /// What is loading (recorded for the view state once shown).
    source: VolumeSource,
    progress: Arc<AtomicU32>,
    rx: Receiver<Delivery>,
}

/// What the loading thread sends: for a large file read in place, first a strided preview, then the volume.
enum Delivery {
    Preview(Volume, Vec<u64>),
    Done(Result<(Volume, Vec<u64>), String>),
}

/// A volume that finished loading.
pub(super) struct Arrived {
    pub(super) volume: Volume,
    pub(super) histogram: Vec<u64>,
    pub(super) source: VolumeSource,
    pub(super) label: String,
    /// It is the command line's volume: `Some(--time)`.
    pub(super) initial: Option<Option<u32>>,
    /// A strided preview shown while the volume itself is read (its load goes on).
    pub(super) preview: bool,
}

/// Loads in the background, one at a time, and what waits for them.
pub(super) struct Loader {
    loading: Option<Loading>,
    /// The volume named on the command line is loading: `--time` applies once it is there (if it fails, the
    /// window stays open on an empty scene, showing the error).
    pub(super) initial: Option<Option<u32>>,
    /// A session to restore once its volume is shown.
    pub(super) pending_restore: Option<ViewState>,
    /// An open file dialog's answer (None inside: cancelled, or no dialog available, e.g. no desktop portal).
    dialog: Option<Receiver<Option<PathBuf>>>,
    /// When the dialog was asked for: an answer of no file sooner than [`NO_DIALOG_WITHIN`] means none was shown.
    dialog_asked: Instant,
    /// The budgets and `--max-dim`: a larger volume is shown at a coarser pyramid level.
    limits: Limits,
    /// The channel of an OME-Zarr image to load (`--channel`; `None`: channel 0).
    pub(super) channel: Option<u32>,
    /// The load under way showed a preview: the transfer function it opened with (the volume replacing it keeps
    /// one the user set since). Forgotten when a load starts or fails.
    pub(super) preview_tf: Option<Option<crate::transfer::function::TransferFunction>>,
    /// Wakes the event loop when the loading thread delivers (frames are paced while a load is under way).
    waker: EventLoopProxy<()>,
}

/// The viewer's histogram of normalised values, over every step of a series (as its range is): the automatic
/// transfer function's bins, so that the viewer opens a file with the function `render --preset auto` gives.
pub(super) fn value_histogram(v: &Volume) -> Vec<u64> {
    crate::transfer::auto::value_histogram(v, crate::transfer::auto::AUTO_BINS)
}

/// What a volume is shown within: the host and GPU budgets (the device's 3-D texture limit with them) and the
/// user's `--max-dim`.
#[derive(Clone, Debug)]
pub(super) struct Limits {
    pub(super) budgets: crate::pyramid::budget::Budgets,
    pub(super) max_dim: Option<u32>,
    /// Where levels read from files are kept (`None`: `--no-cache`).
    pub(super) cache: Option<crate::scale::cache::PyramidCache>,
}

impl Limits {
    /// What a volume is read within: the host budget alone (the GPU budget decides whether it is uploaded whole
    /// or streamed).
    pub(super) fn read_budgets(&self) -> crate::pyramid::budget::Budgets {
        crate::pyramid::budget::Budgets {
            gpu: None,
            ..self.budgets
        }
    }
}

/// Loads any format `formats::open` reads (raw with the given options) within `limits`: read at the finest level
/// the host budget holds (one step over the GPU budget whole is streamed through a pool of bricks); a time series,
/// shown whole step by step, at the finest level that fits the GPU budget too. A volume larger than they allow is
/// shown at a coarser pyramid level, with a note, rather than refused. A level read from its file comes with its
/// pyramid-cache write, left to the caller.
pub(super) fn open_source(
    source: &VolumeSource,
    limits: &Limits,
    series: Option<&str>,
    channel: Option<u32>,
    progress: &mut dyn FnMut(f32),
) -> Result<crate::scale::Opened, String> {
    let host_only = limits.read_budgets();
    let mut opened = match source {
        VolumeSource::Builtin(name, size) => volume::builtin(name, *size)
            .and_then(|v| crate::scale::fit(v, &host_only, false))
            .map(|volume| crate::scale::Opened { volume, keep: None })
            .map_err(|e| e.to_string())?,
        VolumeSource::Memory(v) => crate::scale::fit(v.as_ref().clone(), &host_only, false)
            .map(|volume| crate::scale::Opened { volume, keep: None })
            .map_err(|e| e.to_string())?,
        VolumeSource::File(path, raw) => {
            let opts = formats::OpenOptions {
                raw: raw.clone(),
                max_dim: limits.max_dim,
                series: series.map(str::to_string),
                channel,
                ..Default::default()
            };
            // A series whose header says so (in place or compressed) is read at its GPU level at once; one read
            // whole by its format's reader is reduced to it below.
            let steps = formats::in_place::claimed_shape(path).map_or(1, |(_, _, steps)| steps);
            let budgets = if steps > 1 { limits.budgets } else { host_only };
            crate::scale::open_deferred(path, &opts, budgets, limits.cache.as_ref(), progress)
                .map_err(|e| e.to_string())?
        }
    };
    if opened.volume.timesteps() > 1 && opened.keep.is_none() {
        opened.volume = crate::scale::fit(opened.volume, &limits.budgets, false).map_err(|e| e.to_string())?;
    }
    Ok(opened)
}

fn load_in_background(
    source: VolumeSource,
    limits: Limits,
    (series, channel): (Option<String>, Option<u32>),
    waker: EventLoopProxy<()>,
) -> Loading {
    let label = match (&source, &series) {
        (VolumeSource::Builtin(name, _), _) => name.clone(),
        (VolumeSource::Memory(v), _) => v.name.clone(),
        (VolumeSource::File(path, _), None) => path.display().to_string(),
        (VolumeSource::File(path, _), Some(s)) => format!("{} (series {s})", path.display()),
    };
    let progress = Arc::new(AtomicU32::new(0));
    let (tx, rx) = std::sync::mpsc::channel();
    // Each delivery wakes the event loop, so that it is shown at once.
    let send = move |d: Delivery| {
        let _ = tx.send(d);
        let _ = waker.send_event(());
    };
    let p = progress.clone();
    let recorded = source.clone();
    std::thread::spawn(move || {
        // A large file read in place or a large DICOM series is shown first from every k-th voxel (scale::preview),
        // then refined.
        if let VolumeSource::File(path, raw) = &source {
            let opts = formats::OpenOptions {
                raw: raw.clone(),
                series: series.clone(),
                ..Default::default()
            };
            let budgets = limits.read_budgets();
            if let Ok(Some(v)) = crate::scale::preview_within(path, &opts, budgets, limits.cache.as_ref()) {
                let h = value_histogram(&v);
                send(Delivery::Preview(v, h));
            }
        }
        // Reading is 90% of the bar, the histogram the rest.
        let result = open_source(&source, &limits, series.as_deref(), channel, &mut |f| {
            p.store((0.9 * f).to_bits(), Ordering::Relaxed)
        });
        p.store(0.9f32.to_bits(), Ordering::Relaxed);
        let mut keep = None;
        let analysed: Result<(Volume, Vec<u64>), String> = result.map(|opened| {
            let h = value_histogram(&opened.volume);
            // The cache is written once the volume is shown, from a copy.
            keep = opened.keep.map(|k| (k, opened.volume.clone()));
            (opened.volume, h)
        });
        p.store(1.0f32.to_bits(), Ordering::Relaxed);
        send(Delivery::Done(analysed));
        if let Some((k, copy)) = keep {
            let written = k.write(copy);
            if let Some(note) = written
                .notes
                .iter()
                .find(|n| n.starts_with("the pyramid cache was not written"))
            {
                eprintln!("note: {note}");
            }
        }
    });
    Loading {
        label,
        source: recorded,
        progress,
        rx,
    }
}

impl Loader {
    pub(super) fn new(limits: Limits, restore: Option<ViewState>, waker: EventLoopProxy<()>) -> Loader {
        Loader {
            loading: None,
            initial: None,
            pending_restore: restore,
            dialog: None,
            dialog_asked: Instant::now(),
            limits,
            channel: None,
            preview_tf: None,
            waker,
        }
    }

    /// A preview was shown for the load that just ended and the user has changed its transfer function since
    /// (`tf`, the one shown now); forgets the preview.
    pub(super) fn preview_edited(&mut self, tf: &Option<crate::transfer::function::TransferFunction>) -> bool {
        self.preview_tf.take().is_some_and(|shown| shown != *tf)
    }

    pub(super) fn limits(&self) -> &Limits {
        &self.limits
    }

    /// A load is under way.
    pub(super) fn busy(&self) -> bool {
        self.loading.is_some()
    }

    /// A file dialog is open.
    pub(super) fn dialog_open(&self) -> bool {
        self.dialog.is_some()
    }

    /// Starts loading `source` unless a load is under way.
    pub(super) fn start(&mut self, source: VolumeSource, messages: &mut Messages) {
        self.start_series(source, None, messages);
    }

    /// Starts loading `source`, from a DICOM folder holding several series the one `series` names (a number or
    /// UID; `None`: the largest), unless a load is under way.
    pub(super) fn start_series(&mut self, source: VolumeSource, series: Option<String>, messages: &mut Messages) {
        if self.loading.is_some() {
            messages.status = Some("a volume is already loading".into());
            return;
        }
        messages.error = None;
        messages.about = Topic::Volume;
        self.preview_tf = None;
        let waker = self.waker.clone();
        self.loading = Some(load_in_background(
            source,
            self.limits.clone(),
            (series, self.channel),
            waker,
        ));
    }

    /// Shows the platform's file dialog (unless one is open); it blocks until the user answers, so it runs on
    /// its own thread.
    pub(super) fn open_dialog(&mut self) {
        if self.dialog.is_some() {
            return;
        }
        let (tx, rx) = std::sync::mpsc::channel();
        self.dialog_asked = Instant::now();
        std::thread::spawn(move || {
            let _ = tx.send(rfd::FileDialog::new().set_title("Load volume").pick_file());
        });
        self.dialog = Some(rx);
    }

    /// The file the dialog's user chose, once they have. No dialog shown (an answer of none within
    /// [`NO_DIALOG_WITHIN`]): the viewer's own chooser opens in its place.
    pub(super) fn poll_dialog(&mut self, model: &mut Model) -> Option<PathBuf> {
        let answer = match self.dialog.as_ref()?.try_recv() {
            Err(TryRecvError::Empty) => return None,
            Ok(answer) => answer,
            Err(TryRecvError::Disconnected) => None,
        };
        self.dialog = None;
        let files = &mut model.files;
        files.open_note = None;
        if answer.is_none() {
            if self.dialog_asked.elapsed() < NO_DIALOG_WITHIN {
                files.chooser = Some(FileChooser::near(&files.load_path));
            } else {
                files.open_note = Some("no file chosen".into());
            }
        }
        answer
    }

    /// Takes a finished load, or shows the progress of one under way. A failed load leaves the old volume (for
    /// the command line's, the empty placeholder) and says why in the panel and on stderr.
    pub(super) fn poll(&mut self, model: &mut Model) -> Option<Arrived> {
        let messages = &mut model.messages;
        if self.loading.is_some() {
            messages.about = Topic::Volume;
        }
        let Some(loading) = &self.loading else { return None };
        match loading.rx.try_recv() {
            Ok(Delivery::Preview(volume, histogram)) => {
                return Some(Arrived {
                    volume,
                    histogram,
                    source: loading.source.clone(),
                    label: loading.label.clone(),
                    initial: None,
                    preview: true,
                });
            }
            Ok(Delivery::Done(Ok((volume, histogram)))) => {
                let (label, source) = (loading.label.clone(), loading.source.clone());
                self.loading = None;
                messages.loading = None;
                let initial = self.initial.take();
                return Some(Arrived {
                    volume,
                    histogram,
                    source,
                    label,
                    initial,
                    preview: false,
                });
            }
            Ok(Delivery::Done(Err(e))) => {
                self.pending_restore = None;
                self.preview_tf = None;
                if self.initial.take().is_some() {
                    // The command line's volume: the window stays open on the empty placeholder, with the error
                    // where a load from the panel shows it, so that another file can be opened.
                    model.volume.label = "no volume: open one below".into();
                }
                eprintln!("could not load {}: {e}", loading.label);
                messages.error = Some(crate::viewer::model::files::load_error_text(
                    &loading.label,
                    &e.to_string(),
                ));
                self.loading = None;
                messages.loading = None;
            }
            Err(TryRecvError::Empty) => {
                let p = f32::from_bits(loading.progress.load(Ordering::Relaxed));
                messages.loading = Some((loading.label.clone(), p));
            }
            Err(TryRecvError::Disconnected) => {
                self.preview_tf = None;
                messages.error = Some(format!("{}: the loader stopped unexpectedly", loading.label));
                self.loading = None;
                messages.loading = None;
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewer::model::tf::TfEditorState;

    #[test]
    fn a_compressed_series_over_the_budgets_is_read_at_its_gpu_level() {
        // A series is shown whole, step by step: read at the level the GPU budget takes whole, even where its file
        // is decoded as a stream (and that level kept in the pyramid cache).
        let dir = std::env::temp_dir().join(format!("volcast-loading-series-{}", std::process::id()));
        let budgets =
            crate::pyramid::budget::Budgets::host(Some(10 << 10)).with_gpu(crate::pyramid::budget::GpuBudget {
                bytes: 2 << 10,
                max_dim: 16384,
            });
        let limits = Limits {
            budgets,
            max_dim: None,
            cache: Some(crate::scale::cache::PyramidCache::new(Some(dir.clone()))),
        };
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/nibabel/example_nifti2.nii.gz");
        let source = VolumeSource::File(path, Default::default());
        let opened = open_source(&source, &limits, None, None, &mut |_| {}).expect("opened");
        assert_eq!(opened.volume.timesteps(), 2);
        assert!(
            crate::render::placement::fits_gpu_whole(&opened.volume, &budgets),
            "{:?} is over the GPU budget",
            opened.volume.dims
        );
        let _ = std::fs::remove_dir_all(dir);
    }

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
