//! Volume file formats end to end through `formats::open`: files written here (round trips, known values,
//! detached data, path escapes, hostile input) and the real volumes in ../shared/data against their raw twins.

use crate::common;

use std::path::{Path, PathBuf};
use volcast::formats;
use volcast::formats::{Endian, Format, OpenOptions, RawOptions};
use volcast::volume::{self, Volume, VoxelType};

fn open(path: &Path) -> Result<Volume, volume::VolumeError> {
    formats::open(path, &OpenOptions::default())
}

fn err(path: &Path) -> String {
    open(path).expect_err("should fail").to_string()
}

fn gzip(data: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}

/// The test data folder `../shared/data`, or None after recording the skip (a failure with CI=true).
fn shared_data() -> Option<PathBuf> {
    common::shared_data("")
}

#[test]
fn committed_samples_load_with_known_values() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let v = open(&data.join("ramp.vtk")).unwrap();
    assert_eq!(
        (v.format.as_str(), v.dims, v.source_type),
        ("VTK legacy", [4, 3, 2], VoxelType::I16)
    );
    assert_eq!(v.spacing(), [1.0, 1.0, 2.5]);
    assert_eq!((v.value(0, 0, 0), v.value(3, 2, 1)), (-12.0, 11.0));
    let v = open(&data.join("ramp.nhdr")).unwrap();
    assert_eq!(
        (v.format.as_str(), v.dims, v.source_type),
        ("NRRD", [4, 3, 2], VoxelType::U16)
    );
    assert_eq!(v.spacing(), [0.5, 0.5, 1.0]);
    assert_eq!((v.value(1, 0, 0), v.value(3, 2, 1)), (100.0, 2300.0));
    let v = open(&data.join("ramp.mhd")).unwrap();
    assert_eq!(
        (v.format.as_str(), v.dims, v.source_type),
        ("MetaImage", [4, 3, 2], VoxelType::F32)
    );
    assert_eq!(v.range, [-1.0, 10.5]);
    let v = open(&data.join("slice.dcm")).unwrap();
    assert_eq!(
        (v.format.as_str(), v.dims, v.source_type),
        ("DICOM", [3, 4, 1], VoxelType::I16)
    );
    assert_eq!(v.spacing(), [0.25, 0.5, 5.0]);
    assert_eq!((v.stored(0, 0, 0), v.value(0, 0, 0)), (-6.0, -1030.0));
    assert_eq!(v.range, [-1030.0, -1019.0]);
}

#[test]
fn formats_are_detected_by_content_not_just_name() {
    let dir = common::scratch("formats-formats_are_detected_by_content_not_just_name");
    let vtk = b"# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 1 1\nPOINT_DATA 2\nSCALARS s float\nLOOKUP_TABLE default\n1 2\n";
    let p = dir.write("data.bin", vtk);
    assert_eq!(formats::detect_format(&p).unwrap(), Format::Vtk);
    assert_eq!(open(&p).unwrap().value(1, 0, 0), 2.0);
    let p = dir.write(
        "x.dat",
        b"NRRD0004\ntype: uchar\ndimension: 1\nsizes: 2\nencoding: raw\n\n\x07\x09",
    );
    assert_eq!(formats::detect_format(&p).unwrap(), Format::Nrrd);
    let p = dir.write(
        "x.mha",
        b"NDims = 1\nDimSize = 1\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n\x05",
    );
    assert_eq!(formats::detect_format(&p).unwrap(), Format::MetaImage);
    // A folder is judged by its files: this one holds none that is TIFF or DICOM; one with a DICOM file is a series.
    assert!(formats::detect_format(&dir).is_err());
    let series = common::scratch("formats-formats_are_detected_by_content_not_just_name-series");
    let slice = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/slice.dcm")).unwrap();
    series.write("1.dcm", &slice);
    assert_eq!(formats::detect_format(&series).unwrap(), Format::Dicom);
    let p = dir.write("thing_2x1x1_uint8.raw", &[1, 2]);
    assert_eq!(formats::detect_format(&p).unwrap(), Format::Raw);
}

