//! OME-Zarr: stores written by ome-zarr-py (0.4 on Zarr v2 with blosc, 0.5 on v3), zarr-python 3 (sharded, zstd,
//! missing chunks, tczyx with omero channels) and a napari-style czyx gzip store, each read back by ome-zarr-py
//! (tests/data/zarr/make.py → expected.json): shapes, values and the affine per level, the level rule, channels and
//! time steps. Then hostile stores built here, each refused with a message naming the store and the problem.

use crate::common;

use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use volcast::formats;
use volcast::formats::OpenOptions;
use volcast::volume::{Volume, VoxelType};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/zarr").join(name)
}

fn expected(name: &str) -> Value {
    serde_json::from_slice(&std::fs::read(data(name).join("expected.json")).unwrap()).unwrap()
}

fn open_with(path: &Path, opts: &OpenOptions) -> Volume {
    formats::open(path, opts).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn err_with(path: &Path, opts: &OpenOptions) -> String {
    match formats::open(path, opts) {
        Ok(v) => panic!("{} opened: {:?}", path.display(), v.dims),
        Err(e) => e.to_string(),
    }
}

/// The level's (x, y, z) dims from its shape (last space axis fastest; 2-D gives depth 1).
fn dims_of(shape: &[u64], space: usize) -> [u32; 3] {
    let n = shape.len();
    let z = if space == 3 { shape[n - 3] } else { 1 };
    [shape[n - 1] as u32, shape[n - 2] as u32, z as u32]
}

fn assert_affine(v: &Volume, want: &Value, what: &str) {
    let rows = v.geometry.rows();
    for r in 0..4 {
        for c in 0..4 {
            let w = want[r][c].as_f64().unwrap();
            assert!(
                (rows[r][c] - w).abs() <= 1e-9 + 1e-6 * w.abs(),
                "{what}: affine {rows:?} != {want}"
            );
        }
    }
}

fn check_values(v: &mut Volume, e: &Value, channel: u64, what: &str) {
    for s in e["values"].as_array().unwrap() {
        if s.get("c").and_then(Value::as_u64).unwrap_or(0) != channel {
            continue;
        }
        let t = s.get("t").and_then(Value::as_u64).unwrap_or(0) as u32;
        v.show_step(t).unwrap();
        let at = |k: &str| s[k].as_u64().unwrap() as u32;
        let got = v.value(at("x"), at("y"), at("z"));
        let want = s["value"].as_f64().unwrap();
        assert!(
            (got - want).abs() <= 1e-6 * want.abs().max(1.0),
            "{what}: {s} read {got}"
        );
    }
}

#[test]
fn every_oracle_store_reads_as_ome_zarr_py_reads_it() {
    let stores = [
        "v04_blosc.zarr",
        "v05.zarr",
        "sharded_tczyx.zarr",
        "napari_czyx.zarr",
        "yx.zarr",
        "dtype_uint8.zarr",
        "dtype_int8.zarr",
        "dtype_uint16.zarr",
        "dtype_int16.zarr",
        "dtype_uint32.zarr",
        "dtype_int32.zarr",
        "dtype_float32.zarr",
        "dtype_float64.zarr",
    ];
    for name in stores {
        let e = expected(name);
        let axes: Vec<&str> = e["axes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a.as_str().unwrap())
            .collect();
        let space = axes.iter().filter(|a| ["x", "y", "z"].contains(a)).count();
        let channels = if axes.contains(&"c") { 2 } else { 1 };
        for c in 0..channels {
            let opts = OpenOptions {
                channel: Some(c as u32),
                ..Default::default()
            };
            let mut v = open_with(&data(name), &opts);
            let level0 = &e["levels"][0];
            let shape: Vec<u64> = level0["shape"]
                .as_array()
                .unwrap()
                .iter()
                .map(|d| d.as_u64().unwrap())
                .collect();
            assert_eq!(v.dims, dims_of(&shape, space), "{name}");
            assert_eq!(v.format, "OME-Zarr");
            assert_eq!(
                v.source_type,
                VoxelType::parse(e["dtype"].as_str().unwrap()).unwrap(),
                "{name}"
            );
            assert!(!v.geometry.anatomical, "{name}");
            assert!(
                v.notes.iter().any(|n| n.contains("no anatomical frame")),
                "{name}: {:?}",
                v.notes
            );
            assert_affine(&v, &level0["affine"], name);
            let steps = if axes.contains(&"t") { shape[0] as u32 } else { 1 };
            assert_eq!(v.timesteps(), steps, "{name}");
            check_values(&mut v, &e, c, name);
        }
    }
}

#[test]
fn the_finest_level_that_fits_is_read_as_stored() {
    let e = expected("v04_blosc.zarr");
    for (max_dim, k) in [(16, 0), (15, 1), (8, 1), (7, 2), (4, 2)] {
        let opts = OpenOptions {
            max_dim: Some(max_dim),
            ..Default::default()
        };
        let v = open_with(&data("v04_blosc.zarr"), &opts);
        let level = &e["levels"][k];
        let shape: Vec<u64> = level["shape"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap())
            .collect();
        assert_eq!(v.dims, dims_of(&shape, 3), "max {max_dim}");
        assert_affine(&v, &level["affine"], &format!("level {k}"));
        if k > 0 {
            let note = format!("level {k} of 3 (");
            assert!(
                v.notes
                    .iter()
                    .any(|n| n.starts_with(&note) && n.contains("level 0 (16x12x8) is too large")),
                "{:?}",
                v.notes
            );
        }
    }
    // Smaller than the coarsest level: the coarsest is downsampled, as any other format would be.
    let opts = OpenOptions {
        max_dim: Some(2),
        ..Default::default()
    };
    let v = open_with(&data("v04_blosc.zarr"), &opts);
    assert!(v.dims.iter().all(|&d| d <= 2), "{:?}", v.dims);
    assert!(v.notes.iter().any(|n| n.contains("no level fits")), "{:?}", v.notes);
}

#[test]
fn channels_and_missing_chunks_of_the_sharded_store() {
    let store = data("sharded_tczyx.zarr");
    let mut v = open_with(
        &store,
        &OpenOptions {
            channel: Some(1),
            ..Default::default()
        },
    );
    v.show_step(1).unwrap();
    // Never-written chunks (t 1, channel 1, z 0..2) read as the fill value 7.
    for z in 0..2 {
        for (x, y) in [(0, 0), (7, 7), (3, 5)] {
            assert_eq!(v.value(x, y, z), 7.0);
        }
    }
    assert!(
        v.notes.iter().any(|n| n.contains("channel 1 (GFP) of 2")),
        "{:?}",
        v.notes
    );
    let e = err_with(
        &store,
        &OpenOptions {
            channel: Some(2),
            ..Default::default()
        },
    );
    assert!(
        e.contains("sharded_tczyx.zarr") && e.contains("channel 2 does not exist") && e.contains("0 (DAPI), 1 (GFP)"),
        "{e}"
    );
}

// ---- hostile stores ----

/// A v3 store: group attributes `ome`, and level arrays (path, metadata) with chunk files (key, bytes).
fn v3_store(dir: &Path, name: &str, ome: Value, arrays: &[(&str, Value)], chunks: &[(&str, Vec<u8>)]) -> PathBuf {
    let root = dir.join(name);
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let group = json!({"zarr_format": 3, "node_type": "group", "attributes": {"ome": ome}});
    std::fs::write(root.join("zarr.json"), group.to_string()).unwrap();
    for (path, meta) in arrays {
        std::fs::create_dir_all(root.join(path)).unwrap();
        std::fs::write(root.join(path).join("zarr.json"), meta.to_string()).unwrap();
    }
    for (key, bytes) in chunks {
        let p = root.join(key);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, bytes).unwrap();
    }
    root
}

fn ome(paths: &[&str]) -> Value {
    let datasets: Vec<Value> = paths
        .iter()
        .map(|p| json!({"path": p, "coordinateTransformations": [{"type": "scale", "scale": [1.0, 1.0, 1.0]}]}))
        .collect();
    json!({"version": "0.5", "multiscales": [{"axes": [
        {"name": "z", "type": "space"}, {"name": "y", "type": "space"}, {"name": "x", "type": "space"}],
        "datasets": datasets}]})
}

fn array(shape: [u64; 3], dtype: &str, codecs: Value) -> Value {
    json!({"zarr_format": 3, "node_type": "array", "shape": shape, "data_type": dtype,
        "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": shape}},
        "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
        "fill_value": 0, "codecs": codecs})
}

