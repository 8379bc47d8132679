//! `volcast render --turntable` and `--keyframes` end to end, under validation, on a 32³ helix at 48x40: the frames
//! are the plain renders they claim to be, the GIF decodes to them at the right rate and loops, and bad input is
//! refused before anything is written.

use crate::common;

use common::{volcast_ok, volcast_validated};
use std::path::{Path, PathBuf};
use volcast::scene::camera::Camera;
use volcast::scene::settings::RenderSettings;
use volcast::scene::view_state::{ViewState, VolumeRef};

const VOLUME: [&str; 4] = ["--builtin", "helix", "--builtin-size", "32"];
const SIZE: (u32, u32) = (48, 40);

fn s(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("read dir")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn png(path: &Path) -> image::RgbaImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8()
}

/// The frames are the same render (same settings up to float rounding of the camera), so they must agree to the
/// last bit but for a rare rounding of a colour channel: at most 1/255 anywhere.
fn assert_same(a: &Path, b: &Path) {
    let (x, y) = (png(a), png(b));
    assert_eq!(x.dimensions(), y.dimensions(), "{} vs {}", a.display(), b.display());
    let worst = x
        .as_raw()
        .iter()
        .zip(y.as_raw())
        .map(|(p, q)| p.abs_diff(*q))
        .max()
        .unwrap_or(0);
    assert!(
        worst <= 1,
        "{} and {} differ by up to {worst}/255",
        a.display(),
        b.display()
    );
    let lit = x
        .pixels()
        .filter(|p| p[0] as u32 + p[1] as u32 + p[2] as u32 > 30)
        .count();
    assert!(
        lit > 50,
        "{} is (nearly) empty: the comparison proves nothing",
        a.display()
    );
}

/// The GIF's frames: (width, height, delay in 1/100 s), and whether it loops forever.
fn decode_gif(path: &Path) -> (Vec<(u16, u16, u16)>, bool) {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut d = gif::DecodeOptions::new().read_info(file).expect("a GIF");
    let mut frames = Vec::new();
    while let Some(f) = d.read_next_frame().expect("a frame") {
        frames.push((f.width, f.height, f.delay));
    }
    (frames, d.repeat() == gif::Repeat::Infinite)
}

fn render_args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let size = "48x40";
    ["render"]
        .into_iter()
        .chain(VOLUME)
        .chain(["--size", size])
        .chain(extra.iter().copied())
        .collect()
}

#[test]
fn turntable_writes_its_frames_and_a_looping_gif() {
    let dir = common::scratch("cli-movie-turntable");
    let out = dir.join("spin.png");
    let view = ["--azimuth", "20", "--elevation", "30"];
    let o = volcast_ok(&render_args(
        &[&view[..], &["--turntable", "6", "-o", s(&out)]].concat(),
    ));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("wrote 6 frames") && stdout.contains("spin-0005.png") && stdout.contains("spin.gif"),
        "{stdout}"
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("6/6 frames (100%)"), "progress:\n{stderr}");
    let frames: Vec<String> = (0..6).map(|k| format!("spin-{k:04}.png")).collect();
    assert_eq!(names(&dir), [&frames[..], &["spin.gif".to_string()]].concat());
    let (gif_frames, loops) = decode_gif(&dir.join("spin.gif"));
    // 25 fps by default: 4/100 s a frame.
    assert_eq!(gif_frames, vec![(48, 40, 4); 6]);
    assert!(loops, "the GIF loops forever");

    // Frame 0 is the plain render; frame 3 (180°) the plain render from the other side.
    let plain = dir.join("plain.png");
    volcast_ok(&render_args(&[&view[..], &["-o", s(&plain)]].concat()));
    assert_same(&dir.join(&frames[0]), &plain);
    let behind = dir.join("behind.png");
    volcast_ok(&render_args(&[
        "--azimuth",
        "200",
        "--elevation",
        "30",
        "-o",
        s(&behind),
    ]));
    assert_same(&dir.join(&frames[3]), &behind);
    // The other frames are other views (the turntable turns).
    assert_ne!(png(&dir.join(&frames[1])), png(&dir.join(&frames[0])));

    // --fps sets the delay.
    let slow = dir.join("slow.png");
    volcast_ok(&render_args(&["--turntable", "2", "--fps", "10", "-o", s(&slow)]));
    assert_eq!(decode_gif(&dir.join("slow.gif")).0, vec![(48, 40, 10); 2]);
}

