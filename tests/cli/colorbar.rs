//! `volcast render --colorbar` and `--preset auto` end to end: the image grows by a strip at the right that is
//! exactly the library's colour bar for the classification in use (data-unit ticks, "HU" for CT), and the
//! rendered pixels stay as they were; `--scale-bar` draws a bar of a round length at the camera target's depth.

use crate::common;

use common::scratch;
use std::path::{Path, PathBuf};
use volcast::transfer::colorbar::{colorbar, layout, ColorbarSpec};
use volcast::transfer::function::{Classification, TransferFunction};

/// Renders under validation; the layer must stay silent.
fn render(args: &[&str], out: &Path) -> image::RgbaImage {
    let out_arg = out.to_str().expect("a UTF-8 path");
    common::volcast_ok(&[&["render"], args, &["--size", "64x48", "--validate", "-o", out_arg]].concat());
    image::open(out).expect("read the PNG").to_rgba8()
}

/// A tiny CT-like volume: int16 from −1024 HU (air) to 2000 HU (bone), no modality tag.
fn tiny_ct() -> PathBuf {
    let path = scratch("cli-colorbar").join("tinyct_8x8x8_int16.raw");
    let bytes: Vec<u8> = (0..512i32)
        .flat_map(|i| ((-1024 + i * 3024 / 511) as i16).to_le_bytes())
        .collect();
    std::fs::write(&path, bytes).expect("write the volume");
    path
}

#[test]
fn colorbar_strip_is_appended_and_the_render_kept() {
    let ct = tiny_ct();
    let ct = ct.to_str().unwrap();
    let plain = render(&[ct, "--preset", "auto"], &scratch("cli-colorbar").join("plain.png"));
    let barred = render(
        &[ct, "--preset", "auto", "--colorbar"],
        &scratch("cli-colorbar").join("barred.png"),
    );
    assert_eq!((plain.width(), plain.height()), (64, 48));
    assert_eq!(barred.height(), 48, "the height is kept");
    for y in 0..48 {
        for x in 0..64 {
            assert_eq!(plain.get_pixel(x, y), barred.get_pixel(x, y), "render pixel ({x}, {y})");
        }
    }
    // The auto preset of a volume spanning −1024..2000 HU is the CT preset, labelled in HU.
    let tf = TransferFunction::preset(volcast::transfer::auto::CT_PRESET).unwrap();
    let class = Classification::Function(tf);
    let spec = ColorbarSpec {
        classification: &class,
        window: [0.0, 1.0],
        range: [-1024.0, 2000.0],
        unit: Some("HU"),
        background: [0, 0, 0],
    };
    let want = colorbar(&spec, 48);
    assert_eq!(barred.width(), 64 + want.width(), "the image grows by the bar's width");
    for y in 0..48 {
        for x in 0..want.width() {
            assert_eq!(
                barred.get_pixel(64 + x, y),
                want.get_pixel(x, y),
                "strip pixel ({x}, {y})"
            );
        }
    }
    // The strip shows something: ink of the labels, and the bone colours of the upper half of the bar.
    let l = layout(&spec, 48);
    let top = barred.get_pixel(64 + l.bar_x[0], l.bar_y[0]);
    assert!(top[0] > 200 && top[1] > 200, "bone is near white: {top:?}");
    let ink = (0..48)
        .flat_map(|y| (l.label_x..want.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| barred.get_pixel(64 + x, y)[0] == 235)
        .count();
    assert!(ink > 40, "labels drawn ({ink} pixels)");
}

#[test]
fn colorbar_of_the_simple_model_follows_the_window_and_background() {
    let out = render(
        &[
            "--builtin",
            "colormap",
            "--builtin-size",
            "8",
            "--colormap",
            "viridis",
            "--window",
            "20%,80%",
            "--background",
            "1,1,1",
            "--colorbar",
        ],
        &scratch("cli-colorbar").join("simple.png"),
    );
    let class = Classification::Simple {
        colormap: volcast::transfer::Colormap::Viridis,
        step_alpha: 0.1,
        multiplied: false,
    };
    let spec = ColorbarSpec {
        classification: &class,
        window: [0.2, 0.8],
        range: volcast::volume::builtin("colormap", Some(8)).unwrap().range,
        unit: None,
        background: [255, 255, 255],
    };
    let want = colorbar(&spec, 48);
    assert_eq!(out.width(), 64 + want.width());
    for y in 0..48 {
        for x in 0..want.width() {
            assert_eq!(out.get_pixel(64 + x, y), want.get_pixel(x, y), "strip pixel ({x}, {y})");
        }
    }
}

/// `--scale-bar`: a bar at the bottom left as long as a round length at the camera target's depth, measured here
/// from the camera alone: the tiny CT is 8 mm across (1 mm voxels; the box's longest side is 1 world unit), seen
/// orthographically from 2 units at 30°, so a 240-pixel-high view spans 2·2·tan(15°) units = 8.57 mm. The bar
/// takes at most a fifth of the 320-pixel width (64 px = 2.29 mm): 2 mm. Everything else is the render's.
#[test]
fn scale_bar_measures_round_millimetres_at_the_target() {
    let ct = tiny_ct();
    let ct = ct.to_str().unwrap();
    let dir = scratch("cli-colorbar");
    let view = [
        "render",
        ct,
        "--ortho",
        "--distance",
        "2",
        "--fov",
        "30",
        "--size",
        "320x240",
        "--validate",
    ];
    let shot = |extra: &[&str], name: &str| {
        let out = dir.join(name);
        common::volcast_ok(&[&view[..], extra, &["-o", out.to_str().unwrap()]].concat());
        image::open(&out).expect("read the PNG").to_rgba8()
    };
    let (plain, barred) = (shot(&[], "plain-view.png"), shot(&["--scale-bar"], "scale-bar.png"));
    let px_per_mm = 240.0 / (2.0 * 2.0 * 15f64.to_radians().tan()) / 8.0;
    let want = (2.0 * px_per_mm).round() as u32;
    // The bar: 2 rows ending 6 pixels above the bottom, from 6 pixels in.
    let white = |x: u32, y: u32| barred.get_pixel(x, y).0[..3] == [255, 255, 255];
    let run = (6..320).take_while(|&x| white(x, 233)).count() as u32;
    assert_eq!(run, want, "a 2 mm bar at {px_per_mm:.3} px/mm");
    assert!(white(6, 232) && !white(6, 234));
    let changed: Vec<(u32, u32)> = (0..240)
        .flat_map(|y| (0..320).map(move |x| (x, y)))
        .filter(|&(x, y)| plain.get_pixel(x, y) != barred.get_pixel(x, y))
        .collect();
    let label = changed.iter().filter(|&&(_, y)| y < 232).count();
    assert!(label > 20, "a label above the bar ({label} pixels)");
    assert!(
        changed.iter().all(|&(x, y)| x < 6 + want && (221..234).contains(&y)),
        "only the bar and its label change the render"
    );
}