#[test]
fn raw_endian_and_header_bytes() {
    let dir = common::scratch("formats-raw_endian_and_header_bytes");
    let mut bytes = b"HEADER!!".to_vec();
    for v in [1u16, 2, 3, 0x1234] {
        bytes.extend(v.to_be_bytes());
    }
    let p = dir.write("scan.img", &bytes);
    let opts = OpenOptions {
        raw: RawOptions {
            dims: Some([2, 2, 1]),
            voxel_type: Some(VoxelType::U16),
            spacing: None,
        },
        endian: Endian::Big,
        header_bytes: 8,
        ..OpenOptions::default()
    };
    let v = formats::open(&p, &opts).unwrap();
    assert_eq!(v.value(1, 1, 0), f64::from(0x1234));
    assert_eq!(v.format, "raw");
    let e = formats::open(
        &p,
        &OpenOptions {
            header_bytes: 9,
            ..opts.clone()
        },
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "scan.img: the file is 16 bytes but a 9-byte header plus 2x2x1 uint16 needs 17"
    );
}

/// Detached data files are found as the specifications, ITK and pynrrd find them: relative to the header (`..`
/// included), absolute, or through a symbolic link; a missing one is named by the path tried.
#[test]
fn detached_nrrd_and_metaimage_find_their_data_as_itk_does() {
    let dir = common::scratch("formats-detached_nrrd_and_metaimage_find_their_data");
    let data: Vec<u8> = (0u8..8).collect();
    dir.write("sub/v.raw", &data);
    dir.write("secret.raw", &data);
    dir.write("v.raw.gz", &gzip(&data));
    let nhdr = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: sub/v.raw\n";
    let v = open(&dir.write("a.nhdr", nhdr.as_bytes())).unwrap();
    assert_eq!(v.value(1, 1, 1), 7.0);
    let gz = nhdr.replace("raw\ndata file: sub/v.raw", "gzip\ndata file: v.raw.gz");
    assert_eq!(open(&dir.write("gz.nhdr", gz.as_bytes())).unwrap().value(1, 0, 1), 5.0);
    let up = nhdr.replace("sub/v.raw", "../secret.raw");
    assert_eq!(
        open(&dir.write("sub/up.nhdr", up.as_bytes())).unwrap().value(1, 1, 1),
        7.0
    );
    let secret = dir.join("secret.raw");
    let absolute = nhdr.replace("sub/v.raw", secret.to_str().unwrap());
    assert_eq!(
        open(&dir.write("other/abs.nhdr", absolute.as_bytes()))
            .unwrap()
            .value(1, 0, 0),
        1.0
    );
    #[cfg(unix)]
    {
        let link = dir.join("other/link.raw");
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(&secret, &link).unwrap();
        let linked = nhdr.replace("sub/v.raw", "link.raw");
        assert_eq!(
            open(&dir.write("other/linked.nhdr", linked.as_bytes()))
                .unwrap()
                .value(0, 1, 0),
            2.0
        );
    }
    let missing = nhdr.replace("sub/v.raw", "nothere.raw");
    let e = err(&dir.write("missing.nhdr", missing.as_bytes()));
    let tried = dir.join("nothere.raw");
    assert!(
        e.contains(&format!(
            "missing.nhdr: its data file 'nothere.raw' cannot be read at {}",
            tried.display()
        )),
        "{e}"
    );

    let mhd = "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementSpacing = 1 2 3\nElementType = MET_UCHAR\nElementDataFile = sub/v.raw\n";
    let v = open(&dir.write("a.mhd", mhd.as_bytes())).unwrap();
    assert_eq!((v.value(0, 1, 1), v.spacing()), (6.0, [1.0, 2.0, 3.0]));
    let v = open(&dir.write("sub/b.mhd", mhd.replace("sub/v.raw", "../secret.raw").as_bytes())).unwrap();
    assert_eq!(v.value(0, 1, 1), 6.0);
    // A device is not a data file, whatever the header says (reading it would not end).
    let e = err(&dir.write("dev.mhd", mhd.replace("sub/v.raw", "/dev/zero").as_bytes()));
    assert!(e.contains("/dev/zero is not a regular file"), "{e}");
    // A short detached file: the claim is checked against its size before allocating.
    let big = nhdr.replace("2 2 2", "100 100 100");
    let e = err(&dir.write("big.nhdr", big.as_bytes()));
    assert!(e.contains("the voxel data end after 8 of the 1000000 bytes"), "{e}");
}

