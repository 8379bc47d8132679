//! `--overlay`, `--threshold` and `--labels` as a user writes them, on the real MNI data in ../shared: the T1 with the
//! motor z-map at |z| ≥ 3 and the AAL atlas (its mricron table found beside it), and the refusals of bad layers.

use crate::common::{scratch, shared_data, stderr, stdout, volcast, volcast_ok};

#[test]
fn t1_with_a_thresholded_z_map_and_atlas_regions_renders_in_depth() {
    let (Some(t1), Some(z), Some(aal)) = (
        shared_data("native/colin27_t1/ch2.nii.gz"),
        shared_data("native/motor_zmap/image_10426.nii.gz"),
        shared_data("native/aal_labels/aal.nii.gz"),
    ) else {
        return;
    };
    let dir = scratch("layers-cli");
    let out = dir.join("fig.png");
    let (t1, z, aal, out_s) = (
        t1.to_str().unwrap(),
        z.to_str().unwrap(),
        aal.to_str().unwrap(),
        out.to_str().unwrap(),
    );
    let cut = ["--view", "superior", "--clip-plane", "0,0,-1,-38", "--size", "256x256"];
    let mut args = vec![
        "render",
        t1,
        "--overlay",
        z,
        "--threshold",
        "3",
        "--labels",
        aal,
        "--label-ids",
        "1,2",
    ];
    args.extend(cut);
    args.extend(["-o", out_s]);
    let o = volcast_ok(&args);
    let err = stderr(&o);
    assert!(err.contains("labels: 116 ids") && err.contains("aal.nii.txt"), "{err}");
    let image = image::open(&out).expect("the figure").to_rgba8();
    // The z-map's positive (warm) and negative (cool) blobs both show over the grey brain.
    let (warm, cool) = warm_and_cool(&image);
    assert!(warm > 60 && cool > 15, "warm {warm} px, cool {cool} px: {}", stdout(&o));
    // A movie shows the layers too: the turntable's first frame is the figure.
    let spin = dir.join("spin.png");
    let movie: Vec<&str> = args[..args.len() - 2]
        .iter()
        .copied()
        .chain(["--turntable", "2", "-o", spin.to_str().unwrap()])
        .collect();
    volcast_ok(&movie);
    let first = image::open(dir.join("spin-0000.png"))
        .expect("the movie's first frame")
        .to_rgba8();
    assert!(
        first == image,
        "the turntable's first frame differs from the still figure"
    );
    // The T1 alone at the same view has (next to) neither.
    let alone = dir.join("alone.png");
    let mut args = vec!["render", t1];
    args.extend(cut);
    args.extend(["-o", alone.to_str().unwrap()]);
    volcast_ok(&args);
    let image = image::open(&alone).expect("the T1").to_rgba8();
    let (warm, cool) = warm_and_cool(&image);
    assert!(warm < 5 && cool < 5, "the T1 alone: warm {warm} px, cool {cool} px");
}

