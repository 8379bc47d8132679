//! Rule 12's spaced rays in the reference: the marched size, and the stretch's taps and values worked by hand.

use crate::common;

use common::stretch::{marched, stretch, taps};
use image::{Rgba, RgbaImage};
use volcast::scene::settings::RenderSettings;

#[test]
fn the_marched_size_rounds_up_and_a_sample_count_is_never_spaced() {
    let mut s = RenderSettings::new(77, 53, glam::Vec3::ONE);
    assert_eq!(marched(&s), (77, 53));
    s.sampling.ray_spacing = 2;
    assert_eq!(marched(&s), (39, 27));
    s.sampling.ray_spacing = 4;
    assert_eq!(marched(&s), (20, 14));
    s.pipeline.count_samples = true;
    assert_eq!(marched(&s), (77, 53));
}

#[test]
fn the_stretch_reads_pixel_centres_and_repeats_the_edge() {
    // Output 4 from 2: centres 0.5, 1.5, 2.5, 3.5 land at −0.25, 0.25, 0.75, 1.25 between the source's centres.
    assert_eq!(taps(0, 4, 2), (0, 0, 0.75));
    assert_eq!(taps(1, 4, 2), (0, 1, 0.25));
    assert_eq!(taps(2, 4, 2), (0, 1, 0.75));
    assert_eq!(taps(3, 4, 2), (1, 1, 0.25));
    let small = RgbaImage::from_fn(2, 1, |x, _| Rgba([if x == 0 { 0 } else { 200 }, 10, 255, 255]));
    let wide = stretch(&small, 4, 1);
    let reds: Vec<u8> = wide.pixels().map(|p| p[0]).collect();
    assert_eq!(reds, [0, 50, 150, 200]);
    assert!(wide.pixels().all(|p| p[1] == 10 && p[2] == 255 && p[3] == 255));
    // Not a whole multiple: 3 from 2 puts the middle pixel halfway.
    assert_eq!(stretch(&small, 3, 1).get_pixel(1, 0)[0], 100);
}
