//! The first image of a large DICOM series or multi-frame file (docs/large-volumes.md, "The first image"): every
//! k-th voxel along each axis, each kept slice decoded from its own file or frame as the loader decodes it (every
//! codec gdcmconv wrote, pydicom's oblique, uneven and multi-frame files). Voxel j of the preview is voxel k·j of
//! the file loaded whole, placed where that voxel lies, with the same rescale and modality; a series large at the
//! level it is shown gets one through `scale::preview_within`, a small one none.

use crate::common;
use std::path::PathBuf;
use volcast::formats;
use volcast::formats::OpenOptions;
use volcast::pyramid::budget::Budgets;
use volcast::volume::Volume;

fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel)
}

/// Asserts that `preview` holds every `k`-th voxel of `whole` along each axis, placed where that voxel lies.
fn assert_every_kth_voxel(name: &str, preview: &Volume, whole: &Volume, k: u32) {
    assert_eq!(preview.dims, whole.dims.map(|n| n.div_ceil(k)), "{name}");
    let [w, h, d] = preview.dims;
    for (x, y, z) in (0..d).flat_map(|z| (0..h).flat_map(move |y| (0..w).map(move |x| (x, y, z)))) {
        let (p, q) = ([x, y, z], [x * k, y * k, z * k]);
        assert_eq!(
            preview.value(x, y, z),
            whole.value(q[0], q[1], q[2]),
            "{name}: voxel {p:?}"
        );
        let at = |v: &Volume, i: [u32; 3]| v.geometry.affine.transform_point3(glam::DVec3::from(i.map(f64::from)));
        assert!(
            at(preview, p).distance(at(whole, q)) < 1e-9,
            "{name}: voxel {p:?} is placed apart"
        );
    }
    assert_eq!(preview.scaling, whole.scaling, "{name}");
    assert_eq!(preview.modality, whole.modality, "{name}");
    assert_eq!(preview.format, "DICOM", "{name}");
    assert!(
        preview
            .notes
            .iter()
            .any(|n| n.contains(&format!("a preview of 1 voxel in {k} per axis"))),
        "{name}: {:?}",
        preview.notes
    );
}

#[test]
fn a_preview_keeps_every_kth_voxel_of_a_series_or_multi_frame_file() {
    let mut paths: Vec<PathBuf> = ["u8", "u16", "i16"]
        .iter()
        .flat_map(|kind| ["native", "rle", "jpeg", "jpegls", "j2k"].map(|codec| data(&format!("dicom/{kind}_{codec}"))))
        .collect();
    paths.extend(["world/dicom_oblique", "world/dicom_uneven"].map(data));
    paths.extend(
        [
            "enhanced_ct_native",
            "enhanced_ct_rle",
            "enhanced_ct_j2k",
            "multiframe_ct_native",
        ]
        .map(|name| data(&format!("dicom/{name}.dcm"))),
    );
    for path in paths {
        let name = path.display().to_string();
        let place = volcast::scale::dicom_slice_by_slice(&path, &OpenOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .unwrap_or_else(|| panic!("{name}: not read slice by slice"));
        let whole = formats::open(&path, &OpenOptions::default()).expect("whole");
        for k in [2, 4] {
            let preview = volcast::scale::preview::strided(&place, k).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_every_kth_voxel(&name, &preview, &whole, k);
        }
    }
}

/// A 512×512×256 series (2²⁶ voxels, the least that gets a preview) is previewed from every 4th voxel, 64 of its
/// files decoded; held at level 1 by a small host budget it is not (2²³ voxels open fast enough), and a small series
/// gets none.
#[test]
fn a_large_series_is_previewed_before_it_is_read() {
    let dir = common::dicom_series::large(&common::scratch("dicom-preview").join("series"), [512, 512, 256]);
    let opts = OpenOptions::default();
    let preview = volcast::scale::preview_within(&dir, &opts, Budgets::host(Some(1 << 30)), None)
        .expect("a preview")
        .expect("a large series gets a preview");
    assert!(
        preview.notes.iter().any(|n| n.contains("(128x128x64 of 512x512x256)")),
        "{:?}",
        preview.notes
    );
    let whole = formats::open(&dir, &opts).expect("whole");
    assert_eq!(
        whole.value(3, 5, 7),
        f64::from(3 + 2 * 5 + 3 * 7),
        "the series as written"
    );
    assert_every_kth_voxel("the large series", &preview, &whole, 4);
    let level1 = volcast::scale::preview_within(&dir, &opts, Budgets::host(Some(20 << 20)), None).expect("level 1");
    assert!(level1.is_none(), "a series shown at 256x256x128 gets no preview");
    std::fs::remove_dir_all(&dir).ok();
    let small = volcast::scale::preview_within(&data("dicom/u8_native"), &opts, Budgets::host(None), None);
    assert!(small.expect("small").is_none(), "a 16x12x6 series gets no preview");
}
