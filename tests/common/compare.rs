//! Image comparison for reference tests: error statistics over the pixels that show the volume, bounds that say
//! what they catch, and images a person can look at when a test fails.
//!
//! A pixel's error is the largest absolute difference of its three 8-bit channels (units of 1/255). Statistics
//! against the reference are taken over the *object pixels* (see [`object_mask`]): background pixels agree
//! trivially, and counting them would dilute a real error by however much of the image is empty.

use super::reference::{background_pixel, Rendered};
use image::{Rgba, RgbaImage};
use std::fmt;
use std::path::PathBuf;

/// Error statistics over a set of pixels, in units of 1/255.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageDiff {
    /// Pixels compared.
    pub pixels: u64,
    pub mean: f64,
    /// 99th percentile (nearest rank).
    pub p99: f64,
    pub max: f64,
    /// Share of the compared pixels (0..1) whose error exceeds 1/255, i.e. more than rounding.
    pub over_1: f64,
    /// `histogram[e]`: pixels with error e.
    histogram: Vec<u64>,
}

impl ImageDiff {
    /// Pixels whose error exceeds `e`.
    pub fn above(&self, e: u8) -> u64 {
        self.histogram[usize::from(e) + 1..].iter().sum()
    }

    /// The mean error with the `n` largest errors left out (the outliers a bound allows: on an object of a few
    /// hundred pixels one silhouette pixel would otherwise move the mean by a tenth of a level).
    pub fn mean_without(&self, n: u64) -> f64 {
        let kept = self.pixels.saturating_sub(n);
        if kept == 0 {
            return 0.0;
        }
        let (mut left, mut sum) = (kept, 0u64);
        for (e, &count) in self.histogram.iter().enumerate() {
            let take = count.min(left);
            sum += take * e as u64;
            left -= take;
        }
        sum as f64 / kept as f64
    }
}

impl fmt::Display for ImageDiff {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} px: mean {:.3}/255, p99 {:.0}/255, max {:.0}/255, {:.2}% over 1/255",
            self.pixels,
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

/// Compares the RGB of two images of the same size at the pixels (row-major) where `mask` holds; alpha is
/// ignored (both are opaque by rule 8).
pub fn diff_where(a: &RgbaImage, b: &RgbaImage, mask: &[bool]) -> ImageDiff {
    assert_eq!(a.dimensions(), b.dimensions(), "compared images differ in size");
    assert_eq!(mask.len(), (a.width() * a.height()) as usize, "mask size");
    let mut histogram = vec![0u64; 256];
    for ((p, q), &m) in a.pixels().zip(b.pixels()).zip(mask) {
        if m {
            histogram[usize::from(pixel_error(p, q))] += 1;
        }
    }
    let n: u64 = histogram.iter().sum();
    if n == 0 {
        return ImageDiff {
            pixels: 0,
            mean: 0.0,
            p99: 0.0,
            max: 0.0,
            over_1: 0.0,
            histogram,
        };
    }
    // Nearest rank ceil(0.99·n), in integers so that n = 100 gives exactly the 99th value.
    let rank = (99 * n).div_ceil(100).max(1);
    let mut seen = 0;
    let mut p99 = 0;
    for (e, &count) in histogram.iter().enumerate() {
        seen += count;
        if seen >= rank {
            p99 = e;
            break;
        }
    }
    let max = histogram.iter().rposition(|&c| c > 0).unwrap_or(0);
    ImageDiff {
        pixels: n,
        mean: histogram
            .iter()
            .enumerate()
            .map(|(e, &c)| (e as u64 * c) as f64)
            .sum::<f64>()
            / n as f64,
        p99: p99 as f64,
        max: max as f64,
        over_1: histogram[2..].iter().sum::<u64>() as f64 / n as f64,
        histogram,
    }
}

/// Compares two whole images (for GPU-against-GPU checks, where "the same image" is the claim).
pub fn diff(a: &RgbaImage, b: &RgbaImage) -> ImageDiff {
    diff_where(a, b, &vec![true; (a.width() * a.height()) as usize])
}

/// The object pixels of a comparison with the reference: where the reference's ray showed the volume, or where
/// either image is not the background. The second part keeps a GPU image that draws something where the
/// reference shows nothing (or the reverse, through a colour equal to the background) from escaping the statistics.
pub fn object_mask(actual: &RgbaImage, expected: &Rendered, background: glam::Vec3) -> Vec<bool> {
    let bg = background_pixel(background);
    actual
        .pixels()
        .zip(expected.image.pixels())
        .zip(&expected.object)
        .map(|((a, e), &shows)| shows || *a != bg || *e != bg)
        .collect()
}

/// `actual` against the reference rendering `expected` of the same settings, over the object pixels.
pub fn against_reference(actual: &RgbaImage, expected: &Rendered, background: glam::Vec3) -> ImageDiff {
    diff_where(actual, &expected.image, &object_mask(actual, expected, background))
}

/// Two GPU images of the same settings against each other, over the object pixels of both and of the reference.
pub fn between(a: &RgbaImage, b: &RgbaImage, expected: &Rendered, background: glam::Vec3) -> ImageDiff {
    let bg = background_pixel(background);
    let mask: Vec<bool> = object_mask(a, expected, background)
        .into_iter()
        .zip(b.pixels())
        .map(|(m, p)| m || *p != bg)
        .collect();
    diff_where(a, b, &mask)
}

/// How far an image may be from another: over the compared pixels, at most `outliers` pixels with an error above
/// `max` (silhouette pixels, where the GPU's rasteriser or f32 slab test and the reference's f64 one may decide a
/// grazing ray differently), mean ≤ `mean` without those outliers, and p99 ≤ `p99`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub mean: f64,
    pub p99: f64,
    pub max: u8,
    pub outliers: u64,
}

impl Bounds {
    /// `Err` naming every bound `d` breaks.
    pub fn check(&self, d: &ImageDiff) -> Result<(), String> {
        let mut broken = Vec::new();
        let mean = d.mean_without(self.outliers);
        if mean > self.mean {
            broken.push(format!(
                "mean {mean:.3} (without {} outliers) > {}",
                self.outliers, self.mean
            ));
        }
        if d.p99 > self.p99 {
            broken.push(format!("p99 {} > {}", d.p99, self.p99));
        }
        let above = d.above(self.max);
        if above > self.outliers {
            broken.push(format!(
                "{above} px above {}/255 (at most {} allowed)",
                self.max, self.outliers
            ));
        }
        if broken.is_empty() {
            Ok(())
        } else {
            Err(broken.join(", "))
        }
    }
}

impl fmt::Display for Bounds {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "mean ≤ {}, p99 ≤ {}, ≤ {} px above {}",
            self.mean, self.p99, self.outliers, self.max
        )
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
