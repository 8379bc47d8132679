//! Headerless raw files (little-endian unless told otherwise), named in the open-scivis convention
//! `NAME_WxHxD_TYPE.raw`.

use super::decode::{self, DecodeError, Endian, Progress};
use crate::volume::{check_dims, check_spacing, MissingLayout, Volume, VolumeError, VoxelType};
use std::fs::File;
use std::path::Path;

/// Layout a user gives explicitly; anything left `None` comes from the file name.
#[derive(Clone, Debug, Default)]
pub struct RawOptions {
    pub dims: Option<[u32; 3]>,
    pub voxel_type: Option<VoxelType>,
    /// Defaults to 1 on every axis.
    pub spacing: Option<[f32; 3]>,
}

/// What else a raw file may need ([`super::OpenOptions`] carries these; kept out of [`RawOptions`] so code that
/// builds one by its three fields keeps compiling).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct RawExtras {
    pub endian: Endian,
    pub header_bytes: u64,
}

/// The parts of `NAME_WxHxD_TYPE[.ext]` with TYPE still unparsed, so a caller can tell "not this pattern" from
/// "this pattern with a type we don't support".
fn split_scivis_name(file_name: &str) -> Option<(String, [u32; 3], &str)> {
    // Accept a path too: only the last component names the volume.
    let base = file_name.rsplit(['/', '\\']).next().unwrap_or(file_name);
    let (rest, type_and_ext) = base.rsplit_once('_')?;
    let (name, dims_text) = rest.rsplit_once('_')?;
    // The type ends at the first dot: "uint8.raw" and a bare "uint8" both work.
    let type_text = type_and_ext.split('.').next().unwrap_or(type_and_ext);
    if name.is_empty() || type_text.is_empty() {
        return None;
    }
    let mut parts = dims_text.split(['x', 'X']);
    let mut dims = [0u32; 3];
    for d in &mut dims {
        let text = parts.next()?;
        // `u32::from_str` accepts a leading '+'; a file name with one is not this pattern.
        if text.is_empty() || !text.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        *d = text.parse().ok()?;
    }
    if parts.next().is_some() {
        return None;
    }
    Some((name.to_string(), dims, type_text))
}

/// Parses the open-scivis naming NAME_WxHxD_TYPE.raw, e.g. "skull_256x256x256_uint8.raw" -> ("skull",[256,256,256],U8).
/// Takes a file name or path (uses the file name part). None if it doesn't match or TYPE is unknown.
/// Dimensions are returned as written (even 0); [`Volume::new`] judges them.
pub fn parse_scivis_name(file_name: &str) -> Option<(String, [u32; 3], VoxelType)> {
    let (name, dims, type_text) = split_scivis_name(file_name)?;
    Some((name, dims, VoxelType::parse(type_text)?))
}

/// Headerless little-endian raw file; dims/type from `opts`, else from the file name; spacing default 1.
///
/// The file's size is checked against dims × type before anything is allocated or read.
pub fn load_raw(path: &Path, opts: &RawOptions) -> Result<Volume, VolumeError> {
    load_raw_with_progress(path, opts, RawExtras::default(), &mut Progress::none())
}

pub(crate) fn load_raw_with_progress(
    path: &Path,
    opts: &RawOptions,
    extras: RawExtras,
    progress: &mut Progress,
) -> Result<Volume, VolumeError> {
    let file_name = match path.file_name() {
        Some(n) => n.to_string_lossy().into_owned(),
        None => path.display().to_string(),
    };
    let (name, dims, voxel_type) = layout(path, &file_name, opts)?;
    let spacing = opts.spacing.unwrap_or([1.0; 3]);
    let (count, expected) = sizes(dims, voxel_type, spacing)?;
    check_file_size(path, &file_name, extras, dims, voxel_type, expected)?;

    let io_error = |source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = File::open(path).map_err(io_error)?;
    let (offset, endian) = (extras.header_bytes, extras.endian);
    let data = decode::read_file_at(&file, offset, voxel_type, endian, count, progress).map_err(|e| match e {
        DecodeError::Io(source) => io_error(source),
        DecodeError::OutOfMemory => VolumeError::OutOfMemory { dims, bytes: expected },
        // The size was checked, so only a file that shrank while being read gets here.
        DecodeError::Truncated { got } => VolumeError::Truncated {
            file: file_name.clone(),
            actual: got,
            expected,
            dims,
            voxel_type,
        },
        DecodeError::BadValue { .. } => VolumeError::NotAFile {
            path: path.to_path_buf(),
        },
    })?;
    let mut volume = Volume::new(name, dims, spacing, voxel_type, data)?;
    volume.format = "raw".into();
    Ok(volume)
}

