//! NIfTI-1 and NIfTI-2 `.nii` and `.nii.gz` (and `.hdr`/`.img` pairs), and Analyze 7.5 `.hdr`/`.img` pairs, either
//! byte order. The three share one reader: only the header's layout differs ([`common`] does the rest).
//!
//! The header is parsed by hand rather than with the `nifti` crate: it is 348 (or 540) fixed-layout bytes, and the
//! crate reads the whole volume into an `ndarray` (the file's bytes plus a converted copy plus a shaped copy), pulls
//! in ndarray/nalgebra/num, and sizes its allocations from the header alone — the opposite of the one-pass,
//! size-checked loading volcast needs for multi-gigabyte and hostile files.

mod analyze;
mod common;
mod nifti2;

use super::decode::{self, DecodeError, Progress};
use super::format::{self, header_error, DataLocation, Encoding, Header, Source};
use crate::volume::{Volume, VolumeError};
use common::{Fields, Placement, Reader};
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

pub(crate) const HEADER_SIZE: usize = 348;

/// True if `prefix` starts with a NIfTI-1 header (sizeof_hdr 348 in either byte order, magic at 344) or a NIfTI-2
/// one (540, magic at 4). Analyze 7.5 has no magic: its `.hdr` name decides.
pub(crate) fn is_nifti(prefix: &[u8]) -> bool {
    let nifti1 = prefix.len() >= HEADER_SIZE
        && common::endian_of(prefix, 348).is_some()
        && (&prefix[344..348] == b"n+1\0" || &prefix[344..348] == b"ni1\0");
    nifti1 || nifti2::is_nifti2(prefix)
}

pub(crate) fn is_gzip(prefix: &[u8]) -> bool {
    prefix.starts_with(&[0x1f, 0x8b])
}

/// Parses the NIfTI-1, NIfTI-2 or Analyze 7.5 header at the start of `bytes`.
pub fn parse_header(bytes: &[u8]) -> Result<Header, VolumeError> {
    parse(bytes, "NIfTI data")
}

/// The header's length, told by sizeof_hdr (348 for NIfTI-1 and Analyze, 540 for NIfTI-2); 348 if it is neither.
fn header_len(bytes: &[u8]) -> usize {
    if common::endian_of(bytes, nifti2::HEADER_SIZE as i32).is_some() {
        nifti2::HEADER_SIZE
    } else {
        HEADER_SIZE
    }
}

/// [`parse`] for a file named `file`: a header without NIfTI-1's magic is Analyze 7.5 only in a `.hdr`, as nibabel
/// has it; in a `.nii` it is a broken NIfTI-1.
pub(crate) fn parse_file(bytes: &[u8], file: &str) -> Result<Header, VolumeError> {
    let header = parse(bytes, file)?;
    if header.format == analyze::FORMAT && !file.to_ascii_lowercase().ends_with(".hdr") {
        return Err(header_error(
            file,
            "not a NIfTI-1 file: the magic is neither 'n+1' nor 'ni1' (a header without it is read as Analyze 7.5 \
             only from a .hdr)"
                .into(),
        ));
    }
    Ok(header)
}

/// Picks the layout by sizeof_hdr and magic: 540 is NIfTI-2; 348 is NIfTI-1 with its magic, else Analyze 7.5.
fn parse(bytes: &[u8], file: &str) -> Result<Header, VolumeError> {
    let err = |problem: String| header_error(file, problem);
    if header_len(bytes) == nifti2::HEADER_SIZE {
        return nifti2::parse(bytes, file);
    }
    if bytes.len() < HEADER_SIZE {
        return Err(err(format!(
            "{} bytes is too short for a NIfTI-1 header (348 bytes)",
            bytes.len()
        )));
    }
    let Some(endian) = common::endian_of(bytes, 348) else {
        return Err(err(
            "not a NIfTI or Analyze file: sizeof_hdr is neither 348 (NIfTI-1, Analyze 7.5) nor 540 (NIfTI-2)".into(),
        ));
    };
    let single_file = match &bytes[344..348] {
        b"n+1\0" => true,
        b"ni1\0" => false,
        _ => return analyze::parse(bytes, endian, file),
    };
    let r = Reader { bytes, endian };
    let fields = Fields {
        format: "NIfTI-1",
        header_size: HEADER_SIZE,
        single_file,
        dim: [0, 1, 2, 3, 4, 5, 6, 7].map(|i| i64::from(r.i16(40 + 2 * i))),
        datatype: r.i16(70),
        pixdim: [76, 80, 84, 88].map(|at| r.f32(at)),
        vox_offset: r.f32(108),
        scaling: common::nifti_scaling(r.f32(112), r.f32(116)),
        xyzt_units: bytes[123],
        placement: Placement::Nifti {
            qform_code: i32::from(r.i16(252)),
            sform_code: i32::from(r.i16(254)),
            quatern: [256, 260, 264].map(|at| r.f32(at)),
            qoffset: [268, 272, 276].map(|at| r.f32(at)),
            srow: [280, 296, 312].map(|at| [0, 1, 2, 3].map(|c| r.f32(at + 4 * c))),
        },
    };
    common::build(&fields, endian, file)
}

