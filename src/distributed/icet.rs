//! Sort-last image compositing with IceT (vendor/icet-sys): every rank hands in its own full-frame image, rank 0
//! gets the composite. One tile of `width × height` shown on rank 0, the sequential strategy (the right one for a
//! single tile: it skips IceT's tile-bookkeeping allgathers) with radix-k for the single-image compositing,
//! `f32` RGBA colour, a transparent black background.
//!
//! What IceT does with the pixels (read from the vendored `draw.c`, `image.c`, `compress_func_body.h`):
//! - [`Blend::Over`]: a pixel whose alpha is exactly 0 is background and dropped, even if its colour is not 0
//!   (additive light with no coverage is lost). The rest are blended front to back with the premultiplied over
//!   operator, `front + (1 - front.a) * back`, so the result is premultiplied too. `order[0]` is the front.
//! - [`Blend::ClosestDepth`]: a pixel whose depth is not below 1.0 (or is NaN) is background: it comes back as
//!   colour (0, 0, 0, 0) and depth 1.0 whatever colour it had. Otherwise the smaller depth wins (strictly: on a
//!   tie the winner depends on the compositing tree).
//! - The background is (0, 0, 0, 0), so `ICET_CORRECT_COLORED_BACKGROUND` has nothing to correct and stays off.
//! - IceT reads buffers as rows bottom to top; with one full-frame tile and no viewport the row order is only
//!   carried through, so the rows come out in the order they went in.
//!
//! IceT keeps its current context, last error and diagnostics state in C globals and is not thread-safe, so
//! every call here holds one process-wide lock. All ranks must call [`Compositor::new`] and
//! [`Compositor::composite`] together (they are collective); arguments that fail the checks return before
//! the collective call, so check them the same way on every rank or the other ranks will wait.

use std::ptr;
use std::sync::{Mutex, MutexGuard};

use icet_sys as sys;
use mpi::topology::SimpleCommunicator;
use mpi::traits::AsRaw;

/// How the ranks' images are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    /// Ordered premultiplied over (`ICET_COMPOSITE_MODE_BLEND` with `ICET_ORDERED_COMPOSITE`).
    Over,
    /// Z-buffer: the fragment with the smallest depth wins (`ICET_COMPOSITE_MODE_Z_BUFFER`).
    ClosestDepth,
}

/// The composite, on the display rank (rank 0) only.
#[derive(Clone, Debug, PartialEq)]
pub struct Composited {
    /// `width * height * 4` premultiplied RGBA, rows in the order given.
    pub rgba: Vec<f32>,
    /// `width * height` depths for [`Blend::ClosestDepth`] (1.0 where no rank had anything), `None` for Over.
    pub depth: Option<Vec<f32>>,
}

/// What the last [`Compositor::composite`] cost this rank.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Bytes this rank sent (`ICET_BYTES_SENT`, a 32-bit counter in IceT).
    pub bytes_sent: u64,
    /// Seconds spent compositing on this rank (`ICET_COMPOSITE_TIME`: the frame's time less render and read-back).
    pub composite_seconds: f64,
}

/// An IceT context over a duplicate of an MPI communicator; dropping it destroys both (drop it before the MPI
/// `Universe`: after `MPI_Finalize` the two are leaked instead, as MPI can no longer free the communicators).
pub struct Compositor {
    context: sys::IceTContext,
    communicator: sys::IceTCommunicator,
    width: u32,
    height: u32,
    ranks: usize,
    stats: Stats,
}

/// IceT's C globals (current context, error, diagnostics) are shared by all contexts and threads.
static ICET: Mutex<()> = Mutex::new(());

fn lock() -> MutexGuard<'static, ()> {
    ICET.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// IceT measures buffers in `IceTSizeType` (`i32`) bytes, 20 per pixel here plus run lengths: stay well inside.
const MAX_PIXELS: usize = i32::MAX as usize / 32;
const BACKGROUND: [f32; 4] = [0.0; 4];

