//! Analyze 7.5 (Mayo's dbh.h): the 348-byte header NIfTI-1 grew from, without its magic, always a .hdr/.img pair.
//! SPM's additions are read as nibabel's `Spm2AnalyzeImage` (what `nibabel.load` gives for such a file) reads them:
//! the `originator` field as a 1-based origin voxel, `funused1`/`funused2` as scale and offset.

use super::common::{self, Fields, Placement, Reader};
use crate::formats::decode::Endian;
use crate::formats::format::Header;
use crate::volume::{Scaling, VolumeError};

pub(super) const FORMAT: &str = "Analyze 7.5";

/// The caller has checked sizeof_hdr (348, which gave `endian`), the length and that NIfTI-1's magic is absent.
pub(super) fn parse(bytes: &[u8], endian: Endian, file: &str) -> Result<Header, VolumeError> {
    let r = Reader { bytes, endian };
    let fields = Fields {
        format: FORMAT,
        header_size: super::HEADER_SIZE,
        single_file: false,
        dim: [0, 1, 2, 3, 4, 5, 6, 7].map(|i| i64::from(r.i16(40 + 2 * i))),
        datatype: r.i16(70),
        pixdim: [76, 80, 84, 88].map(|at| r.f32(at)),
        vox_offset: r.f32(108),
        scaling: spm2_scaling(&r),
        // Analyze names its units in text (vox_units); NIfTI's unit code has no place here.
        xyzt_units: 0,
        placement: Placement::Analyze {
            origin: [253, 255, 257].map(|at| r.i16(at)),
        },
    };
    common::build(&fields, endian, file)
}

/// SPM2's spm_vol_ana.m as nibabel's Spm2AnalyzeHeader.get_slope_inter has it: a finite non-zero scale factor
/// (funused1) with the offset in funused2 (0 if not finite); else the ratio of the calibrated range
/// (cal_min..cal_max) to the stored one (glmin..glmax) when both are non-zero; else none.
fn spm2_scaling(r: &Reader) -> Scaling {
    let (slope, intercept) = (r.f32(112), r.f32(116));
    if slope.is_finite() && slope != 0.0 {
        let intercept = if intercept.is_finite() { intercept } else { 0.0 };
        return common::nifti_scaling(slope, intercept);
    }
    let (glmax, glmin) = (f64::from(r.i32(140)), f64::from(r.i32(144)));
    let (cal_max, cal_min) = (r.f32(124), r.f32(128));
    let (stored, calibrated) = (glmax - glmin, cal_max - cal_min);
    if stored != 0.0 && calibrated != 0.0 && calibrated.is_finite() {
        let slope = calibrated / stored;
        return common::nifti_scaling(slope, cal_min - slope * glmin);
    }
    Scaling::IDENTITY
}
