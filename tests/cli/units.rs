//! Values in the data's own units (issue 61): `--window`, `--iso` and `--surface` take HU for a CT, z for a z-map,
//! or a percentage of the range written as one. On a uint16 volume of values 0–4000, the values in units and the
//! same places as percentages render the same image; a bare fraction (written before units) renders a sliver of
//! the range, and says how to write a fraction.

use crate::common;

use common::scratch::write_raw;

/// A uint16 ball of 0–4000 (4000 at the centre, falling off with the radius), 24³.
fn ball() -> Vec<String> {
    let path = common::scratch("cli-units").join("ball_24x24x24_uint16.raw");
    write_raw(&path, [24; 3], |_, p, out| {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        out.extend(((4000.0 * (1.0 - 2.0 * r).max(0.0)).round() as u16).to_le_bytes());
    });
    let path = path.to_string_lossy().into_owned();
    [
        path.as_str(),
        "--colormap",
        "grayscale",
        "--size",
        "48x48",
        "--validate",
    ]
    .map(String::from)
    .to_vec()
}

fn render(args: &[&str], name: &str) -> (image::RgbaImage, String) {
    let out = common::scratch("cli-units").join(format!("{name}.png"));
    let volume = ball();
    let mut all: Vec<&str> = vec!["render"];
    all.extend(volume.iter().map(String::as_str));
    all.extend(args);
    all.extend(["-o", out.to_str().expect("UTF-8")]);
    let o = common::volcast_ok(&all);
    (image::open(&out).expect("a PNG").to_rgba8(), common::stderr(&o))
}

#[test]
fn windows_iso_values_and_surfaces_take_data_units_or_percentages() {
    let (units, quiet) = render(&["--window", "1000,3000"], "window-units");
    let (percent, _) = render(&["--window", "25%,75%"], "window-percent");
    assert_eq!(units, percent, "1000–3000 of 0–4000 is 25%–75%");
    assert!(!quiet.contains("note: --window"), "{quiet}");
    let (bare, note) = render(&["--window", "0.25,0.75"], "window-bare");
    assert_ne!(bare, units, "0.25–0.75 is now a sliver of 0–4000");
    assert!(
        note.contains("note: --window is in the data's units") && note.contains("--window 25%,75%"),
        "{note}"
    );

    let iso = ["--mode", "iso", "--iso"];
    let (units, _) = render(
        &[&iso[..], &["2000", "--surface", "1000,1,0,0,0.5"]].concat(),
        "iso-units",
    );
    let (percent, _) = render(
        &[&iso[..], &["50%", "--surface", "25%,1,0,0,0.5"]].concat(),
        "iso-percent",
    );
    assert_eq!(units, percent, "iso 2000 is 50%, surface 1000 is 25%");
    let (other, _) = render(
        &[&iso[..], &["50%", "--surface", "60%,1,0,0,0.5"]].concat(),
        "iso-other",
    );
    assert_ne!(units, other, "the surface's value is read");
}
