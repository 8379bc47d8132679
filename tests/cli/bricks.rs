//! The brick pool through the binary (docs/large-volumes.md, "Bricks, levels and the page table"): cutting a volume
//! into bricks changes nothing at level 0, and `--level L` shows level L of its pyramid through the pool, with a
//! note; a level past the top is the top.

use crate::common;

use common::{stderr, volcast_ok};

/// The mean absolute difference of two images' channels, in 1/255.
fn mean_difference(a: &std::path::Path, b: &std::path::Path) -> f64 {
    let (a, b) = (image::open(a).unwrap().to_rgb8(), image::open(b).unwrap().to_rgb8());
    assert_eq!(a.dimensions(), b.dimensions());
    let sum: f64 = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(&x, &y)| f64::from(x.abs_diff(y)))
        .sum();
    sum / a.as_raw().len() as f64
}

/// `render` of the built-in helix at `edge`³ into a `size` image.
fn helix<'a>(edge: &'a str, size: &'a str) -> [&'a str; 7] {
    ["render", "--builtin", "helix", "--builtin-size", edge, "--size", size]
}

#[test]
fn bricks_change_nothing_and_levels_show_the_pyramid() {
    let dir = common::scratch("cli-bricks");
    let out = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let base = helix("64", "128x128");
    volcast_ok(&[&base[..], &["-o", &out("whole.png")]].concat());
    volcast_ok(&[&base[..], &["--brick-size", "16", "-o", &out("bricks.png")]].concat());
    let d = mean_difference(&dir.join("whole.png"), &dir.join("bricks.png"));
    assert!(d < 0.02, "bricks of 16 changed the image by {d:.3}/255");
    let o = volcast_ok(
        &[
            &base[..],
            &["--brick-size", "16", "--level", "1", "-o", &out("level1.png")],
        ]
        .concat(),
    );
    let err = stderr(&o);
    assert!(
        err.contains("note: showing level 1 (32x32x32) of the pyramid everywhere, through bricks of 16x16x16"),
        "{err}"
    );
    let d = mean_difference(&dir.join("whole.png"), &dir.join("level1.png"));
    assert!(d > 0.05 && d < 6.0, "level 1 differs from level 0 by {d:.3}/255");
    // Past the top (64 in bricks of 16: level 2 is one brick) the top is shown.
    let o = volcast_ok(
        &[
            &base[..],
            &["--brick-size", "16", "--level", "7", "-o", &out("top.png")],
        ]
        .concat(),
    );
    let err = stderr(&o);
    assert!(
        err.contains("note: showing level 2 (16x16x16) of the pyramid everywhere"),
        "{err}"
    );
    assert!(
        err.contains("--level 7 is past the coarsest level of bricks of 16x16x16 (2)"),
        "{err}"
    );
}

/// A volume over the GPU budget whole is streamed through a pool that budget holds (half of it), at the levels the
/// screen rule gives within it, with a note; a budget for one brick shows the top level; `--level` that does not
/// fit the pool is refused with the numbers.
#[test]
fn a_volume_over_the_gpu_budget_is_streamed() {
    let dir = common::scratch("cli-stream");
    let out = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let base = helix("256", "192x192");
    volcast_ok(&[&base[..], &["-o", &out("whole.png")]].concat());
    let o = volcast_ok(&[&base[..], &["--gpu-budget", "24M", "-o", &out("stream.png")]].concat());
    let err = stderr(&o);
    assert!(
        err.contains(
            "note: helix is over the GPU budget whole (24 MiB); streamed through a pool of 36 bricks of 64x64x64"
        ),
        "{err}"
    );
    assert!(err.contains("level 0 in") && err.contains("level 1 in"), "{err}");
    let d = mean_difference(&dir.join("whole.png"), &dir.join("stream.png"));
    assert!(
        d > 0.0 && d < 0.5,
        "the streamed image differs from the whole one by {d:.3}/255"
    );
    let o = volcast_ok(&[&base[..], &["--gpu-budget", "1M", "-o", &out("top.png")]].concat());
    let err = stderr(&o);
    assert!(
        err.contains("a pool of 1 bricks") && err.contains("level 2 in 64 of its 64"),
        "{err}"
    );
    let o =
        common::volcast_validated(&[&base[..], &["--gpu-budget", "8M", "--level", "0", "-o", &out("l0.png")]].concat());
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("--level 0 needs 64 bricks and the GPU budget holds 12 (--gpu-budget, or a coarser --level)"),
        "{err}"
    );
}
