//! The binary's other commands end to end, each GPU command under `--validate` with zero messages: `compare`
//! (its images, `compare.md` and `compare.json`, and a view where the two setups do not agree), `info` on every
//! format, `devices` and `--device`, and the options of `render` that print or write rather than draw.

use crate::common;

use common::{stderr, stdout, volcast};
use std::path::{Path, PathBuf};

/// Runs a GPU command with `--validate`; asserts it succeeded with zero validation messages and returns stdout.
fn validated(args: &[&str]) -> String {
    common::stdout(&common::volcast_ok(args))
}

const VIEWS: [&str; 9] = [
    "oblique",
    "axis-y",
    "axis-z",
    "grazing",
    "close-up",
    "inside",
    "on-face",
    "near-plane-cut",
    "slab-inside",
];

fn read_rows(dir: &Path) -> Vec<serde_json::Value> {
    let json = std::fs::read_to_string(dir.join("compare.json")).expect("compare.json");
    let rows: serde_json::Value = serde_json::from_str(&json).expect("valid JSON");
    rows.as_array().expect("an array of rows").clone()
}

#[test]
fn compare_writes_its_images_and_tables() {
    let dir = common::scratch("cli-tools-agree");
    let out = dir.to_str().unwrap();
    let stdout = validated(&[
        "compare",
        "--builtin",
        "helix",
        "--builtin-size",
        "48",
        "--size",
        "64x48",
        "--frames",
        "1",
        "--out",
        out,
    ]);
    let rows = read_rows(&dir);
    assert_eq!(rows.len(), VIEWS.len(), "one row per view");
    for (row, view) in rows.iter().zip(VIEWS) {
        assert_eq!(row["view"], view);
        assert_eq!((row["width"].as_u64(), row["height"].as_u64()), (Some(64), Some(48)));
        for key in ["max", "mean", "p99", "over_1"] {
            let x = row["diff"][key].as_f64().unwrap_or(f64::NAN);
            assert!(x.is_finite() && x >= 0.0, "{view}: diff.{key} = {x}");
        }
        assert!(row["diff"]["object_pixels"].as_u64().is_some_and(|n| n > 0), "{view}");
        assert!(row["diff"]["psnr_db"].is_number() || row["diff"]["psnr_db"].is_null());
        for method in ["faces_ms", "analytic_ms"] {
            let total = row[method]["total_ms"].as_f64().unwrap_or(f64::NAN);
            assert!(total > 0.0, "{view}: {method}.total_ms = {total}");
        }
        assert!(row["faces_ms"]["entry_ms"].as_f64().is_some_and(|t| t > 0.0));
        // Two RGBA32F targets of 64×48 for faces; none for analytic.
        assert_eq!(row["faces_extra_bytes"].as_u64(), Some(64 * 48 * 32), "{view}");
        assert_eq!(row["analytic_extra_bytes"].as_u64(), Some(0), "{view}");
        assert_eq!(row["agree"], true, "{view}: {}", row["verdict"]);
        assert!(row["verdict"].as_str().is_some_and(|v| v.starts_with("agree")));
        for suffix in ["faces", "analytic", "diff", "side-by-side"] {
            let png = dir.join(format!("{view}-{suffix}.png"));
            let img = image::open(&png).unwrap_or_else(|e| panic!("{}: {e}", png.display()));
            let expected_width = if suffix == "side-by-side" { 3 * 64 + 2 * 4 } else { 64 };
            assert_eq!((img.width(), img.height()), (expected_width, 48), "{}", png.display());
        }
        assert!(stdout.contains(view), "{stdout}");
    }
    let md = std::fs::read_to_string(dir.join("compare.md")).expect("compare.md");
    assert_eq!(
        md.lines().count(),
        2 + VIEWS.len(),
        "header, rule and one line per view:\n{md}"
    );
    assert!(md.lines().skip(2).all(|l| l.trim_end().ends_with("| agree |")), "{md}");
    assert!(!stdout.contains("differ beyond the bound"), "{stdout}");
}

/// Half-float position targets quantise a ray's ends to 1/2048 of the box: in a close-up that moves whole
/// samples, and `compare` must say the setups differ (so `agree` can be false).
#[test]
fn compare_reports_setups_that_differ() {
    let dir = common::scratch("cli-tools-differ");
    let out = dir.to_str().unwrap();
    let stdout = validated(&[
        "compare",
        "--builtin",
        "helix",
        "--builtin-size",
        "128",
        "--size",
        "96x96",
        "--frames",
        "1",
        "--positions",
        "rgba16f",
        "--out",
        out,
    ]);
    let rows = read_rows(&dir);
    let close_up = rows.iter().find(|r| r["view"] == "close-up").expect("a close-up row");
    assert_eq!(close_up["agree"], false, "{close_up}");
    assert!(close_up["verdict"].as_str().is_some_and(|v| v.starts_with("differ")));
    assert_eq!(
        close_up["faces_extra_bytes"].as_u64(),
        Some(96 * 96 * 16),
        "two RGBA16F targets"
    );
    let differing = rows.iter().filter(|r| r["agree"] == false).count();
    assert!(
        stdout.contains(&format!("{differing} view(s) differ beyond the bound")),
        "{stdout}"
    );
    let md = std::fs::read_to_string(dir.join("compare.md")).unwrap();
    assert!(
        md.lines()
            .any(|l| l.starts_with("| close-up ") && l.trim_end().ends_with("| differ |")),
        "{md}"
    );
}

fn data(rel: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(rel)
        .to_string_lossy()
        .into_owned()
}

