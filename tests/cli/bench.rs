//! `volcast bench --quick` end to end, always under `--validate` with zero messages: it runs, prints
//! well-formed positive numbers, and its JSON has the fields scripts rely on. Never asserts speed (the machine is
//! shared and lavapipe is a CPU).

use crate::common;

use common::{stderr, stdout};
use std::process::Output;

fn bench(args: &[&str]) -> Output {
    common::volcast(&[&["bench"], args].concat())
}

fn positive(cell: &str, what: &str) -> f64 {
    let v: f64 = cell
        .parse()
        .unwrap_or_else(|_| panic!("{what} '{cell}' is not a number"));
    assert!(v.is_finite() && v > 0.0, "{what} = {v} should be finite and positive");
    v
}

#[test]
fn quick_bench_prints_valid_numbers_without_validation_errors() {
    let out = bench(&["--quick", "--validate"]);
    let (stdout, stderr) = (stdout(&out), stderr(&out));
    assert!(
        out.status.success(),
        "exit {:?}\nstdout:\n{stdout}\nstderr:\n{stderr}",
        out.status
    );
    assert!(
        stderr.contains("validation: 0 errors, 0 warnings"),
        "validation must be clean:\n{stderr}"
    );

    let rate_line = stdout
        .lines()
        .find(|l| l.contains("G samples/s"))
        .unwrap_or_else(|| panic!("no sample-only line:\n{stdout}"));
    let rate = rate_line
        .split(':')
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .unwrap_or("");
    positive(rate, "sample-only rate");

    let lines: Vec<&str> = stdout.lines().collect();
    let header = lines
        .iter()
        .position(|l| {
            l.split_whitespace()
                .eq(volcast::measure::bench::TABLE_COLUMNS.iter().copied())
        })
        .unwrap_or_else(|| panic!("no table header:\n{stdout}"));
    let col = |name: &str| {
        volcast::measure::bench::TABLE_COLUMNS
            .iter()
            .position(|c| *c == name)
            .unwrap()
    };
    let rows: Vec<Vec<&str>> = lines[header + 1..]
        .iter()
        .take_while(|l| !l.trim().is_empty())
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(rows.len(), 6, "one row per method and shading:\n{stdout}");
    let mut methods = Vec::new();
    for row in &rows {
        assert_eq!(row.len(), volcast::measure::bench::TABLE_COLUMNS.len(), "row {row:?}");
        methods.push((row[col("method")], row[col("shading")]));
        for name in [
            "wall_med", "wall_min", "wall_max", "gpu_med", "gpu_min", "gpu_max", "march",
        ] {
            positive(row[col(name)], name);
        }
        assert!(positive(row[col("wall_min")], "wall_min") <= positive(row[col("wall_max")], "wall_max"));
        let seg = positive(row[col("seg_spp")], "samples on the segments per pixel");
        let spp = positive(row[col("spp")], "samples per pixel");
        if row[col("shading")] == "off" {
            // Without gradients every sample lies on the segment (shading adds six per visible step).
            assert!(spp <= seg + 1e-9, "samples taken {spp} exceed the segments' {seg}");
        }
        positive(row[col("Gsamples/s")], "effective rate");
        positive(row[col("of_raw")], "fraction of the raw rate");
    }
    methods.sort();
    assert_eq!(
        methods,
        [
            ("analytic", "off"),
            ("analytic", "on"),
            ("compute", "off"),
            ("compute", "on"),
            ("faces", "off"),
            ("faces", "on")
        ]
    );
    let faces = rows.iter().find(|r| r[col("method")] == "faces").unwrap();
    positive(faces[col("entry")], "entry pass");
    positive(faces[col("exit")], "exit pass");
}

#[test]
fn quick_bench_json_has_the_expected_fields() {
    let out = bench(&["--quick", "--json", "--validate"]);
    let stdout = stdout(&out);
    let stderr = stderr(&out);
    assert!(out.status.success(), "stderr:\n{stderr}");
    assert!(
        stderr.contains("validation: 0 errors, 0 warnings"),
        "validation must be clean:\n{stderr}"
    );
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("not JSON ({e}):\n{stdout}"));
    assert!(v["device"].is_string());
    let rates = v["sample_only"].as_array().expect("sample_only array");
    assert!(!rates.is_empty());
    for r in rates {
        assert!(r["format"].is_string());
        assert!(r["gsamples_per_s"].as_f64().is_some_and(|x| x.is_finite() && x > 0.0));
    }
    let results = v["results"].as_array().expect("results array");
    assert_eq!(results.len(), 6);
    for r in results {
        for key in ["scene", "volume", "format", "method", "shading"] {
            assert!(r[key].is_string(), "{key} in {r}");
        }
        for key in ["wall_ms", "gpu_ms"] {
            for stat in ["median", "min", "max"] {
                let x = r[key][stat].as_f64().unwrap_or(f64::NAN);
                assert!(x.is_finite() && x > 0.0, "{key}.{stat} = {x}");
            }
        }
        for key in [
            "segment_samples_per_pixel",
            "samples_per_pixel",
            "effective_gsamples_per_s",
            "fraction_of_raw",
        ] {
            let x = r[key].as_f64().unwrap_or(f64::NAN);
            assert!(x.is_finite() && x > 0.0, "{key} = {x}");
        }
        assert!(r["width"].as_u64().is_some_and(|w| w > 0));
        assert!(r["gpu_allocated_bytes"].as_u64().is_some_and(|b| b > 0));
    }
    assert!(v["skipped"].is_array());
}

