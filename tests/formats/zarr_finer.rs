//! An OME-Zarr store held at a coarser level keeps its level 0 behind it (docs/large-volumes.md, "Full resolution
//! from the file"): a streamed pool reads finer bricks from the store's level 0 (only the chunks under each box),
//! reduced by the pyramid's rule. Every box of every finer level equals that level of the pyramid made from the
//! store's level 0, for stores written by ome-zarr-py (Zarr v2 with blosc, channels) and by `volcast convert` (small
//! chunks, so that boxes straddle them); `--max-dim` and a store whose levels are placed otherwise get none.

use crate::common;
use std::path::{Path, PathBuf};
use volcast::convert::source::Source;
use volcast::formats;
use volcast::formats::OpenOptions;
use volcast::pyramid::budget::Budgets;
use volcast::volume::{Volume, VoxelData};

fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel)
}

/// `path` opened within a host budget one byte short of `level0_bytes`.
fn held(path: &Path, opts: &OpenOptions, host: u64) -> Volume {
    volcast::scale::open(path, opts, Budgets::host(Some(host)), None, &mut |_| {})
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Every finer level of `held`, read whole and as a box at an odd offset, equals `level(l)`.
fn assert_boxes_are_the_pyramid(name: &str, held: &Volume, level: impl Fn(u32) -> Volume) {
    let finer = held
        .finer
        .as_ref()
        .unwrap_or_else(|| panic!("{name}: the store's level 0 stays behind"));
    for l in 0..finer.held() {
        let want = level(l);
        let d = want.dims;
        assert_eq!(finer.read(l, [0; 3], d).unwrap(), want.data, "{name}: level {l} whole");
        let lo = d.map(|n| n / 2);
        let size = [0, 1, 2].map(|a| d[a] - lo[a]);
        let got = finer.read(l, lo, size).unwrap();
        let at = |p: [u32; 3], s: [u32; 3]| (p[0] + s[0] * (p[1] + s[1] * p[2])) as usize;
        for z in 0..size[2] {
            for y in 0..size[1] {
                for x in 0..size[0] {
                    let (i, j) = (at([x, y, z], size), at([lo[0] + x, lo[1] + y, lo[2] + z], d));
                    let same = match (&got, &want.data) {
                        (VoxelData::U8(a), VoxelData::U8(b)) => a[i] == b[j],
                        (VoxelData::U16(a), VoxelData::U16(b)) => a[i] == b[j],
                        (VoxelData::F32(a), VoxelData::F32(b)) => a[i].to_bits() == b[j].to_bits(),
                        _ => false,
                    };
                    assert!(same, "{name}: level {l} box {lo:?} at {x},{y},{z}");
                }
            }
        }
    }
}

#[test]
fn stores_from_ome_zarr_py_stream_their_level_0() {
    // (store, channel, level 0's bytes): each held at level 1 within one byte less.
    for (rel, channel, bytes) in [
        ("zarr/v04_blosc.zarr", None, 16 * 12 * 8 * 2),
        ("zarr/napari_czyx.zarr", Some(1), 8 * 6 * 4 * 4),
        ("zarr/v05.zarr", None, 12 * 10 * 6 * 4),
    ] {
        let path = data(rel);
        let opts = OpenOptions {
            channel,
            ..Default::default()
        };
        let v = held(&path, &opts, bytes - 1);
        let whole = formats::open(&path, &opts).expect("level 0");
        assert_eq!(
            v.finer.as_ref().map(|f| (f.held(), f.dims())),
            Some((1, whole.dims)),
            "{rel}"
        );
        assert_eq!(v.finer.as_ref().unwrap().geometry(), whole.geometry, "{rel}");
        let source = Source::Loaded(Box::new(whole.clone()));
        assert_boxes_are_the_pyramid(rel, &v, |l| match l {
            0 => whole.clone(),
            _ => volcast::scale::read::read_level(&source, l, 1 << 30, Vec::new(), &mut |_| {}).unwrap(),
        });
        // `--max-dim` asks for no more than the level it chose.
        let capped = OpenOptions {
            max_dim: Some(v.dims.into_iter().max().unwrap()),
            ..opts
        };
        assert!(held(&path, &capped, bytes - 1).finer.is_none(), "{rel}");
    }
}

#[test]
fn a_store_volcast_wrote_streams_its_level_0_across_chunks() {
    // 37x21x40 int16 with negative values, in chunks of 8: held at level 2, levels 0 and 1 from the store.
    let dims = [37u32, 21, 40];
    let values: Vec<i16> = (0..dims.iter().product::<u32>())
        .map(|i| ((i as i64 * 7919) % 601 - 300) as i16)
        .collect();
    let dir = common::scratch("zarr-finer-convert");
    let raw = dir.write("v_37x21x40_int16.raw", bytemuck::cast_slice(&values));
    let whole = formats::open(&raw, &OpenOptions::default()).expect("raw");
    let store = dir.join("v.ome.zarr");
    let opts = volcast::convert::ConvertOptions {
        version: volcast::convert::layout::OmeVersion::V05,
        chunk: 8,
        shard: None,
        compression: volcast::convert::Compression::Zstd,
        reduce: volcast::pyramid::reduce::Reduce::Mean,
        step: None,
        stored: false,
    };
    let source = Source::Loaded(Box::new(whole.clone()));
    volcast::convert::convert(&source, &store, &opts, &mut |_| {}).expect("convert");
    let level1: u64 = 19 * 11 * 20 * 2;
    let v = held(&store, &OpenOptions::default(), level1 - 1);
    assert_eq!((v.dims, v.finer.as_ref().map(|f| f.held())), ([10, 6, 10], Some(2)));
    assert_boxes_are_the_pyramid("convert", &v, |l| match l {
        0 => formats::open(&store, &OpenOptions::default()).expect("level 0"),
        _ => volcast::scale::read::read_level(&source, l, 1 << 30, Vec::new(), &mut |_| {}).unwrap(),
    });
    assert!(
        v.finer.as_ref().unwrap().read(2, [0; 3], [1; 3]).is_err(),
        "the held level is not read"
    );
}

#[test]
fn a_store_whose_levels_are_placed_otherwise_keeps_its_level() {
    // v05.zarr with its level 1 placed at level 0's first voxel (no half-voxel translation): finer bricks would not
    // sit where the held ones do, so none are read.
    let dir = common::scratch("zarr-finer-misplaced");
    let store = dir.join("v05.zarr");
    copy_folder(&data("zarr/v05.zarr"), &store);
    let meta = store.join("zarr.json");
    let mut json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&meta).expect("read")).unwrap();
    let shift = &mut json["attributes"]["ome"]["multiscales"][0]["datasets"][1]["coordinateTransformations"][1];
    assert_eq!(shift["type"], "translation");
    shift["translation"] = serde_json::json!([0.0, 0.0, 0.0]);
    std::fs::write(&meta, json.to_string()).expect("write");
    let v = held(&store, &OpenOptions::default(), 12 * 10 * 6 * 4 - 1);
    assert_eq!(v.dims, [6, 5, 3]);
    assert!(v.finer.is_none(), "a level placed otherwise streams nothing finer");
}

fn copy_folder(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("folder");
    for entry in std::fs::read_dir(from).expect("read") {
        let path = entry.expect("entry").path();
        let dst = to.join(path.file_name().expect("name"));
        if path.is_dir() {
            copy_folder(&path, &dst);
        } else {
            std::fs::copy(&path, &dst).expect("copy");
        }
    }
}
