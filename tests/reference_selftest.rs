//! Proves the CPU reference itself against closed forms, so that a GPU test failing against it points at the GPU.
//!
//! Most cases use a 16³ volume of constant value on a unit cube, looked at head-on along -z through the centre
//! pixel of an odd-sized image: that ray crosses the box over exactly L = 1 = 16 voxels, so with step length `s`
//! it takes n = #{k : (k + 0.5)·s < 16} samples and, with opacity α per voxel, reaches A = 1 - (1 - α)^(n·s).

mod common;

use common::compare;
use common::reference::{quantise, ray_segment, render_reference, Reference};
use glam::{DVec3, Vec3};
use image::RgbaImage;
use volcast::camera::Camera;
use volcast::settings::RenderSettings;
use volcast::volume::{Volume, VoxelData, VoxelType};

const N: u32 = 16;
/// Odd, so that pixel (CENTRE, CENTRE) looks exactly along the view axis.
const SIZE: u32 = 9;
const CENTRE: u32 = SIZE / 2;
const BACKGROUND: Vec3 = Vec3::new(0.2, 0.4, 0.6);
const STEP_ALPHA: f32 = 0.2;

/// `1 - α` as the reference sees it (0.2 is not exact in f32).
fn keep() -> f64 {
    1.0 - f64::from(STEP_ALPHA)
}

/// A 16³ volume on the unit cube whose voxels are `value(x, y, z)`, normalised with the data range fixed at
/// [0, 2] (so raw 1 reads 0.5 whatever the data's own range is).
fn volume_from(value: impl Fn(u32, u32, u32) -> f32) -> Volume {
    let mut data = Vec::with_capacity((N * N * N) as usize);
    for z in 0..N {
        for y in 0..N {
            for x in 0..N {
                data.push(value(x, y, z));
            }
        }
    }
    let mut volume =
        Volume::new("selftest", [N; 3], [1.0; 3], VoxelType::F32, VoxelData::F32(data)).expect("a valid volume");
    volume.range = [0.0, 2.0];
    volume
}

fn constant_volume() -> Volume {
    volume_from(|_, _, _| 1.0)
}

/// Looking down -z at the unit cube from z = 3, window [0,1] (so the constant volume has c = 0.5), no early stop.
fn head_on(volume: &Volume, size: u32) -> RenderSettings {
    let mut s = RenderSettings::new(size, size, volume.extent());
    s.camera = Camera::looking_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);
    s.window = [0.0, 1.0];
    s.step_alpha = STEP_ALPHA;
    s.early_termination = 1.0;
    s.background = BACKGROUND;
    s
}

fn lut_rgb(s: &RenderSettings, c: f64) -> DVec3 {
    let lut = s.colormap.lut();
    let i = (c * 255.0).floor() as usize;
    let t = c * 255.0 - i as f64;
    let rgb = |e: [u8; 4]| DVec3::new(e[0].into(), e[1].into(), e[2].into()) / 255.0;
    rgb(lut[i]) * (1.0 - t) + rgb(lut[(i + 1).min(255)]) * t
}

fn expected_samples(distance_in_voxels: f64, step_length: f64) -> u32 {
    (0..)
        .take_while(|&k| (f64::from(k) + 0.5) * step_length < distance_in_voxels)
        .count() as u32
}

fn assert_near(what: &str, actual: f64, expected: f64, tolerance: f64) {
    assert!(
        (actual - expected).abs() <= tolerance,
        "{what}: {actual} but expected {expected} (± {tolerance})"
    );
}

fn assert_all_background(image: &RgbaImage, what: &str) {
    let bg = quantise(BACKGROUND.as_dvec3());
    for (x, y, p) in image.enumerate_pixels() {
        assert_eq!(*p, bg, "{what}: pixel ({x}, {y}) is not the background");
    }
}