#[test]
fn nifti_files_round_trip_in_both_byte_orders_and_gzip() {
    let dir = common::scratch("formats-nifti_files_round_trip_in_both_byte_orders_and_gzip");
    for (big, gz) in [(false, false), (true, false), (false, true), (true, true)] {
        let mut h = vec![0u8; 352];
        let p16 = |h: &mut Vec<u8>, at: usize, v: i16| {
            h[at..at + 2].copy_from_slice(&if big { v.to_be_bytes() } else { v.to_le_bytes() })
        };
        let pf = |h: &mut Vec<u8>, at: usize, v: f32| {
            h[at..at + 4].copy_from_slice(&if big { v.to_be_bytes() } else { v.to_le_bytes() })
        };
        h[0..4].copy_from_slice(&if big {
            348i32.to_be_bytes()
        } else {
            348i32.to_le_bytes()
        });
        for (i, d) in [3i16, 2, 2, 2].iter().enumerate() {
            p16(&mut h, 40 + 2 * i, *d);
        }
        p16(&mut h, 70, 512); // uint16
        pf(&mut h, 80, 0.5);
        pf(&mut h, 84, 0.75);
        pf(&mut h, 88, 1.25);
        pf(&mut h, 108, 352.0);
        pf(&mut h, 112, 0.5);
        pf(&mut h, 116, 100.0);
        h[344..348].copy_from_slice(b"n+1\0");
        for v in [0u16, 1, 2, 3, 4, 5, 6, 65535] {
            h.extend(if big { v.to_be_bytes() } else { v.to_le_bytes() });
        }
        let name = if gz { "v.nii.gz" } else { "v.nii" };
        let bytes = if gz { gzip(&h) } else { h };
        let v = open(&dir.write(name, &bytes)).unwrap();
        assert_eq!((v.dims, v.spacing()), ([2, 2, 2], [0.5, 0.75, 1.25]), "{big} {gz}");
        assert_eq!(v.stored(1, 1, 1), 65535.0);
        assert_eq!(v.value(1, 1, 1), 65535.0 * 0.5 + 100.0);
        assert_eq!(v.range, [100.0, 65535.0 * 0.5 + 100.0]);
        assert_eq!(v.name, "v");
    }
}

#[test]
fn hostile_files_give_clear_errors() {
    let dir = common::scratch("formats-hostile_files_give_clear_errors");
    let vtk = "# vtk DataFile Version 3.0\nt\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 100000 100000 100000\nPOINT_DATA 1000000000000000\nSCALARS s float\nLOOKUP_TABLE default\n";
    assert!(err(&dir.write("huge.vtk", vtk.as_bytes())).contains("exceed the limit of 16384 per axis"));
    let nrrd = "NRRD0004\ntype: float\ndimension: 3\nsizes: 1000 1000 500\nencoding: gzip\n\n";
    let mut bytes = nrrd.as_bytes().to_vec();
    bytes.extend(gzip(&[0u8; 100]));
    let e = err(&dir.write("bomb.nrrd", &bytes));
    assert!(e.contains("bytes of gzip data cannot hold the 2000000000 bytes"), "{e}");
    let mha = "NDims = 3\nDimSize = 2 2 2\nElementType = MET_SHORT\nCompressedData = True\nElementDataFile = LOCAL\n";
    let mut bytes = mha.as_bytes().to_vec();
    bytes.extend(b"definitely not zlib");
    let e = err(&dir.write("broken.mha", &bytes));
    assert!(e.contains("broken.mha: the zlib data is corrupt"), "{e}");
    let e = err(&dir.write("short.nii", &[0u8; 100]));
    assert!(
        e.contains("short.nii: 100 bytes is too short for a NIfTI-1 header"),
        "{e}"
    );
    let e = err(&dir.write("bad.nii.gz", &[0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 3, 1, 2, 3]));
    assert!(e.contains("bad.nii.gz: the gzip data is corrupt"), "{e}");
    let e = err(&dir.write("junk.dcm", b"this is not dicom"));
    assert!(e.contains("junk.dcm: not a readable DICOM file"), "{e}");
    let empty = common::scratch("formats-hostile_files_give_clear_errors-empty");
    assert!(err(&empty).contains("the folder holds neither TIFF nor DICOM files"));
}