fn bytes_codec() -> Value {
    json!([{"name": "bytes", "configuration": {"endian": "little"}}])
}

fn hostile(dir: &Path, name: &str, want: &[&str], build: impl FnOnce(&Path, &str) -> PathBuf) {
    let store = build(dir, name);
    let e = err_with(&store, &OpenOptions::default());
    assert!(e.contains(name), "{name}: message does not name the store: {e}");
    for w in want {
        assert!(e.contains(w), "{name}: {e}");
    }
    let o = common::volcast(&["info", store.to_str().unwrap()]);
    let stderr = common::stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{name}: {stderr}");
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
}

#[test]
fn hostile_chunks_are_refused() {
    let dir = common::scratch("formats-zarr-hostile_chunks_are_refused");
    // A zstd frame that claims a terabyte for a 64-byte chunk.
    hostile(
        &dir,
        "zstd_claim.zarr",
        &["zstd frame claims", "decompression bomb"],
        |d, n| {
            let mut frame = vec![0x28, 0xB5, 0x2F, 0xFD, 0xE0];
            frame.extend((1u64 << 40).to_le_bytes());
            frame.extend([1, 0, 0, 0]);
            let codecs = json!([{"name": "bytes", "configuration": {"endian": "little"}}, {"name": "zstd", "configuration": {"level": 3, "checksum": false}}]);
            v3_store(
                d,
                n,
                ome(&["0"]),
                &[("0", array([4, 4, 4], "uint8", codecs))],
                &[("0/c/0/0/0", frame)],
            )
        },
    );
    // A real gzip stream of 64 MiB of zeros (~64 KiB) for a 64-byte chunk: stopped one byte past the chunk.
    hostile(
        &dir,
        "gzip_bomb.zarr",
        &["gzip stream decodes to more than", "64 bytes"],
        |d, n| {
            use std::io::Write;
            let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
            let zeros = vec![0u8; 1 << 20];
            for _ in 0..64 {
                gz.write_all(&zeros).unwrap();
            }
            let codecs = json!([{"name": "bytes", "configuration": {"endian": "little"}}, {"name": "gzip", "configuration": {"level": 5}}]);
            v3_store(
                d,
                n,
                ome(&["0"]),
                &[("0", array([4, 4, 4], "uint8", codecs))],
                &[("0/c/0/0/0", gz.finish().unwrap())],
            )
        },
    );
    // A shard whose second inner chunk is a zstd frame claiming a terabyte (the first is a real 8-byte chunk).
    hostile(
        &dir,
        "shard_bomb.zarr",
        &["zstd frame claims", "decompression bomb"],
        |d, n| {
            let inner = json!([{"name": "bytes", "configuration": {"endian": "little"}}, {"name": "zstd", "configuration": {"level": 3, "checksum": false}}]);
            let codecs = json!([{"name": "sharding_indexed", "configuration": {"chunk_shape": [2, 2, 2], "codecs": inner,
            "index_codecs": [{"name": "bytes", "configuration": {"endian": "little"}}], "index_location": "end"}}]);
            let good = zstd::bulk::compress(&[5u8; 8], 3).unwrap();
            let mut bomb = vec![0x28, 0xB5, 0x2F, 0xFD, 0xE0];
            bomb.extend((1u64 << 40).to_le_bytes());
            bomb.extend([1, 0, 0, 0]);
            let mut shard = good.clone();
            shard.extend(&bomb);
            let mut index = Vec::new();
            for (offset, len) in [(0, good.len()), (good.len(), bomb.len())] {
                index.extend((offset as u64).to_le_bytes());
                index.extend((len as u64).to_le_bytes());
            }
            for _ in 2..8 {
                index.extend(u64::MAX.to_le_bytes());
                index.extend(u64::MAX.to_le_bytes());
            }
            shard.extend(index);
            v3_store(
                d,
                n,
                ome(&["0"]),
                &[("0", array([4, 4, 4], "uint8", codecs))],
                &[("0/c/0/0/0", shard)],
            )
        },
    );
    // An uncompressed chunk of the wrong size.
    hostile(&dir, "short_chunk.zarr", &["level 0"], |d, n| {
        v3_store(
            d,
            n,
            ome(&["0"]),
            &[("0", array([4, 4, 4], "uint16", bytes_codec()))],
            &[("0/c/0/0/0", vec![1; 10])],
        )
    });
}

