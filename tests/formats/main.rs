//! Volume files: every reader against files written (and read back) by the libraries of each format, hostile
//! files refused with a clear message, time series, and volumes placed where the patient has them.

mod dicom;
mod open;
mod tiff;
mod time;
mod vtk;
mod world;