#[test]
fn max_dim_downsamples_or_refuses() {
    let dir = common::scratch("formats-max_dim_downsamples_or_refuses");
    let p = dir.write(
        "wide_8x2x1_uint8.raw",
        &[10, 20, 30, 40, 50, 60, 70, 80, 1, 1, 1, 1, 1, 1, 1, 1],
    );
    let opts = OpenOptions {
        max_dim: Some(4),
        ..OpenOptions::default()
    };
    let v = formats::open(&p, &opts).unwrap();
    assert_eq!((v.dims, v.spacing()), ([4, 2, 1], [2.0, 1.0, 1.0]));
    assert_eq!(v.value(0, 0, 0), 15.0);
    assert!(v.notes[0].starts_with("downsampled from 8x2x1 to 4x2x1"));
    let e = formats::open(
        &p,
        &OpenOptions {
            no_downsample: true,
            ..opts
        },
    )
    .unwrap_err();
    // The error names the file (every open error does).
    assert_eq!(
        e.to_string(),
        format!(
            "{}: 8x2x1 exceeds the maximum dimension 4 and downsampling is off (--no-downsample); raise --max-dim \
             or allow downsampling",
            p.display()
        )
    );
}

#[test]
fn progress_is_reported() {
    let dir = common::scratch("formats-progress_is_reported");
    let p = dir.write("p_64x64x64_uint8.raw", &vec![1u8; 64 * 64 * 64]);
    let mut seen = Vec::new();
    formats::open_with_progress(&p, &OpenOptions::default(), &mut |f| seen.push(f)).unwrap();
    assert_eq!(seen.last(), Some(&1.0));
}

/// Raw file of `name` from the shared data folder, for comparing voxel by voxel.
fn raw_twin(data: &Path, name: &str) -> Volume {
    volume::Volume::open(&data.join("raw").join(name)).expect("raw twin loads")
}

fn assert_same_voxels(a: &Volume, b: &Volume) {
    assert_eq!(a.dims, b.dims);
    let [w, h, d] = a.dims;
    for z in 0..d {
        for y in 0..h {
            for x in 0..w {
                let (va, vb) = (a.stored(x, y, z), b.value(x, y, z));
                assert!(va == vb || (va.is_nan() && vb.is_nan()), "({x},{y},{z}): {va} vs {vb}");
            }
        }
    }
}