/// The volume's name, dimensions and voxel type: from `opts` where given, else from the file name.
pub(crate) fn layout(
    path: &Path,
    file_name: &str,
    opts: &RawOptions,
) -> Result<(String, [u32; 3], VoxelType), VolumeError> {
    let from_name = split_scivis_name(file_name);
    let dims = opts.dims.or(from_name.as_ref().map(|(_, dims, _)| *dims));
    let voxel_type = match (opts.voxel_type, &from_name) {
        (Some(t), _) => Some(t),
        (None, Some((_, _, type_text))) => {
            Some(
                VoxelType::parse(type_text).ok_or_else(|| VolumeError::UnknownTypeInName {
                    file: file_name.to_string(),
                    given: type_text.to_string(),
                })?,
            )
        }
        (None, None) => None,
    };
    let (dims, voxel_type) = match (dims, voxel_type) {
        (Some(d), Some(t)) => (d, t),
        (d, t) => {
            let missing = match (d, t) {
                (None, None) => MissingLayout::Both,
                (None, _) => MissingLayout::Dims,
                _ => MissingLayout::VoxelType,
            };
            return Err(VolumeError::MissingLayout {
                file: file_name.to_string(),
                missing,
            });
        }
    };
    let name = match from_name {
        Some((name, _, _)) => name,
        None => path
            .file_stem()
            .map_or_else(|| file_name.to_string(), |s| s.to_string_lossy().into_owned()),
    };
    Ok((name, dims, voxel_type))
}

/// Checks dimensions and spacing; returns the voxel count and the data's bytes, both addressable on this host.
pub(crate) fn sizes(dims: [u32; 3], voxel_type: VoxelType, spacing: [f32; 3]) -> Result<(usize, u64), VolumeError> {
    let count = check_dims(dims)?;
    check_spacing(dims, spacing)?;
    let too_large = || VolumeError::TooLarge {
        dims,
        voxel_type,
        bytes: count.saturating_mul(voxel_type.size() as u64),
    };
    let expected = count.checked_mul(voxel_type.size() as u64).ok_or_else(too_large)?;
    // On a 32-bit host a legal volume can still be unaddressable.
    let count_usize = usize::try_from(count).map_err(|_| too_large())?;
    usize::try_from(expected).map_err(|_| too_large())?;
    Ok((count_usize, expected))
}

