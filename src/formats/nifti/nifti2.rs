//! NIfTI-2: the NIfTI-1 fields widened to 64 bits (int64 dim and vox_offset, float64 pixdim, quatern, srow) in a
//! 540-byte header with the magic at byte 4 (nifti2.h).

use super::common::{self, Fields, Placement, Reader};
use crate::formats::format::{header_error, Header};
use crate::volume::VolumeError;

pub(crate) const HEADER_SIZE: usize = 540;

/// sizeof_hdr 540 in either byte order and the magic `n+2` (single file) or `ni2` (a .hdr/.img pair).
pub(crate) fn is_nifti2(prefix: &[u8]) -> bool {
    common::endian_of(prefix, HEADER_SIZE as i32).is_some()
        && prefix.len() >= 8
        && (&prefix[4..8] == b"n+2\0" || &prefix[4..8] == b"ni2\0")
}

pub(super) fn parse(bytes: &[u8], file: &str) -> Result<Header, VolumeError> {
    let err = |problem: String| header_error(file, problem);
    if bytes.len() < HEADER_SIZE {
        return Err(err(format!(
            "{} bytes is too short for a NIfTI-2 header (540 bytes)",
            bytes.len()
        )));
    }
    let endian = common::endian_of(bytes, HEADER_SIZE as i32).expect("the caller checked sizeof_hdr");
    let single_file = match &bytes[4..8] {
        b"n+2\0" => true,
        b"ni2\0" => false,
        _ => return Err(err("not a NIfTI-2 file: the magic is neither 'n+2' nor 'ni2'".into())),
    };
    let r = Reader { bytes, endian };
    let fields = Fields {
        format: "NIfTI-2",
        header_size: HEADER_SIZE,
        single_file,
        dim: [0, 1, 2, 3, 4, 5, 6, 7].map(|i| r.i64(16 + 8 * i)),
        datatype: r.i16(12),
        pixdim: [104, 112, 120, 128].map(|at| r.f64(at)),
        // Offsets beyond 2^53 lose precision here, but everything beyond 1e12 is refused anyway.
        vox_offset: r.i64(168) as f64,
        scaling: common::nifti_scaling(r.f64(176), r.f64(184)),
        xyzt_units: r.i32(500).to_le_bytes()[0],
        placement: Placement::Nifti {
            qform_code: r.i32(344),
            sform_code: r.i32(348),
            quatern: [352, 360, 368].map(|at| r.f64(at)),
            qoffset: [376, 384, 392].map(|at| r.f64(at)),
            srow: [400, 432, 464].map(|at| [0, 1, 2, 3].map(|c| r.f64(at + 8 * c))),
        },
    };
    common::build(&fields, endian, file)
}
