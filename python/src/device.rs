//! The process's one Vulkan device, owned by one thread that runs every GPU job in turn: calls from several Python
//! threads queue here, and none of them holds the GIL while it waits. The device is made by the first job, kept for
//! the next, made again only when a call asks for other device options (`device=`, `validate=`, `texture=`,
//! `brick_size=`), and destroyed by [`shutdown`] (registered with `atexit`), which reports the validation layer's
//! messages, leaked objects included.

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::sync::mpsc::{Receiver, Sender};
use std::sync::{Mutex, OnceLock};
use volcast::cli::args::GpuArgs;
use volcast::gpu::Gpu;
use volcast::render::headless::Headless;
use volcast::volume::Volume;

/// The volume the device shows, as placed: which volume and under which placement options, and the coarser level
/// placed where it did not fit whole.
pub struct Shown {
    pub key: String,
    pub reduced: Option<Volume>,
}

/// The device and its headless renderer.
pub struct Device {
    pub gpu: Gpu,
    pub headless: Headless,
    options: String,
    pub shown: Option<Shown>,
}

/// The device thread's state.
#[derive(Default)]
pub struct Slot {
    device: Option<Device>,
}

/// What device options a call asks for, as text to compare.
fn options_key(args: &GpuArgs) -> String {
    let o = args.options();
    format!(
        "{:?} {:?} {:?} {:?}",
        o.validation, o.device, o.texel_policy, o.brick_side
    )
}

impl Slot {
    /// The device `args` asks for: the one kept, or a new one where there is none or it was made with other options.
    pub fn device(&mut self, args: &GpuArgs) -> anyhow::Result<&mut Device> {
        let key = options_key(args);
        if self.device.as_ref().is_some_and(|d| d.options != key) {
            self.close();
        }
        if self.device.is_none() {
            let gpu = Gpu::new(&args.options())?;
            let headless = Headless::new(&gpu)?;
            self.device = Some(Device {
                gpu,
                headless,
                options: key,
                shown: None,
            });
        }
        Ok(self.device.as_mut().expect("made above"))
    }

    /// Destroys the device; returns whether it validated and the validation layer's error and warning counts,
    /// taken after the device is gone (so leaked objects count).
    fn close(&mut self) -> Option<(bool, usize, usize)> {
        let Device { gpu, headless, .. } = self.device.take()?;
        headless.destroy(&gpu);
        let validating = gpu.validation_enabled();
        let log = gpu.log.clone();
        drop(gpu);
        Some((validating, log.error_count(), log.warning_count()))
    }
}

type Job = Box<dyn FnOnce(&mut Slot) + Send>;

/// The queue of the device thread, started by the first job.
fn queue() -> &'static Mutex<Sender<Job>> {
    static QUEUE: OnceLock<Mutex<Sender<Job>>> = OnceLock::new();
    QUEUE.get_or_init(|| {
        let (tx, rx) = std::sync::mpsc::channel::<Job>();
        std::thread::Builder::new()
            .name("volcast-device".into())
            .spawn(move || {
                let mut slot = Slot::default();
                for job in rx {
                    // A panic (a bug) ends only its job: the caller hears that the worker gave no answer, and the
                    // device, whose state the job may have left half-changed, is let go rather than used again.
                    let unwound = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| job(&mut slot)));
                    if unwound.is_err() {
                        // Leaked whole: destroying a device whose objects may be mid-change is not valid Vulkan.
                        std::mem::forget(slot.device.take());
                    }
                }
            })
            .expect("cannot start volcast's device thread");
        Mutex::new(tx)
    })
}

/// Queues `job` on the device thread; its answer arrives on the receiver.
pub fn submit<T: Send + 'static>(job: impl FnOnce(&mut Slot) -> T + Send + 'static) -> PyResult<Receiver<T>> {
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    let job: Job = Box::new(move |slot| {
        let _ = tx.send(job(slot));
    });
    queue()
        .lock()
        .map_err(|_| PyRuntimeError::new_err("volcast's device queue is poisoned"))?
        .send(job)
        .map_err(|_| PyRuntimeError::new_err("volcast's device thread has ended"))?;
    Ok(rx)
}

/// Destroys the device (if one was made) after the jobs queued before it; returns `None` where there was none, else
/// `(validating, errors, warnings)`: the validation layer's counts, leaked objects included.
#[pyfunction]
pub fn shutdown(py: Python<'_>) -> PyResult<Option<(bool, usize, usize)>> {
    let rx = submit(|slot| slot.close())?;
    crate::wait::wait(py, rx, None)
}

/// The validation layer's error and warning counts so far on the device kept (None: no device, or not validating).
#[pyfunction]
pub fn validation_counts(py: Python<'_>) -> PyResult<Option<(usize, usize)>> {
    let rx = submit(|slot| {
        let d = slot.device.as_ref()?;
        let log = &d.gpu.log;
        d.gpu
            .validation_enabled()
            .then(|| (log.error_count(), log.warning_count()))
    })?;
    crate::wait::wait(py, rx, None)
}

/// The name of the device renders run on (made now if none is yet, with the default options).
#[pyfunction]
pub fn device_name(py: Python<'_>) -> PyResult<String> {
    let rx = submit(|slot| {
        let args = crate::options::default_gpu_args();
        slot.device(&args).map(|d| d.gpu.device_name.clone())
    })?;
    crate::wait::wait(py, rx, None)?.map_err(|e| crate::errors::to_py(e, crate::errors::While::Rendering))
}
