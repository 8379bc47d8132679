//! Volume files: every reader against files written (and read back) by the libraries of each format, hostile
//! files refused with a clear message, time series, and volumes placed where the patient has them.

// Public: this binary's tests use only part of what the tests share, and rustc counts a crate's public items as
// used, so the rest is not dead code here (tests/common/mod.rs).
#[path = "../common/mod.rs"]
pub mod common;

mod decoded_finer;
mod dicom;
mod dicom_preview;
mod dicom_slices;
mod headers;
mod open;
mod streamed;
mod tiff;
mod time;
mod vtk;
mod world;
mod zarr;
mod zarr_finer;
