//! File formats make volumes: one reader per format (raw, VTK legacy and XML ImageData, NRRD, NIfTI and Analyze,
//! MetaImage, DICOM, TIFF stacks, OME-Zarr), each turning a file or folder into a [`Volume`](crate::volume::Volume).
//! [`open`] picks the reader by content, then by name; [`in_place`] says where a file's voxels lie on disk so that
//! they can be read by box or slab instead of whole. Pure code, no Vulkan. The model the readers fill
//! (`crate::volume`) knows nothing of files: a new format touches only this room.

mod decode;
pub(crate) mod dicom;
mod format;
pub mod in_place;
pub mod label_table;
mod metaimage;
pub(crate) mod nifti;
mod nrrd;
mod open;
mod raw;
mod tiff_stack;
mod unsupported;
mod vtk;
pub(crate) mod zarr;

pub use decode::Endian;
pub use open::{detect_format, format_by_name, open, open_with_progress, open_within, Format, OpenOptions};
pub use raw::{from_native_bytes, load_raw, parse_scivis_name, RawOptions};

/// Parsers that read from memory and never touch the file system: the fuzz targets drive these.
pub mod from_bytes {
    pub use super::dicom::from_bytes as dicom;
    pub use super::format::{DataLocation, Encoding, Header};
    pub use super::metaimage::{from_bytes as metaimage, parse_header as metaimage_header};
    pub use super::nifti::{from_bytes as nifti, parse_header as nifti_header};
    pub use super::nrrd::{from_bytes as nrrd, parse_header as nrrd_header};
    pub use super::tiff_stack::from_bytes as tiff;
    pub use super::vtk::vti::from_bytes as vti;
    pub use super::vtk::{from_bytes as vtk, parse_header as vtk_header};
    pub use super::zarr::from_bytes::{zarr_chunk, zarr_meta};
}
