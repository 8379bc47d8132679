//! DICOM series over the host budget (docs/large-volumes.md, "How files are read"): read slice by slice, each file
//! decoded on its own (native, RLE, JPEG, JPEG-LS and JPEG 2000 as gdcmconv wrote them; an oblique and an unevenly
//! spaced series from pydicom; the shared MRI series), into the pyramid level the budget holds, never held whole.
//! Each level equals the same level made from the series loaded whole by the DICOM reader (`scale::fit`), voxel
//! for voxel, with the same placement, rescale, modality and series; a cut slice is refused naming its file.

use crate::common;
use std::path::{Path, PathBuf};
use volcast::formats;
use volcast::formats::OpenOptions;
use volcast::pyramid::budget::Budgets;
use volcast::volume;

fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel)
}

fn open_within(path: &Path, opts: &OpenOptions, host: u64) -> Result<volume::Volume, volume::VolumeError> {
    volcast::scale::open(path, opts, Budgets::host(Some(host)), None, &mut |_| {})
}

/// Opens `path` within `host` bytes, asserts it was read slice by slice into a level of `dims`, and that the level
/// equals the one made from the series loaded whole.
fn assert_sliced_level_is_the_whole_ones(path: &Path, opts: &OpenOptions, host: u64, dims: [u32; 3]) {
    let by = match path.file_name().and_then(|n| n.to_str()) {
        _ if path.is_dir() => "slices were decoded one file at a time",
        Some("multiframe_ct_native.dcm") => "frames lie uncompressed and in order in the file: read in place",
        _ => "frames were decoded one at a time from where they lie in the file",
    };
    let name = path.display();
    let sliced = open_within(path, opts, host).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(sliced.dims, dims, "{name}");
    assert!(
        sliced.notes.iter().any(|n| n.contains(by)),
        "{name}: {:?}",
        sliced.notes
    );
    let whole = formats::open(path, opts).expect("whole");
    let reduced = volcast::scale::fit(whole, &Budgets::host(Some(host)), false).expect("reduced");
    assert_eq!(reduced.dims, dims, "{name}");
    assert!(
        sliced.data == reduced.data,
        "{name}: the level differs from the whole series'"
    );
    assert_eq!(sliced.geometry, reduced.geometry, "{name}");
    assert_eq!(sliced.scaling, reduced.scaling, "{name}");
    assert_eq!(sliced.source_type, reduced.source_type, "{name}");
    assert_eq!(sliced.range, reduced.range, "{name}");
    assert_eq!(sliced.modality, reduced.modality, "{name}");
    assert_eq!(sliced.series, reduced.series, "{name}");
    assert_eq!(sliced.format, "DICOM", "{name}");
}

#[test]
fn series_over_the_host_budget_are_read_slice_by_slice_into_their_level() {
    // 16x12x6 (2 or 3 KiB); 1 KiB holds level 1 only.
    for kind in ["u8", "u16", "i16"] {
        for codec in ["native", "rle", "jpeg", "jpegls", "j2k"] {
            let path = data(&format!("dicom/{kind}_{codec}"));
            assert_sliced_level_is_the_whole_ones(&path, &OpenOptions::default(), 1 << 10, [8, 6, 3]);
        }
    }
    let lossy = data("dicom/u8_jpeg_lossy");
    assert_sliced_level_is_the_whole_ones(&lossy, &OpenOptions::default(), 1 << 10, [8, 6, 3]);
    // 48x44x16 int16 (66 KiB): an oblique series, and one of uneven spacing resampled as the reader does.
    for rel in ["world/dicom_series", "world/dicom_oblique", "world/dicom_uneven"] {
        assert_sliced_level_is_the_whole_ones(&data(rel), &OpenOptions::default(), 16 << 10, [24, 22, 8]);
    }
}

