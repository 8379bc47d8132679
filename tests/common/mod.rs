//! What volcast's integration tests share: the independent CPU reference renderer and the rules' cases, image
//! comparison and the GPU-against-reference judge, running the binary, scratch folders, the X session of the
//! viewer tests, shared test data and the reporting of skipped tests.
//!
//! Each test binary (tests/KIND/main.rs) declares it `pub`: a binary uses only part of it, and rustc counts a
//! crate's public items as used (as it does a library's), so the rest is not dead code there.

pub mod bounds;
pub mod cases;
pub mod classify;
pub mod compare;
pub mod dicom_series;
pub mod gpu;
pub mod layers;
pub mod levels;
pub mod light;
pub mod march;
pub mod placement;
pub mod rays;
pub mod reference;
pub mod run;
pub mod scratch;
pub mod segments;
pub mod stretch;
pub mod strides;
pub mod ui_wait;
pub mod x11;
pub mod xdnd;

pub use run::{stderr, stdout, volcast, volcast_command, volcast_ok, volcast_validated};
pub use scratch::{scratch, Scratch};

use std::io::Write;
use std::path::PathBuf;
use std::sync::{Mutex, Once};

/// `../shared` beside the crate (found from the crate's own directory, never an absolute path).
pub fn shared_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join("shared")
}

/// `../shared/data/<rel>`, where the large test volumes live (not in git); `None` after [`skip`] if missing.
pub fn shared_data(rel: &str) -> Option<PathBuf> {
    let path = shared_dir().join("data").join(rel);
    if path.exists() {
        return Some(path);
    }
    skip(&format!("../shared/data/{rel} not found ({})", path.display()));
    None
}

/// The pinned Python environment with zarr-python and ome-zarr-py (`.ci/python-env` builds it): `VOLCAST_TEST_PYTHON`,
/// else `.venv-tests/bin/python` in the repository; `None` after [`skip`] if neither exists.
pub fn test_python() -> Option<PathBuf> {
    let path = std::env::var_os("VOLCAST_TEST_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(".venv-tests/bin/python"));
    if path.exists() {
        return Some(path);
    }
    skip(&format!(
        "no test Python at {} (run `bash .ci/python-env`)",
        path.display()
    ));
    None
}

static SKIPPED: Mutex<Vec<String>> = Mutex::new(Vec::new());
static SUMMARY: Once = Once::new();

// SAFETY (of the declaration): `atexit` is the C library's, which every Rust program on this platform links.
unsafe extern "C" {
    fn atexit(callback: extern "C" fn()) -> std::ffi::c_int;
}

extern "C" fn print_skip_summary() {
    let skipped = SKIPPED.lock().map(|s| s.clone()).unwrap_or_default();
    if skipped.is_empty() {
        return;
    }
    let binary = std::env::current_exe()
        .ok()
        .and_then(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .unwrap_or_default();
    let binary = binary.rsplit_once('-').map_or(binary.as_str(), |(name, _hash)| name);
    // Straight to the stream: libtest captures only the print macros, so this shows after the binary's results.
    let _ = writeln!(
        std::io::stderr(),
        "SKIPPED in {binary}: {} check(s) did not run: {}",
        skipped.len(),
        skipped.join("; ")
    );
}

/// Records that a check did not run, and why. With `CI=true` (exported by `.ci/run`) a skip fails the test:
/// there, a check that silently did not run would hide that nothing was tested. Elsewhere the test passes and the
/// test binary prints one line naming every skip when it exits, outside libtest's captured output.
pub fn skip(reason: &str) {
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("{reason}: with CI=true nothing may be skipped (../shared must be beside the repository)");
    }
    SUMMARY.call_once(|| {
        // SAFETY: registers a plain `extern "C" fn` that only locks a static and writes to stderr.
        unsafe {
            atexit(print_skip_summary);
        }
    });
    if let Ok(mut skipped) = SKIPPED.lock() {
        skipped.push(reason.to_string());
    }
}
