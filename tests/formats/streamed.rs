//! Compressed files over the host budget (docs/large-volumes.md, "How files are read"): a gzip NIfTI (nibabel), gzip
//! NRRD inline and detached (pynrrd) and a zlib MetaImage (SimpleITK) are decoded once, front to back, into the
//! pyramid level the budget holds, never held whole. Each level equals the same level made from the file loaded
//! whole by its format's own reader (`scale::fit`), voxel for voxel, with the same placement; a truncated stream is
//! refused naming the file.

use crate::common;
use std::path::{Path, PathBuf};
use volcast::volume::budget::Budgets;
use volcast::volume::{self, OpenOptions};

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
        let whole = volume::open(&path, &OpenOptions::default()).expect("whole");
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
