//! The `volcast` binary end to end: a render under validation, and every bad input a user can give ending in a
//! clear message and a non-zero exit, never a panic.

use crate::common;

use common::{scratch, stderr};
use std::process::Output;

/// Runs the binary; commands that use the GPU run under `--validate`, and whatever they print of the layer must be
/// its clean summary.
fn volcast(args: &[&str]) -> Output {
    if matches!(args.first(), Some(&("render" | "compare" | "bench" | "view"))) {
        common::volcast_validated(args)
    } else {
        let o = common::volcast(args);
        common::run::assert_validation_clean(&args, &o);
        o
    }
}

/// `render` of an 8³ built-in with `extra` arguments.
fn tiny_render<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    ["render", "--builtin", "colormap", "--builtin-size", "8"]
        .into_iter()
        .chain(extra.iter().copied())
        .collect()
}

fn assert_fails_with(args: &[&str], needle: &str) {
    assert_exits_with(args, 1, needle);
}

/// A command line that is wrong on its own exits 64, like one that does not parse (docs/cli.md, Exit codes).
fn assert_usage_error(args: &[&str], needle: &str) {
    assert_exits_with(args, 64, needle);
}

fn assert_exits_with(args: &[&str], code: i32, needle: &str) {
    let o = volcast(args);
    let err = stderr(&o);
    assert!(!o.status.success(), "{args:?} succeeded");
    assert_eq!(o.status.code(), Some(code), "{args:?}: exit code; stderr: {err}");
    assert!(err.contains(needle), "{args:?}: expected '{needle}' in stderr:\n{err}");
    assert!(!err.contains("panicked"), "{args:?} panicked:\n{err}");
}