#[test]
fn constant_volume_head_on_matches_closed_form() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let s = head_on(&volume, SIZE);
    let trace = reference.trace(&s, CENTRE, CENTRE);
    let segment = trace.segment.expect("the centre ray hits the box");
    assert_near("segment start", segment.t_start, 2.5, 1e-12);
    assert_near("segment end", segment.t_end, 3.5, 1e-12);
    assert_eq!((trace.samples, trace.composited), (16, 16));

    let alpha = 1.0 - keep().powi(16);
    assert_near("opacity", trace.alpha, alpha, 1e-12);
    // c = 0.5 sits halfway between table entries 127 and 128.
    let color = lut_rgb(&s, 0.5) * alpha;
    assert!(
        (trace.color - color).abs().max_element() < 1e-12,
        "{:?} vs {color:?}",
        trace.color
    );

    let image = render_reference(&volume, &s);
    let expected = quantise(color + (1.0 - alpha) * BACKGROUND.as_dvec3());
    assert_eq!(*image.get_pixel(CENTRE, CENTRE), expected);

    // Off-centre rays cross more or less of the box, but a constant volume keeps every pixel's hue: C = rgb·A.
    for y in 0..SIZE {
        for x in 0..SIZE {
            let t = reference.trace(&s, x, y);
            let closed = lut_rgb(&s, 0.5) * (1.0 - keep().powi(t.samples as i32));
            assert!((t.color - closed).abs().max_element() < 1e-12, "pixel ({x}, {y})");
        }
    }
}

#[test]
fn window_excluding_every_value_gives_the_background() {
    let volume = constant_volume();
    let mut s = head_on(&volume, SIZE);
    s.window = [0.6, 1.0];
    assert_all_background(&render_reference(&volume, &s), "window above the value");
    s.window = [0.0, 0.4];
    assert_all_background(&render_reference(&volume, &s), "window below the value");
    // A window whose edge is the value itself still includes it (the rule excludes only v < lo or v > hi).
    s.window = [0.5, 1.0];
    let trace = Reference::new(&volume).trace(&s, CENTRE, CENTRE);
    assert_eq!(trace.composited, 16);
    assert_near("opacity at c = 0", trace.alpha, 1.0 - keep().powi(16), 1e-12);
}

#[test]
fn slab_restricts_the_segment() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.set_slab(2, 0.25, 0.5);
    let trace = reference.trace(&s, CENTRE, CENTRE);
    let segment = trace.segment.expect("the slab still holds the centre ray");
    assert_near("segment start at the slab's top", segment.t_start, 3.0, 1e-12);
    assert_near("segment length", segment.length(), 0.5, 1e-12);
    assert_eq!(trace.samples, 8, "half the box, half the samples");
    assert_near("opacity", trace.alpha, 1.0 - keep().powi(8), 1e-12);

    // A slab beside the centre ray leaves it without a segment.
    let mut s = head_on(&volume, SIZE);
    s.set_slab(0, 0.9, 0.2);
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert!(trace.segment.is_none());
    assert_eq!(trace.samples, 0);
    assert_eq!(
        quantise(trace.output),
        quantise(BACKGROUND.as_dvec3()),
        "no segment shows the background"
    );
}

#[test]
fn camera_inside_the_box_starts_at_the_near_plane() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.camera = Camera::looking_at(Vec3::new(0.0, 0.0, 0.2), Vec3::new(0.0, 0.0, -1.0));
    s.camera.near = 0.01;
    let near = f64::from(s.camera.near);
    let eye = s.camera.eye.as_dvec3();
    let forward = DVec3::new(0.0, 0.0, -1.0);

    let trace = reference.trace(&s, CENTRE, CENTRE);
    let segment = trace.segment.expect("a ray from inside the box has a segment");
    assert_near("start", segment.t_start, near, 1e-7);
    assert_near("end", segment.t_end, f64::from(s.camera.eye.z) + 0.5, 1e-7);
    assert_eq!(trace.samples, expected_samples(segment.length() * 16.0, 1.0));

    let (image, stats) = reference.render_with_stats(&s);
    assert_eq!(
        stats.hit_pixels, stats.pixels,
        "every ray from inside the box has a segment"
    );
    let bg = quantise(BACKGROUND.as_dvec3());
    assert!(image.pixels().all(|p| *p != bg), "every pixel shows some volume");
    for (x, y) in [(0, 0), (SIZE - 1, 2), (3, SIZE - 1)] {
        let segment = reference.trace(&s, x, y).segment.expect("hit");
        let depth = (segment.at(segment.t_start) - eye).dot(forward);
        assert_near("view depth of an off-centre ray's start", depth, near, 1e-12);
    }
}