#[test]
fn unknown_scene_is_refused_with_the_list() {
    let out = bench(&["--scene", "nope", "--validate"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = stderr(&out);
    assert!(
        stderr.contains("unknown scene 'nope'") && stderr.contains("vtk-helix"),
        "{stderr}"
    );
}

/// `bench --playback --quick`: a 6-step series played twice under validation; the JSON's times are positive, the
/// frame is at least the upload plus the render's median parts, and every step was timed.
#[test]
fn quick_playback_times_every_step_without_validation_errors() {
    let out = bench(&["--playback", "--quick", "--validate", "--json"]);
    let (stdout, stderr) = (stdout(&out), stderr(&out));
    assert!(out.status.success(), "exit {:?}\nstderr:\n{stderr}", out.status);
    assert!(stderr.contains("validation: 0 errors, 0 warnings"), "{stderr}");
    let json: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    assert_eq!(
        (json["steps"].as_u64(), json["frames"].as_u64()),
        (Some(6), Some(6)),
        "{json}"
    );
    for key in ["show_ms", "upload_ms", "render_ms", "frame_ms"] {
        for stat in ["median", "min", "max"] {
            positive(&json[key][stat].to_string(), &format!("{key}.{stat}"));
        }
    }
    let fps = positive(&json["steps_per_second"].to_string(), "steps_per_second");
    assert!((fps - 1e3 / json["frame_ms"]["median"].as_f64().unwrap()).abs() < 1e-6);
}

/// The error column measures what it says: at `--step-length 0.125` with gradients from samples a frame is
/// rendered exactly as the converged image is (same settings), so its error is 0; at 4-voxel steps it is larger
/// than at 1-voxel steps.
#[test]
fn bench_errors_are_against_the_converged_image_at_the_forced_step() {
    let mean_error = |step: &str| -> Vec<(String, f64, f64)> {
        let out = bench(&[
            "--quick",
            "--method",
            "faces",
            "--gradients",
            "samples",
            "--step-length",
            step,
            "--json",
        ]);
        let (stdout, stderr) = (stdout(&out), stderr(&out));
        assert!(out.status.success(), "exit {:?}\nstderr:\n{stderr}", out.status);
        let json: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
        let results = json["results"].as_array().expect("results");
        assert_eq!(results.len(), 2, "shading off and on: {json}");
        results
            .iter()
            .map(|r| {
                assert_eq!(r["step_length"].as_f64(), Some(step.parse().unwrap()), "{r}");
                assert!(r["error"]["object_pixels"].as_u64().unwrap() > 100, "{r}");
                (
                    r["shading"].to_string(),
                    r["error"]["mean"].as_f64().unwrap(),
                    r["error"]["max"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    for (shading, mean, max) in mean_error("0.125") {
        assert_eq!(
            (mean, max),
            (0.0, 0.0),
            "shading {shading}: the converged settings themselves"
        );
    }
    let default = mean_error("1");
    let coarse = mean_error("4");
    for ((shading, fine, _), (_, rough, _)) in default.iter().zip(&coarse) {
        assert!(
            *fine > 0.0 && rough > fine,
            "shading {shading}: error at 1-voxel steps {fine}, at 4-voxel steps {rough}"
        );
    }
}

/// `--quality` repeated times every level against the same converged image: a row per level, each naming it, the
/// coarser levels taking longer steps and erring more (never less) than the finer ones, converged itself exactly.
#[test]
fn bench_times_each_quality_level_against_one_converged_image() {
    let out = bench(&[
        "--quick",
        "--method",
        "faces",
        "--shading",
        "off",
        "--quality",
        "draft",
        "--quality",
        "normal",
        "--quality",
        "converged",
        "--json",
    ]);
    let (stdout, stderr) = (stdout(&out), stderr(&out));
    assert!(out.status.success(), "exit {:?}\nstderr:\n{stderr}", out.status);
    assert_eq!(
        stderr.matches("converged image").count(),
        1,
        "one converged image for the three levels:\n{stderr}"
    );
    let json: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    let rows: Vec<(String, f64, f64)> = json["results"]
        .as_array()
        .expect("results")
        .iter()
        .map(|r| {
            (
                r["quality"].as_str().expect("quality").to_string(),
                r["step_length"].as_f64().expect("step"),
                r["error"]["mean"].as_f64().expect("error"),
            )
        })
        .collect();
    let names: Vec<&str> = rows.iter().map(|r| r.0.as_str()).collect();
    assert_eq!(names, ["draft", "normal", "converged"], "{rows:?}");
    assert!(rows[0].1 > rows[1].1 && rows[1].1 > rows[2].1, "steps shrink: {rows:?}");
    assert!(rows[0].2 >= rows[1].2 && rows[2].2 == 0.0, "errors: {rows:?}");
    // Each level's row carries its error target (the table's `target` column says met or over); none for converged.
    use volcast::scene::quality::Quality;
    let targets: Vec<serde_json::Value> = json["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["target"].clone())
        .collect();
    let want = |q: Quality| serde_json::json!([q.target().0, q.target().1]);
    assert_eq!(
        targets,
        [want(Quality::Draft), want(Quality::Normal), serde_json::Value::Null]
    );
}

/// `bench --scale` on one small scene, as the docs' table is made: the field generated into `--cache`, opened cold,
/// warm and from the pyramid cache within the default budgets, each row with positive times, the scene's own size at
/// level 0 and the bytes it read; then a larger scene over a small `--gpu-budget`, streamed through a pool, whose
/// view four times closer refines some bricks to level 0. No validation message. The generated files stay for the
/// next run; the pyramid cache is emptied.
#[test]
fn scale_bench_opens_its_scenes_cold_warm_and_cached() {
    let dir = common::scratch("scale-bench");
    let cache = dir.join("cache");
    let cache_arg = cache.to_str().expect("utf-8 path");
    let args = ["--scale", "--frames", "1", "--cache", cache_arg, "--validate"];
    let out = bench(&[&args[..], &["--scale-edge", "48", "--size", "64", "--json"]].concat());
    let (json, log) = (stdout(&out), stderr(&out));
    assert!(out.status.success(), "stdout:\n{json}\nstderr:\n{log}");
    assert!(
        log.contains("validation: 0 errors, 0 warnings"),
        "validation must be clean:\n{log}"
    );
    let rows: serde_json::Value = serde_json::from_str(&json).unwrap_or_else(|e| panic!("not JSON ({e}):\n{json}"));
    let rows = rows.as_array().expect("an array of rows");
    let caches: Vec<&str> = rows.iter().map(|r| r["cache"].as_str().unwrap_or("?")).collect();
    assert_eq!(caches, ["cold", "warm", "cached"], "{json}");
    let file = cache.join(rows[0]["scene"].as_str().expect("scene"));
    let file_bytes = std::fs::metadata(&file).map_or(0, |m| m.len());
    assert_eq!(file_bytes, 48 * 48 * 48, "{}", file.display());
    for r in rows {
        assert_eq!(r["file_bytes"].as_u64(), Some(file_bytes), "{r}");
        assert_eq!(r["shown"], serde_json::json!([48, 48, 48]), "{r}");
        assert_eq!(r["level"].as_u64(), Some(0), "{r}");
        assert!(r["streamed"].is_null() && r["close"].is_null(), "{r}");
        for key in ["first_image_s", "refined_s"] {
            let x = r[key].as_f64().unwrap_or(f64::NAN);
            assert!(x.is_finite() && x > 0.0, "{key} = {x} in {r}");
        }
        assert!(r["first_image_s"].as_f64() <= r["refined_s"].as_f64(), "{r}");
        for key in ["rest_ms", "drag_ms"] {
            let x = r[key]["median"].as_f64().unwrap_or(f64::NAN);
            assert!(x.is_finite() && x > 0.0, "{key} = {x} in {r}");
        }
        assert!(r["gpu_bytes"].as_u64().is_some_and(|b| b > 0), "{r}");
        // The whole file is read on each open (rchar counts page-cache reads too).
        assert!(r["read_from_files"].as_u64().is_some_and(|b| b >= file_bytes), "{r}");
    }

    // 256³ over a GPU budget of 32 MiB: a pool of 16 MiB, some 48 bricks of 64³.
    let over = ["--scale-edge", "256", "--size", "128", "--gpu-budget", "32M"];
    let out = bench(&[&args[..], &over[..]].concat());
    let (table, log) = (stdout(&out), stderr(&out));
    assert!(out.status.success(), "stdout:\n{table}\nstderr:\n{log}");
    assert!(log.contains("validation: 0 errors, 0 warnings"), "{log}");
    assert!(
        table.contains("budgets: host ") && table.contains(", GPU 32 MiB"),
        "{table}"
    );
    assert!(table.contains("| scene | cache | shown (level) |"), "{table}");
    let streamed = |l: &&str| l.contains("| 256x256x256 (streamed, ") && l.contains(" slots: level ");
    assert_eq!(table.lines().filter(streamed).count(), 3, "{table}");
    let (_, closer) = table
        .split_once("four times closer")
        .unwrap_or_else(|| panic!("no close view:\n{table}"));
    assert_eq!(closer.matches("| level 0 in ").count(), 3, "{table}");
}