/// Loads an uncompressed or gzip-compressed single-file NIfTI-1 or NIfTI-2 held in memory.
pub fn from_bytes(bytes: &[u8]) -> Result<Volume, VolumeError> {
    let file = "NIfTI data";
    if is_gzip(bytes) {
        return load_gzip(
            &mut &bytes[..],
            bytes.len() as u64,
            ("nifti".into(), None),
            file,
            &mut Progress::none(),
        );
    }
    let mut header = parse_header(bytes)?;
    if header.location != DataLocation::Inline(Some(header_offset(&header))) {
        return Err(header_error(
            file,
            format!(
                "a {} .hdr/.img pair needs its .img file, which cannot be read from memory",
                header.format
            ),
        ));
    }
    pick_channel(&mut header, None, file)?;
    format::load(
        header,
        "nifti".into(),
        file,
        Source::Bytes(bytes),
        &mut Progress::none(),
    )
}

/// Moves `h`'s voxels to channel `channel` (default 0) along `dim[5]`: the volumes before it (each its time steps)
/// are skipped. A channel the file lacks is refused, naming the file.
pub(crate) fn pick_channel(h: &mut Header, channel: Option<u32>, file: &str) -> Result<(), VolumeError> {
    let k = channel.unwrap_or(0);
    if k >= h.channels {
        return Err(header_error(
            file,
            format!(
                "channel {k} does not exist: the file has {} channel(s) along dim[5]",
                h.channels
            ),
        ));
    }
    let step = crate::volume::check_dims(h.dims)?;
    let too_far = || header_error(file, format!("channel {k} lies beyond what a file can hold"));
    let shift = [u64::from(h.timesteps.max(1)), h.voxel_type.size() as u64, u64::from(k)]
        .into_iter()
        .try_fold(step, u64::checked_mul)
        .ok_or_else(too_far)?;
    let moved = |o: u64| o.checked_add(shift).ok_or_else(too_far);
    h.location = match &h.location {
        DataLocation::Inline(Some(o)) => DataLocation::Inline(Some(moved(*o)?)),
        DataLocation::Detached { name, skip: Some(o) } => DataLocation::Detached {
            name: name.clone(),
            skip: Some(moved(*o)?),
        },
        other => other.clone(),
    };
    h.channel = k;
    if h.channels > 1 {
        h.notes.push(format!(
            "channel {k} of {} along dim[5]; choose another with --channel",
            h.channels
        ));
    }
    Ok(())
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
    (name, channel): (String, Option<u32>),
    file: &str,
    progress: &mut Progress,
) -> Result<Volume, VolumeError> {
    let mut inflated = flate2::read::MultiGzDecoder::new(BufReader::new(reader));
    let corrupt = |source| VolumeError::Corrupt {
        file: file.to_string(),
        what: "gzip",
        source,
    };
    let mut head = Vec::with_capacity(nifti2::HEADER_SIZE);
    (&mut inflated)
        .take(HEADER_SIZE as u64)
        .read_to_end(&mut head)
        .map_err(corrupt)?;
    // A NIfTI-2 header is longer; its first bytes say so.
    let rest = header_len(&head) - HEADER_SIZE;
    (&mut inflated)
        .take(rest as u64)
        .read_to_end(&mut head)
        .map_err(corrupt)?;
    let mut header = parse_file(&head, file)?;
    pick_channel(&mut header, channel, file)?;
    let offset = header_offset(&header);
    if offset == u64::MAX {
        return Err(header_error(
            file,
            format!(
                "a compressed {} must be a single file ('n+1' or 'n+2'), not a .hdr/.img pair",
                header.format
            ),
        ));
    }
    // Skip the extensions between the header and the voxels.
    let skip = offset - head.len() as u64;
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
    let step = crate::volume::check_dims(header.dims)?;
    crate::volume::time::check_series_memory(file, header.timesteps, step * header.voxel_type.size() as u64)?;
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

/// Loads a NIfTI or Analyze file, channel `channel` (default 0) of one with a fifth axis.
pub(crate) fn load(path: &Path, channel: Option<u32>, progress: &mut Progress) -> Result<Volume, VolumeError> {
    let file = format::file_label(path);
    let prefix = format::read_prefix(path, nifti2::HEADER_SIZE)?;
    let name = format::volume_name(path);
    if is_gzip(&prefix) {
        let io = |source| VolumeError::Io {
            path: path.to_path_buf(),
            source,
        };
        let len = std::fs::metadata(path).map_err(io)?.len();
        let mut f = File::open(path).map_err(io)?;
        return load_gzip(&mut f, len, (name, channel), &file, progress);
    }
    let mut header = parse_file(&prefix, &file)?;
    pick_channel(&mut header, channel, &file)?;
    let mut data_file = file;
    if let DataLocation::Detached { skip, .. } = header.location {
        // A .hdr/.img pair: the voxels are in the .img beside the header, which the errors from here on name (the
        // caller adds the header's path).
        data_file = format::file_label(&path.with_extension("img"));
        header.location = DataLocation::Detached {
            name: data_file.clone(),
            skip,
        };
    }
    format::load(header, name, &data_file, Source::File(path), progress)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::volume::{VoxelData, VoxelType};

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
    fn four_d_loads_every_step_and_five_d_its_first_channel() {
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
            v.notes.iter().any(|n| n.contains("channel 0 of 2 along dim[5]")) && v.channels.len() == 2,
            "{:?}",
            v.notes
        );
        // A sixth axis: its first group only.
        let v = from_bytes(&nifti_bytes(
            &[6, 2, 2, 1, 4, 1, 2],
            2,
            [1.0; 3],
            (0.0, 0.0),
            false,
            &data,
        ))
        .unwrap();
        assert!(
            v.notes
                .iter()
                .any(|n| n.contains("only the first of 2 groups along dim[6..6]")),
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
        let huge = nifti_bytes(&[3, 16000, 16000, 300], 2, [1.0; 3], (1.0, 0.0), false, &[1; 8]);
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
        assert!(
            e(&b).contains("360 bytes is too short for a NIfTI-2 header (540 bytes)"),
            "{}",
            e(&b)
        );
        b.resize(600, 0);
        assert!(
            e(&b).contains("not a NIfTI-2 file: the magic is neither 'n+2' nor 'ni2'"),
            "{}",
            e(&b)
        );
        let mut b = ok.clone();
        b[0..4].copy_from_slice(&347i32.to_le_bytes());
        assert!(e(&b).contains("sizeof_hdr is neither 348"), "{}", e(&b));
        // Without NIfTI-1's magic a 348-byte header is Analyze 7.5, whose voxels are always in a separate .img.
        let mut b = ok.clone();
        b[344..348].copy_from_slice(b"\0\0\0\0");
        assert!(e(&b).contains("cannot be read from memory"), "{}", e(&b));
        assert_eq!(parse_header(&b).unwrap().format, "Analyze 7.5");
        let mut b = ok.clone();
        b[80..84].copy_from_slice(&f32::NAN.to_le_bytes());
        let v = from_bytes(&b).unwrap();
        assert_eq!(v.spacing()[0], 1.0);
        assert!(v.notes.iter().any(|n| n.contains("pixdim[1] is NaN")));
    }
}
