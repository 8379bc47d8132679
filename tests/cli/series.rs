//! A DICOM folder holding several series, through the binary: `info` lists them, every load says which it took,
//! `--series` picks one by number or UID, and an unknown one exits 64 with the list.

use crate::common;

use common::dicom_series::{self, SERIES};
use common::{stderr, stdout, volcast};

fn folder(name: &str) -> Option<String> {
    let dir = common::scratch(name).join("mixed");
    match dicom_series::make(&dir) {
        Some(d) => Some(d.to_string_lossy().into_owned()),
        None => {
            common::skip("no shared DICOM series (../shared/data/native/brain_pd_mr)");
            None
        }
    }
}

#[test]
fn info_lists_the_series_and_the_largest_is_loaded() {
    let Some(dir) = folder("cli-series-info") else { return };
    let o = volcast(&["info", &dir]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("dims:      256 x 256 x 6"), "{text}");
    for s in &SERIES {
        let line = text
            .lines()
            .find(|l| l.contains(s.uid))
            .unwrap_or_else(|| panic!("{} not listed:\n{text}", s.uid));
        let slices = s.slices.clone().count();
        let want = format!("{}: '{}', MR, {slices} slices of 256 x 256", s.number, s.description);
        assert!(line.contains(&want), "{line}");
        assert_eq!(line.contains("(loaded)"), s.number == 902, "{line}");
    }
    assert!(text.contains("series:    901: "), "{text}");
    assert!(
        text.contains("the folder holds 3 series; loaded series 902 (") && text.contains("--series N or UID"),
        "{text}"
    );
    let json: serde_json::Value = serde_json::from_str(&stdout(&volcast(&["info", "--json", &dir]))).unwrap();
    let listed = json["series"].as_array().expect("a series list");
    assert_eq!(listed.len(), 3);
    assert_eq!(listed[0]["uid"], SERIES[0].uid);
    assert_eq!(listed[1]["loaded"], true);
}

#[test]
fn series_picks_by_number_or_uid_and_an_unknown_one_is_refused_with_the_list() {
    let Some(dir) = folder("cli-series-pick") else { return };
    let o = volcast(&["info", "--series", "903", &dir]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("dims:      256 x 256 x 2"), "{}", stdout(&o));
    assert!(stdout(&o).contains("loaded series 903"), "{}", stdout(&o));
    let o = volcast(&["info", "--series", SERIES[0].uid, &dir]);
    assert!(stdout(&o).contains("dims:      256 x 256 x 4"), "{}", stdout(&o));
    let o = volcast(&["info", "--series", "77", &dir]);
    assert_eq!(o.status.code(), Some(64), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("no series '77'"), "{e}");
    for s in &SERIES {
        assert!(e.contains(s.uid), "{e}");
    }
}

/// `render` (a GPU command) takes --series too and says on stderr which series it loaded.
#[test]
fn render_says_which_series_it_loaded() {
    let Some(dir) = folder("cli-series-render") else { return };
    let out = common::scratch("cli-series-render").join("r.png");
    let o = common::volcast_ok(&[
        "render",
        &dir,
        "--series",
        "901",
        "--size",
        "32x32",
        "-o",
        &out.to_string_lossy(),
    ]);
    let e = stderr(&o);
    assert!(
        e.contains("note: the folder holds 3 series; loaded series 901 ("),
        "{e}"
    );
    assert!(out.exists());
}

/// One file of a series opens the whole series, as in Slicer: that file's series (901 holds slices 1–4), with the
/// folder's others listed; `--series` still picks another. A file alone in its series, or a multi-frame file, is
/// what it is.
#[test]
fn one_file_opens_its_series() {
    let Some(dir) = folder("cli-series-one-file") else {
        return;
    };
    let file = format!("{dir}/slice_002.dcm");
    let o = volcast(&["info", &file]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("dims:      256 x 256 x 4"), "{text}");
    assert!(text.contains("loaded series 901"), "{text}");
    let o = volcast(&["info", "--series", "903", &file]);
    assert!(stdout(&o).contains("dims:      256 x 256 x 2"), "{}", stdout(&o));
    let j2k = format!("{}/tests/data/dicom/i16_j2k/03.dcm", env!("CARGO_MANIFEST_DIR"));
    let one = stdout(&volcast(&["info", &j2k]));
    assert!(one.contains("dims:      16 x 12 x 6"), "{one}");
    // A folder of one series lists it too: its description and modality.
    assert!(
        one.contains("series:    -: (no description), CT, 6 slices of 16 x 12"),
        "{one}"
    );
    let frames = format!(
        "{}/tests/data/dicom/multiframe_ct_native.dcm",
        env!("CARGO_MANIFEST_DIR")
    );
    let alone = stdout(&volcast(&["info", &frames]));
    assert!(alone.contains("name:      multiframe_ct_native"), "{alone}");
}