impl Compositor {
    /// An IceT context over (a duplicate of) `comm`, an intra-communicator such as rsmpi's
    /// `universe.world()`, compositing `width × height` images for display on rank 0. Collective over `comm`.
    ///
    /// # Panics
    /// If MPI is not initialised (or already finalised), if `width` or `height` is 0, or if the image has more
    /// than `i32::MAX / 32` pixels (IceT sizes its buffers in 32-bit byte counts).
    pub fn new(comm: &SimpleCommunicator, width: u32, height: u32) -> Compositor {
        assert!(
            mpi::is_initialized() && !mpi::is_finalized(),
            "IceT needs MPI initialised and not finalised"
        );
        let pixels = (width as usize).checked_mul(height as usize);
        assert!(
            width > 0 && height > 0 && pixels.is_some_and(|p| p <= MAX_PIXELS),
            "IceT image of {width}x{height} pixels: each side must be at least 1 and the whole at most {MAX_PIXELS}"
        );
        let guard = lock();
        // SAFETY: `comm` is a live intra-communicator borrowed from rsmpi and MPI is initialised (checked above);
        // IceT duplicates it (MPI_Comm_dup) and keeps only the duplicate. Open MPI's MPI_Comm is a pointer
        // (mpi-sys wraps it in a newtype, field 0).
        let communicator = unsafe { sys::icetCreateMPICommunicator(comm.as_raw().0.cast()) };
        assert!(
            !communicator.is_null(),
            "icetCreateMPICommunicator returned no communicator"
        );
        // SAFETY: `communicator` was just created by IceT and is non-null; the lock serialises IceT's globals.
        let context = unsafe { sys::icetCreateContext(communicator) };
        assert!(!context.is_null(), "icetCreateContext returned no context");
        let _ = take_error(); // Stale: raised before this context existed.
        let mut ranks = 0;
        // SAFETY: `context` is the current context (icetCreateContext made it so); the sizes fit in i32 (checked
        // above); ICET_NUM_PROCESSES is one IceTInt, written to a live local.
        unsafe {
            sys::icetDiagnostics(sys::ICET_DIAG_ERRORS | sys::ICET_DIAG_ALL_NODES);
            sys::icetResetTiles();
            sys::icetAddTile(0, 0, width as i32, height as i32, 0);
            sys::icetStrategy(sys::ICET_STRATEGY_SEQUENTIAL);
            sys::icetSingleImageStrategy(sys::ICET_SINGLE_IMAGE_STRATEGY_RADIXK);
            sys::icetSetColorFormat(sys::ICET_IMAGE_COLOR_RGBA_FLOAT);
            sys::icetDisable(sys::ICET_CORRECT_COLORED_BACKGROUND);
            sys::icetGetIntegerv(sys::ICET_NUM_PROCESSES, &mut ranks);
        }
        let setup = take_error();
        drop(guard); // Before a panic below, as the compositor's Drop takes the lock.
        let compositor = Compositor {
            context,
            communicator,
            width,
            height,
            ranks: ranks as usize,
            stats: Stats::default(),
        };
        if let Err(e) = setup {
            panic!("setting up IceT failed: {e}");
        }
        compositor
    }

    /// Composites every rank's `rgba` (`width * height * 4` premultiplied linear `f32`) and returns the result
    /// on rank 0, `None` on the other ranks. [`Blend::Over`] takes no depth and `order` listing every rank once,
    /// front to back; [`Blend::ClosestDepth`] takes `width * height` depths in [0, 1] (1.0 = nothing there)
    /// and ignores `order`. Errors: a slice of the wrong length, a bad order, or an error IceT raised.
    pub fn composite(
        &mut self,
        rgba: &[f32],
        depth: Option<&[f32]>,
        blend: Blend,
        order: &[i32],
    ) -> Result<Option<Composited>, String> {
        let pixels = self.width as usize * self.height as usize;
        let depth_ptr = self.check_buffers(rgba, depth, blend)?;
        if blend == Blend::Over {
            check_order(order, self.ranks)?;
        }
        if mpi::is_finalized() {
            return Err("MPI is finalised".to_owned());
        }

        let _guard = lock();
        // SAFETY: `self.context` is alive until Drop; the lock keeps other threads' IceT calls out.
        unsafe { sys::icetSetContext(self.context) };
        // A stale error from before this call is not this composite's.
        let _ = take_error();
        // SAFETY: the context was made current above, under the lock; check_order passed for Blend::Over.
        unsafe { set_mode(blend, order) };
        take_error()?;

        // SAFETY: the colour (pixels * 4 f32) and depth (pixels f32, or null when the depth format is none) buffers
        // match the formats just set and the tile's global viewport, and outlive the call: IceT reads them only
        // inside icetCompositeImage (it keeps the pointers in ICET_RENDER_BUFFER afterwards, but only
        // icetDrawFrame, never called here, would read that again). Null viewport = all pixels valid; null
        // matrices = identity (no bounding vertices are set); BACKGROUND is 4 floats.
        let image = unsafe {
            sys::icetCompositeImage(
                rgba.as_ptr().cast(),
                depth_ptr.cast(),
                ptr::null(),
                ptr::null(),
                ptr::null(),
                BACKGROUND.as_ptr(),
            )
        };
        let (mut bytes, mut seconds) = (0, 0.0);
        // SAFETY: the context is current; each state variable is one value, written to a live local.
        unsafe {
            sys::icetGetIntegerv(sys::ICET_BYTES_SENT, &mut bytes);
            sys::icetGetDoublev(sys::ICET_COMPOSITE_TIME, &mut seconds);
        }
        self.stats = Stats {
            bytes_sent: u64::from(bytes as u32),
            composite_seconds: seconds,
        };
        take_error()?;

        // SAFETY: `image` was just returned by IceT for the current context and no IceT call has run since.
        if unsafe { sys::icetImageIsNull(image) } != 0 {
            return Ok(None);
        }
        // SAFETY: as above; the copies below finish before the next IceT call can reuse the image's buffer.
        unsafe { self.copy_out(image, blend, pixels) }.map(Some)
    }