/// `compare` marches the layers in both ray setups, which agree.
#[test]
fn compare_shows_the_layers_in_both_ray_setups() {
    let (Some(t1), Some(z)) = (
        shared_data("native/colin27_t1/ch2.nii.gz"),
        shared_data("native/motor_zmap/image_10426.nii.gz"),
    ) else {
        return;
    };
    let dir = scratch("layers-compare");
    let o = volcast_ok(&[
        "compare",
        t1.to_str().unwrap(),
        "--overlay",
        z.to_str().unwrap(),
        "--threshold",
        "3",
        "--clip-plane",
        "0,0,-1,-38",
        "--size",
        "128x128",
        "--frames",
        "1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let out = stdout(&o);
    assert!(!out.contains("differ beyond the bound"), "{out}");
    // Seen from above (the view axis-z), the blobs above the cut show in both setups.
    for method in ["faces", "analytic"] {
        let image = image::open(dir.join(format!("axis-z-{method}.png")))
            .expect("the view")
            .to_rgba8();
        let (warm, cool) = warm_and_cool(&image);
        assert!(warm + cool > 20, "{method}: warm {warm} px, cool {cool} px");
    }
}

/// Pixels clearly red (the z-map's positive end) and clearly blue (its negative end).
fn warm_and_cool(image: &image::RgbaImage) -> (usize, usize) {
    let warm = image.pixels().filter(|p| p[0] > p[2] + 60 && p[0] > p[1] + 40).count();
    let cool = image.pixels().filter(|p| p[2] > p[0] + 60 && p[2] > p[1] + 40).count();
    (warm, cool)
}

#[test]
fn bad_layers_are_refused_naming_the_file() {
    let Some(t1) = shared_data("native/colin27_t1/ch2.nii.gz") else {
        return;
    };
    let Some(z) = shared_data("native/motor_zmap/image_10426.nii.gz") else {
        return;
    };
    let dir = scratch("layers-bad");
    let out = dir.join("x.png");
    let (t1, z, out) = (t1.to_str().unwrap(), z.to_str().unwrap(), out.to_str().unwrap());
    // A map of floats is not a label map.
    let o = volcast(&["render", t1, "--labels", z, "-o", out]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("image_10426.nii.gz is not a label map") && err.contains("not integer"),
        "{err}"
    );
    // Layers do not mix with a MIP.
    let o = volcast(&["render", t1, "--overlay", z, "--mode", "mip", "-o", out]);
    assert_eq!(o.status.code(), Some(64), "{}", stderr(&o));
    assert!(stderr(&o).contains("emission and density"), "{}", stderr(&o));
    // A label id below zero.
    let neg = dir.write("neg_4x4x4_int16.raw", &[0xffu8; 128]);
    let o = volcast(&["render", t1, "--labels", neg.to_str().unwrap(), "-o", out]);
    assert!(stderr(&o).contains("negative id -1"), "{}", stderr(&o));
}

#[test]
fn stats_gives_each_atlas_region_its_voxels_volume_and_the_t1_under_it() {
    let (Some(t1), Some(aal)) = (
        shared_data("native/colin27_t1/ch2.nii.gz"),
        shared_data("native/aal_labels/aal.nii.gz"),
    ) else {
        return;
    };
    let o = volcast(&[
        "stats",
        t1.to_str().unwrap(),
        "--labels",
        aal.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("JSON");
    let rows = rows.as_array().expect("rows");
    assert_eq!(rows.len(), 116);
    // Independently: the atlas lies on the T1's grid, so the T1 under a label is its voxels there.
    let open = |p: &std::path::Path| volcast::formats::open(p, &Default::default()).expect("open");
    let (t1v, aalv) = (open(&t1), open(&aal));
    assert_eq!(t1v.geometry.affine, aalv.geometry.affine);
    let [w, h, d] = aalv.dims;
    let (mut n, mut sum, mut max) = (0u64, 0.0, f64::MIN);
    for z in 0..d {
        for y in 0..h {
            for x in 0..w {
                if aalv.value(x, y, z) == 1.0 {
                    let v = t1v.value(x, y, z);
                    (n, sum, max) = (n + 1, sum + v, max.max(v));
                }
            }
        }
    }
    let row = &rows[0];
    assert_eq!(row["id"], 1);
    assert_eq!(row["name"], "Precentral_L");
    assert_eq!(row["voxels"].as_u64(), Some(n));
    assert_eq!(row["volume_mm3"].as_f64(), Some(n as f64), "1 mm voxels");
    let under = &row["under"][0];
    assert!(
        (under["mean"].as_f64().unwrap() - sum / n as f64).abs() < 1e-9,
        "{under}"
    );
    assert_eq!(under["max"].as_f64(), Some(max));
}

#[test]
fn a_slicer_segmentation_shows_every_segment_even_where_they_overlap() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/seg");
    let overlap = data.join("overlap.seg.nrrd");
    let o = volcast(&[
        "stats",
        data.join("two.seg.nrrd").to_str().unwrap(),
        "--labels",
        overlap.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("JSON");
    let got: Vec<(String, u64, u64)> = rows
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| {
            (
                r["name"].as_str().unwrap().to_string(),
                r["id"].as_u64().unwrap(),
                r["voxels"].as_u64().unwrap(),
            )
        })
        .collect();
    let want = [("liver", 1, 216), ("tumour", 2, 36), ("core", 1, 8)].map(|(n, i, v)| (n.to_string(), i, v));
    assert_eq!(got, want, "slicerio's masks (tests/data/seg/make.py)");
    // Under them, the two-segment file (the same grid): the liver reads 1, the tumour 2, the core (in the liver) 1.
    let means: Vec<f64> = rows
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["under"][0]["mean"].as_f64().unwrap())
        .collect();
    assert_eq!(means, [1.0, 2.0, 1.0]);
    // Both layers of the file are rendered.
    let dir = scratch("layers-seg");
    let out = dir.join("seg.png");
    let o = volcast_ok(&[
        "render",
        data.join("two.seg.nrrd").to_str().unwrap(),
        "--labels",
        overlap.to_str().unwrap(),
        "--size",
        "64x64",
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(err.contains("layer 0 of") && err.contains("layer 1 of"), "{err}");
}