/// `info` names the format, dims, type, spacing and range of a file of every format.
#[test]
fn info_on_every_format() {
    let raw_dir = common::scratch("cli-tools-info");
    let raw = raw_dir.join("ramp_4x3x2_int16.raw");
    let values: Vec<u8> = (0..24i16).flat_map(|i| (i - 12).to_le_bytes()).collect();
    std::fs::write(&raw, values).unwrap();
    let mut cases: Vec<(String, [&str; 5])> = vec![
        (
            raw.to_string_lossy().into_owned(),
            ["raw", "4 x 3 x 2", "int16", "1 x 1 x 1", "-12 .. 11"],
        ),
        (
            data("ramp.vtk"),
            ["VTK legacy", "4 x 3 x 2", "int16", "1 x 1 x 2.5", "-12 .. 11"],
        ),
        (
            data("ramp.nhdr"),
            ["NRRD", "4 x 3 x 2", "uint16", "0.5 x 0.5 x 1", "0 .. 2300"],
        ),
        (
            data("ramp.mhd"),
            ["MetaImage", "4 x 3 x 2", "float32", "", "-1 .. 10.5"],
        ),
        (data("slice.dcm"), ["DICOM", "3 x 4 x 1", "int16", "0.25 x 0.5 x 5", ""]),
    ];
    if let Some(nii) = common::shared_data("native/motor_zmap/image_10426.nii.gz") {
        cases.push((
            nii.to_string_lossy().into_owned(),
            ["NIfTI-1", "53 x 63 x 46", "float32", "3 x 3 x 3", ""],
        ));
    }
    if let Some(series) = common::shared_data("native/brain_pd_mr") {
        cases.push((
            series.to_string_lossy().into_owned(),
            // The placement's f32 arithmetic makes the row spacing 0.85937506: printed as the header's 0.859375.
            [
                "DICOM",
                "256 x 256 x 20",
                "int16",
                "0.859375 x 0.859375 x 7.00052\n",
                "0 .. 1059",
            ],
        ));
    }
    for (file, expected) in cases {
        let o = volcast(&["info", &file]);
        let stdout = stdout(&o);
        assert!(o.status.success(), "info {file}: {}", stderr(&o));
        let line = |key: &str| {
            stdout
                .lines()
                .find(|l| l.starts_with(key))
                .map(|l| format!("{l}\n"))
                .unwrap_or_else(|| panic!("info {file}: no '{key}' line in:\n{stdout}"))
        };
        let [format, dims, ty, spacing, range] = expected;
        assert!(line("format:").contains(format), "{file}:\n{stdout}");
        assert!(line("dims:").contains(dims), "{file}:\n{stdout}");
        assert!(line("type:").contains(ty), "{file}:\n{stdout}");
        assert!(line("spacing:").contains(spacing), "{file}:\n{stdout}");
        assert!(stdout.contains(range), "{file}:\n{stdout}");
        assert!(line("gpu:").contains("MiB"), "{file}:\n{stdout}");
    }
}

/// `devices` lists what the loader sees; `--device` picks by index or by part of the name, and an unknown one is
/// refused with the list (exit 2: no usable device).
#[test]
fn devices_and_device_selection() {
    let o = volcast(&["devices"]);
    let stdout = stdout(&o);
    assert!(o.status.success(), "{}", stderr(&o));
    let first = stdout.lines().next().expect("at least one device");
    // The device volcast takes without --device is marked.
    let (first, mark) = first.split_once("  <- ").unwrap_or((first, ""));
    assert!(mark.starts_with("volcast's choice"), "{stdout}");
    let (index, rest) = first.split_once(": ").expect("'N: name (kind, Vulkan x.y.z)'");
    assert_eq!(index, "0");
    assert!(rest.contains("Vulkan 1.3"), "{first}");
    let name_part = rest.split_whitespace().next().unwrap();
    let dir = common::scratch("cli-tools-device");
    let png = dir.join("d.png");
    let png = png.to_str().unwrap();
    for device in ["0", name_part] {
        let out = validated(&[
            "render",
            "--builtin",
            "helix",
            "--builtin-size",
            "16",
            "--size",
            "8x8",
            "--device",
            device,
            "-o",
            png,
        ]);
        assert!(out.contains(name_part), "--device {device}: {out}");
    }
    let o = volcast(&[
        "render",
        "--builtin",
        "helix",
        "--builtin-size",
        "16",
        "--device",
        "no-such-gpu",
        "-o",
        png,
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("no-such-gpu") && err.contains(first), "{err}");
}

/// The `render` options that report or write instead of changing the image.
#[test]
fn reporting_options_of_render() {
    let dir = common::scratch("cli-tools-reporting");
    let png = dir.join("r.png");
    let png = png.to_str().unwrap();
    let base = [
        "render",
        "--builtin",
        "helix",
        "--builtin-size",
        "32",
        "--size",
        "32x32",
        "-o",
        png,
    ];
    let stdout = validated(&[&base[..], &["--timings", "--frames", "3"]].concat());
    let timing = stdout
        .lines()
        .find(|l| l.starts_with("median of 3 frames"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(
        timing.contains("GPU") && timing.contains("entry") && timing.contains("march"),
        "{timing}"
    );
    let stdout = validated(&[&base[..], &["--memory"]].concat());
    let memory = stdout
        .lines()
        .find(|l| l.starts_with("memory:"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(
        memory.contains("peak resident") && memory.contains("GPU allocated"),
        "{memory}"
    );

    let saved = dir.join("saved.json");
    validated(
        &[
            &base[..],
            &["--preset", "ct-bone", "--save-tf", saved.to_str().unwrap()],
        ]
        .concat(),
    );
    let tf = volcast::transfer::function::TransferFunction::load(&saved)
        .expect("--save-tf writes a loadable transfer function");
    assert_eq!(
        tf,
        volcast::transfer::function::TransferFunction::preset("ct-bone").unwrap()
    );
}