#[test]
fn real_nifti_files_match_the_manifest_and_their_raw_twins() {
    let Some(data) = shared_data() else { return };
    // (native file, raw twin, dims, type, spacing, min, max) from MANIFEST.txt.
    let cases = [
        (
            "colin27_t1/ch2.nii.gz",
            "colin27_t1_181x217x181_uint8.raw",
            [181, 217, 181],
            VoxelType::U8,
            [1.0, 1.0, 1.0],
            0.0,
            254.0,
        ),
        (
            "motor_zmap/image_10426.nii.gz",
            "motor_zmap_53x63x46_float32.raw",
            [53, 63, 46],
            VoxelType::F32,
            [3.0, 3.0, 3.0],
            -7.94144,
            7.94135,
        ),
        (
            "dwi_b0_ascm/ascm_out_test.nii.gz",
            "dwi_b0_ascm_58x58x24_float64.raw",
            [58, 58, 24],
            VoxelType::F64,
            [4.0, 4.0, 5.0],
            -117.843,
            2121.07,
        ),
        (
            "dwi_s0_10slices/S0_10slices.nii.gz",
            "dwi_s0_10slices_128x128x10_uint16.raw",
            [128, 128, 10],
            VoxelType::U16,
            [2.0, 2.0, 53.1413],
            0.0,
            4095.0,
        ),
    ];
    for (native, raw, dims, t, spacing, min, max) in cases {
        let v = open(&data.join("native").join(native)).unwrap();
        assert_eq!(
            (v.format.as_str(), v.dims, v.source_type),
            ("NIfTI-1", dims, t),
            "{native}"
        );
        for (got, want) in v.spacing().iter().zip(spacing) {
            assert!((f64::from(*got) - want).abs() < 1e-4, "{native}: {:?}", v.spacing());
        }
        // MANIFEST values are printed to 6 significant digits.
        assert!(
            (v.range[0] - min).abs() <= 1e-5 * min.abs().max(1.0),
            "{native}: {:?}",
            v.range
        );
        assert!(
            (v.range[1] - max).abs() <= 1e-5 * max.abs().max(1.0),
            "{native}: {:?}",
            v.range
        );
        // The raw twins hold the stored values (MANIFEST: no rescale), which these files do not scale.
        assert!(v.scaling.is_identity(), "{native}: {:?}", v.scaling);
        assert_same_voxels(&v, &raw_twin(&data, raw));
    }
    // Its sform is sheared (the slice axis (30, 30, 32) mm is 55° off the in-plane axes): carried as it is.
    let v = open(&data.join("native/dwi_s0_10slices/S0_10slices.nii.gz")).unwrap();
    assert!(v.geometry.shear_deg() > 30.0, "{:?}", v.geometry);
}

#[test]
fn real_dicom_series_matches_its_raw_twin() {
    let Some(data) = shared_data() else { return };
    let v = open(&data.join("native/brain_pd_mr")).unwrap();
    assert_eq!((v.format.as_str(), v.dims), ("DICOM", [256, 256, 20]));
    assert_eq!(v.range, [0.0, 1059.0]);
    // MANIFEST: spacing 0.859375 0.859375 7.0005, slices ordered along the normal; the stack is tilted 7.7°
    // about left-right (world.rs checks the whole affine).
    assert!((v.spacing()[0] - 0.859375).abs() < 1e-6 && (v.spacing()[1] - 0.859375).abs() < 1e-6);
    assert!((v.spacing()[2] - 7.0005).abs() < 1e-3, "{:?}", v.spacing());
    assert!((v.geometry.obliquity_deg() - 7.71).abs() < 0.01, "{:?}", v.geometry);
    assert_same_voxels(&v, &raw_twin(&data, "brain_pd_mr_256x256x20_int16.raw"));
}

#[test]
fn real_ct_head_loads_with_its_range_and_gpu_mapping() {
    let Some(path) = common::shared_data("raw/cranium_ct_256x256x108_int16.raw") else {
        return;
    };
    let opts = formats::RawOptions {
        spacing: Some([0.957031, 0.957031, 1.5]),
        ..Default::default()
    };
    let v = formats::load_raw(&path, &opts).unwrap();
    assert_eq!(v.name, "cranium_ct");
    assert_eq!(v.dims, [256, 256, 108]);
    assert_eq!(v.source_type, VoxelType::I16);
    assert_eq!(v.range, [-1024.0, 2986.0]);
    let e = v.extent();
    assert!((e.z - 108.0 * 1.5 / (256.0 * 0.957031)).abs() < 1e-5, "{e}");
    let (scale, bias) = v.gpu_scale_bias();
    // Air (-1024) maps to 0 and the densest bone to 1 through the shader's affine map.
    let air = f64::from((31744.0f32 / 65535.0) * scale + bias);
    let bone = f64::from((35754.0f32 / 65535.0) * scale + bias);
    assert!(air.abs() < 1e-4 && (bone - 1.0).abs() < 1e-4, "{air} {bone}");
}
