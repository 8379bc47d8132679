//! NIfTI-1 `.nii` and `.nii.gz` (and `.hdr`/`.img` pairs), either byte order.
//!
//! The header is parsed by hand rather than with the `nifti` crate: it is 348 fixed-layout bytes, and the crate
//! reads the whole volume into an `ndarray` (the file's bytes plus a converted copy plus a shaped copy), pulls in
//! ndarray/nalgebra/num, and sizes its allocations from the header alone — the opposite of the one-pass,
//! size-checked loading volcast needs for multi-gigabyte and hostile files.

use super::decode::{self, DecodeError, Endian, Progress};
use super::format::{self, header_error, DataLocation, Encoding, Header, Source};
use super::geometry::{self, Geometry};
use super::{Scaling, Volume, VolumeError, VoxelType};
use glam::{DMat3, DMat4};
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

const FORMAT: &str = "NIfTI-1";
pub(crate) const HEADER_SIZE: usize = 348;

/// True if `prefix` starts with a NIfTI-1 header (sizeof_hdr 348 in either byte order, magic at 344).
pub(crate) fn is_nifti(prefix: &[u8]) -> bool {
    prefix.len() >= HEADER_SIZE
        && (prefix[..4] == 348i32.to_le_bytes() || prefix[..4] == 348i32.to_be_bytes())
        && (&prefix[344..348] == b"n+1\0" || &prefix[344..348] == b"ni1\0")
}

pub(crate) fn is_gzip(prefix: &[u8]) -> bool {
    prefix.starts_with(&[0x1f, 0x8b])
}

struct Fields<'a> {
    bytes: &'a [u8],
    endian: Endian,
}

impl Fields<'_> {
    fn i16(&self, at: usize) -> i16 {
        let b = [self.bytes[at], self.bytes[at + 1]];
        match self.endian {
            Endian::Little => i16::from_le_bytes(b),
            Endian::Big => i16::from_be_bytes(b),
        }
    }

    fn f32(&self, at: usize) -> f32 {
        let mut b = [0u8; 4];
        b.copy_from_slice(&self.bytes[at..at + 4]);
        match self.endian {
            Endian::Little => f32::from_le_bytes(b),
            Endian::Big => f32::from_be_bytes(b),
        }
    }
}

/// Parses the 348-byte NIfTI-1 header at the start of `bytes`.
pub fn parse_header(bytes: &[u8]) -> Result<Header, VolumeError> {
    parse(bytes, "NIfTI data")
}

pub(crate) fn parse(bytes: &[u8], file: &str) -> Result<Header, VolumeError> {
    let err = |problem: String| header_error(file, problem);
    let endian = byte_order(bytes, file)?;
    let magic = &bytes[344..348];
    let single_file = match magic {
        b"n+1\0" => true,
        b"ni1\0" => false,
        _ => return Err(err("not a NIfTI-1 file: the magic is neither 'n+1' nor 'ni1'".into())),
    };
    let f = Fields { bytes, endian };
    let mut h = Header::new(FORMAT);
    h.endian = endian;
    let ndim = read_size(&f, file, &mut h)?;
    h.voxel_type = voxel_type(file, f.i16(70))?;
    let spacing = read_spacing(&f, ndim, &mut h);
    let vox_offset = f.f32(108);
    if !(0.0..1e12).contains(&vox_offset) {
        return Err(err(format!("vox_offset {vox_offset} is not a valid byte offset")));
    }
    let vox_offset = vox_offset as u64;
    if single_file && vox_offset < HEADER_SIZE as u64 {
        return Err(err(format!(
            "vox_offset {vox_offset} points inside the 348-byte header"
        )));
    }
    let (slope, intercept) = (f64::from(f.f32(112)), f64::from(f.f32(116)));
    // The standard: scl_slope == 0 means no scaling; non-finite values are treated the same.
    if slope != 0.0 && slope.is_finite() && intercept.is_finite() && (slope != 1.0 || intercept != 0.0) {
        h.scaling = Scaling { slope, intercept };
    }
    let affine = best_affine(&f, file, spacing, &mut h)?;
    h.geometry = Some(Geometry::anatomical(affine));
    h.spacing = Geometry::anatomical(affine).spacing();
    h.location = if single_file {
        DataLocation::Inline(Some(vox_offset))
    } else {
        DataLocation::Detached {
            name: String::new(),
            skip: Some(vox_offset),
        }
    };
    Ok(h)
}

