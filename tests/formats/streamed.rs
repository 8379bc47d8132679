//! Compressed files over the host budget (docs/large-volumes.md, "How files are read"): a gzip NIfTI (nibabel), gzip
//! NRRD inline and detached (pynrrd) and a zlib MetaImage (SimpleITK) are decoded once, front to back, into the
//! pyramid level the budget holds, never held whole. Each level equals the same level made from the file loaded
//! whole by its format's own reader (`scale::fit`), voxel for voxel, with the same placement; a truncated stream is
//! refused naming the file.

use crate::common;
use std::path::{Path, PathBuf};
use volcast::formats;
use volcast::formats::OpenOptions;
use volcast::pyramid::budget::Budgets;
use volcast::volume;

fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel)
}

fn open_within(path: &Path, host: u64) -> Result<volume::Volume, volume::VolumeError> {
    volcast::scale::open(
        path,
        &OpenOptions::default(),
        Budgets::host(Some(host)),
        None,
        &mut |_| {},
    )
}

#[test]
fn compressed_files_over_the_host_budget_are_decoded_as_a_stream_into_their_level() {
    // (file, host budget, the level it holds): 40 KiB holds none of these whole.
    let cases = [
        ("world/nifti_ras.nii.gz", 40 << 10, [17, 20, 18]),
        ("world/nifti_oblique.nii.gz", 40 << 10, [27, 23, 16]),
        ("world/nrrd_lps.nrrd", 40 << 10, [23, 24, 12]),
        ("world/nrrd_ras.nhdr", 40 << 10, [20, 19, 13]),
        ("world/mha_rip.mha", 40 << 10, [23, 20, 19]),
        // Two time steps: both decoded from the one stream, in order.
        ("nibabel/example_nifti2.nii.gz", 10 << 10, [16, 10, 6]),
    ];
    for (rel, host, dims) in cases {
        let path = data(rel);
        let streamed = open_within(&path, host).unwrap_or_else(|e| panic!("{rel}: {e}"));
        assert_eq!(streamed.dims, dims, "{rel}");
        assert!(
            streamed.notes.iter().any(|n| n.contains("decoded once, as a stream")),
            "{rel}: {:?}",
            streamed.notes
        );
        let whole = formats::open(&path, &OpenOptions::default()).expect("whole");
        let reduced = volcast::scale::fit(whole, &Budgets::host(Some(host)), false).expect("reduced");
        assert_eq!(reduced.dims, dims, "{rel}");
        assert_eq!(streamed.timesteps(), reduced.timesteps(), "{rel}");
        for t in 0..reduced.timesteps() {
            assert!(
                streamed.step_data(t) == reduced.step_data(t),
                "{rel}: step {t} differs from the level of the whole file"
            );
        }
        assert_eq!(streamed.geometry, reduced.geometry, "{rel}");
        assert_eq!(streamed.scaling, reduced.scaling, "{rel}");
        assert_eq!(streamed.source_type, reduced.source_type, "{rel}");
    }
}

#[test]
fn a_truncated_compressed_stream_is_refused_naming_the_file() {
    let dir = common::scratch("streamed-truncated");
    let whole = std::fs::read(data("world/nifti_ras.nii.gz")).expect("file");
    let cut = dir.join("cut.nii.gz");
    // The header and part of the voxels: the stream ends early.
    std::fs::write(&cut, &whole[..whole.len() / 2]).expect("write");
    let e = open_within(&cut, 40 << 10).expect_err("a truncated stream").to_string();
    assert!(e.contains("cut.nii.gz"), "{e}");
    assert!(e.contains("truncated") || e.contains("gzip"), "{e}");
    // A claim the compressed bytes cannot hold is refused before anything is decoded.
    let mut bomb = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    let mut head = flate2::read::GzDecoder::new(&whole[..]);
    let mut header = vec![0u8; 352];
    std::io::Read::read_exact(&mut head, &mut header).expect("header");
    // dim[1..3] = 4096 each: 128 GiB of int16 from a few hundred bytes.
    for i in 0..3 {
        header[42 + 2 * i..44 + 2 * i].copy_from_slice(&4096i16.to_le_bytes());
    }
    std::io::Write::write_all(&mut bomb, &header).expect("gzip");
    let bomb_path = dir.join("bomb.nii.gz");
    std::fs::write(&bomb_path, bomb.finish().expect("gzip")).expect("write");
    let e = open_within(&bomb_path, 40 << 10).expect_err("a bomb").to_string();
    assert!(e.contains("bomb.nii.gz"), "{e}");
}

