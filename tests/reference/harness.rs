//! What the GPU tests judge by, besides the rules: the image comparison (statistics, bounds, masks over the object
//! pixels, the failure images) and the reference's speed at a realistic size.

use crate::common;

use super::scenes::{assert_near, constant_volume, head_on};
use common::compare::{self, Bounds};
use common::reference::Reference;
use glam::Vec3;
use image::{Rgba, RgbaImage};
use volcast::scene::camera::Camera;
use volcast::scene::settings::RenderSettings;

#[test]
fn compare_reports_mean_percentile_max_and_outliers() {
    let a = RgbaImage::from_pixel(10, 10, image::Rgba([10, 20, 30, 255]));
    let zero = compare::diff(&a, &a);
    assert_eq!((zero.mean, zero.p99, zero.max, zero.over_1), (0.0, 0.0, 0.0, 0.0));
    let mut b = a.clone();
    b.put_pixel(3, 4, image::Rgba([10, 27, 25, 255])); // max over RGB: 7
    b.put_pixel(5, 6, image::Rgba([11, 20, 30, 255])); // 1: rounding, not counted in over_1
    let d = compare::diff(&b, &a);
    assert_near("mean", d.mean, 8.0 / 100.0, 1e-12);
    assert_eq!(
        (d.p99, d.max),
        (1.0, 7.0),
        "2 of 100 pixels differ: the 99th percentile is the smaller"
    );
    assert_near("over_1", d.over_1, 1.0 / 100.0, 1e-12);
    assert_eq!((d.above(0), d.above(1), d.above(6), d.above(7)), (2, 1, 1, 0));
    assert_near("mean without the worst pixel", d.mean_without(1), 1.0 / 99.0, 1e-12);
    assert_eq!(d.mean_without(100), 0.0);
    let bounds = |mean, p99, max, outliers| Bounds {
        mean,
        p99,
        max,
        outliers,
    };
    assert!(bounds(0.1, 1.0, 7, 0).check(&d).is_ok());
    assert!(bounds(0.1, 1.0, 6, 1).check(&d).is_ok(), "one outlier allowed");
    let err = bounds(0.05, 0.0, 6, 0).check(&d).unwrap_err();
    assert!(
        err.contains("mean") && err.contains("p99") && err.contains("1 px above 6/255"),
        "{err}"
    );

    // Over a mask: only the masked pixels count, so a uniform error is not diluted by the rest.
    let mut mask = vec![false; 100];
    mask[3 + 4 * 10] = true;
    let masked = compare::diff_where(&b, &a, &mask);
    assert_eq!((masked.pixels, masked.mean, masked.max), (1, 7.0, 7.0));

    compare::write_failure_images("selftest-compare", &b, &a);
    let diff = image::open(compare::failure_dir().join("selftest-compare-diff.png")).expect("diff image written");
    assert_eq!(
        diff.to_rgba8().get_pixel(3, 4).0,
        [0, 70, 50, 255],
        "differences amplified ten times"
    );
}

/// Object pixels: where the reference showed the volume or either image is not the background. A steady error
/// on a small object is not diluted by the empty rest of the image.
#[test]
fn object_pixels_exclude_agreeing_background_only() {
    let volume = constant_volume();
    let mut s = head_on(&volume, 33);
    s.camera = Camera::looking_at(Vec3::new(0.0, 0.0, 6.0), Vec3::ZERO);
    let expected = Reference::new(&volume).render_full(&s);
    let objects = expected.object.iter().filter(|&&o| o).count();
    assert!(objects > 20 && objects < 33 * 33 / 2, "{objects} object pixels");
    let mut actual = expected.image.clone();
    for (i, p) in actual.pixels_mut().enumerate() {
        if expected.object[i] {
            p[1] = p[1].saturating_add(2);
        }
    }
    let d = compare::against_reference(&actual, &expected, s.background);
    assert_eq!(d.pixels as usize, objects);
    assert_near("a steady 2/255 error is 2/255 on the object", d.mean, 2.0, 1e-12);
    // A GPU image that draws where the reference shows nothing is compared there too.
    actual.put_pixel(0, 0, Rgba([255, 0, 0, 255]));
    let d = compare::against_reference(&actual, &expected, s.background);
    assert_eq!((d.pixels as usize, d.max), (objects + 1, 204.0), "255 − 51 in red");
}

/// A realistic size, to keep the reference fast enough for the GPU tests (printed, not asserted: timing is noisy).
#[test]
fn reference_speed_on_a_builtin_volume() {
    let size = 128;
    let volume = volcast::volume::builtin("helix", Some(size)).expect("builtin helix");
    let s = RenderSettings::new(128, 128, volume.extent());
    let start = std::time::Instant::now();
    let (image, stats) = Reference::new(&volume).render_with_stats(&s);
    eprintln!(
        "helix {size}³ at 128x128: {:.0} ms, {:.1} samples per pixel, {} of {} pixels hit",
        start.elapsed().as_secs_f64() * 1e3,
        stats.samples_per_pixel(),
        stats.hit_pixels,
        stats.pixels
    );
    assert!(stats.hit_pixels > 0);
    assert!(
        image.pixels().any(|p| p[0] != 0 || p[1] != 0 || p[2] != 0),
        "the helix is visible"
    );
}
