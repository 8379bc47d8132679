//! Time series (4-D NIfTI, NRRD, MetaImage, a DICOM series with temporal positions) against oracle files written
//! by nibabel, pynrrd, SimpleITK and pydicom and read back by them (tests/data/time/make.py → expected.json): every step's voxels, the series' value range, the
//! affine; each shown step rendered against the independent reference under validation; the CLI's `--time` and
//! `info`; headers claiming more steps than memory holds.

use crate::common;

use common::bounds::REFERENCE;
use common::cases::standard_cases;
use common::compare::diff;
use common::gpu::{finish, validated_gpu, Judge, METHODS};
use common::{stderr, stdout, volcast};
use std::path::{Path, PathBuf};
use volcast::formats;
use volcast::render::headless::Headless;
use volcast::volume::Volume;

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/time")
}

fn expected() -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(data().join("expected.json")).unwrap()).unwrap()
}

fn open(name: &str) -> Volume {
    formats::open(&data().join(name), &Default::default()).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn every_step_of_every_oracle_loads() {
    let all = expected();
    let cases = all["cases"].as_object().unwrap();
    assert_eq!(cases.len(), 5);
    for (name, e) in cases {
        let mut v = open(name);
        let f = |x: &serde_json::Value| x.as_f64().unwrap();
        let dims: Vec<u32> = e["dims"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap() as u32)
            .collect();
        assert_eq!(v.dims.to_vec(), dims, "{name}");
        let steps = e["steps"].as_array().unwrap();
        assert_eq!(v.timesteps() as usize, steps.len(), "{name}");
        assert_eq!(
            v.stored_range,
            [f(&e["min"]), f(&e["max"])],
            "{name}: the range is the whole series'"
        );
        if let Some(aff) = e.get("affine") {
            let rows = v.geometry.rows();
            for (r, want_row) in aff.as_array().unwrap().iter().enumerate() {
                for (c, want) in want_row.as_array().unwrap().iter().enumerate() {
                    assert!((rows[r][c] - f(want)).abs() < 1e-6, "{name}: affine {rows:?}");
                }
            }
        }
        let (slope, intercept) = (e.get("slope").map_or(1.0, f), e.get("intercept").map_or(0.0, f));
        assert_eq!((v.scaling.slope, v.scaling.intercept), (slope, intercept), "{name}");
        // Shown in a scrambled order, so a step left behind by the swap shows.
        let n = steps.len();
        let order: Vec<usize> = (0..n).rev().step_by(2).chain((0..n).rev().skip(1).step_by(2)).collect();
        assert_eq!(order.len(), n);
        for t in order {
            v.show_step(t as u32).unwrap();
            assert_eq!(v.shown_step() as usize, t);
            let want = steps[t].as_array().unwrap();
            let [w, h, d] = v.dims;
            for z in 0..d {
                for y in 0..h {
                    for x in 0..w {
                        let i = (x + w * (y + h * z)) as usize;
                        assert_eq!(v.stored(x, y, z), f(&want[i]), "{name}: step {t} voxel ({x}, {y}, {z})");
                    }
                }
            }
        }
        assert_eq!(
            v.stored_range,
            [f(&e["min"]), f(&e["max"])],
            "{name}: showing a step keeps the range"
        );
    }
}

/// Each shown step is what reaches the GPU: steps 0, 3 and 6 against the reference, and no two alike.
#[test]
fn shown_steps_render_against_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let mut images = Vec::new();
    for name in ["fmri_f32.nii.gz", "sim_u16.nrrd"] {
        let mut v = open(name);
        for t in [0, 3, 6] {
            v.show_step(t).unwrap();
            v.name = format!("{}-t{t}", name.split('.').next().unwrap());
            headless.set_volume(&gpu, &v).expect("upload");
            let cases: Vec<_> = standard_cases(&v, 48).into_iter().take(2).collect();
            let s = cases[0].settings.clone();
            judge.run_cases(("reference", REFERENCE), &gpu, &mut headless, &v, cases, METHODS);
            images.push(headless.render(&gpu, &s).expect("render").image);
        }
    }
    for pair in images.chunks(3) {
        assert!(
            diff(&pair[0], &pair[1]).max > 8.0 && diff(&pair[1], &pair[2]).max > 8.0,
            "steps look alike"
        );
    }
    finish(gpu, headless, judge);
}

#[test]
fn cli_shows_timesteps_and_renders_one() {
    let file = data().join("sim_u16.nrrd");
    let file = file.to_str().unwrap();
    let o = volcast(&["info", "--json", file]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(json["timesteps"], 7);
    assert_eq!(json["value_range"], serde_json::json!([3.0, 293.0]));
    let o = volcast(&["info", file]);
    let out = stdout(&o);
    assert!(o.status.success() && out.contains("timesteps: 7 (showing 0"), "{out}");
    let dir = common::scratch("formats-time-cli");
    let png = |t: &str| dir.join(format!("t{t}.png"));
    for t in ["2", "5"] {
        let out = png(t);
        common::volcast_ok(&[
            "render",
            file,
            "--time",
            t,
            "--size",
            "48x48",
            "--validate",
            "-o",
            out.to_str().unwrap(),
        ]);
    }
    let a = image::open(png("2")).unwrap().to_rgba8();
    let b = image::open(png("5")).unwrap().to_rgba8();
    assert!(diff(&a, &b).max > 8.0, "--time 2 and --time 5 give the same image");
    let o = volcast(&[
        "render",
        file,
        "--time",
        "7",
        "--size",
        "48x48",
        "-o",
        png("7").to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(
        !o.status.success() && err.contains("time step 7 does not exist: the volume has 7 (0 to 6)"),
        "{err}"
    );
}

/// A header claiming more steps than memory holds is refused before anything is read; one claiming more than
/// the per-axis limit of steps is refused by the header check.
#[test]
fn series_beyond_memory_are_refused_up_front() {
    let mut nii = std::fs::read(data().join("cine_i16.nii")).unwrap();
    // dim[1..3] = 1024 and dim[4] = 16000: 1024^3 int16 steps (2 GiB each), 32 TB together.
    for (i, v) in [(1, 1024i16), (2, 1024), (3, 1024), (4, 16000)] {
        nii[40 + 2 * i..42 + 2 * i].copy_from_slice(&v.to_le_bytes());
    }
    let dir = common::scratch("formats-time-hostile");
    let path = dir.join("huge_series.nii");
    std::fs::write(&path, &nii).unwrap();
    let e = formats::open(&path, &Default::default())
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("huge_series.nii") && e.contains("16000 time steps of 2147483648 bytes need"),
        "{e}"
    );
    nii[48..50].copy_from_slice(&20000i16.to_le_bytes());
    std::fs::write(&path, &nii).unwrap();
    let e = formats::open(&path, &Default::default())
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(e.contains("has 20000 time steps, more than the limit of 16384"), "{e}");
}