    /// The depth buffer's pointer for IceT (null without depth), once `rgba` and `depth` have the lengths this
    /// tile and `blend` need.
    fn check_buffers(&self, rgba: &[f32], depth: Option<&[f32]>, blend: Blend) -> Result<*const f32, String> {
        let pixels = self.width as usize * self.height as usize;
        if rgba.len() != pixels * 4 {
            return Err(format!(
                "rgba has {} floats, {}x{} RGBA needs {}",
                rgba.len(),
                self.width,
                self.height,
                pixels * 4
            ));
        }
        match (blend, depth) {
            (Blend::Over, None) => Ok(ptr::null()),
            (Blend::Over, Some(_)) => Err("Blend::Over takes no depth".to_owned()),
            (Blend::ClosestDepth, None) => Err("Blend::ClosestDepth needs a depth buffer".to_owned()),
            (Blend::ClosestDepth, Some(d)) if d.len() != pixels => Err(format!(
                "depth has {} floats, {}x{} needs {pixels}",
                d.len(),
                self.width,
                self.height
            )),
            (Blend::ClosestDepth, Some(d)) => Ok(d.as_ptr()),
        }
    }

    /// What the last composite cost this rank (zero before the first).
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Copies the composite out of IceT's buffer.
    ///
    /// # Safety
    /// `image` must be the non-null image icetCompositeImage just returned for this (current) context, with no
    /// IceT call since, and the IceT lock held.
    unsafe fn copy_out(&self, image: sys::IceTImage, blend: Blend, pixels: usize) -> Result<Composited, String> {
        // SAFETY: `image` is valid (the caller's contract); these read its header only.
        let (w, h) = unsafe { (sys::icetImageGetWidth(image), sys::icetImageGetHeight(image)) };
        if (w, h) != (self.width as i32, self.height as i32) {
            return Err(format!(
                "IceT returned a {w}x{h} image for a {}x{} tile",
                self.width, self.height
            ));
        }
        // SAFETY: as above; returns null (raising an error) unless the colour is float RGBA.
        let color = unsafe { sys::icetImageGetColorcf(image) };
        take_error()?;
        if color.is_null() {
            return Err("IceT returned an image without a float colour buffer".to_owned());
        }
        // SAFETY: a width x height float RGBA image (both checked above) holds pixels * 4 floats at `color`,
        // left alone until the next IceT call, after this copy.
        let rgba = unsafe { std::slice::from_raw_parts(color, pixels * 4) }.to_vec();
        let depth = match blend {
            Blend::Over => None,
            Blend::ClosestDepth => {
                // SAFETY: as above; returns null (raising an error) unless the depth is float.
                let d = unsafe { sys::icetImageGetDepthcf(image) };
                take_error()?;
                if d.is_null() {
                    return Err("IceT returned an image without a float depth buffer".to_owned());
                }
                // SAFETY: a width x height ICET_IMAGE_DEPTH_FLOAT buffer holds `pixels` floats at `d`.
                Some(unsafe { std::slice::from_raw_parts(d, pixels) }.to_vec())
            }
        };
        Ok(Composited { rgba, depth })
    }
}