/// The byte order that makes sizeof_hdr 348; refuses short headers, NIfTI-2 and other files.
fn byte_order(bytes: &[u8], file: &str) -> Result<Endian, VolumeError> {
    let err = |problem: String| header_error(file, problem);
    if bytes.len() < HEADER_SIZE {
        return Err(err(format!(
            "{} bytes is too short for a NIfTI-1 header (348 bytes)",
            bytes.len()
        )));
    }
    if bytes[..4] == 348i32.to_le_bytes() {
        Ok(Endian::Little)
    } else if bytes[..4] == 348i32.to_be_bytes() {
        Ok(Endian::Big)
    } else if bytes[..4] == 540i32.to_le_bytes() || bytes[..4] == 540i32.to_be_bytes() {
        Err(err(
            "NIfTI-2 is not supported; convert to NIfTI-1 (e.g. nibabel, c3d)".into()
        ))
    } else {
        Err(err("not a NIfTI-1 file: sizeof_hdr is not 348".into()))
    }
}

/// Sets the header's dimensions and time steps from `dim`; returns dim[0], the number of dimensions.
fn read_size(f: &Fields, file: &str, h: &mut Header) -> Result<i16, VolumeError> {
    let ndim = f.i16(40);
    if !(1..=7).contains(&ndim) {
        return Err(header_error(
            file,
            format!("dim[0] = {ndim}: the number of dimensions must be 1 to 7"),
        ));
    }
    let dim: Vec<i64> = (1..=ndim as usize).map(|i| i64::from(f.i16(40 + 2 * i))).collect();
    h.dims = format::dims_from(file, "dim", &dim)?;
    // dim[4] is time: every step is loaded. Higher axes (dim[5..7]) are not: the first of them.
    h.timesteps = dim.get(3).map_or(1, |&t| t.max(1) as u32);
    let extra: i64 = dim.iter().skip(4).product();
    if extra > 1 {
        h.notes.push(format!(
            "{ndim}-D NIfTI: only the first of {extra} groups along dim[5..{ndim}] is loaded"
        ));
    }
    Ok(ndim)
}

/// The voxel type of a NIfTI `datatype` code; the types volcast cannot read are named in the error.
fn voxel_type(file: &str, datatype: i16) -> Result<VoxelType, VolumeError> {
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
                format: FORMAT,
                given: format!("datatype {other} ({name})"),
            });
        }
    })
}

