//! `render -h` and `--help` as a new user reads them: `-h` fits one screen, `--help` lists every option under
//! headings (input, view, colour, lighting, quality, output…), and what they say agrees with the code: every voxel
//! type, every format, the defaults the code uses, and no internal jargon ("rule 5").

use crate::common;

use common::stdout;
use volcast::scene::settings::{DEFAULT_STEP_ALPHA, DEFAULT_WINDOW};
use volcast::volume::VoxelType;

const HEADINGS: [&str; 9] = [
    "Input:",
    "GPU:",
    "Output:",
    "View:",
    "Colour:",
    "Compositing:",
    "Lighting:",
    "Quality:",
    "Cut:",
];

/// The long options a help text names at the start of its lines.
fn options(help: &str) -> Vec<String> {
    help.lines()
        .filter_map(|l| l.trim_start().split_once("--"))
        .filter(|(before, _)| before.is_empty() || before.ends_with(", "))
        .map(|(_, rest)| rest.split([' ', '<']).next().unwrap_or("").to_string())
        .collect()
}

#[test]
fn render_help_is_grouped_short_and_true() {
    let short = stdout(&common::volcast(&["render", "-h"]));
    let long = stdout(&common::volcast(&["render", "--help"]));
    let lines = short.lines().count();
    assert!(lines <= 60, "render -h is {lines} lines:\n{short}");
    for heading in HEADINGS {
        assert!(
            long.lines().any(|l| l == heading),
            "--help has no '{heading}' heading:\n{long}"
        );
    }
    assert!(short.contains("--help"), "-h says where the rest is");
    // -h shows a subset of --help; --help shows every option of the parser.
    let (few, all) = (options(&short), options(&long));
    assert!(few.len() >= 20 && few.iter().all(|o| all.contains(o)), "{few:?}");
    assert!(all.len() > few.len() + 30, "{} of {}", few.len(), all.len());
    for o in [
        "state",
        "preset",
        "window",
        "mode",
        "quality",
        "output",
        "turntable",
        "type",
        "dims",
    ] {
        assert!(few.iter().any(|f| f == o), "-h leaves out --{o}");
    }
    // What it says is what the code does.
    assert!(
        !long.to_lowercase().contains("rule "),
        "--help refers to the rendering rules by number"
    );
    let type_line = long.lines().skip_while(|l| !l.contains("--type")).nth(1).unwrap_or("");
    for t in VoxelType::ALL {
        assert!(
            type_line.contains(t.name()),
            "--type's help leaves out {t}: {type_line}"
        );
    }
    assert!(long.contains("OME-Zarr") && long.contains("DICOM") && long.contains("NIfTI"));
    let [lo, hi] = DEFAULT_WINDOW;
    let percent = |f: f32| (f * 100.0).round();
    assert!(
        long.contains(&format!("else {}%,{}%", percent(lo), percent(hi))),
        "--window's default"
    );
    assert!(
        long.contains(&format!("[default: {DEFAULT_STEP_ALPHA}]")),
        "--step-alpha's default"
    );
    assert!(
        !long.contains("[default: cool-warm]"),
        "a file's colours come from the automatic transfer function"
    );
}