#[test]
fn hostile_metadata_is_refused() {
    let dir = common::scratch("formats-zarr-hostile_metadata_is_refused");
    let plain = || array([2, 2, 2], "uint8", bytes_codec());
    hostile(&dir, "petabytes.zarr", &["too large to load"], |d, n| {
        v3_store(
            d,
            n,
            ome(&["0"]),
            &[("0", array([1 << 20, 1 << 20, 1 << 20], "uint8", bytes_codec()))],
            &[],
        )
    });
    for (i, path) in ["../outside", "/abs", "a/../../b"].iter().enumerate() {
        hostile(&dir, &format!("escape{i}.zarr"), &["leaves the store"], |d, n| {
            v3_store(d, n, ome(&[path]), &[], &[])
        });
    }
    hostile(&dir, "unknown_codec.zarr", &["level 0", "frobnicate"], |d, n| {
        let codecs = json!([{"name": "bytes", "configuration": {"endian": "little"}}, {"name": "frobnicate"}]);
        v3_store(d, n, ome(&["0"]), &[("0", array([2, 2, 2], "uint8", codecs))], &[])
    });
    for dtype in ["uint64", "int64", "float16", "complex64", "bool"] {
        let named = format!("unsupported OME-Zarr voxel type '{dtype}'");
        // A fill value of 0 is not even valid for complex and bool arrays: zarrs says so, naming the type.
        let want = if ["complex64", "bool"].contains(&dtype) {
            dtype.to_string()
        } else {
            named
        };
        hostile(&dir, &format!("{dtype}.zarr"), &[&want], |d, n| {
            v3_store(d, n, ome(&["0"]), &[("0", array([2, 2, 2], dtype, bytes_codec()))], &[])
        });
    }
    hostile(&dir, "missing_level.zarr", &["level 0 ('0') is missing"], |d, n| {
        v3_store(d, n, ome(&["0"]), &[], &[])
    });
    hostile(&dir, "truncated_level.zarr", &["level 0 ('0')"], |d, n| {
        let root = v3_store(d, n, ome(&["0"]), &[("0", plain())], &[]);
        std::fs::write(root.join("0/zarr.json"), &plain().to_string()[..40]).unwrap();
        root
    });
    hostile(
        &dir,
        "truncated_group.zarr",
        &["Zarr group metadata cannot be read"],
        |d, n| {
            let root = v3_store(d, n, ome(&["0"]), &[("0", plain())], &[]);
            let text = std::fs::read_to_string(root.join("zarr.json")).unwrap();
            std::fs::write(root.join("zarr.json"), &text[..text.len() / 2]).unwrap();
            root
        },
    );
    hostile(&dir, "no_ome.zarr", &["without OME-Zarr metadata"], |d, n| {
        let root = v3_store(d, n, json!(null), &[], &[]);
        std::fs::write(
            root.join("zarr.json"),
            json!({"zarr_format": 3, "node_type": "group", "attributes": {"foo": 1}}).to_string(),
        )
        .unwrap();
        root
    });
    hostile(
        &dir,
        "bare_array.zarr",
        &["a Zarr array, not an OME-Zarr image"],
        |d, n| {
            let root = d.join(n);
            let _ = std::fs::remove_dir_all(&root);
            std::fs::create_dir_all(&root).unwrap();
            std::fs::write(root.join("zarr.json"), plain().to_string()).unwrap();
            root
        },
    );
}

