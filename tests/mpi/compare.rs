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
/// each rank: a compressed stream is not read by box), orthographic from below; its automatic transfer function is
/// placed by the histogram, which the ranks add up, under a window.
#[test]
fn a_mirrored_placement_in_an_orthographic_view_from_below() {
    let nii =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/native/motor_zmap/image_10426.nii.gz");
    same_image(
        "mirrored",
        vec![nii.display().to_string()],
        &[
            "--ortho",
            "--elevation",
            "-50",
            "--azimuth",
            "120",
            "--window",
            "10%,95%",
        ],
        &[8],
    );
}

/// A dense generated volume (shells and a lattice of blobs, 100 x 90 x 70 uint16, named as open-scivis names raw
/// files), written for the test.
fn dense_volume(dir: &std::path::Path) -> Vec<String> {
    let [w, h, d] = [100usize, 90, 70];
    let mut bytes = Vec::with_capacity(w * h * d * 2);
    for z in 0..d {
        for y in 0..h {
            for x in 0..w {
                let p = [
                    x as f64 / w as f64 - 0.5,
                    y as f64 / h as f64 - 0.5,
                    z as f64 / d as f64 - 0.5,
                ];
                let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() * 2.2;
                let blobs = ((x as f64 / 5.0).sin() * (y as f64 / 6.0).sin() * (z as f64 / 4.0).sin()).max(0.0);
                let v = ((1.0 - r).max(0.0) * 40000.0 + blobs * 20000.0 * f64::from(u8::from(r < 1.0))) as u16;
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    let path = dir.join("shells_100x90x70_uint16.raw");
    std::fs::write(&path, bytes).unwrap();
    vec![path.display().to_string()]
}

/// Without early termination (which each rank applies to its own share: a ray the single process ends at 99%
/// opacity gets the rest of its light under mpirun, up to 1% of it), the shares composite to exactly the single
/// image: same samples, same segments, strides included (the ring of bricks around each box), shaded, on a dense
/// volume where every ray crosses seams.
#[test]
fn without_early_termination_the_image_is_exactly_the_single_one() {
    let dir = scratch("exact");
    let volume = dense_volume(&dir);
    let dir2 = scratch("exact-run");
    for (args, ranks) in [
        // Faint classification: many bricks take strides of 2 and 4.
        (
            vec![
                "--max-stride",
                "4",
                "--colormap",
                "grayscale",
                "--step-alpha",
                "0.01",
                "--azimuth",
                "20",
                "--elevation",
                "30",
            ],
            vec![2, 8],
        ),
        (
            vec!["--shading", "--azimuth", "-70", "--clip-plane", "0.3,1,0,0.1"],
            vec![4],
        ),
    ] {
        let mut all = volume.clone();
        all.extend(["--size", "128x128", "--early-termination", "1"].map(String::from));
        all.extend(args.iter().map(|s| s.to_string()));
        let one = dir2.join("one.png");
        let o = single(&all, &one);
        assert!(o.status.success(), "single process: {}", text(&o));
        for n in ranks {
            let many = dir2.join(format!("{n}.png"));
            let o = mpirun(n, &all, &many);
            assert!(o.status.success(), "{n} ranks: {}", text(&o));
            assert_eq!(
                difference(&one, &many),
                (0, 0),
                "{args:?} on {n} ranks ({})",
                dir2.display()
            );
        }
    }
    std::fs::remove_dir_all(dir).ok();
    std::fs::remove_dir_all(dir2).ok();
}
