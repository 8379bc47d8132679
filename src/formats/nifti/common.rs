//! What NIfTI-1, NIfTI-2 and Analyze 7.5 share once their fixed layouts are decoded: the size and time axis, the
//! datatype table, the spacing, and the placement (sform, qform or the Analyze/SPM base affine), as nibabel reads
//! them.

use crate::formats::decode::Endian;
use crate::formats::format::{self, header_error, DataLocation, Header};
use crate::volume::geometry::{self, Geometry};
use crate::volume::{Scaling, VolumeError, VoxelType};
use glam::{DMat3, DMat4};

/// Reads fixed-offset fields of one byte order; callers check the length before.
pub(super) struct Reader<'a> {
    pub bytes: &'a [u8],
    pub endian: Endian,
}

impl Reader<'_> {
    fn take<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut b = [0u8; N];
        b.copy_from_slice(&self.bytes[at..at + N]);
        if self.endian == Endian::Big {
            b.reverse();
        }
        b
    }

    pub fn i16(&self, at: usize) -> i16 {
        i16::from_le_bytes(self.take(at))
    }

    pub fn i32(&self, at: usize) -> i32 {
        i32::from_le_bytes(self.take(at))
    }

    pub fn i64(&self, at: usize) -> i64 {
        i64::from_le_bytes(self.take(at))
    }

    pub fn f32(&self, at: usize) -> f64 {
        f64::from(f32::from_le_bytes(self.take(at)))
    }

    pub fn f64(&self, at: usize) -> f64 {
        f64::from_le_bytes(self.take(at))
    }
}

/// The byte order in which the first four bytes read `size` (sizeof_hdr), if either does.
pub(super) fn endian_of(bytes: &[u8], size: i32) -> Option<Endian> {
    match bytes.get(..4)? {
        b if b == size.to_le_bytes() => Some(Endian::Little),
        b if b == size.to_be_bytes() => Some(Endian::Big),
        _ => None,
    }
}

/// Where the volume lies, as each format records it.
pub(super) enum Placement {
    /// NIfTI: the sform if its code is set, else the qform, else the Analyze base affine.
    Nifti {
        qform_code: i32,
        sform_code: i32,
        quatern: [f64; 3],
        qoffset: [f64; 3],
        srow: [[f64; 4]; 3],
    },
    /// Analyze 7.5 has no orientation; SPM99 keeps a 1-based origin voxel in `originator` (zero when unset).
    Analyze { origin: [i16; 3] },
}

/// One header's fields, decoded from its own layout (field names from nifti1.h / nifti2.h / dbh.h).
pub(super) struct Fields {
    pub format: &'static str,
    pub header_size: usize,
    pub single_file: bool,
    /// dim[0..=7]: dim[0] is the number of dimensions.
    pub dim: [i64; 8],
    pub datatype: i16,
    /// pixdim[0..=3]: qfac, then the voxel sizes.
    pub pixdim: [f64; 4],
    pub vox_offset: f64,
    pub scaling: Scaling,
    pub xyzt_units: u8,
    pub placement: Placement,
}

/// The standard: scl_slope == 0 means no scaling; non-finite values are treated the same.
pub(super) fn nifti_scaling(slope: f64, intercept: f64) -> Scaling {
    if slope != 0.0 && slope.is_finite() && intercept.is_finite() && (slope != 1.0 || intercept != 0.0) {
        Scaling { slope, intercept }
    } else {
        Scaling::IDENTITY
    }
}

