//! `volcast convert` end to end: stores read back by zarr-python and ome-zarr-py (tests/python/read_back.py, the
//! pinned environment), never by volcast's own reader. Level 0 must equal the input's voxels, level 1 the documented
//! mean (or label rule) of level 0 computed here, and the axes, scales and translations must follow the placement
//! convention (docs/cli.md, convert) for what `volcast info --json` says of the input.

use crate::common;
use common::{stderr, stdout, volcast};
use serde_json::Value;
use std::path::Path;

/// zarr-python's and ome-zarr-py's view of `store`, each level's values dumped beside it; `None` (skipped) without
/// the pinned Python.
fn read_back(store: &Path) -> Option<(Value, Vec<Vec<f64>>)> {
    let python = common::test_python()?;
    let dump = store.with_extension("dump");
    let _ = std::fs::remove_dir_all(&dump);
    std::fs::create_dir_all(&dump).unwrap();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/python/read_back.py");
    let o = std::process::Command::new(python)
        .args([script, &store.to_string_lossy(), &dump.to_string_lossy()])
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "read_back.py: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let json: Value = serde_json::from_slice(&o.stdout).unwrap();
    let levels = (0..json["levels"].as_array().unwrap().len())
        .map(|k| {
            let bytes = std::fs::read(dump.join(format!("level{k}.f64"))).unwrap();
            bytes
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
                .collect()
        })
        .collect();
    // ome-zarr-py sees the same levels and values as zarr-python.
    let py = &json["ome_zarr_py"];
    assert_eq!(py["levels"], json["levels"].as_array().unwrap().len(), "{json}");
    assert_eq!(py["data_equal"], true, "{json}");
    Some((json, levels))
}

fn convert_ok(args: &[&str]) -> String {
    let mut all = vec!["convert"];
    all.extend_from_slice(args);
    let o = volcast(&all);
    assert!(o.status.success(), "{:?}: {}", all, stderr(&o));
    format!("{}{}", stdout(&o), stderr(&o))
}

/// The documented rule for one level from the one above (`dims` x, y, z; x fastest): the mean of each block of up
/// to 2x2x2 voxels (axes of length 1 not halved), rounded half away from zero for integer types.
fn expected_mean(fine: &[f64], [w, h, d]: [usize; 3], integer: bool) -> Vec<f64> {
    reduce_blocks(fine, [w, h, d], |block| {
        let mean = block.iter().sum::<f64>() / block.len() as f64;
        if integer {
            mean.round()
        } else {
            f64::from(mean as f32)
        }
    })
}

fn reduce_blocks(fine: &[f64], [w, h, d]: [usize; 3], rule: impl Fn(&[f64]) -> f64) -> Vec<f64> {
    let step = |n: usize| if n > 1 { 2 } else { 1 };
    let (fx, fy, fz) = (step(w), step(h), step(d));
    let mut out = Vec::new();
    for z in (0..d).step_by(fz) {
        for y in (0..h).step_by(fy) {
            for x in (0..w).step_by(fx) {
                let mut block = Vec::new();
                for zz in z..(z + fz).min(d) {
                    for yy in y..(y + fy).min(h) {
                        for xx in x..(x + fx).min(w) {
                            block.push(fine[xx + w * (yy + h * zz)]);
                        }
                    }
                }
                out.push(rule(&block));
            }
        }
    }
    out
}

fn info(args: &[&str]) -> Value {
    let mut all = vec!["info", "--json"];
    all.extend_from_slice(args);
    let o = volcast(&all);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&stdout(&o)).unwrap()
}