/// One multi-frame file (pydicom's enhanced CT, frames stored shuffled, placed and rescaled by its functional groups;
/// gdcmconv's RLE and JPEG 2000 of it, one fragment per frame) over the host budget is read frame by frame from where
/// each frame lies into its level; one whose frames lie in order, every bit stored (pydicom's classic multi-frame CT),
/// is read in place like a raw file, its finer levels by box from it. A file cut short is refused naming it, never
/// read past its end.
#[test]
fn a_multi_frame_file_over_the_host_budget_is_read_frame_by_frame_into_its_level() {
    let dir = common::scratch("dicom-frames");
    let in_place = data("dicom/multiframe_ct_native.dcm");
    let v = open_within(&in_place, &OpenOptions::default(), 1 << 10).expect("in place");
    assert!(v.finer.is_some(), "finer levels from the file without the cache");
    for name in [
        "enhanced_ct_native",
        "enhanced_ct_rle",
        "enhanced_ct_j2k",
        "multiframe_ct_native",
    ] {
        let path = data(&format!("dicom/{name}.dcm"));
        // 16x12x6 int16 (2.25 KiB); 1 KiB holds level 1 only.
        assert_sliced_level_is_the_whole_ones(&path, &OpenOptions::default(), 1 << 10, [8, 6, 3]);
        let bytes = std::fs::read(&path).unwrap();
        let cut = dir.write(&format!("cut_{name}.dcm"), &bytes[..bytes.len() - 100]);
        let e = open_within(&cut, &OpenOptions::default(), 1 << 10).expect_err("a cut file");
        let e = e.to_string();
        assert!(
            e.contains(&format!("cut_{name}.dcm")) && e.contains("truncated"),
            "{name}: {e}"
        );
    }
}

/// A multi-frame file whose header runs past the first prefix read (a 3 MiB private element before PixelData) is
/// found by reading more, and read in place all the same.
#[test]
fn a_multi_frame_file_with_a_long_header_is_read_in_place() {
    let bytes = std::fs::read(data("dicom/multiframe_ct_native.dcm")).unwrap();
    let pixels = bytes
        .windows(8)
        .rposition(|w| w == b"\xE0\x7F\x10\x00OW\x00\x00")
        .expect("PixelData");
    let pad = 3 << 20;
    let mut element = b"\xDF\x7F\x10\x00OB\x00\x00".to_vec();
    element.extend((pad as u32).to_le_bytes());
    element.resize(element.len() + pad, 7);
    let long = [&bytes[..pixels], &element[..], &bytes[pixels..]].concat();
    let path = common::scratch("dicom-frames-long").write("multiframe_ct_native.dcm", &long);
    assert_sliced_level_is_the_whole_ones(&path, &OpenOptions::default(), 1 << 10, [8, 6, 3]);
}

/// The fuzz findings (hostile DICOM files) opened within a budget that would read them frame by frame: each is
/// refused with an error naming the file, as the loader refuses it, never a panic or an allocation by a claimed size.
#[test]
fn hostile_dicom_files_within_a_small_budget_are_refused_naming_the_file() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap().flatten() {
        let path = entry.path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if !name.starts_with("fuzz-dicom") {
            continue;
        }
        let e = open_within(&path, &OpenOptions::default(), 64)
            .expect_err(&name)
            .to_string();
        let loader = formats::open(&path, &OpenOptions::default())
            .expect_err(&name)
            .to_string();
        assert!(e.starts_with(&format!("{name}: ")), "{e}");
        assert_eq!(e, loader, "{name}: the loader's error");
        seen += 1;
    }
    assert!(seen >= 10, "the fuzz findings are in tests/data");
    // NumberOfFrames claiming 99999 frames of 6 stored: refused by its size before any frame is looked for.
    let bytes = std::fs::read(data("dicom/multiframe_ct_native.dcm")).unwrap();
    let (six, many) = (b"\x28\x00\x08\x00IS\x02\x006 ", b"\x28\x00\x08\x00IS\x06\x0099999 ");
    let at = bytes.windows(six.len()).position(|w| w == six).expect("NumberOfFrames");
    let claim = common::scratch("dicom-frames-claim").write(
        "claim.dcm",
        &[&bytes[..at], &many[..], &bytes[at + six.len()..]].concat(),
    );
    let e = open_within(&claim, &OpenOptions::default(), 1 << 10)
        .expect_err("99999 frames")
        .to_string();
    let loader = formats::open(&claim, &OpenOptions::default())
        .expect_err("99999 frames")
        .to_string();
    assert!(e.contains("99999") && e == loader, "{e} / {loader}");
}