/// The header volcast loads from `f`, read from a file of byte order `endian`.
pub(super) fn build(f: &Fields, endian: Endian, file: &str) -> Result<Header, VolumeError> {
    let err = |problem: String| header_error(file, problem);
    let mut h = Header::new(f.format);
    h.endian = endian;
    read_size(f, file, &mut h)?;
    h.voxel_type = voxel_type(f.format, file, f.datatype)?;
    let spacing = read_spacing(f, &mut h);
    if !(0.0..1e12).contains(&f.vox_offset) {
        return Err(err(format!("vox_offset {} is not a valid byte offset", f.vox_offset)));
    }
    let vox_offset = f.vox_offset as u64;
    if f.single_file && vox_offset < f.header_size as u64 {
        return Err(err(format!(
            "vox_offset {vox_offset} points inside the {}-byte header",
            f.header_size
        )));
    }
    h.scaling = f.scaling;
    let affine = placement(f, file, spacing, &mut h)?;
    h.geometry = Some(Geometry::anatomical(affine));
    h.spacing = Geometry::anatomical(affine).spacing();
    h.location = if f.single_file {
        DataLocation::Inline(Some(vox_offset))
    } else {
        DataLocation::Detached {
            name: String::new(),
            skip: Some(vox_offset),
        }
    };
    Ok(h)
}

/// The most channels along `dim[5]` that are listed and can be chosen; a larger axis is read as before, its first
/// volume only.
const MAX_CHANNELS: i64 = 256;

/// Sets the header's dimensions and time steps from `dim`.
fn read_size(f: &Fields, file: &str, h: &mut Header) -> Result<(), VolumeError> {
    let ndim = f.dim[0];
    if !(1..=7).contains(&ndim) {
        return Err(header_error(
            file,
            format!("dim[0] = {ndim}: the number of dimensions must be 1 to 7"),
        ));
    }
    let dim = &f.dim[1..=ndim as usize];
    h.dims = format::dims_from(file, "dim", dim)?;
    // dim[4] is time: every step is loaded. Higher axes (dim[5..7]) are not: the first of them.
    h.timesteps = dim.get(3).map_or(1, |&t| t.max(1) as u32);
    // dims_from bounds each by u32::MAX, so three of them can overflow an i64.
    // dim[5] holds channels (one is read: nifti::pick_channel), up to MAX_CHANNELS; higher axes only their first.
    let channels = dim.get(4).map_or(1, |&c| c.max(1));
    let listed = channels <= MAX_CHANNELS;
    h.channels = if listed { channels as u32 } else { 1 };
    let skip = if listed { 5 } else { 4 };
    let extra = dim.iter().skip(skip).fold(1i64, |a, &d| a.saturating_mul(d));
    if extra > 1 {
        h.notes.push(format!(
            "{ndim}-D {}: only the first of {extra} groups along dim[{}..{ndim}] is loaded",
            f.format,
            skip + 1
        ));
    }
    Ok(())
}

/// The voxel type of a NIfTI (and Analyze) `datatype` code; the types volcast cannot read are named in the error.
fn voxel_type(format: &'static str, file: &str, datatype: i16) -> Result<VoxelType, VolumeError> {
    Ok(match datatype {
        2 => VoxelType::U8,
        4 => VoxelType::I16,
        8 => VoxelType::I32,
        16 => VoxelType::F32,
        64 => VoxelType::F64,
        256 => VoxelType::I8,
        512 => VoxelType::U16,
        768 => VoxelType::U32,
        other => {
            let name = match other {
                1 => "binary (1 bit)",
                32 => "complex64",
                128 => "rgb24",
                1024 => "int64",
                1280 => "uint64",
                1536 => "float128",
                1792 => "complex128",
                2048 => "complex256",
                2304 => "rgba32",
                _ => "unknown",
            };
            return Err(VolumeError::UnsupportedType {
                file: file.to_string(),
                format,
                given: format!("datatype {other} ({name})"),
            });
        }
    })
}

/// The spacing from pixdim (1 where it is unusable), noting a unit other than mm; sets and returns it.
fn read_spacing(f: &Fields, h: &mut Header) -> [f64; 3] {
    let mut spacing = [1.0f64; 3];
    for (i, s) in spacing.iter_mut().enumerate() {
        if (i as i64) < f.dim[0] {
            let p = f.pixdim[i + 1];
            // pixdim of 0 is common for unused or 2-D axes.
            if p.is_finite() && p != 0.0 {
                *s = p.abs();
            } else {
                h.notes.push(format!("pixdim[{}] is {p}: spacing 1 is used", i + 1));
            }
        }
    }
    h.spacing = spacing;
    let units = match f.xyzt_units & 0x07 {
        1 => Some("m"),
        2 => Some("mm"),
        3 => Some("µm"),
        _ => None,
    };
    if let Some(u) = units.filter(|&u| u != "mm") {
        h.notes
            .push(format!("spacing is in {u}, as the header says (not converted to mm)"));
    }
    spacing
}