/// The store's axis names, slowest first.
fn axis_names(json: &Value) -> Vec<&str> {
    json["axes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["name"].as_str().unwrap())
        .collect()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

fn close(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-6 * (1.0 + y.abs()))
}

/// Level k's scale and translation by the convention, from level 0's and its span per axis (z, y, x).
fn placed(scale0: &[f64], translation0: &[f64], span: [f64; 3]) -> (Vec<f64>, Vec<f64>) {
    let s = (0..3).map(|i| scale0[i] * span[i]).collect();
    let t = (0..3)
        .map(|i| translation0[i] + (span[i] - 1.0) / 2.0 * scale0[i])
        .collect();
    (s, t)
}

/// The CT head (int16) read in place, spacing given, as OME-Zarr 0.4 with blosc: every level's shape, type, axes and
/// placement, level 0 the file's voxels, level 1 their rounded mean.
#[test]
fn ct_head_raw_to_ome_zarr_04_with_blosc() {
    let Some(raw) = common::shared_data("raw/cranium_ct_256x256x108_int16.raw") else {
        return;
    };
    let dir = common::scratch("cli-convert-ct");
    let store = dir.join("ct.ome.zarr");
    let (raw_s, store_s) = (raw.to_string_lossy(), store.to_string_lossy());
    let spacing = ["--spacing", "0.957031", "0.957031", "1.5"];
    let mut args = vec![
        &*raw_s,
        &*store_s,
        "--ome-zarr-version",
        "0.4",
        "--compression",
        "blosc",
    ];
    args.extend(spacing);
    let said = convert_ok(&args);
    assert!(said.contains("3 levels: 256x256x108, 128x128x54, 64x64x27"), "{said}");
    assert!(said.contains("int16, the file's type"), "{said}");
    let Some((json, levels)) = read_back(&store) else {
        return;
    };
    assert_eq!(json["zarr_format"], 2);
    assert_eq!(json["ome_version"], "0.4");
    assert_eq!(json["name"], "cranium_ct");
    assert_eq!(axis_names(&json), ["z", "y", "x"]);
    assert!(json["axes"]
        .as_array()
        .unwrap()
        .iter()
        .all(|a| a["unit"] == "millimeter" && a["type"] == "space"));
    let l = json["levels"].as_array().unwrap();
    assert_eq!(l[0]["shape"], serde_json::json!([108, 256, 256]));
    assert_eq!(l[2]["shape"], serde_json::json!([27, 64, 64]));
    assert_eq!(l[0]["dtype"], "int16");
    assert_eq!(l[0]["chunks"], serde_json::json!([64, 64, 64]));
    assert!(l[0]["compressors"][0].as_str().unwrap().contains("Blosc"), "{}", l[0]);
    let bytes = std::fs::read(&raw).unwrap();
    let voxels: Vec<f64> = bytes
        .chunks_exact(2)
        .map(|b| f64::from(i16::from_le_bytes([b[0], b[1]])))
        .collect();
    assert!(levels[0] == voxels, "level 0 differs from the file's voxels");
    assert!(
        levels[1] == expected_mean(&voxels, [256, 256, 108], true),
        "level 1 is not the mean"
    );
    let i = info(&[&raw_s, spacing[0], spacing[1], spacing[2], spacing[3]]);
    let sp = floats(&i["spacing"]);
    let scale0 = vec![sp[2], sp[1], sp[0]];
    assert!(close(&floats(&l[0]["scale"]), &scale0), "{}", l[0]);
    assert!(close(&floats(&l[0]["translation"]), &[0.0; 3]), "{}", l[0]);
    let (s2, t2) = placed(&scale0, &[0.0; 3], [4.0; 3]);
    assert!(
        close(&floats(&l[2]["scale"]), &s2) && close(&floats(&l[2]["translation"]), &t2),
        "{}",
        l[2]
    );
    assert_eq!(json["volcast"]["frame"], Value::Null);
}

/// A built-in volume (loaded, not a file) as OME-Zarr 0.5 with zstd: level 0 equals the generator's voxels.
#[test]
fn builtin_volume_to_ome_zarr_05() {
    let dir = common::scratch("cli-convert-builtin");
    let store = dir.join("helix.ome.zarr");
    let said = convert_ok(&[
        "--builtin",
        "helix",
        "--builtin-size",
        "100",
        "-o",
        &store.to_string_lossy(),
    ]);
    assert!(said.contains("2 levels: 100x100x100, 50x50x50"), "{said}");
    let Some((json, levels)) = read_back(&store) else {
        return;
    };
    assert_eq!(json["zarr_format"], 3);
    assert_eq!(json["ome_version"], "0.5");
    let v = volcast::volume::builtin("helix", Some(100)).unwrap();
    let expected: Vec<f64> = (0..100u32)
        .flat_map(|z| (0..100u32).flat_map(move |y| (0..100u32).map(move |x| (x, y, z))))
        .map(|(x, y, z)| v.stored(x, y, z))
        .collect();
    assert!(levels[0] == expected, "level 0 differs from the built-in's voxels");
    let integer = json["levels"][0]["dtype"].as_str().unwrap().contains("int");
    assert!(levels[1] == expected_mean(&expected, [100; 3], integer));
    assert!(json["levels"][0]["compressors"][0].as_str().unwrap().contains("Zstd"));
    let l1 = &json["levels"][1];
    assert!(
        close(&floats(&l1["scale"]), &[2.0; 3]) && close(&floats(&l1["translation"]), &[0.5; 3]),
        "{l1}"
    );
}

/// The fMRI map (NIfTI, LAS: x flipped) loaded from .nii.gz and read in place from the same file uncompressed: the
/// same store either way, float32, a note that the placement is only the nearest axis-aligned one, and the exact
/// affine and RAS frame under "volcast".
#[test]
fn flipped_nifti_keeps_its_affine_and_frame() {
    let Some(gz) = common::shared_data("native/motor_zmap/image_10426.nii.gz") else {
        return;
    };
    let dir = common::scratch("cli-convert-nifti");
    let mut nii = Vec::new();
    std::io::Read::read_to_end(
        &mut flate2::read::GzDecoder::new(std::fs::File::open(&gz).unwrap()),
        &mut nii,
    )
    .unwrap();
    let plain = dir.write("motor.nii", &nii);
    let (a, b) = (dir.join("gz.ome.zarr"), dir.join("plain.ome.zarr"));
    let said = convert_ok(&[&gz.to_string_lossy(), &a.to_string_lossy()]);
    assert!(said.contains("nearest axis-aligned placement"), "{said}");
    assert!(said.contains("float32"), "{said}");
    convert_ok(&[&plain.to_string_lossy(), &b.to_string_lossy()]);
    let Some((ja, la)) = read_back(&a) else { return };
    let (jb, lb) = read_back(&b).unwrap();
    assert!(la == lb, "the in-place read differs from the loaded one");
    assert_eq!(ja["levels"], jb["levels"]);
    assert_eq!(ja["levels"][0]["dtype"], "float32");
    assert_eq!(ja["levels"].as_array().unwrap().len(), 1, "53x63x46 fits in 64³");
    let i = info(&[&gz.to_string_lossy()]);
    let rows = i["affine_ras"].as_array().unwrap();
    let written = ja["volcast"]["affine"].as_array().unwrap();
    for r in 0..3 {
        assert!(
            close(&floats(&written[r]), &floats(&rows[r])),
            "{written:?} vs {rows:?}"
        );
    }
    assert_eq!(ja["volcast"]["frame"], "RAS");
    assert!(floats(&written[0])[0] < 0.0, "LAS: x flipped");
    let origin = [floats(&rows[2])[3], floats(&rows[1])[3], floats(&rows[0])[3]];
    let sp = floats(&i["spacing"]);
    let l0 = &ja["levels"][0];
    assert!(close(&floats(&l0["scale"]), &[sp[2], sp[1], sp[0]]), "{l0}");
    assert!(close(&floats(&l0["translation"]), &origin), "{l0}");
}

/// An odd-sized big-endian uint16 raw generated here, sharded (128³ shards of 64³ chunks): odd edges in level 1's
/// mean, big-endian bytes swapped, three levels, shards read back.
#[test]
fn odd_sized_raw_sharded() {
    let dir = common::scratch("cli-convert-odd");
    let (w, h, d) = (131usize, 67usize, 70usize);
    let values: Vec<u16> = (0..w * h * d).map(|i| ((i * 7919) % 65521) as u16).collect();
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
    let raw = dir.write("odd_131x67x70_uint16.raw", &bytes);
    let store = dir.join("odd.ome.zarr");
    let said = convert_ok(&[
        &raw.to_string_lossy(),
        &store.to_string_lossy(),
        "--endian",
        "big",
        "--shard",
        "128",
    ]);
    assert!(said.contains("3 levels: 131x67x70, 66x34x35, 33x17x18"), "{said}");
    let Some((json, levels)) = read_back(&store) else {
        return;
    };
    let l = json["levels"].as_array().unwrap();
    assert_eq!(l[0]["shards"], serde_json::json!([128, 128, 128]));
    assert_eq!(l[0]["chunks"], serde_json::json!([64, 64, 64]));
    let fine: Vec<f64> = values.iter().map(|&v| f64::from(v)).collect();
    assert!(levels[0] == fine);
    let l1 = expected_mean(&fine, [w, h, d], true);
    assert!(levels[1] == l1, "level 1 is not the mean at odd edges");
    assert!(levels[2] == expected_mean(&l1, [66, 34, 35], true));
}

/// Label data: the most common value of each block (ties: the smallest), or with `--labels nearest` its first voxel.
#[test]
fn labels_take_the_mode_or_the_first_voxel() {
    let dir = common::scratch("cli-convert-labels");
    let (w, h, d) = (67usize, 66usize, 65usize);
    let labels: Vec<u8> = (0..w * h * d).map(|i| ((i * 31 + i / 97) % 5) as u8).collect();
    let raw = dir.write("labels_67x66x65_uint8.raw", &labels);
    let fine: Vec<f64> = labels.iter().map(|&v| f64::from(v)).collect();
    let mode = |b: &[f64]| {
        let mut best = (0usize, f64::MAX);
        for &v in b {
            let n = b.iter().filter(|&&u| u == v).count();
            if n > best.0 || (n == best.0 && v < best.1) {
                best = (n, v);
            }
        }
        best.1
    };
    // Also Zarr v3 without compression and with blosc (lz4).
    for (flag, rule, compressor) in [
        (
            vec!["--compression", "none", "--labels"],
            &mode as &dyn Fn(&[f64]) -> f64,
            None,
        ),
        (
            vec!["--compression", "blosc", "--labels", "nearest"],
            &|b: &[f64]| b[0],
            Some("Blosc"),
        ),
    ] {
        let store = dir.join(format!("labels-{}.ome.zarr", flag.len()));
        let mut args = vec![raw.to_str().unwrap(), store.to_str().unwrap()];
        args.extend(flag);
        convert_ok(&args);
        let Some((json, levels)) = read_back(&store) else {
            return;
        };
        let compressors = json["levels"][0]["compressors"].as_array().unwrap();
        match compressor {
            None => assert!(compressors.is_empty(), "{compressors:?}"),
            Some(name) => assert!(compressors[0].as_str().unwrap().contains(name), "{compressors:?}"),
        }
        assert!(levels[0] == fine);
        assert!(levels[1] == reduce_blocks(&fine, [w, h, d], rule), "{args:?}");
    }
}

/// An existing output is refused (exit 64, nothing touched) unless --overwrite, which replaces only a Zarr store; an
/// output whose folder cannot be made and a truncated raw input fail with messages that name the paths.
#[test]
fn existing_unwritable_and_truncated() {
    let dir = common::scratch("cli-convert-errors");
    let raw = dir.write("small_8x8x8_uint8.raw", &[7u8; 512]);
    let store = dir.join("small.ome.zarr");
    let (raw_s, store_s) = (raw.to_string_lossy(), store.to_string_lossy());
    convert_ok(&[&raw_s, &store_s]);
    let o = volcast(&["convert", &raw_s, &store_s]);
    assert_eq!(o.status.code(), Some(64), "{}", stderr(&o));
    assert!(stderr(&o).contains("exists; pass --overwrite"), "{}", stderr(&o));
    convert_ok(&[&raw_s, &store_s, "--overwrite"]);
    // A plain file is never replaced, --overwrite or not.
    let file = dir.write("notes.txt", b"keep me");
    let o = volcast(&["convert", &raw_s, &file.to_string_lossy(), "--overwrite"]);
    assert_eq!(o.status.code(), Some(64), "{}", stderr(&o));
    assert_eq!(std::fs::read(&file).unwrap(), b"keep me");
    // A folder inside a file cannot be made (root ignores permission bits, so a mode would not test this).
    let inside = file.join("out.ome.zarr");
    let o = volcast(&["convert", &raw_s, &inside.to_string_lossy()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("notes.txt/out.ome.zarr"), "{}", stderr(&o));
    let short = dir.write("short_16x16x16_uint8.raw", &[1u8; 4000]);
    let o = volcast(&[
        "convert",
        &short.to_string_lossy(),
        &dir.join("short.ome.zarr").to_string_lossy(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("short_16x16x16_uint8.raw"), "{}", stderr(&o));
    assert!(
        !dir.join("short.ome.zarr").exists(),
        "nothing is written for an input that cannot be read"
    );
    let o = volcast(&[
        "convert",
        &raw_s,
        &dir.join("x.ome.zarr").to_string_lossy(),
        "--ome-zarr-version",
        "0.4",
        "--shard",
        "128",
    ]);
    assert_eq!(o.status.code(), Some(64), "{}", stderr(&o));
}

/// A 4-D NRRD (read in place, big-endian int16, LPS space) writes a leading t axis; each step goes through the same
/// pipeline, and `--time N` writes that step alone as a 3-D store.
#[test]
fn time_series_gets_a_t_axis() {
    let dir = common::scratch("cli-convert-series");
    let (w, h, d, t) = (70usize, 66usize, 3usize, 2usize);
    let values: Vec<i16> = (0..w * h * d * t).map(|i| ((i * 131) % 4001) as i16 - 2000).collect();
    let mut bytes = format!(
        "NRRD0004\ntype: int16\ndimension: 4\nsizes: {w} {h} {d} {t}\nencoding: raw\nendian: big\n\
         space: left-posterior-superior\nspace directions: (1,0,0) (0,2,0) (0,0,3) none\nspace origin: (10,20,30)\n\n"
    )
    .into_bytes();
    bytes.extend(values.iter().flat_map(|v| v.to_be_bytes()));
    let nrrd = dir.write("series.nrrd", &bytes);
    let store = dir.join("series.ome.zarr");
    let said = convert_ok(&[&nrrd.to_string_lossy(), &store.to_string_lossy()]);
    assert!(said.contains("x 2 time steps"), "{said}");
    let Some((json, levels)) = read_back(&store) else {
        return;
    };
    assert_eq!(axis_names(&json), ["t", "z", "y", "x"]);
    assert_eq!(json["axes"][0]["type"], "time");
    let l = json["levels"].as_array().unwrap();
    assert_eq!(l[0]["shape"], serde_json::json!([2, 3, 66, 70]));
    assert_eq!(l[0]["dtype"], "int16");
    let fine: Vec<f64> = values.iter().map(|&v| f64::from(v)).collect();
    assert!(levels[0] == fine);
    let step = w * h * d;
    let mut l1 = expected_mean(&fine[..step], [w, h, d], true);
    l1.extend(expected_mean(&fine[step..], [w, h, d], true));
    assert!(levels[1] == l1, "each step's level 1 is its own mean");
    // LPS → RAS: x and y flipped, so the placement is the nearest axis-aligned one; the affine says all.
    assert_eq!(json["volcast"]["frame"], "RAS");
    assert_eq!(json["volcast"]["affine"][0][0], -1.0);
    let one = dir.join("step1.ome.zarr");
    convert_ok(&[&nrrd.to_string_lossy(), &one.to_string_lossy(), "--time", "1"]);
    let (json, levels) = read_back(&one).unwrap();
    assert_eq!(json["levels"][0]["shape"], serde_json::json!([3, 66, 70]));
    assert!(levels[0] == fine[step..]);
}

/// A MetaImage header with a detached data file is read in place from that file; so is a raw file, while a
/// compressed NIfTI is loaded.
#[test]
fn uncompressed_files_are_read_in_place() {
    let dir = common::scratch("cli-convert-in-place");
    let values: Vec<i16> = (0..5 * 4 * 3).map(|i| i * 97 - 2000).collect();
    dir.write(
        "vol.raw",
        &values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>(),
    );
    let mhd = dir.write(
        "vol.mhd",
        b"ObjectType = Image\nNDims = 3\nDimSize = 5 4 3\nElementType = MET_SHORT\nElementSpacing = 0.5 1 2\n\
          BinaryData = True\nBinaryDataByteOrderMSB = False\nElementDataFile = vol.raw\n",
    );
    let store = dir.join("mhd.ome.zarr");
    let said = convert_ok(&[&mhd.to_string_lossy(), &store.to_string_lossy()]);
    assert!(said.contains("vol.raw in place"), "{said}");
    let Some((json, levels)) = read_back(&store) else {
        return;
    };
    assert_eq!(json["levels"][0]["dtype"], "int16");
    assert!(levels[0] == values.iter().map(|&v| f64::from(v)).collect::<Vec<_>>());
    if let Some(gz) = common::shared_data("native/motor_zmap/image_10426.nii.gz") {
        let said = convert_ok(&[&gz.to_string_lossy(), &dir.join("gz.ome.zarr").to_string_lossy()]);
        assert!(!said.contains("in place"), "{said}");
    }
}
