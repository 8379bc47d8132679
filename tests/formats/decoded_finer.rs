//! Decoded files' finer levels (docs/large-volumes.md, "A decoded file's level 0"): a file that must be decoded to be
//! read (gzip NIfTI from nibabel, gzip NRRD inline and detached from pynrrd, zlib MetaImage from SimpleITK, `.vti`
//! arrays in zlib, LZ4 and LZMA blocks and base64 from VTK, DICOM series in every codec gdcmconv wrote) and held at
//! a coarser level keeps its level 0 in the pyramid cache as it is decoded. Level 0 read back from there, whole and
//! by box, equals the file loaded whole by its format's reader, voxel for voxel, and so it does from the cache on
//! the next open. A rescaled file (the int16 series here, CT's rescale intercept) does so in its stored values, and
//! its held level, read back from the cache, keeps the rescale and the file's range.

use crate::common;
use std::path::PathBuf;
use volcast::formats;
use volcast::formats::OpenOptions;
use volcast::pyramid::budget::Budgets;
use volcast::scale::cache::PyramidCache;
use volcast::volume::{self, VoxelData};

fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel)
}

/// The box `lo..lo + size` of `v`'s voxels (x fastest).
fn cut(v: &VoxelData, dims: [u32; 3], lo: [u32; 3], size: [u32; 3]) -> VoxelData {
    let index = |x: u32, y: u32, z: u32| (lo[0] + x + dims[0] * (lo[1] + y + dims[1] * (lo[2] + z))) as usize;
    let all = (0..size[2]).flat_map(|z| (0..size[1]).flat_map(move |y| (0..size[0]).map(move |x| (x, y, z))));
    match v {
        VoxelData::U8(d) => VoxelData::U8(all.map(|(x, y, z)| d[index(x, y, z)]).collect()),
        VoxelData::U16(d) => VoxelData::U16(all.map(|(x, y, z)| d[index(x, y, z)]).collect()),
        VoxelData::F32(d) => VoxelData::F32(all.map(|(x, y, z)| d[index(x, y, z)]).collect()),
    }
}

#[test]
fn decoded_files_show_their_level_0_from_the_pyramid_cache() {
    let mut cases: Vec<(String, Option<&str>)> = [
        "world/nifti_ras.nii.gz",
        "world/nifti_oblique.nii.gz",
        "world/nrrd_lps.nrrd",
        "world/nrrd_ras.nhdr",
        "world/mha_rip.mha",
        "vtk/vti_zlib.vti",
        "vtk/vti_lz4.vti",
        "vtk/vti_lzma.vti",
        "vtk/vti_appended_base64.vti",
        "vtk/vti_zlib_base64.vti",
    ]
    .iter()
    .map(|r| (r.to_string(), None))
    .collect();
    cases.push(("vtk/vti_zlib.vti".into(), Some("label")));
    // One multi-frame file each, read frame by frame: frames stored shuffled, a rescale, native and compressed.
    for codec in ["native", "rle", "j2k"] {
        cases.push((format!("dicom/enhanced_ct_{codec}.dcm"), None));
    }
    // Frames in order: read in place, its finer levels by box from the file itself.
    cases.push(("dicom/multiframe_ct_native.dcm".into(), None));
    for kind in ["u8", "u16", "i16"] {
        for codec in ["native", "rle", "jpeg", "jpegls", "j2k"] {
            cases.push((format!("dicom/{kind}_{codec}"), None));
        }
    }
    let dir = common::scratch("decoded-finer");
    for (k, (rel, array)) in cases.iter().enumerate() {
        let what = format!("{rel} {array:?}");
        let path = data(rel);
        let opts = OpenOptions {
            array: array.map(String::from),
            ..Default::default()
        };
        let whole = formats::open(&path, &opts).expect("whole");
        // A budget one voxel short of level 0: level 1 held.
        let host = whole.dims.iter().map(|&d| u64::from(d)).product::<u64>() * whole.source_type.size() as u64 - 1;
        let cache = PyramidCache::new(Some(dir.join(format!("cache-{k}"))));
        let mut first: Option<volume::Volume> = None;
        for open in ["first", "cached"] {
            let v = volcast::scale::open(&path, &opts, Budgets::host(Some(host)), Some(&cache), &mut |_| {})
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            // The held level carries the file's rescale (the int16 series have one) and its range, from the file
            // and from the cache alike: the cache keeps the stored values and the rescale beside them.
            assert_eq!((v.scaling, v.range), (whole.scaling, whole.range), "{what} ({open})");
            assert_eq!(
                v.notes.iter().any(|n| n.contains("read from the pyramid cache")),
                open == "cached",
                "{what}"
            );
            if let Some(f) = &first {
                assert!(
                    v.data == f.data && v.source_type == f.source_type,
                    "{what}: the cached level differs"
                );
            }
            let finer = v
                .finer
                .as_ref()
                .unwrap_or_else(|| panic!("{what} ({open}): no finer levels: {:?}", v.notes));
            assert_eq!((finer.held(), finer.dims()), (1, whole.dims), "{what}");
            let dims = whole.dims;
            let level0 = finer.read(0, [0; 3], dims).expect("level 0");
            assert!(
                level0 == whole.data,
                "{what} ({open}): level 0 differs from the file loaded whole"
            );
            let (lo, size) = ([1, 1, 1], dims.map(|d| d - 2));
            let inner = finer.read(0, lo, size).expect("a box");
            assert!(
                inner == cut(&whole.data, dims, lo, size),
                "{what} ({open}): a box of level 0"
            );
            first.get_or_insert(v);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