/// nibabel's precedence (Nifti1Header.get_best_affine): the sform if its code is set, else the qform, else the
/// "base" affine of an Analyze image; for Analyze, Spm99AnalyzeHeader.get_origin_affine.
fn placement(f: &Fields, file: &str, spacing: [f64; 3], h: &mut Header) -> Result<DMat4, VolumeError> {
    let (affine, from) = match f.placement {
        Placement::Nifti { sform_code, srow, .. } if sform_code > 0 => (geometry::from_rows(srow), "sform"),
        Placement::Nifti {
            qform_code,
            quatern,
            qoffset,
            ..
        } if qform_code > 0 => {
            // pixdim[0] is qfac: −1 negates the third axis; 0 counts as 1 (nifti1.h).
            (geometry::nifti_qform(quatern, f.pixdim[0], spacing, qoffset), "qform")
        }
        Placement::Nifti { .. } => {
            h.notes.push(
                "no qform or sform: placed as nibabel does (pixdim, x flipped as Analyze stores it, centred)".into(),
            );
            let centre = h.dims.map(|d| (f64::from(d) - 1.0) / 2.0);
            (base_affine(spacing, centre), "pixdim")
        }
        Placement::Analyze { origin } => (analyze_affine(f, origin, h), "pixdim"),
    };
    if affine.to_cols_array().iter().any(|v| !v.is_finite()) || DMat3::from_mat4(affine).determinant() == 0.0 {
        return Err(header_error(
            file,
            format!("its {from} gives no valid voxel-to-world affine (not finite, or axes that are zero or parallel)"),
        ));
    }
    Ok(affine)
}

/// Analyze's storage is radiological by convention: x is flipped, and voxel `origin` (0-based) is at world 0.
fn base_affine(zooms: [f64; 3], origin: [f64; 3]) -> DMat4 {
    geometry::from_rows([
        [-zooms[0], 0.0, 0.0, origin[0] * zooms[0]],
        [0.0, zooms[1], 0.0, -origin[1] * zooms[1]],
        [0.0, 0.0, zooms[2], -origin[2] * zooms[2]],
    ])
}

/// nibabel's Spm99AnalyzeHeader.get_origin_affine (which its Spm2AnalyzeImage, what nibabel.load gives for an
/// Analyze .hdr, uses): pixdim as stored (signed; 1 where unusable), x flipped; SPM's 1-based origin voxel at
/// world 0 when it is set and within (−dim, 2·dim) on every axis, else the centre.
fn analyze_affine(f: &Fields, origin: [i16; 3], h: &mut Header) -> DMat4 {
    let zooms = [1, 2, 3].map(|i| {
        let p = f.pixdim[i];
        if p.is_finite() && p != 0.0 {
            p
        } else {
            1.0
        }
    });
    let dims = h.dims.map(f64::from);
    let origin = origin.map(f64::from);
    let usable = origin.iter().any(|&o| o != 0.0) && (0..3).all(|i| origin[i] > -dims[i] && origin[i] < 2.0 * dims[i]);
    let (voxel, placed) = if usable {
        (origin.map(|o| o - 1.0), "SPM's origin voxel at 0")
    } else {
        ([0, 1, 2].map(|i| (dims[i] - 1.0) / 2.0), "centred")
    };
    h.notes.push(format!(
        "Analyze 7.5 records no orientation: placed as nibabel and SPM do (x flipped, as Analyze is usually stored, \
         {placed}); left and right may be swapped"
    ));
    base_affine(zooms, voxel)
}