#[test]
fn the_shared_mri_series_and_one_series_of_several_read_slice_by_slice() {
    let Some(brain) = common::shared_data("native/brain_pd_mr") else {
        return;
    };
    let whole = formats::open(&brain, &OpenOptions::default()).expect("brain");
    let [x, y, z] = whole.dims;
    let half = [x.div_ceil(2), y.div_ceil(2), z.div_ceil(2)];
    let bytes = u64::from(x * y * z) * 2;
    assert_sliced_level_is_the_whole_ones(&brain, &OpenOptions::default(), bytes / 2, half);
    // A folder of three series: the one asked for, and every series listed as the reader lists them.
    let dir = common::scratch("dicom-slices-series");
    let Some(folder) = common::dicom_series::make(&dir) else {
        return;
    };
    let chosen = &common::dicom_series::SERIES[1];
    let opts = OpenOptions {
        series: Some(chosen.uid.to_string()),
        ..Default::default()
    };
    assert_sliced_level_is_the_whole_ones(&folder, &opts, 256 << 10, [x.div_ceil(2), y.div_ceil(2), 3]);
}

#[test]
fn a_series_that_fits_is_read_whole_and_a_cut_slice_is_refused_naming_its_file() {
    let path = data("dicom/i16_rle");
    let v = open_within(&path, &OpenOptions::default(), 1 << 20).expect("fits");
    assert_eq!(v.dims, [16, 12, 6]);
    assert!(
        !v.notes.iter().any(|n| n.contains("slices were decoded")),
        "{:?}",
        v.notes
    );
    // A copy of a native series with one slice's pixels cut short.
    let dir = common::scratch("dicom-slices-cut");
    for entry in std::fs::read_dir(data("dicom/i16_native")).expect("series") {
        let from = entry.expect("entry").path();
        std::fs::copy(&from, dir.join(from.file_name().expect("name"))).expect("copy");
    }
    let cut = dir.join("03.dcm");
    let bytes = std::fs::read(&cut).expect("slice");
    std::fs::write(&cut, &bytes[..bytes.len() - 100]).expect("cut");
    let e = open_within(&dir, &OpenOptions::default(), 1 << 10)
        .expect_err("a cut slice")
        .to_string();
    assert!(e.contains("03.dcm"), "{e}");
}

#[test]
fn a_series_level_is_kept_in_the_pyramid_cache_until_one_of_its_files_changes() {
    // An unsigned series without a rescale (a rescaled file's levels are not cached).
    let dir = common::scratch("dicom-slices-cache");
    let series = dir.join("series");
    std::fs::create_dir_all(&series).expect("folder");
    for entry in std::fs::read_dir(data("dicom/u16_jpegls")).expect("series") {
        let from = entry.expect("entry").path();
        std::fs::copy(&from, series.join(from.file_name().expect("name"))).expect("copy");
    }
    let cache = volcast::scale::cache::PyramidCache::new(Some(dir.join("cache")));
    let open = || {
        volcast::scale::open(
            &series,
            &OpenOptions::default(),
            Budgets::host(Some(1 << 10)),
            Some(&cache),
            &mut |_| {},
        )
        .expect("open")
    };
    let has = |v: &volume::Volume, text: &str| v.notes.iter().any(|n| n.contains(text));
    let first = open();
    assert!(
        has(&first, "slices were decoded one file at a time"),
        "{:?}",
        first.notes
    );
    let again = open();
    assert!(has(&again, "read from the pyramid cache"), "{:?}", again.notes);
    assert!(again.data == first.data && again.geometry == first.geometry);
    assert_eq!((&again.modality, &again.series), (&first.modality, &first.series));
    // One slice written again (same bytes, a later time): the entry is stale and the level is read again.
    let slice = series.join("02.dcm");
    let bytes = std::fs::read(&slice).expect("slice");
    std::thread::sleep(std::time::Duration::from_millis(20));
    std::fs::write(&slice, bytes).expect("rewrite");
    let changed = open();
    assert!(
        has(&changed, "the file changed since it was made"),
        "{:?}",
        changed.notes
    );
    assert!(changed.data == first.data);
}