/// volcast's own placement (`metadata.volcast`, as `volcast convert` writes it) makes the volume anatomical with
/// that affine and scaling; one whose voxel sizes disagree with the scale is ignored with a note.
#[test]
fn volcast_placement_metadata_is_used_when_it_agrees() {
    let dir = common::scratch("formats-zarr-volcast_placement");
    let make = |name: &str, x_step: f64| {
        let mut o = ome(&["0"]);
        o["multiscales"][0]["datasets"][0]["coordinateTransformations"][0]["scale"] = json!([3.0, 2.0, 1.0]);
        o["multiscales"][0]["metadata"] = json!({"volcast": {
            "affine": [[-x_step, 0.0, 0.0, 10.0], [0.0, 2.0, 0.0, -5.0], [0.0, 0.0, 3.0, 7.0], [0.0, 0.0, 0.0, 1.0]],
            "frame": "RAS", "scaling": {"slope": 2.0, "intercept": -1.0}}});
        let chunk: Vec<u8> = (0..8).collect();
        v3_store(
            &dir,
            name,
            o,
            &[("0", array([2, 2, 2], "uint8", bytes_codec()))],
            &[("0/c/0/0/0", chunk)],
        )
    };
    let v = open_with(&make("agrees.zarr", 1.0), &OpenOptions::default());
    assert!(v.geometry.anatomical);
    assert_eq!(v.geometry.rows()[0], [-1.0, 0.0, 0.0, 10.0]);
    assert_eq!(v.value(1, 0, 0), 2.0 * 1.0 - 1.0);
    let v = open_with(&make("disagrees.zarr", 4.0), &OpenOptions::default());
    assert!(!v.geometry.anatomical);
    assert!(
        v.notes.iter().any(|n| n.contains("volcast placement metadata ignored")),
        "{:?}",
        v.notes
    );
}

/// The zarr_meta fuzzer's finding, kept as its seed: an omero colour with a two-byte character made
/// ome_zarr_metadata panic slicing it; the metadata now parses with the channels dropped and a note.
#[test]
fn fuzz_finding_non_ascii_colour_is_not_a_panic() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fuzz/seeds/zarr_meta/fuzz-non-ascii-colour.json"
    );
    let bytes = std::fs::read(path).unwrap();
    let _ = formats::from_bytes::zarr_meta(&bytes);
}
