//! `volcast info` and `render` on OME-Zarr stores through the binary: the channels with their omero names, windows
//! and colours, the level chosen under `--max-dim`, `--channel` and its error, the JSON's `channels`.

use crate::common;

use common::{stderr, stdout, volcast, volcast_ok};

fn store(name: &str) -> String {
    format!("{}/tests/data/zarr/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn info_lists_channels_and_the_level() {
    let o = volcast(&["info", &store("sharded_tczyx.zarr"), "--channel", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("format:    OME-Zarr"), "{text}");
    assert!(
        text.contains("channels:  0: DAPI, window 10 .. 200, colour #0000FF\n"),
        "{text}"
    );
    assert!(
        text.contains("1: GFP, window 50 .. 240, colour #00FF00 (loaded)"),
        "{text}"
    );
    assert!(text.contains("timesteps: 2"), "{text}");
    let o = volcast(&["info", &store("v04_blosc.zarr"), "--max-dim", "8"]);
    let text = stdout(&o);
    assert!(text.contains("dims:      8 x 6 x 4"), "{text}");
    assert!(
        text.contains(
            "note:      level 1 of 3 (8x6x4); level 0 (16x12x8) is too large: 16 exceeds the maximum dimension 8"
        ),
        "{text}"
    );
    let o = volcast(&["info", "--json", &store("napari_czyx.zarr")]);
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let channels = &json["channels"];
    assert_eq!(channels[1]["name"], "nuclei");
    assert_eq!(channels[0]["loaded"], true);
    assert_eq!(channels[0]["color"], serde_json::json!([255, 0, 255]));
}

#[test]
fn a_missing_channel_is_refused_with_the_list() {
    let o = volcast(&["info", &store("sharded_tczyx.zarr"), "--channel", "3"]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("sharded_tczyx.zarr") && e.contains("channel 3 does not exist") && e.contains("0 (DAPI), 1 (GFP)"),
        "{e}"
    );
}

#[test]
fn a_store_renders() {
    let dir = common::scratch("cli-zarr-render");
    let out = dir.join("v05.png");
    volcast_ok(&[
        "render",
        &store("v05.zarr"),
        "-o",
        out.to_str().unwrap(),
        "--size",
        "64x64",
    ]);
    // Not an empty frame: the store's ramp shows against the black background.
    let image = image::open(&out).unwrap().to_rgba8();
    assert!(
        image.pixels().any(|p| p[0] > 0 || p[1] > 0 || p[2] > 0),
        "the render is blank"
    );
}

/// A view state names the store and its channel: `render --state` shows that channel, as `--channel` does.
#[test]
fn a_state_keeps_the_channel() {
    let dir = common::scratch("cli-zarr-state");
    let path = std::path::PathBuf::from(store("sharded_tczyx.zarr"));
    let png = |name: &str, args: &[&str]| {
        let out = dir.join(name);
        let mut all = vec!["render", "--size", "48x40", "-o", out.to_str().unwrap()];
        all.extend_from_slice(args);
        let o = volcast(&all);
        assert!(o.status.success(), "{}", stderr(&o));
        std::fs::read(out).unwrap()
    };
    let extent = volcast::formats::open(&path, &Default::default()).unwrap().extent();
    let state = volcast::scene::view_state::ViewState {
        volume: volcast::scene::view_state::VolumeRef {
            path: Some(path.clone()),
            channel: Some(1),
            ..Default::default()
        },
        settings: volcast::scene::settings::RenderSettings::new(48, 40, extent),
        viewer: None,
        layer_files: Default::default(),
    };
    let write = |name: &str, state: &volcast::scene::view_state::ViewState| {
        let file = dir.join(name);
        std::fs::write(&file, state.to_json()).unwrap();
        file.to_str().unwrap().to_string()
    };
    let with_channel = write("state1.json", &state);
    assert!(std::fs::read_to_string(&with_channel)
        .unwrap()
        .contains("\"channel\": 1"));
    let mut plain = state.clone();
    plain.volume.channel = None;
    let without = write("state0.json", &plain);
    let from_state = png("state.png", &["--state", &with_channel]);
    let asked = png("asked.png", &["--state", &without, "--channel", "1"]);
    let channel0 = png("c0.png", &["--state", &without]);
    assert_eq!(from_state, asked);
    assert_ne!(from_state, channel0);
}

/// What `volcast convert` writes, volcast reads back with the input's exact placement: the fMRI map (LAS, x flipped,
/// which OME-Zarr's scale and translation cannot say) keeps its affine and RAS frame through the "volcast" key, for
/// Zarr v3 and v2 alike; the values and range are the input's.
#[test]
fn convert_round_trip_keeps_the_affine_and_frame() {
    let Some(nii) = common::shared_data("native/motor_zmap/image_10426.nii.gz") else {
        return;
    };
    let dir = common::scratch("cli-zarr-round-trip");
    let info = |path: &str| -> serde_json::Value {
        let o = volcast(&["info", "--json", path]);
        assert!(o.status.success(), "{}", stderr(&o));
        serde_json::from_str(&stdout(&o)).unwrap()
    };
    let source = info(&nii.to_string_lossy());
    for version in ["0.5", "0.4"] {
        let out = dir.join(format!("motor-{version}.ome.zarr"));
        let o = volcast(&[
            "convert",
            &nii.to_string_lossy(),
            &out.to_string_lossy(),
            "--ome-zarr-version",
            version,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let back = info(&out.to_string_lossy());
        assert_eq!(back["format"], "OME-Zarr");
        assert_eq!(back["anatomical"], source["anatomical"], "{back}");
        assert_eq!(back["affine_ras"], source["affine_ras"], "OME-Zarr {version}: {back}");
        assert_eq!(back["dims"], source["dims"]);
        assert_eq!(back["value_range"], source["value_range"]);
    }
}

/// `--channels` shows a store's other channels over the one `--channel` shows, each in its omero colour: DAPI
/// (blue) over GFP (green) adds blue, and GFP over DAPI adds green; a channel the store lacks, or a file without
/// channels, is refused naming the file.
#[test]
fn every_channel_shows_in_its_own_colour() {
    let dir = common::scratch("cli-zarr-channels");
    let path = store("sharded_tczyx.zarr");
    let render = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec!["render", &path, "--size", "96x96", "-o", out.to_str().unwrap()];
        args.extend(extra);
        volcast_ok(&args);
        let image = image::open(&out).unwrap().to_rgba8();
        [0, 1, 2].map(|c| image.pixels().map(|p| u64::from(p[c])).sum::<u64>())
    };
    let dapi = render("dapi.png", &[]);
    let with_gfp = render("dapi-gfp.png", &["--channels", "all"]);
    let gfp = render("gfp.png", &["--channel", "1"]);
    let with_dapi = render("gfp-dapi.png", &["--channel", "1", "--channels", "0"]);
    assert!(dapi[2] > 2 * dapi[1] + 1000, "DAPI alone is blue: {dapi:?}");
    assert!(
        with_gfp[1] > dapi[1] + 50_000,
        "GFP adds green: {with_gfp:?} over {dapi:?}"
    );
    assert!(gfp[1] > 2 * gfp[2] + 1000, "GFP alone is green: {gfp:?}");
    assert!(
        with_dapi[2] > gfp[2] + 50_000,
        "DAPI adds blue: {with_dapi:?} over {gfp:?}"
    );
    let o = volcast(&[
        "render",
        &path,
        "--channels",
        "2",
        "-o",
        dir.join("x.png").to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("sharded_tczyx") && e.contains("the channels are 0 to 1"),
        "{e}"
    );
    let o = volcast(&[
        "render",
        &store("v05.zarr"),
        "--channels",
        "all",
        "-o",
        dir.join("x.png").to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("--channels needs a file with channels"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).ok();
}
