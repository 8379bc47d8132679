//! `--clip-plane` through the binary under `--validate`: a cut removes the expected half of a tiny render, the
//! flipped plane the other half, a plane beyond the box nothing; a view state file carries the plane (and one
//! written before planes existed still loads); bad planes are refused with a clear message.

use crate::common;

use common::{scratch, volcast};
use image::RgbaImage;
use volcast::scene::camera::Camera;
use volcast::scene::clip::ClipPlane;
use volcast::scene::settings::RenderSettings;
use volcast::scene::view_state::{ViewState, VolumeRef};

const SIZE: u32 = 32;
const VOLUME: &[&str] = &["--builtin", "colormap", "--builtin-size", "16"];
/// Orthographic, looking along +y with +z up: +x runs to the right of the image, and the box's centre is its centre.
const VIEW: &[&str] = &["--view-dir", "0,1,0", "--ortho", "--size", "32x32"];

/// `volcast render <args> --validate -o NAME.png`; panics on a failure or a validation message.
fn render(args: &[&str], name: &str) -> RgbaImage {
    let out = scratch("cli-clip").join(format!("{name}.png"));
    common::volcast_ok(&[&["render"], args, &["--validate", "-o", out.to_str().unwrap()]].concat());
    image::open(&out).expect("a PNG").to_rgba8()
}

/// Pixels other than the (black) background in the left and right halves.
fn shown(image: &RgbaImage) -> (usize, usize) {
    let mut halves = (0, 0);
    for (x, _, p) in image.enumerate_pixels() {
        if p.0[..3] != [0, 0, 0] {
            if x < image.width() / 2 {
                halves.0 += 1;
            } else {
                halves.1 += 1;
            }
        }
    }
    halves
}

#[test]
fn a_plane_removes_the_half_behind_its_normal() {
    let plain = render(&[VOLUME, VIEW].concat(), "plain");
    let (left, right) = shown(&plain);
    assert!(
        left > 100 && right > 100,
        "the volume fills both halves: {left}, {right}"
    );
    // Keep x ≥ 0 (the right half); the flipped plane keeps the left; the offset is in mm (16 mm box).
    let (l, r) = shown(&render(&[VOLUME, VIEW, &["--clip-plane", "1,0,0"]].concat(), "right"));
    assert_eq!(l, 0, "left half cut away");
    assert!(r > 100, "right half kept: {r}");
    let (l, r) = shown(&render(&[VOLUME, VIEW, &["--clip-plane", "-2,0,0,0"]].concat(), "left"));
    assert_eq!(r, 0, "right half cut away");
    assert!(l > 100, "left half kept: {l}");
    // An offset of 4 mm keeps the right quarter of the 16 mm box: it starts 3/4 of the way across the box's
    // columns in the plain image.
    let columns = |image: &RgbaImage| {
        let xs: Vec<u32> = image
            .enumerate_pixels()
            .filter(|(_, _, p)| p.0[..3] != [0, 0, 0])
            .map(|(x, _, _)| x)
            .collect();
        (*xs.iter().min().unwrap(), *xs.iter().max().unwrap())
    };
    let (first, last) = columns(&plain);
    let quarter = render(&[VOLUME, VIEW, &["--clip-plane", "1,0,0,4"]].concat(), "quarter");
    let expected = f64::from(first) + 0.75 * f64::from(last + 1 - first);
    let cut = f64::from(columns(&quarter).0);
    assert!(
        (cut - expected).abs() <= 1.0,
        "the cut starts at column {cut}, expected {expected}"
    );
    let all = render(&[VOLUME, VIEW, &["--clip-plane", "0.2,1,-0.3,-100"]].concat(), "all");
    assert!(all == plain, "a plane beyond the box keeps the image");
}

#[test]
fn bad_planes_are_refused_clearly() {
    for (plane, needle) in [
        ("0,0,0", "non-zero"),
        ("0,0,0,3", "non-zero"),
        ("nan,1,0", "non-zero"),
        ("1,2", "NX,NY,NZ"),
        ("x,y,z", "NX,NY,NZ"),
        ("1,0,0,inf", "offset"),
    ] {
        for command in ["render", "compare"] {
            let o = volcast(&[&[command], VOLUME, &["--clip-plane", plane]].concat());
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(64), "{command} --clip-plane {plane}: {err}");
            assert!(err.contains("--clip-plane") && err.contains(needle), "{plane}: {err}");
            assert!(!err.contains("panicked"), "{err}");
        }
    }
}

/// `render --state` takes the plane from the file (ViewState flattens RenderSettings), and a file without the key
/// (written before planes existed) renders the whole volume.
#[test]
fn a_view_state_carries_the_plane() {
    let mut settings = RenderSettings::new(SIZE, SIZE, glam::Vec3::ONE);
    settings.camera = Camera::looking_at(glam::Vec3::new(0.0, -2.0, 0.0), glam::Vec3::ZERO);
    settings.camera.ortho = true;
    settings.cut.clip_plane = Some(ClipPlane::new(glam::Vec3::X, 0.0).unwrap());
    let state = ViewState {
        volume: VolumeRef {
            builtin: Some("colormap".into()),
            builtin_size: Some(16),
            spacing: [1.0; 3],
            ..VolumeRef::default()
        },
        settings,
        viewer: None,
        layer_files: Default::default(),
    };
    let json = state.to_json();
    assert!(json.contains("\"clip_plane\""), "{json}");
    let path = scratch("cli-clip").join("state.json");
    std::fs::write(&path, &json).unwrap();
    let (l, r) = shown(&render(&["--state", path.to_str().unwrap()], "state"));
    assert_eq!(l, 0, "the state's plane cuts the left half");
    assert!(r > 100, "{r}");

    let mut old: serde_json::Value = serde_json::from_str(&json).unwrap();
    old.as_object_mut().unwrap().remove("clip_plane");
    let old_path = scratch("cli-clip").join("state-old.json");
    std::fs::write(&old_path, old.to_string()).unwrap();
    let (l, r) = shown(&render(&["--state", old_path.to_str().unwrap()], "state-old"));
    assert!(l > 100 && r > 100, "{l}, {r}");

    let mut bad = old.clone();
    bad["clip_plane"] = serde_json::json!({"normal": [0, 0, 0], "offset": 1});
    let bad_path = scratch("cli-clip").join("state-bad.json");
    std::fs::write(&bad_path, bad.to_string()).unwrap();
    let o = volcast(&["render", "--state", bad_path.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("state-bad.json") && err.contains("non-zero"), "{err}");
}
