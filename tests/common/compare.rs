//! Image comparison for reference tests: error statistics, and images a person can look at when a test fails.

#![allow(dead_code)]

use image::{Rgba, RgbaImage};
use std::fmt;
use std::path::PathBuf;

/// Per-pixel error (the largest absolute RGB channel difference), summarised in units of 1/255.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageDiff {
    pub mean: f64,
    /// 99th percentile (nearest rank).
    pub p99: f64,
    pub max: f64,
    /// Share of pixels (0..1) whose error exceeds 1/255, i.e. more than rounding.
    pub over_1: f64,
}

impl fmt::Display for ImageDiff {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "mean {:.3}/255, p99 {:.0}/255, max {:.0}/255, {:.2}% of pixels over 1/255",
            self.mean,
            self.p99,
            self.max,
            self.over_1 * 100.0
        )
    }
}

fn pixel_error(a: &Rgba<u8>, b: &Rgba<u8>) -> u8 {
    (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0)
}

/// Compares the RGB of two images of the same size (alpha is ignored: both are opaque by rule 8).
pub fn diff(a: &RgbaImage, b: &RgbaImage) -> ImageDiff {
    assert_eq!(a.dimensions(), b.dimensions(), "compared images differ in size");
    let mut errors: Vec<u8> = a.pixels().zip(b.pixels()).map(|(p, q)| pixel_error(p, q)).collect();
    if errors.is_empty() {
        return ImageDiff {
            mean: 0.0,
            p99: 0.0,
            max: 0.0,
            over_1: 0.0,
        };
    }
    errors.sort_unstable();
    let n = errors.len();
    // Nearest rank ceil(0.99·n), in integers so that n = 100 gives exactly the 99th value.
    let rank = (99 * n).div_ceil(100).max(1);
    ImageDiff {
        mean: errors.iter().map(|&e| f64::from(e)).sum::<f64>() / n as f64,
        p99: f64::from(errors[rank - 1]),
        max: f64::from(errors[n - 1]),
        over_1: errors.iter().filter(|&&e| e > 1).count() as f64 / n as f64,
    }
}

/// The difference per channel, amplified ×10 so that errors of a few 1/255 are visible.
pub fn diff_image(a: &RgbaImage, b: &RgbaImage) -> RgbaImage {
    assert_eq!(a.dimensions(), b.dimensions(), "compared images differ in size");
    RgbaImage::from_fn(a.width(), a.height(), |x, y| {
        let (p, q) = (a.get_pixel(x, y), b.get_pixel(x, y));
        let d = |c: usize| (u32::from(p[c].abs_diff(q[c])) * 10).min(255) as u8;
        Rgba([d(0), d(1), d(2), 255])
    })
}

/// `target/test-failures/` in the crate, created if needed (git-ignored with the rest of `target/`).
pub fn failure_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("test-failures");
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("cannot create {}: {e}", dir.display()));
    dir
}

/// Writes `<name>-actual.png`, `<name>-expected.png` and `<name>-diff.png` and prints where they went.
pub fn write_failure_images(name: &str, actual: &RgbaImage, expected: &RgbaImage) {
    let dir = failure_dir();
    let write = |suffix: &str, image: &RgbaImage| {
        let path = dir.join(format!("{name}-{suffix}.png"));
        match image.save(&path) {
            Ok(()) => eprintln!("wrote {}", path.display()),
            Err(e) => eprintln!("could not write {}: {e}", path.display()),
        }
    };
    write("actual", actual);
    write("expected", expected);
    if actual.dimensions() == expected.dimensions() {
        write("diff", &diff_image(actual, expected));
    }
}

/// Panics, after writing the failure images, if the mean or the 99th percentile error exceeds its bound (units
/// of 1/255).
pub fn assert_close(name: &str, actual: &RgbaImage, expected: &RgbaImage, max_mean: f64, max_p99: f64) -> ImageDiff {
    if actual.dimensions() != expected.dimensions() {
        write_failure_images(name, actual, expected);
        panic!(
            "{name}: image is {}x{} but the reference is {}x{}",
            actual.width(),
            actual.height(),
            expected.width(),
            expected.height()
        );
    }
    let d = diff(actual, expected);
    eprintln!("{name}: {d}");
    if d.mean > max_mean || d.p99 > max_p99 {
        write_failure_images(name, actual, expected);
        panic!("{name}: differs from the reference: {d}; allowed mean {max_mean}/255, p99 {max_p99}/255");
    }
    d
}