/// `.vti` files as VTK and ParaView write them (arrays appended, raw or base64), over the host budget: raw
/// uncompressed ones are read in place, the others (zlib, lz4 and lzma blocks, UInt32 and UInt64 headers, base64) by
/// range, each slab decoding only the characters and blocks under it. For every array of each file, the level equals
/// the same level of the file loaded whole, with the same placement; inline arrays are still read whole.
#[test]
fn vti_files_over_the_host_budget_are_read_where_they_lie() {
    use volcast::formats::in_place::{compressed, in_place};
    // (file, encoded: read by range rather than in place): all 7x6x5, written by VTK (tests/data/README.md).
    let cases = [
        ("vtk/vti_appended_raw.vti", false),
        ("vtk/vti_uint64_raw.vti", false),
        ("vtk/vti_big_endian.vti", false),
        ("vtk/vti_extent.vti", false),
        ("vtk/vti_direction.vti", false),
        ("vtk/vti_zlib.vti", true),
        ("vtk/vti_lz4.vti", true),
        ("vtk/vti_lzma.vti", true),
        ("vtk/vti_uint64_header.vti", true),
        ("vtk/vti_appended_base64.vti", true),
        ("vtk/vti_zlib_base64.vti", true),
    ];
    let budgets = Budgets::host(Some(150));
    for (rel, packed) in cases {
        for array in [None, Some("density"), Some("label")] {
            let what = format!("{rel} {array:?}");
            let path = data(rel);
            let opts = OpenOptions {
                array: array.map(String::from),
                ..Default::default()
            };
            let place = match packed {
                false => in_place(&path, &opts).expect("in place"),
                true => compressed(&path, &opts).expect("blocks").filter(|p| p.blocks.is_some()),
            };
            assert!(place.is_some(), "{what}: not read where it lies");
            let level = volcast::scale::open(&path, &opts, budgets, None, &mut |_| {}).expect(&what);
            assert_ne!(level.dims, [7, 6, 5], "{what}: a coarser level");
            let noted = level.notes.iter().any(|n| n.contains("decoded once, on every core"));
            assert_eq!(noted, packed, "{what}: {:?}", level.notes);
            let whole = formats::open(&path, &opts).expect("whole");
            let reduced = volcast::scale::fit(whole, &budgets, false).expect("reduced");
            assert_eq!(level.dims, reduced.dims, "{what}");
            assert!(
                level.data == reduced.data,
                "{what}: differs from the level of the whole file"
            );
            assert_eq!(level.geometry, reduced.geometry, "{what}");
            assert_eq!(level.source_type, reduced.source_type, "{what}");
            assert_eq!(level.arrays, reduced.arrays, "{what}: the file's arrays");
            // Within the budget, an encoded array is decoded by range at full resolution: the loader's volume.
            let full = volcast::scale::open(&path, &opts, Budgets::host(Some(1 << 20)), None, &mut |_| {});
            let full = full.expect(&what);
            let loaded = formats::open(&path, &opts).expect("whole");
            assert!(
                full.data == loaded.data && full.range == loaded.range,
                "{what}: level 0"
            );
            assert_eq!(
                (full.geometry, &full.arrays),
                (loaded.geometry, &loaded.arrays),
                "{what}"
            );
            let by_range = full.notes.iter().any(|n| n.contains("decoded once, on every core"));
            assert_eq!(by_range, packed, "{what}: {:?}", full.notes);
        }
    }
    let inline = data("vtk/vti_zlib_inline.vti");
    let opts = OpenOptions::default();
    assert!(in_place(&inline, &opts).unwrap().is_none() && compressed(&inline, &opts).unwrap().is_none());
}

/// A compressed `.vti` cut short, or whose block header claims more than the file holds, is refused naming the file
/// before any block is decoded.
#[test]
fn a_cut_or_lying_compressed_vti_is_refused_naming_the_file() {
    let dir = common::scratch("streamed-vti");
    let whole = std::fs::read(data("vtk/vti_zlib.vti")).expect("file");
    // The appended bytes start after the underscore that follows <AppendedData>; the default array (`ramp`) is the
    // first, its header 3 + 4 UInt32 words (4 blocks of 64 bytes) before its blocks.
    let tag = whole.windows(13).position(|w| w == b"<AppendedData").expect("appended");
    let at = tag + whole[tag..].iter().position(|&b| b == b'_').expect("underscore") + 1;
    let cut = dir.join("cut.vti");
    std::fs::write(&cut, &whole[..at + 28 + 10]).expect("write");
    let e = open_within(&cut, 150).expect_err("a cut file").to_string();
    assert!(e.contains("cut.vti") && e.contains("past the file's end"), "{e}");
    let mut lying = whole.clone();
    lying[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    let path = dir.join("lying.vti");
    std::fs::write(&path, &lying).expect("write");
    let e = open_within(&path, 150).expect_err("a lying header").to_string();
    assert!(e.contains("lying.vti"), "{e}");
}