/// The spacing from pixdim (1 where it is unusable), noting a unit other than mm; sets and returns it.
fn read_spacing(f: &Fields, ndim: i16, h: &mut Header) -> [f64; 3] {
    let mut spacing = [1.0f64; 3];
    for (i, s) in spacing.iter_mut().enumerate() {
        if i < ndim as usize {
            let p = f64::from(f.f32(80 + 4 * i));
            // pixdim of 0 is common for unused or 2-D axes.
            if p.is_finite() && p != 0.0 {
                *s = p.abs();
            } else {
                h.notes.push(format!("pixdim[{}] is {p}: spacing 1 is used", i + 1));
            }
        }
    }
    h.spacing = spacing;
    let units = match f.bytes[123] & 0x07 {
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
/// "base" affine of an Analyze image: pixdim with x flipped (radiological storage), centred on the volume.
fn best_affine(f: &Fields, file: &str, spacing: [f64; 3], h: &mut Header) -> Result<DMat4, VolumeError> {
    let (qform, sform) = (f.i16(252), f.i16(254));
    let affine = if sform > 0 {
        let row = |at: usize| [0, 1, 2, 3].map(|c| f64::from(f.f32(at + 4 * c)));
        geometry::from_rows([row(280), row(296), row(312)])
    } else if qform > 0 {
        let quaternion = [256, 260, 264].map(|at| f64::from(f.f32(at)));
        let offset = [268, 272, 276].map(|at| f64::from(f.f32(at)));
        // pixdim[0] is qfac: −1 negates the third axis; 0 counts as 1 (nifti1.h).
        let qfac = f64::from(f.f32(76));
        geometry::nifti_qform(quaternion, qfac, spacing, offset)
    } else {
        h.notes
            .push("no qform or sform: placed as nibabel does (pixdim, x flipped as Analyze stores it, centred)".into());
        let centre = h.dims.map(|d| (f64::from(d) - 1.0) / 2.0);
        geometry::from_rows([
            [-spacing[0], 0.0, 0.0, centre[0] * spacing[0]],
            [0.0, spacing[1], 0.0, -centre[1] * spacing[1]],
            [0.0, 0.0, spacing[2], -centre[2] * spacing[2]],
        ])
    };
    if affine.to_cols_array().iter().any(|v| !v.is_finite()) || DMat3::from_mat4(affine).determinant() == 0.0 {
        return Err(header_error(
            file,
            format!(
                "its {} gives no valid voxel-to-world affine (not finite, or axes that are zero or parallel)",
                if sform > 0 { "sform" } else { "qform" }
            ),
        ));
    }
    Ok(affine)
}

/// Loads an uncompressed or gzip-compressed single-file NIfTI-1 held in memory.
pub fn from_bytes(bytes: &[u8]) -> Result<Volume, VolumeError> {
    let file = "NIfTI data";
    if is_gzip(bytes) {
        return load_gzip(
            &mut &bytes[..],
            bytes.len() as u64,
            "nifti".into(),
            file,
            &mut Progress::none(),
        );
    }
    let header = parse_header(bytes)?;
    if header.location != DataLocation::Inline(Some(header_offset(&header))) {
        return Err(header_error(
            file,
            "a 'ni1' header needs its .img file, which cannot be read from memory".into(),
        ));
    }
    format::load(
        header,
        "nifti".into(),
        file,
        Source::Bytes(bytes),
        &mut Progress::none(),
    )
}

fn header_offset(h: &Header) -> u64 {
    match h.location {
        DataLocation::Inline(Some(o)) => o,
        _ => u64::MAX,
    }
}

/// `.nii.gz`: the header is inside the gzip stream and the voxels follow it at `vox_offset` of the inflated
/// bytes, so the stream is read once, front to back.
fn load_gzip(
    reader: &mut dyn Read,
    compressed_len: u64,
    name: String,
    file: &str,
    progress: &mut Progress,
) -> Result<Volume, VolumeError> {
    let mut inflated = flate2::read::MultiGzDecoder::new(BufReader::new(reader));
    let corrupt = |source| VolumeError::Corrupt {
        file: file.to_string(),
        what: "gzip",
        source,
    };
    let mut head = Vec::with_capacity(HEADER_SIZE);
    (&mut inflated)
        .take(HEADER_SIZE as u64)
        .read_to_end(&mut head)
        .map_err(corrupt)?;
    let mut header = parse(&head, file)?;
    let offset = header_offset(&header);
    if offset == u64::MAX {
        return Err(header_error(
            file,
            "a compressed NIfTI must be single-file ('n+1')".into(),
        ));
    }
    // Skip the extensions between the header and the voxels.
    let skip = offset - HEADER_SIZE as u64;
    if skip > compressed_len.saturating_mul(1032) {
        return Err(header_error(
            file,
            format!("vox_offset {offset} is beyond what {compressed_len} compressed bytes can hold"),
        ));
    }
    let skipped = std::io::copy(&mut (&mut inflated).take(skip), &mut std::io::sink()).map_err(corrupt)?;
    if skipped < skip {
        return Err(header_error(file, format!("the file ends before vox_offset {offset}")));
    }
    let step = super::check_dims(header.dims)?;
    super::time::check_series_memory(file, header.timesteps, step * header.voxel_type.size() as u64)?;
    let count = step * u64::from(header.timesteps.max(1));
    let needed = count * header.voxel_type.size() as u64;
    // The claim is checked against what the compressed bytes can hold before the output is allocated.
    header.encoding = Encoding::Gzip;
    format::check_compressed(&header, file, compressed_len, needed)?;
    header.encoding = Encoding::Raw;
    let (t, e) = (header.voxel_type, header.endian);
    let data = decode::read_binary(&mut inflated, t, e, count as usize, decode::CHUNK_BYTES, progress).map_err(
        |err| match err {
            DecodeError::Truncated { got } => VolumeError::Truncated {
                file: file.to_string(),
                actual: got,
                expected: needed,
                dims: header.dims,
                voxel_type: t,
            },
            DecodeError::OutOfMemory => VolumeError::OutOfMemory {
                dims: header.dims,
                bytes: needed,
            },
            DecodeError::Io(source) => corrupt(source),
            DecodeError::BadValue { .. } => header_error(file, "unexpected ASCII value in binary data".into()),
        },
    )?;
    header.into_volume(name, data)
}

pub(crate) fn load(path: &Path, progress: &mut Progress) -> Result<Volume, VolumeError> {
    let file = format::file_label(path);
    let prefix = format::read_prefix(path, HEADER_SIZE)?;
    let name = format::volume_name(path);
    if is_gzip(&prefix) {
        let io = |source| VolumeError::Io {
            path: path.to_path_buf(),
            source,
        };
        let len = std::fs::metadata(path).map_err(io)?.len();
        let mut f = File::open(path).map_err(io)?;
        return load_gzip(&mut f, len, name, &file, progress);
    }
    let mut header = parse(&prefix, &file)?;
    if let DataLocation::Detached { skip, .. } = header.location {
        // A .hdr/.img pair: the voxels are in the .img beside the header.
        let img = path.with_extension("img");
        header.location = DataLocation::Detached {
            name: format::file_label(&img),
            skip,
        };
    }
    format::load(header, name, &file, Source::File(path), progress)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::volume::VoxelData;

    /// A minimal NIfTI-1 header + data, for tests here and in the fuzz seeds.
    pub(crate) fn nifti_bytes(
        dims: &[i16],
        datatype: i16,
        pixdim: [f32; 3],
        slope_inter: (f32, f32),
        big_endian: bool,
        data: &[u8],
    ) -> Vec<u8> {
        let mut h = vec![0u8; 352];
        let put16 = |h: &mut Vec<u8>, at: usize, v: i16| {
            let b = if big_endian { v.to_be_bytes() } else { v.to_le_bytes() };
            h[at..at + 2].copy_from_slice(&b);
        };
        let put32 = |h: &mut Vec<u8>, at: usize, b4: [u8; 4], be: [u8; 4]| {
            h[at..at + 4].copy_from_slice(if big_endian { &be } else { &b4 });
        };
        put32(&mut h, 0, 348i32.to_le_bytes(), 348i32.to_be_bytes());
        // dims[0] is the number of dimensions, as in the header.
        for (i, &d) in dims.iter().enumerate() {
            put16(&mut h, 40 + 2 * i, d);
        }
        put16(&mut h, 70, datatype);
        for (i, p) in pixdim.iter().enumerate() {
            put32(&mut h, 80 + 4 * i, p.to_le_bytes(), p.to_be_bytes());
        }
        put32(&mut h, 108, 352f32.to_le_bytes(), 352f32.to_be_bytes());
        put32(&mut h, 112, slope_inter.0.to_le_bytes(), slope_inter.0.to_be_bytes());
        put32(&mut h, 116, slope_inter.1.to_le_bytes(), slope_inter.1.to_be_bytes());
        h[123] = 2;
        h[344..348].copy_from_slice(b"n+1\0");
        h.extend_from_slice(data);
        h
    }

    fn gzip(data: &[u8]) -> Vec<u8> {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        e.write_all(data).unwrap();
        e.finish().unwrap()
    }

    #[test]
    fn both_byte_orders_scaling_and_gzip() {
        let values: [i16; 6] = [-3, 0, 7, 100, -32768, 32767];
        for big in [false, true] {
            let data: Vec<u8> = values
                .iter()
                .flat_map(|v| if big { v.to_be_bytes() } else { v.to_le_bytes() })
                .collect();
            let bytes = nifti_bytes(&[3, 2, 1, 3], 4, [0.5, 2.0, 3.0], (2.0, -10.0), big, &data);
            for b in [bytes.clone(), gzip(&bytes)] {
                let v = from_bytes(&b).unwrap();
                assert_eq!(v.dims, [2, 1, 3]);
                assert_eq!(v.spacing(), [0.5, 2.0, 3.0]);
                assert_eq!(v.source_type, VoxelType::I16);
                assert!(matches!(v.data, VoxelData::U16(_)));
                assert_eq!(v.stored(0, 0, 0), -3.0);
                assert_eq!(v.value(0, 0, 0), -16.0);
                assert_eq!(v.value(1, 0, 1), 190.0);
                assert_eq!(v.stored_range, [-32768.0, 32767.0]);
                assert_eq!(v.range, [-65546.0, 65524.0]);
                assert_eq!(v.format, "NIfTI-1");
            }
        }
    }

    #[test]
    fn four_d_loads_every_step_and_five_d_the_first_group() {
        let data: Vec<u8> = (0..16).collect();
        let mut v = from_bytes(&nifti_bytes(&[4, 2, 2, 1, 4], 2, [1.0; 3], (0.0, 0.0), false, &data)).unwrap();
        assert_eq!((v.dims, v.timesteps()), ([2, 2, 1], 4));
        assert_eq!((v.value(1, 1, 0), v.stored_range), (3.0, [0.0, 15.0]));
        v.show_step(3).unwrap();
        assert_eq!(v.value(1, 1, 0), 15.0);
        let data: Vec<u8> = (0..32).collect();
        let v = from_bytes(&nifti_bytes(&[5, 2, 2, 1, 4, 2], 2, [1.0; 3], (0.0, 0.0), false, &data)).unwrap();
        assert_eq!((v.timesteps(), v.stored_range), (4, [0.0, 15.0]));
        assert!(
            v.notes
                .iter()
                .any(|n| n.contains("only the first of 2 groups along dim[5..5]")),
            "{:?}",
            v.notes
        );
        assert!(v.scaling.is_identity());
    }

    #[test]
    fn hostile_headers() {
        let ok = nifti_bytes(&[3, 2, 2, 2], 2, [1.0; 3], (1.0, 0.0), false, &[1; 8]);
        let e = |b: &[u8]| from_bytes(b).unwrap_err().to_string();
        let mut b = ok.clone();
        b[44] = 0;
        assert!(e(&b).contains("zero or negative size"), "{}", e(&b));
        b[44..46].copy_from_slice(&(-5i16).to_le_bytes());
        assert!(e(&b).contains("zero or negative size"), "{}", e(&b));
        let big = nifti_bytes(&[3, 30000, 30000, 30000], 2, [1.0; 3], (1.0, 0.0), false, &[1; 8]);
        assert!(e(&big).contains("exceed the limit"), "{}", e(&big));
        let huge = nifti_bytes(&[3, 16000, 16000, 9], 2, [1.0; 3], (1.0, 0.0), false, &[1; 8]);
        assert!(e(&huge).contains("more than the limit"), "{}", e(&huge));
        let many = nifti_bytes(&[3, 1000, 1000, 1000], 2, [1.0; 3], (1.0, 0.0), false, &[1; 8]);
        assert!(
            e(&many).contains("the voxel data end after 8 of the 1000000000 bytes"),
            "{}",
            e(&many)
        );
        assert!(
            e(&gzip(&many)).contains("bytes of gzip data cannot hold"),
            "{}",
            e(&gzip(&many))
        );
        let cplx = nifti_bytes(&[3, 2, 2, 2], 32, [1.0; 3], (1.0, 0.0), false, &[1; 64]);
        assert!(e(&cplx).contains("datatype 32 (complex64)"), "{}", e(&cplx));
        assert!(e(&ok[..8]).contains("too short"));
        assert!(
            e(&ok[..353]).contains("end after 1 of the 8 bytes"),
            "{}",
            e(&ok[..353])
        );
        let gz = gzip(&ok);
        assert!(
            e(&gz[..gz.len() - 12]).contains("gzip data is corrupt") || e(&gz[..gz.len() - 12]).contains("end after")
        );
        let mut bad_gz = gz.clone();
        bad_gz[12] ^= 0xff;
        assert!(
            e(&bad_gz).contains("corrupt") || e(&bad_gz).contains("NIfTI"),
            "{}",
            e(&bad_gz)
        );
        let mut b = ok.clone();
        b[108..112].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(e(&b).contains("vox_offset NaN"), "{}", e(&b));
        let mut b = ok.clone();
        b[0..4].copy_from_slice(&540i32.to_le_bytes());
        assert!(e(&b).contains("NIfTI-2 is not supported"));
        let mut b = ok.clone();
        b[80..84].copy_from_slice(&f32::NAN.to_le_bytes());
        let v = from_bytes(&b).unwrap();
        assert_eq!(v.spacing()[0], 1.0);
        assert!(v.notes.iter().any(|n| n.contains("pixdim[1] is NaN")));
    }
}