impl Drop for Compositor {
    fn drop(&mut self) {
        if mpi::is_finalized() {
            return; // MPI_Comm_free is no longer allowed: leak the context and its two communicator duplicates.
        }
        let _guard = lock();
        // SAFETY: both handles were created in `new` and are destroyed once, here; icetDestroyContext frees the
        // context's own duplicate and clears the current context if it was this one.
        unsafe {
            sys::icetDestroyContext(self.context);
            sys::icetDestroyMPICommunicator(self.communicator);
        }
    }
}

/// Sets IceT's composite mode for `blend`: ordered blending in `order`, or the closest depth.
///
/// # Safety
/// An IceT context is current, and for [`Blend::Over`] `order` holds each of its ICET_NUM_PROCESSES ranks exactly
/// once ([`check_order`]), which is what icetCompositeOrder indexes with.
unsafe fn set_mode(blend: Blend, order: &[i32]) {
    // SAFETY: the caller's contract above.
    unsafe {
        match blend {
            Blend::Over => {
                sys::icetCompositeMode(sys::ICET_COMPOSITE_MODE_BLEND);
                sys::icetSetDepthFormat(sys::ICET_IMAGE_DEPTH_NONE);
                sys::icetEnable(sys::ICET_ORDERED_COMPOSITE);
                sys::icetCompositeOrder(order.as_ptr());
            }
            Blend::ClosestDepth => {
                sys::icetCompositeMode(sys::ICET_COMPOSITE_MODE_Z_BUFFER);
                sys::icetSetDepthFormat(sys::ICET_IMAGE_DEPTH_FLOAT);
                sys::icetDisable(sys::ICET_ORDERED_COMPOSITE);
                // On by default, it would drop the composited depth from the result.
                sys::icetDisable(sys::ICET_COMPOSITE_ONE_BUFFER);
            }
        }
    }
}

/// `order` must list each of `0..ranks` exactly once.
fn check_order(order: &[i32], ranks: usize) -> Result<(), String> {
    let mut seen = vec![false; ranks];
    for &rank in order {
        match usize::try_from(rank).ok().and_then(|r| seen.get_mut(r)) {
            Some(s) if !*s => *s = true,
            _ => {
                return Err(format!(
                    "composite order {order:?} is not a permutation of the {ranks} ranks"
                ))
            }
        }
    }
    if order.len() != ranks {
        return Err(format!(
            "composite order {order:?} is not a permutation of the {ranks} ranks"
        ));
    }
    Ok(())
}

/// IceT's last error (cleared by reading it; IceT records warnings' codes here too).
fn take_error() -> Result<(), String> {
    // SAFETY: icetGetError reads and clears a C global; callers hold the IceT lock.
    let code = unsafe { sys::icetGetError() };
    let name = match code {
        sys::ICET_NO_ERROR => return Ok(()),
        sys::ICET_SANITY_CHECK_FAIL => "ICET_SANITY_CHECK_FAIL",
        sys::ICET_INVALID_ENUM => "ICET_INVALID_ENUM",
        sys::ICET_BAD_CAST => "ICET_BAD_CAST",
        sys::ICET_OUT_OF_MEMORY => "ICET_OUT_OF_MEMORY",
        sys::ICET_INVALID_OPERATION => "ICET_INVALID_OPERATION",
        sys::ICET_INVALID_VALUE => "ICET_INVALID_VALUE",
        _ => "unknown IceT error",
    };
    Err(format!(
        "IceT raised {name} (0x{code:08X}); its message is on this rank's stdout"
    ))
}

#[cfg(test)]
mod tests {
    use super::check_order;

    #[test]
    fn order_must_be_a_permutation() {
        assert!(check_order(&[2, 0, 1], 3).is_ok());
        assert!(check_order(&[0, 1], 3).is_err());
        assert!(check_order(&[0, 1, 1], 3).is_err());
        assert!(check_order(&[0, 1, 3], 3).is_err());
        assert!(check_order(&[0, -1, 2], 3).is_err());
        assert!(check_order(&[0, 1, 2, 0], 3).is_err());
    }
}