#[test]
fn opacity_correction_keeps_opacity_per_distance() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let at_one_voxel = 1.0 - keep().powi(16);
    for step_length in [0.25f32, 0.5, 0.7, 1.0, 1.3, 2.0, 4.0] {
        let mut s = head_on(&volume, SIZE);
        s.step_length = step_length;
        let trace = reference.trace(&s, CENTRE, CENTRE);
        let sl = f64::from(step_length);
        let n = expected_samples(16.0, sl);
        assert_eq!(trace.samples, n, "step length {step_length}");
        let closed = 1.0 - keep().powf(f64::from(n) * sl);
        assert_near(
            &format!("opacity at step length {step_length}"),
            trace.alpha,
            closed,
            1e-12,
        );
        // Only the rounding of 16 voxels to whole steps changes the opacity.
        assert_near(
            &format!("opacity drift at step length {step_length}"),
            trace.alpha,
            at_one_voxel,
            0.01,
        );
    }
}

#[test]
fn early_termination_caps_opacity() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.step_alpha = 0.5;
    for (threshold, samples) in [(0.9f32, 4), (0.99, 7), (0.5, 1), (1.0, 16)] {
        s.early_termination = threshold;
        let trace = reference.trace(&s, CENTRE, CENTRE);
        assert_eq!(trace.samples, samples, "termination at {threshold}");
        assert_near("opacity", trace.alpha, 1.0 - 0.5f64.powi(samples as i32), 1e-12);
        assert_eq!(trace.terminated_early, threshold < 1.0);
        assert!((trace.color - lut_rgb(&s, 0.5) * trace.alpha).abs().max_element() < 1e-12);
    }
}

#[test]
fn multiplied_alpha_scales_opacity_by_the_windowed_value() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.multiplied_alpha = true;
    s.window = [0.25, 1.0];
    let c = (0.5 - 0.25) / 0.75;
    let trace = reference.trace(&s, CENTRE, CENTRE);
    let alpha = 1.0 - (1.0 - c * f64::from(STEP_ALPHA)).powi(16);
    assert_near("opacity", trace.alpha, alpha, 1e-12);
    assert!((trace.color - lut_rgb(&s, c) * alpha).abs().max_element() < 1e-12);
}

#[test]
fn nan_samples_are_transparent() {
    // The far half (z texels 0..8) is NaN: the 8 samples in the near half see only finite texels (texel 8 is the
    // lowest they touch), the other 8 each touch a NaN texel with non-zero weight.
    let volume = volume_from(|_, _, z| if z < N / 2 { f32::NAN } else { 1.0 });
    let trace = Reference::new(&volume).trace(&head_on(&volume, SIZE), CENTRE, CENTRE);
    assert_eq!((trace.samples, trace.composited), (16, 8));
    assert_near("opacity", trace.alpha, 1.0 - keep().powi(8), 1e-12);
}

#[test]
fn trilinear_interpolates_between_texel_centres_and_clamps_at_edges() {
    let volume = volume_from(|x, _, _| x as f32 / 8.0); // normalised: x / 16
    let reference = Reference::new(&volume);
    let tex = |x: f64| DVec3::new(x, 0.3, 0.7);
    assert_near("texel centre", reference.sample(tex(3.5 / 16.0)), 3.0 / 16.0, 1e-15);
    assert_near("between centres", reference.sample(tex(4.0 / 16.0)), 3.5 / 16.0, 1e-15);
    assert_near("clamped below", reference.sample(tex(0.0)), 0.0, 1e-15);
    assert_near("clamped above", reference.sample(tex(1.0)), 15.0 / 16.0, 1e-15);
}

/// Screen orientation: row 0 is the top (+z seen from +y) and screen right is world -x (from `Camera`'s docs).
#[test]
fn image_orientation_follows_the_camera() {
    // Value 1 (v = 0.5) only where x < 0 and z > 0; the window [0.25, 1] keeps samples with v ≥ 0.25, which
    // trilinear blending across the planes x = 0 and z = 0 reaches only up to those planes themselves.
    let volume = volume_from(|x, _, z| if x < N / 2 && z >= N / 2 { 1.0 } else { 0.0 });
    let mut s = RenderSettings::new(33, 33, volume.extent());
    s.camera = Camera::orbit(0.0, 0.0, 3.0, Vec3::ZERO);
    s.window = [0.25, 1.0];
    s.background = BACKGROUND;
    let image = render_reference(&volume, &s);
    let bg = quantise(BACKGROUND.as_dvec3());
    let mut top_right = 0;
    for (x, y, p) in image.enumerate_pixels() {
        if *p == bg {
            continue;
        }
        assert!(
            x >= 16 && y <= 16,
            "volume seen at pixel ({x}, {y}), outside the top-right quadrant"
        );
        top_right += 1;
    }
    assert!(top_right > 50, "only {top_right} pixels show the volume");
}