/// The file must be a plain file of exactly the header plus `expected` bytes, checked before anything is read.
pub(crate) fn check_file_size(
    path: &Path,
    file_name: &str,
    extras: RawExtras,
    dims: [u32; 3],
    voxel_type: VoxelType,
    expected: u64,
) -> Result<(), VolumeError> {
    let metadata = std::fs::metadata(path).map_err(|source| VolumeError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if !metadata.is_file() {
        return Err(VolumeError::NotAFile {
            path: path.to_path_buf(),
        });
    }
    if metadata.len().checked_sub(extras.header_bytes) == Some(expected) {
        return Ok(());
    }
    if extras.header_bytes > 0 {
        return Err(VolumeError::Header {
            file: file_name.to_string(),
            problem: format!(
                "the file is {} bytes but a {}-byte header plus {}x{}x{} {voxel_type} needs {}",
                metadata.len(),
                extras.header_bytes,
                dims[0],
                dims[1],
                dims[2],
                u128::from(extras.header_bytes) + u128::from(expected)
            ),
        });
    }
    Err(VolumeError::SizeMismatch {
        file: file_name.to_string(),
        actual: metadata.len(),
        dims,
        voxel_type,
        expected,
    })
}

/// Voxels of `voxel_type` in the host's byte order, x fastest (the bytes of a C-ordered numpy array of shape
/// (z, y, x)), as a volume: the conversion a raw file of the same bytes gets, so both render alike. Named `name`,
/// format "array".
pub fn from_native_bytes(
    name: &str,
    dims: [u32; 3],
    voxel_type: VoxelType,
    spacing: [f32; 3],
    bytes: &[u8],
) -> Result<Volume, VolumeError> {
    let (count, expected) = sizes(dims, voxel_type, spacing)?;
    if bytes.len() as u64 != expected {
        return Err(VolumeError::DataLength {
            dims,
            expected: count as u64,
            actual: bytes.len() / voxel_type.size(),
        });
    }
    let endian = Endian::NATIVE;
    let mut reader = bytes;
    let data =
        decode::read_binary(&mut reader, voxel_type, endian, count, 64 << 20, &mut Progress::none()).map_err(|e| {
            match e {
                DecodeError::OutOfMemory => VolumeError::OutOfMemory { dims, bytes: expected },
                _ => VolumeError::DataLength {
                    dims,
                    expected: count as u64,
                    actual: bytes.len() / voxel_type.size(),
                },
            }
        })?;
    let mut volume = Volume::new(name, dims, spacing, voxel_type, data)?;
    volume.format = "array".into();
    Ok(volume)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelData;
    use std::path::PathBuf;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A fresh directory under the system temp dir, removed on drop. Unique per process and per test so
    /// parallel tests (and parallel `cargo test` runs) never share files.
    struct TempDir(PathBuf);

    impl TempDir {
        fn new() -> TempDir {
            static NEXT: AtomicUsize = AtomicUsize::new(0);
            let n = NEXT.fetch_add(1, Ordering::Relaxed);
            let path = std::env::temp_dir().join(format!("volcast-raw-test-{}-{n}", std::process::id()));
            std::fs::create_dir_all(&path).expect("create temp dir");
            TempDir(path)
        }

        fn write(&self, name: &str, bytes: &[u8]) -> PathBuf {
            let path = self.0.join(name);
            std::fs::write(&path, bytes).expect("write temp file");
            path
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn load(dir: &TempDir, name: &str, bytes: &[u8]) -> Result<Volume, VolumeError> {
        load_raw(&dir.write(name, bytes), &RawOptions::default())
    }

    #[test]
    fn scivis_names() {
        assert_eq!(
            parse_scivis_name("skull_256x256x256_uint8.raw"),
            Some(("skull".to_string(), [256, 256, 256], VoxelType::U8))
        );
        assert_eq!(
            parse_scivis_name("/data/raw/cranium_ct_256x256x108_int16.raw"),
            Some(("cranium_ct".to_string(), [256, 256, 108], VoxelType::I16))
        );
        assert_eq!(
            parse_scivis_name("dwi_s0_10slices_128x128x10_uint16.raw"),
            Some(("dwi_s0_10slices".to_string(), [128, 128, 10], VoxelType::U16))
        );
        assert_eq!(
            parse_scivis_name(r"C:\data\motor_zmap_53x63x46_float32.raw"),
            Some(("motor_zmap".to_string(), [53, 63, 46], VoxelType::F32))
        );
        assert_eq!(
            parse_scivis_name("a_1X2x3_DOUBLE.RAW"),
            Some(("a".to_string(), [1, 2, 3], VoxelType::F64))
        );
        assert_eq!(
            parse_scivis_name("a_1x2x3_float"),
            Some(("a".to_string(), [1, 2, 3], VoxelType::F32))
        );
        // Zero is a match; Volume::new rejects it with its own message.
        assert_eq!(
            parse_scivis_name("a_0x2x3_u8.raw"),
            Some(("a".to_string(), [0, 2, 3], VoxelType::U8))
        );

        for bad in [
            "skull.raw",
            "skull_256x256_uint8.raw",
            "skull_256x256x256x2_uint8.raw",
            "skull_256x256x256.raw",
            "_256x256x256_uint8.raw",
            "skull_256x256x256_.raw",
            "skull_axbxc_uint8.raw",
            "skull_256x+256x256_uint8.raw",
            "skull_256x256x_uint8.raw",
            "skull_256x256x256_int64.raw",
            "skull_99999999999x1x1_uint8.raw",
            "",
        ] {
            assert_eq!(parse_scivis_name(bad), None, "{bad}");
        }
    }

    #[test]
    fn loads_uint8() {
        let dir = TempDir::new();
        let bytes: Vec<u8> = (0..24).map(|i| i * 10).collect();
        let v = load(&dir, "ramp_4x3x2_uint8.raw", &bytes).unwrap();
        assert_eq!(v.name, "ramp");
        assert_eq!(v.dims, [4, 3, 2]);
        assert_eq!(v.spacing(), [1.0; 3]);
        assert_eq!(v.source_type, VoxelType::U8);
        assert!(matches!(v.data, VoxelData::U8(_)));
        assert_eq!(v.value(1, 2, 1), f64::from((1 + 4 * (2 + 3)) * 10));
        assert_eq!(v.range, [0.0, 230.0]);
        assert_eq!(v.gpu_bytes(), &bytes[..]);
    }

    #[test]
    fn loads_uint16() {
        let dir = TempDir::new();
        let values: [u16; 8] = [0, 1, 256, 4095, 65535, 7, 300, 1000];
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let v = load(&dir, "u_2x2x2_uint16.raw", &bytes).unwrap();
        assert_eq!(v.source_type, VoxelType::U16);
        assert!(matches!(v.data, VoxelData::U16(_)));
        assert_eq!(v.value(0, 1, 0), 256.0);
        assert_eq!(v.value(0, 0, 1), 65535.0);
        assert_eq!(v.value(1, 1, 1), 1000.0);
        assert_eq!(v.range, [0.0, 65535.0]);
        assert_eq!(v.gpu_texel_size(), 2);
    }

    #[test]
    fn loads_int16_with_bias() {
        let dir = TempDir::new();
        let values: [i16; 6] = [-1024, 0, 2986, -32768, 32767, -1];
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let v = load(&dir, "ct_3x2x1_int16.raw", &bytes).unwrap();
        assert_eq!(v.source_type, VoxelType::I16);
        let VoxelData::U16(stored) = &v.data else {
            panic!("int16 must be stored as U16")
        };
        assert_eq!(stored, &[31744, 32768, 35754, 0, 65535, 32767]);
        assert_eq!(v.value(0, 0, 0), -1024.0);
        assert_eq!(v.value(2, 0, 0), 2986.0);
        assert_eq!(v.value(0, 1, 0), -32768.0);
        assert_eq!(v.value(1, 1, 0), 32767.0);
        assert_eq!(v.value(2, 1, 0), -1.0);
        assert_eq!(v.range, [-32768.0, 32767.0]);
    }

    #[test]
    fn loads_float32() {
        let dir = TempDir::new();
        let values: [f32; 4] = [-7.5, 0.25, f32::NAN, 3.0e6];
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let v = load(&dir, "z_1x4x1_float32.raw", &bytes).unwrap();
        assert_eq!(v.source_type, VoxelType::F32);
        assert_eq!(v.value(0, 0, 0), -7.5);
        assert_eq!(v.value(0, 1, 0), 0.25);
        assert!(v.value(0, 2, 0).is_nan());
        assert_eq!(v.value(0, 3, 0), 3.0e6);
        assert_eq!(v.range, [-7.5, 3.0e6]);
    }

    #[test]
    fn loads_float64_as_f32() {
        let dir = TempDir::new();
        let values: [f64; 5] = [-117.843, 2121.07, 0.1, f64::INFINITY, 1e300];
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let v = load(&dir, "dwi_5x1x1_float64.raw", &bytes).unwrap();
        assert_eq!(v.source_type, VoxelType::F64);
        let VoxelData::F32(stored) = &v.data else {
            panic!("float64 must be stored as F32")
        };
        assert_eq!(stored.len(), 5);
        assert_eq!(v.value(0, 0, 0), f64::from(-117.843f32));
        assert_eq!(v.value(2, 0, 0), f64::from(0.1f32));
        // 1e300 is beyond f32 and becomes +inf, which the range ignores like any other inf.
        assert_eq!(v.value(4, 0, 0), f64::INFINITY);
        assert_eq!(v.range, [f64::from(-117.843f32), f64::from(2121.07f32)]);
        assert_eq!(v.gpu_texel_size(), 4);
    }

    #[test]
    fn options_override_the_name() {
        let dir = TempDir::new();
        let bytes: Vec<u8> = [1u16, 2, 3, 4].iter().flat_map(|v| v.to_le_bytes()).collect();
        let path = dir.write("thing_8x1x1_uint8.raw", &bytes);
        let opts = RawOptions {
            dims: Some([2, 2, 1]),
            voxel_type: Some(VoxelType::U16),
            spacing: Some([0.5, 0.5, 2.0]),
        };
        let v = load_raw(&path, &opts).unwrap();
        assert_eq!(v.name, "thing");
        assert_eq!(v.dims, [2, 2, 1]);
        assert_eq!(v.source_type, VoxelType::U16);
        assert_eq!(v.spacing(), [0.5, 0.5, 2.0]);
        assert_eq!(v.value(1, 1, 0), 4.0);

        // A name that says nothing: everything from the options, name from the file stem.
        let path = dir.write("scan.bin", &[9, 8, 7]);
        let opts = RawOptions {
            dims: Some([3, 1, 1]),
            voxel_type: Some(VoxelType::U8),
            spacing: None,
        };
        let v = load_raw(&path, &opts).unwrap();
        assert_eq!(v.name, "scan");
        assert_eq!(v.value(2, 0, 0), 7.0);
        // The type from the options wins over an unknown type in the name.
        let path = dir.write("x_3x1x1_int64.raw", &[1, 2, 3]);
        let opts = RawOptions {
            voxel_type: Some(VoxelType::U8),
            ..RawOptions::default()
        };
        assert_eq!(load_raw(&path, &opts).unwrap().dims, [3, 1, 1]);
    }

    #[test]
    fn size_mismatch_is_reported_before_reading() {
        let dir = TempDir::new();
        let err = load(&dir, "skull_4x4x4_uint16.raw", &[0; 100]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "file skull_4x4x4_uint16.raw is 100 bytes but 4x4x4 uint16 needs 128"
        );

        // 2^31 float64 voxels would be 16 GiB: the size check must refuse before any allocation.
        let err = load(&dir, "big_16384x16384x8_float64.raw", &[0; 10]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "file big_16384x16384x8_float64.raw is 10 bytes but 16384x16384x8 float64 needs 17179869184"
        );
    }

    #[test]
    fn layout_errors() {
        let dir = TempDir::new();
        let err = load(&dir, "volume.raw", &[0; 8]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "cannot tell the dimensions and voxel type of volume.raw: pass --dims W H D --type T or name the file \
             NAME_WxHxD_TYPE.raw"
        );
        let path = dir.write("volume2.raw", &[0; 8]);
        let opts = RawOptions {
            dims: Some([2, 2, 2]),
            ..RawOptions::default()
        };
        let err = load_raw(&path, &opts).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("cannot tell the voxel type of volume2.raw: --dims is given but --type is missing; pass --type T, one of uint8"),
            "{err}"
        );
        let opts = RawOptions {
            voxel_type: Some(VoxelType::U8),
            ..RawOptions::default()
        };
        let err = load_raw(&path, &opts).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("cannot tell the dimensions of volume2.raw: --type is given but --dims is missing"),
            "{err}"
        );

        let err = load(&dir, "seg_2x2x2_int64.raw", &[0; 64]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "unknown voxel type 'int64' in file name seg_2x2x2_int64.raw: use one of uint8, int8, uint16, int16, \
             uint32, int32, float32, float64, or pass --type T"
        );
    }

    #[test]
    fn dimension_and_spacing_errors() {
        let dir = TempDir::new();
        let err = load(&dir, "flat_4x0x4_uint8.raw", &[]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "dimensions 4x0x4 contain a zero; every dimension must be at least 1"
        );

        let err = load(&dir, "wide_20000x1x1_uint8.raw", &[0; 4]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "dimensions 20000x1x1 exceed the limit of 16384 per axis"
        );

        let err = load(&dir, "huge_16384x16384x257_uint8.raw", &[0; 4]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "dimensions 16384x16384x257 make 68987912192 voxels, more than the limit of 68719476736 (2^36)"
        );

        let path = dir.write("s_1x1x1_uint8.raw", &[5]);
        for spacing in [
            [1.0, 0.0, 1.0],
            [-0.5, 1.0, 1.0],
            [1.0, 1.0, f32::NAN],
            [1.0, f32::INFINITY, 1.0],
        ] {
            let opts = RawOptions {
                spacing: Some(spacing),
                ..RawOptions::default()
            };
            let err = load_raw(&path, &opts).unwrap_err();
            assert!(matches!(err, VolumeError::BadSpacing { .. }), "{spacing:?}: {err}");
        }
    }

    #[test]
    fn file_errors() {
        let dir = TempDir::new();
        let missing = dir.0.join("gone_2x2x2_uint8.raw");
        let err = load_raw(&missing, &RawOptions::default()).unwrap_err();
        let VolumeError::Io { source, .. } = &err else {
            panic!("expected an I/O error, got {err}")
        };
        assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        let text = err.to_string();
        assert!(
            text.starts_with(&format!("cannot read {}: ", missing.display())),
            "{text}"
        );
        assert!(text.ends_with(&source.to_string()), "{text}");

        let sub = dir.0.join("dir_1x1x1_uint8.raw");
        std::fs::create_dir(&sub).unwrap();
        let err = load_raw(&sub, &RawOptions::default()).unwrap_err();
        assert_eq!(err.to_string(), format!("{} is not a regular file", sub.display()));
    }
}