#[test]
fn renders_the_helix_under_validation() {
    let out = scratch("cli").join("helix.png");
    let o = volcast(&[
        "render",
        "--builtin",
        "helix",
        "--size",
        "96x80",
        "--validate",
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "render failed:\n{err}");
    assert!(err.contains("validation: 0 errors, 0 warnings"), "{err}");
    let img = image::open(&out).expect("a PNG").to_rgba8();
    assert_eq!(img.dimensions(), (96, 80));
    let lit = img
        .pixels()
        .filter(|p| p[0] as u32 + p[1] as u32 + p[2] as u32 > 30)
        .count();
    assert!(
        lit > 96 * 80 / 20,
        "the helix should cover a good part of the image, {lit} pixels lit"
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("rendered helix (256x256x256 uint8"), "{stdout}");
}

#[test]
fn analytic_method_and_timings_run() {
    let out = scratch("cli").join("ml.png");
    let o = volcast(&[
        "render",
        "--builtin",
        "marschner-lobb",
        "--size",
        "64x64",
        "--method",
        "analytic",
        "--timings",
        "--frames",
        "2",
        "--validate",
        "-o",
        out.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("validation: 0 errors, 0 warnings"),
        "{}",
        stderr(&o)
    );
    assert!(text.contains("analytic ray setup"), "{text}");
    assert!(
        text.contains("median of 2 frames") && text.contains("(march "),
        "{text}"
    );
}

#[test]
fn bad_volumes_give_clear_errors() {
    let short = scratch("cli").join("short_8x8x8_uint16.raw");
    std::fs::write(&short, vec![0u8; 100]).unwrap();
    assert_fails_with(
        &["info", short.to_str().unwrap()],
        "is 100 bytes but 8x8x8 uint16 needs 1024",
    );

    let unnamed = scratch("cli").join("scan.raw");
    std::fs::write(&unnamed, vec![0u8; 64]).unwrap();
    assert_fails_with(&["info", unnamed.to_str().unwrap()], "--dims W H D --type T");
    assert_fails_with(
        &[
            "info",
            unnamed.to_str().unwrap(),
            "--dims",
            "4",
            "4",
            "4",
            "--type",
            "uint12",
        ],
        "uint12",
    );
    assert_fails_with(
        &[
            "info",
            unnamed.to_str().unwrap(),
            "--dims",
            "0",
            "4",
            "4",
            "--type",
            "uint8",
        ],
        "0",
    );
    assert_fails_with(
        &[
            "info",
            unnamed.to_str().unwrap(),
            "--dims",
            "100000",
            "100000",
            "100000",
            "--type",
            "uint8",
        ],
        "100000",
    );
    assert_fails_with(
        &["info", "/nonexistent/vol_8x8x8_uint8.raw"],
        "/nonexistent/vol_8x8x8_uint8.raw",
    );
    // The cause once, not twice ("…(os error 2): …(os error 2)").
    let o = volcast(&["info", "/nonexistent/vol_8x8x8_uint8.raw"]);
    assert_eq!(stderr(&o).matches("(os error 2)").count(), 1, "{}", stderr(&o));
    // A size the file does not have names the file and both sizes (found before anything is read; the voxel
    // count alone no longer refuses: a file read in place is shown at the pyramid level the budgets take).
    let huge = scratch("cli").join("huge_3000x3000x3000_uint16.raw");
    std::fs::write(&huge, vec![0u8; 16]).unwrap();
    assert_fails_with(
        &["info", huge.to_str().unwrap()],
        "huge_3000x3000x3000_uint16.raw is 16 bytes but 3000x3000x3000 uint16 needs 54000000000",
    );
    assert_usage_error(&["info", "--builtin", "teapot"], "helix");
    // No volume at all is the command line's fault: exit 64, for info as for render.
    assert_usage_error(&["render"], "no volume given");
    assert_usage_error(&["info"], "no volume given");
    // --dims without --type says that --type is missing, and does not ask for the dims again.
    let untyped = scratch("cli").join("untyped.raw");
    std::fs::write(&untyped, vec![0u8; 8]).unwrap();
    let o = volcast(&["info", untyped.to_str().unwrap(), "--dims", "2", "2", "2"]);
    let err = stderr(&o);
    assert!(
        err.contains("--dims is given but --type is missing; pass --type T, one of uint8"),
        "{err}"
    );
    assert!(!err.contains("pass --dims"), "{err}");
}

#[test]
fn bad_settings_give_clear_errors() {
    assert_usage_error(&tiny_render(&["--window", "80%,20%"]), "window");
    assert_usage_error(&tiny_render(&["--colormap", "jet"]), "viridis");
    // A misspelled value gets the nearest name, as clap does for a misspelled flag.
    for (extra, needle) in [
        (
            &["--colormap", "viridsi"][..],
            "unknown colormap 'viridsi' (did you mean 'viridis'?)",
        ),
        (&["--mode", "emision"], "(did you mean 'emission'?)"),
        (&["--preset", "ct-bnoe"], "(did you mean 'ct-bone'?)"),
        (&["--quality", "draf"], "(did you mean 'draft'?)"),
    ] {
        assert_usage_error(&tiny_render(extra), needle);
    }
    assert_usage_error(&tiny_render(&["--step-length", "0"]), "step length");
    assert_usage_error(&tiny_render(&["--size", "0x10"]), "image size");
    // One message per condition.
    assert_usage_error(
        &tiny_render(&["--eye", "0.2,0,0", "--look-at", "0.2,0,0"]),
        "must differ from the point it looks at",
    );
    assert_usage_error(
        &tiny_render(&["--fov", "200"]),
        "field of view 200° must be in 1..170 degrees",
    );
    assert_usage_error(&tiny_render(&["--view-dir", "0,0,0"]), "non-zero direction");
    // The lighting options: each bad value is named.
    for (extra, needle) in [
        (&["--light", "0,0,0"][..], "light direction"),
        (&["--light-color", "2,0,0"][..], "light colour"),
        (&["--light-intensity", "99"][..], "light intensity"),
        (&["--mode", "iso", "--iso-opacity", "0"][..], "opacity"),
        (
            &[
                "--mode",
                "iso",
                "--surface",
                "0.1",
                "--surface",
                "0.2",
                "--surface",
                "0.3",
                "--surface",
                "0.4",
            ][..],
            "at most 4 iso-surfaces",
        ),
    ] {
        assert_usage_error(&tiny_render(extra), needle);
    }
    // Names that are not among the choices list the choices.
    for (extra, needle) in [
        (&["--mode", "blend"][..], "unknown mode 'blend'; choose one of emission"),
        (&["--preset", "bones"], "unknown preset 'bones'; choose one of ct-bone"),
        (&["--view", "top"], "unknown view 'top'; choose one of anterior"),
        (&["--quality", "best"], "unknown quality 'best'"),
        (&["--texture", "huge"], "huge"),
    ] {
        assert_usage_error(&tiny_render(extra), needle);
    }
    assert_usage_error(&["view", "--preset", "nope"], "unknown preset 'nope'");
    // The viewer's transfer function is read before any window opens, and a bad one names itself.
    assert_fails_with(&["view", "--tf", "/nonexistent/tf.json"], "/nonexistent/tf.json");
}

/// A render that fails writes nothing: a name volcast cannot write, or a folder that does not exist, is refused
/// with exit 64 before rendering, and no empty file is left behind.
#[test]
fn a_failed_render_leaves_no_file() {
    for name in ["failed.gif", "failed"] {
        let out = scratch("cli").join(name);
        let _ = std::fs::remove_file(&out);
        assert_usage_error(
            &tiny_render(&["-o", out.to_str().unwrap()]),
            "volcast writes PNG, JPEG and TIFF images",
        );
        assert!(!out.exists(), "{name} was left behind");
    }
    assert_usage_error(
        &tiny_render(&["-o", "/nonexistent/dir/x.png"]),
        "the folder /nonexistent/dir does not exist",
    );
    let out = scratch("cli").join("failed-size.png");
    let _ = std::fs::remove_file(&out);
    assert_usage_error(
        &tiny_render(&["--size", "0x4", "-o", out.to_str().unwrap()]),
        "image size",
    );
    assert!(!out.exists());
}

/// `-o` names the format: a JPEG or TIFF holds the same picture as the PNG (JPEG within its loss).
#[test]
fn jpeg_and_tiff_by_extension() {
    let dir = scratch("cli-formats");
    let png = dir.join("f.png");
    assert!(volcast(&tiny_render(&["-o", png.to_str().unwrap()])).status.success());
    let want = image::open(&png).unwrap().to_rgb8();
    for name in ["f.jpg", "f.TIFF"] {
        let out = dir.join(name);
        let o = volcast(&tiny_render(&["-o", out.to_str().unwrap()]));
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let bytes = std::fs::read(&out).unwrap();
        let got: Vec<u8> = if name.ends_with(".jpg") {
            assert!(bytes.starts_with(&[0xff, 0xd8, 0xff]), "{name} is not a JPEG");
            let mut d = jpeg_decoder::Decoder::new(&bytes[..]);
            d.decode().unwrap()
        } else {
            let mut d = tiff::decoder::Decoder::new(std::io::Cursor::new(bytes)).unwrap();
            let tiff::decoder::DecodingResult::U8(rgba) = d.read_image().unwrap() else {
                panic!("{name}: not 8-bit")
            };
            rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect()
        };
        assert_eq!(got.len(), want.as_raw().len(), "{name}");
        let worst = got
            .iter()
            .zip(want.as_raw())
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap();
        let limit = if name.ends_with(".jpg") { 40 } else { 0 };
        assert!(worst <= limit, "{name}: differs from the PNG by up to {worst}");
    }
}

/// Shadows and occlusion asked of a projection render it unlit, with a note saying so.
#[test]
fn shadows_in_mip_render_with_a_note() {
    let out = scratch("cli").join("mip-shadows.png");
    let o = volcast(&tiny_render(&[
        "--mode",
        "mip",
        "--shadows",
        "-o",
        out.to_str().unwrap(),
    ]));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("mip is not lit"), "{}", stderr(&o));
}

/// `volcast FILE` is `volcast view FILE` (tested through X in tests/viewer/panel.rs); a subcommand's name wins over
/// a file of that name, and a misspelled subcommand keeps clap's suggestion rather than becoming a file to open.
#[test]
fn subcommands_win_over_file_names() {
    let dir = scratch("cli-subcommand-names");
    std::fs::write(dir.join("info"), b"a file named like a subcommand").unwrap();
    let o = common::volcast_command()
        .current_dir(&dir)
        .args(["info", "--builtin", "helix", "--builtin-size", "8"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("8 x 8 x 8"),
        "info ran, not the viewer"
    );
    let o = common::volcast(&["rendr", "--builtin", "helix"]);
    assert_eq!(o.status.code(), Some(64));
    assert!(
        stderr(&o).contains("similar subcommand exists: 'render'"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn clap_rejects_malformed_arguments() {
    for args in [
        &["render", "--builtin", "helix", "--size", "big"][..],
        &["render", "--builtin", "helix", "--slice", "w:0.5:0.1"],
        &["render", "--builtin", "helix", "--eye", "1,2"],
        &["render", "--builtin", "helix", "--method", "magic"],
        &["render", "--builtin", "helix", "--surface", "0.3,0.5"],
        &["render", "--builtin", "helix", "--iso-color", "pink"],
        &["render", "--builtin", "helix", "--light", "up"],
    ] {
        let o = volcast(args);
        assert_eq!(
            o.status.code(),
            Some(64),
            "{args:?}: usage errors exit 64 (2 is no Vulkan)"
        );
        assert!(!stderr(&o).contains("panicked"));
    }
}

#[test]
fn no_vulkan_driver_is_a_clear_error_with_exit_2() {
    let o = common::volcast_command()
        .args([
            "render",
            "--builtin",
            "colormap",
            "--builtin-size",
            "8",
            "-o",
            "/dev/null",
        ])
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .output()
        .expect("run volcast");
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("apt-get install mesa-vulkan-drivers"), "{err}");
}

#[test]
fn info_reports_the_ct_head() {
    let Some(path) = common::shared_data("raw/cranium_ct_256x256x108_int16.raw") else {
        return;
    };
    let o = volcast(&["info", path.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(text.contains("256 x 256 x 108") && text.contains("int16"), "{text}");
    assert!(text.contains("-1024 .. 2986"), "{text}");
    assert!(text.contains("R16_UNORM"), "{text}");
}