/// A view state of the 32³ helix from azimuth/elevation, with `window`.
fn write_state(dir: &Path, name: &str, builtin: &str, azimuth: f32, elevation: f32, window: [f32; 2]) -> PathBuf {
    let extent = volcast::volume::builtin("helix", Some(32)).expect("helix").extent();
    let mut settings = RenderSettings::new(SIZE.0, SIZE.1, extent);
    let distance = settings.camera.eye.length();
    settings.camera = Camera::orbit(azimuth, elevation, distance, glam::Vec3::ZERO);
    settings.colour.window = window;
    let state = ViewState {
        volume: VolumeRef {
            builtin: Some(builtin.into()),
            builtin_size: Some(32),
            ..VolumeRef::default()
        },
        settings,
        viewer: None,
        layer_files: Default::default(),
    };
    let path = dir.join(name);
    std::fs::write(&path, state.to_json()).expect("write a state");
    path
}

#[test]
fn keyframes_start_pass_and_end_on_their_states() {
    let dir = common::scratch("cli-movie-keyframes");
    let a = write_state(&dir, "a.json", "helix", 10.0, 20.0, [0.1, 1.0]);
    let b = write_state(&dir, "b.json", "helix", 120.0, 50.0, [0.3, 0.9]);
    let c = write_state(&dir, "c.json", "helix", 250.0, -10.0, [0.2, 1.0]);
    let out = dir.join("path.png");
    let o = volcast_ok(&[
        "render",
        "--keyframes",
        s(&a),
        s(&b),
        s(&c),
        "--frames",
        "5",
        "-o",
        s(&out),
    ]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("wrote 5 frames"));
    let (gif_frames, loops) = decode_gif(&dir.join("path.gif"));
    assert_eq!(gif_frames, vec![(48, 40, 4); 5]);
    assert!(loops);
    // Frames 0, 2 and 4 of 5 over two segments are the three states exactly.
    for (k, state) in [(0, &a), (2, &b), (4, &c)] {
        let plain = dir.join(format!("state-{k}.png"));
        volcast_ok(&["render", "--state", s(state), "-o", s(&plain)]);
        assert_same(&dir.join(format!("path-{k:04}.png")), &plain);
    }
    let between = png(&dir.join("path-0001.png"));
    assert_ne!(between, png(&dir.join("path-0000.png")));
    assert_ne!(between, png(&dir.join("path-0002.png")));
}

/// Runs a command that must fail with `code` and `needle` in its message, leaving the folder as it was.
fn refused(dir: &Path, args: &[&str], code: i32, needle: &str) {
    let before = names(dir);
    let o = volcast_validated(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(code), "{args:?}:\n{err}");
    assert!(err.contains(needle), "{args:?}: expected '{needle}' in:\n{err}");
    assert_eq!(names(dir), before, "{args:?} left files behind");
}

#[test]
fn bad_movies_are_refused_and_write_nothing() {
    let dir = common::scratch("cli-movie-bad");
    let out = dir.join("m.png");
    let o = s(&out);
    let a = write_state(&dir, "a.json", "helix", 10.0, 20.0, [0.1, 1.0]);
    let other = write_state(&dir, "other.json", "box", 40.0, 20.0, [0.1, 1.0]);
    for n in ["0", "3601", "many"] {
        refused(
            &dir,
            &render_args(&["--turntable", n, "-o", o]),
            64,
            "a turntable has 1 to 3600 frames",
        );
    }
    for fps in ["0", "51", "fast"] {
        refused(
            &dir,
            &render_args(&["--turntable", "2", "--fps", fps, "-o", o]),
            64,
            "--fps",
        );
    }
    refused(
        &dir,
        &render_args(&["--turntable", "2", "-o", s(&dir.join("m.gif"))]),
        64,
        "NAME.png",
    );
    let (a, other) = (s(&a), s(&other));
    refused(
        &dir,
        &["render", "--keyframes", a, a, "-o", o],
        64,
        "--keyframes needs --frames N",
    );
    refused(
        &dir,
        &["render", "--keyframes", a, a, "--frames", "1", "-o", o],
        64,
        "--frames 1",
    );
    refused(
        &dir,
        &["render", "--keyframes", a, other, "--frames", "3", "-o", o],
        1,
        "show different volumes",
    );
    refused(
        &dir,
        &["render", "--keyframes", a, other, "--frames", "3", "-o", o],
        1,
        "other.json",
    );
    let missing = s(&dir.join("missing.json")).to_string();
    refused(
        &dir,
        &["render", "--keyframes", a, &missing, "--frames", "3", "-o", o],
        1,
        "missing.json",
    );
    refused(
        &dir,
        &render_args(&["--turntable", "2", "-o", s(&dir.join("no/such/m.png"))]),
        1,
        "m.gif",
    );
}
