//! `render --state FILE.json` with other options: each option given overrides the saved view's value and leaves
//! the rest as saved. So `--state S --size 1024x800` is a high-resolution figure of the session, and `--state S
//! --OPTION` renders exactly as a state S' that differs from S in that one field.

use crate::common;

use common::volcast_ok;
use glam::Vec3;
use std::path::{Path, PathBuf};
use volcast::scene::camera::Camera;
use volcast::scene::settings::{CompositeMode, RenderSettings};
use volcast::scene::view_state::{ViewState, VolumeRef};
use volcast::transfer::Colormap;

fn s(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

/// The saved view: the 32³ helix at 48x40, from azimuth 10, elevation 20, window 0.2-1.
fn saved() -> ViewState {
    let extent = volcast::volume::builtin("helix", Some(32)).expect("helix").extent();
    let mut settings = RenderSettings::new(48, 40, extent);
    let distance = settings.camera.eye.length();
    settings.camera = Camera::orbit(10.0, 20.0, distance, Vec3::ZERO);
    settings.colour.window = [0.2, 1.0];
    ViewState {
        volume: VolumeRef {
            builtin: Some("helix".into()),
            builtin_size: Some(32),
            ..VolumeRef::default()
        },
        settings,
        viewer: None,
        layer_files: Default::default(),
    }
}

fn write(dir: &Path, name: &str, state: &ViewState) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, state.to_json()).expect("write a state");
    path
}

fn render(dir: &Path, name: &str, args: &[&str]) -> image::RgbaImage {
    let out = dir.join(name);
    let mut all = vec!["render", "--validate"];
    all.extend_from_slice(args);
    all.extend(["-o", s(&out)]);
    let o = volcast_ok(&all);
    assert!(String::from_utf8_lossy(&o.stdout).contains("rendered"));
    image::open(&out).expect("the PNG").to_rgba8()
}

#[test]
fn options_beside_a_state_override_its_values_and_keep_the_rest() {
    let dir = common::scratch("cli-state-overrides");
    let base = saved();
    let state = write(&dir, "state.json", &base);
    let plain = render(&dir, "plain.png", &["--state", s(&state)]);
    assert_eq!(plain.dimensions(), (48, 40), "the state alone renders at its size");

    // Each case: the options given, and the state they must render as.
    let turned = {
        let mut v = base.clone();
        let d = v.settings.camera.eye.length();
        v.settings.camera = Camera::orbit(90.0, 20.0, d, Vec3::ZERO);
        v
    };
    let mut cases: Vec<(&str, Vec<&str>, ViewState)> = vec![
        ("size", vec!["--size", "96x80"], {
            let mut v = base.clone();
            (v.settings.width, v.settings.height) = (96, 80);
            v
        }),
        ("window", vec!["--window", "50%,100%"], {
            let mut v = base.clone();
            v.settings.colour.window = [0.5, 1.0];
            v
        }),
        ("azimuth", vec!["--azimuth", "90"], turned),
        ("colormap", vec!["--colormap", "plasma"], {
            let mut v = base.clone();
            v.settings.colour.colormap = Colormap::Plasma;
            v
        }),
        ("mode", vec!["--mode", "mip"], {
            let mut v = base.clone();
            v.settings.compositing.mode = CompositeMode::Mip;
            v
        }),
    ];
    for (name, options, expected) in cases.drain(..) {
        let expected_file = write(&dir, &format!("{name}-expected.json"), &expected);
        let want = render(&dir, &format!("{name}-expected.png"), &["--state", s(&expected_file)]);
        let mut args = vec!["--state", s(&state)];
        args.extend(options.iter().copied());
        let got = render(&dir, &format!("{name}.png"), &args);
        assert_eq!(got.dimensions(), want.dimensions(), "{name}");
        assert!(
            got == want,
            "--state with {options:?} renders as the state with that field changed"
        );
        if name != "size" {
            assert!(got != plain, "{options:?} changed nothing");
        }
    }
}