/// The silhouette of the box's front face, projected with `Camera`'s own matrices (the GPU's convention), matches
/// the reference's rays, also for a wide image.
#[test]
fn silhouette_matches_the_camera_projection() {
    let volume = constant_volume();
    let (width, height) = (64u32, 32u32);
    let mut s = head_on(&volume, SIZE);
    (s.width, s.height) = (width, height);
    s.step_alpha = 0.5;
    let image = render_reference(&volume, &s);

    let clip_from_world = s.camera.projection(width as f32 / height as f32) * s.camera.view();
    let to_pixel = |p: Vec3| {
        let ndc = clip_from_world.project_point3(p);
        ((ndc.x + 1.0) * 0.5 * width as f32, (ndc.y + 1.0) * 0.5 * height as f32)
    };
    let (x0, y0) = to_pixel(Vec3::new(-0.5, -0.5, 0.5));
    let (x1, y1) = to_pixel(Vec3::new(0.5, 0.5, 0.5));
    let (xs, ys) = ((x0.min(x1), x0.max(x1)), (y0.min(y1), y0.max(y1)));
    // Centres are ≥ 0.05 px from the projected edge here, so the reading is unambiguous.
    let bg = quantise(BACKGROUND.as_dvec3());
    for (x, y, p) in image.enumerate_pixels() {
        let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
        let inside = cx > xs.0 && cx < xs.1 && cy > ys.0 && cy < ys.1;
        assert!(
            (cx - xs.0).abs().min((cx - xs.1).abs()) > 0.05 && (cy - ys.0).abs().min((cy - ys.1).abs()) > 0.05,
            "the test geometry puts a pixel centre on the silhouette"
        );
        assert_eq!(*p != bg, inside, "pixel ({x}, {y}); projected face x {xs:?} y {ys:?}");
    }
    // Square pixels: the square face covers as many columns as rows.
    assert!(((xs.1 - xs.0) - (ys.1 - ys.0)).abs() < 1e-3);
}

#[test]
fn ray_segment_handles_misses_parallel_rays_and_a_start_inside() {
    let (lo, hi) = (DVec3::splat(-0.5), DVec3::splat(0.5));
    let down = DVec3::new(0.0, 0.0, -1.0);
    assert_eq!(
        ray_segment(DVec3::new(0.0, 0.0, 3.0), down, lo, hi, 0.0),
        Some((2.5, 3.5))
    );
    assert_eq!(ray_segment(DVec3::new(0.7, 0.0, 3.0), down, lo, hi, 0.0), None);
    assert_eq!(
        ray_segment(DVec3::new(0.0, 0.0, 3.0), -down, lo, hi, 0.0),
        None,
        "box behind the eye"
    );
    let (t0, t1) = ray_segment(DVec3::new(0.0, 0.0, 0.2), down, lo, hi, 0.01).expect("starting inside");
    assert_near("start inside the box at t_min", t0, 0.01, 1e-15);
    assert_near("exit", t1, 0.7, 1e-15);
    // Along a face: the boundary counts as inside, as in the slab test's closed interval.
    assert_eq!(
        ray_segment(DVec3::new(0.5, 0.0, 3.0), down, lo, hi, 0.0),
        Some((2.5, 3.5))
    );
}

#[test]
fn compare_reports_mean_percentile_and_max() {
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
    compare::assert_close("selftest-compare", &b, &a, 0.1, 1.0);
    compare::write_failure_images("selftest-compare", &b, &a);
    let diff = image::open(compare::failure_dir().join("selftest-compare-diff.png")).expect("diff image written");
    assert_eq!(
        diff.to_rgba8().get_pixel(3, 4).0,
        [0, 70, 50, 255],
        "differences amplified ten times"
    );
}

#[test]
#[should_panic(expected = "differs from the reference")]
fn compare_fails_over_the_percentile_bound() {
    let a = RgbaImage::from_pixel(10, 10, image::Rgba([10, 20, 30, 255]));
    let mut b = a.clone();
    // Two of 100 pixels off by 7: the 99th percentile is 7.
    b.put_pixel(3, 4, image::Rgba([10, 27, 25, 255]));
    b.put_pixel(5, 6, image::Rgba([10, 27, 25, 255]));
    compare::assert_close("selftest-compare-fails", &b, &a, 1.0, 6.0);
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
