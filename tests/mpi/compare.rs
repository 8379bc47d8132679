//! The image of N ranks equals the single-process image: views where the compositing order matters.

use super::{ct_head, mpirun, scratch, single, text};

/// Per channel, how far the two images are apart: the largest difference, and how many pixels differ by more
/// than 2/255.
pub fn difference(a: &std::path::Path, b: &std::path::Path) -> (u8, usize) {
    let (a, b) = (image::open(a).unwrap().to_rgba8(), image::open(b).unwrap().to_rgba8());
    assert_eq!(a.dimensions(), b.dimensions());
    let mut worst = 0u8;
    let mut over = 0;
    for (p, q) in a.pixels().zip(b.pixels()) {
        let d = (0..4).map(|c| p.0[c].abs_diff(q.0[c])).max().unwrap();
        worst = worst.max(d);
        over += usize::from(d > 2);
    }
    (worst, over)
}

/// Renders `args` on one process and on each of `ranks`, and checks every N-rank image against the single one.
pub fn same_image(name: &str, volume: Vec<String>, args: &[&str], ranks: &[usize]) {
    let dir = scratch(name);
    let mut all = volume;
    all.extend(["--size", "160x160"].map(String::from));
    all.extend(args.iter().map(|s| s.to_string()));
    let one = dir.join("one.png");
    let o = single(&all, &one);
    assert!(o.status.success(), "single process: {}", text(&o));
    for &n in ranks {
        let many = dir.join(format!("{n}.png"));
        let o = mpirun(n, &all, &many);
        assert!(o.status.success(), "{n} ranks: {}", text(&o));
        let (worst, over) = difference(&one, &many);
        // Within 2/255 everywhere, silhouettes included: no outlier is allowed (none has occurred).
        assert!(
            worst <= 2,
            "{name} on {n} ranks: largest difference {worst}/255, {over} pixels over 2/255 ({})",
            dir.display()
        );
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn an_oblique_view_on_2_4_and_8_ranks() {
    same_image(
        "oblique",
        ct_head(),
        &["--azimuth", "35", "--elevation", "25"],
        &[2, 4, 8],
    );
}

#[test]
fn the_camera_inside_the_volume() {
    same_image(
        "inside",
        ct_head(),
        &["--distance", "0.35", "--azimuth", "200", "--elevation", "-10"],
        &[4],
    );
}

#[test]
fn a_clip_plane_across_the_seams() {
    same_image(
        "clip",
        ct_head(),
        &["--azimuth", "60", "--clip-plane", "1,0.4,0.2,0.05"],
        &[4],
    );
}

/// The fMRI map of ../shared/data in LAS orientation (its affine mirrors x), from its gzip NIfTI (read whole by
/// each rank: a compressed stream is not read by box), orthographic from below.
#[test]
fn a_mirrored_placement_in_an_orthographic_view_from_below() {
    let nii =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/native/motor_zmap/image_10426.nii.gz");
    same_image(
        "mirrored",
        vec![nii.display().to_string()],
        &["--ortho", "--elevation", "-50", "--azimuth", "120"],
        &[8],
    );
}
