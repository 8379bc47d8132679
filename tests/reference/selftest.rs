//! Proves the CPU reference itself against closed forms, so that a GPU test failing against it points at the GPU.
//!
//! Most cases use a 16³ volume on a unit cube, looked at head-on along -z through the centre pixel of an odd-sized
//! image: that ray crosses the box over exactly L = 1 = 16 voxels, so with step length `s` it takes
//! n = #{k : (k + o)·s < 16} samples (o = 0.5 without jitter). Emission and density composite the n + 1 segments
//! between the ray's start, its samples and its end (rule 6, pre-integrated), so with opacity α per voxel a
//! constant volume reaches A = 1 - (1 - α)^16 at every step length. Colours are composited in linear light and
//! encoded to sRGB once (rule 8).

use common::classify::{encode, jitter_offset, linear_to_srgb, srgb_to_linear};
use common::compare::{self, Bounds};
use common::rays::{pixel_ray, ray_segment};
use common::reference::{quantise, render_reference, Reference};
use glam::{DVec3, Vec3};
use image::{Rgba, RgbaImage};
use volcast::scene::camera::Camera;
use volcast::scene::settings::{CompositeMode, RenderSettings, Shading};
use volcast::transfer::function::{TfUnits, TransferFunction};
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

/// A volume of `dims` voxels with `spacing` whose voxels are `value(x, y, z)`, normalised with the data range fixed
/// at `range`.
fn volume_with(dims: [u32; 3], spacing: [f32; 3], range: [f64; 2], value: impl Fn(u32, u32, u32) -> f32) -> Volume {
    let mut data = Vec::with_capacity((dims[0] * dims[1] * dims[2]) as usize);
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                data.push(value(x, y, z));
            }
        }
    }
    let mut volume =
        Volume::new("selftest", dims, spacing, VoxelType::F32, VoxelData::F32(data)).expect("a valid volume");
    volume.range = range;
    volume
}

/// A 16³ volume on the unit cube whose voxels are `value(x, y, z)`, normalised with the data range fixed at
/// [0, 2] (so raw 1 reads 0.5 whatever the data's own range is).
fn volume_from(value: impl Fn(u32, u32, u32) -> f32) -> Volume {
    volume_with([N; 3], [1.0; 3], [0.0, 2.0], value)
}

fn constant_volume() -> Volume {
    volume_from(|_, _, _| 1.0)
}

/// A 16³ unit cube whose normalised value is z/16 at texel z: along z, v(tex) = tex − 1/32, clamped to [0, 15/16].
fn z_ramp() -> Volume {
    volume_with([N; 3], [1.0; 3], [0.0, 16.0], |_, _, z| z as f32)
}

/// Looking down -z at the unit cube from z = 3, window [0,1] (so the constant volume has v = 0.5), no early stop,
/// samples at the step midpoints.
fn head_on(volume: &Volume, size: u32) -> RenderSettings {
    let mut s = RenderSettings::new(size, size, volume.extent());
    s.camera = Camera::looking_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);
    s.window = [0.0, 1.0];
    s.step_alpha = STEP_ALPHA;
    s.early_termination = 1.0;
    s.background = BACKGROUND;
    s.jitter = None;
    s
}

/// A transfer function (normalised units) with colour `srgb` and opacity `alpha` everywhere.
fn constant_tf(srgb: [f32; 3], alpha: f32) -> TransferFunction {
    TransferFunction {
        name: "constant".into(),
        units: TfUnits::Normalized,
        colors: vec![[0.0, srgb[0], srgb[1], srgb[2]], [1.0, srgb[0], srgb[1], srgb[2]]],
        colormap: Default::default(),
        opacity: vec![[0.0, alpha], [1.0, alpha]],
    }
}

/// Grey level = v (sRGB), opacity `alpha`.
fn grey_ramp_tf(alpha: f32) -> TransferFunction {
    TransferFunction {
        colors: vec![[0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 1.0]],
        ..constant_tf([0.0; 3], alpha)
    }
}

fn linear(c: Vec3) -> DVec3 {
    let c = c.as_dvec3();
    DVec3::new(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z))
}

/// The pixel a miss shows: the background, decoded for compositing and encoded again.
fn background_pixel() -> Rgba<u8> {
    quantise(encode(linear(BACKGROUND)))
}

/// The reference's classification colour at `v` (linear light), for the tests of compositing.
fn table_rgb(volume: &Volume, s: &RenderSettings, v: f64) -> DVec3 {
    Reference::new(volume).classifier(s).rgb(v)
}

fn expected_samples(distance_in_voxels: f64, step_length: f64) -> u32 {
    expected_samples_at(distance_in_voxels, step_length, 0.5)
}

fn expected_samples_at(distance_in_voxels: f64, step_length: f64, offset: f64) -> u32 {
    (0..)
        .take_while(|&k| (f64::from(k) + offset) * step_length < distance_in_voxels)
        .count() as u32
}

/// Rule 6's segment lengths (in steps' units of voxels) of a ray `distance` voxels long at step length `step` with
/// start offset `offset`: from the start to the first sample, between samples, from the last sample to the end.
fn segment_lengths(distance: f64, step: f64, offset: f64) -> Vec<f64> {
    let samples = expected_samples_at(distance, step, offset);
    let mut points = vec![0.0];
    points.extend((0..samples).map(|k| (f64::from(k) + offset) * step));
    points.push(distance);
    points.windows(2).map(|w| w[1] - w[0]).collect()
}

fn assert_near(what: &str, actual: f64, expected: f64, tolerance: f64) {
    assert!(
        (actual - expected).abs() <= tolerance,
        "{what}: {actual} but expected {expected} (± {tolerance})"
    );
}

fn assert_near3(what: &str, actual: DVec3, expected: DVec3, tolerance: f64) {
    assert!(
        (actual - expected).abs().max_element() <= tolerance,
        "{what}: {actual} but expected {expected} (± {tolerance})"
    );
}

fn assert_all_background(image: &RgbaImage, what: &str) {
    let bg = background_pixel();
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
    assert_eq!((trace.samples, trace.composited), (16, 17), "16 samples, 17 segments");

    let alpha = 1.0 - keep().powi(16);
    assert_near("opacity", trace.alpha, alpha, 1e-12);
    // v = 0.5 sits halfway between table entries 2047 and 2048.
    let color = table_rgb(&volume, &s, 0.5) * alpha;
    assert_near3("colour", trace.color, color, 1e-7);

    // Rule 8: over the background in linear light, encoded to sRGB once.
    let image = render_reference(&volume, &s);
    let linear_out = color + (1.0 - alpha) * linear(BACKGROUND);
    assert_near3("linear output", trace.linear, linear_out, 1e-7);
    let srgb = |c: f64| linear_to_srgb(c);
    let expected = quantise(DVec3::new(srgb(linear_out.x), srgb(linear_out.y), srgb(linear_out.z)));
    assert_eq!(*image.get_pixel(CENTRE, CENTRE), expected);

    // Off-centre rays cross more or less of the box, but a constant volume keeps every pixel's hue: C = rgb·A,
    // with A from the ray's length through the box (16 voxels per unit).
    let (tracer, rgb) = (reference.tracer(&s), table_rgb(&volume, &s, 0.5));
    for y in 0..SIZE {
        for x in 0..SIZE {
            let t = tracer.trace(x, y);
            let length = t.segment.map_or(0.0, |seg| seg.length()) * 16.0;
            let closed = rgb * (1.0 - keep().powf(length));
            assert_near3(&format!("pixel ({x}, {y})"), t.color, closed, 1e-7);
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
    // A window whose edge is the value itself still includes it, at full opacity (the rule excludes only v < lo
    // or v > hi).
    s.window = [0.5, 1.0];
    let trace = Reference::new(&volume).trace(&s, CENTRE, CENTRE);
    assert_eq!(trace.composited, 17);
    let a = f64::from(STEP_ALPHA);
    assert_near(
        "opacity at the window's edge",
        trace.alpha,
        1.0 - (1.0 - a).powi(16),
        1e-12,
    );
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
        background_pixel(),
        "no segment shows the background"
    );
    assert_eq!(
        background_pixel(),
        Rgba([51, 102, 153, 255]),
        "sRGB → linear → sRGB keeps the bytes"
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
    let bg = background_pixel();
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
        // The segments cover the whole ray, whatever the step: the opacity of 16 voxels exactly.
        assert_near(
            &format!("opacity at step length {step_length}"),
            trace.alpha,
            at_one_voxel,
            1e-12,
        );
    }
}

#[test]
fn early_termination_caps_opacity() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.step_alpha = 0.5;
    // After sample j (from 1) the ray has crossed j − 0.5 voxels; without termination all 16.
    for (threshold, samples, depth) in [(0.9f32, 4, 3.5), (0.99, 8, 7.5), (0.5, 2, 1.5), (1.0, 16, 16.0)] {
        s.early_termination = threshold;
        let trace = reference.trace(&s, CENTRE, CENTRE);
        assert_eq!(trace.samples, samples, "termination at {threshold}");
        assert_near("opacity", trace.alpha, 1.0 - 0.5f64.powf(depth), 1e-12);
        assert_eq!(trace.terminated_early, threshold < 1.0);
        assert_near3("colour", trace.color, table_rgb(&volume, &s, 0.5) * trace.alpha, 1e-7);
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
    // The table is linear in c between neighbouring entries, so the lookup gives c × step alpha up to f32 rounding.
    let alpha = 1.0 - (1.0 - c * f64::from(STEP_ALPHA)).powi(16);
    assert_near("opacity", trace.alpha, alpha, 1e-6);
    assert_near3("colour", trace.color, table_rgb(&volume, &s, 0.5) * trace.alpha, 1e-7);
}

#[test]
fn nan_samples_are_transparent() {
    // The far half (z texels 0..8) is NaN: the 8 samples in the near half see only finite texels (texel 8 is the
    // lowest they touch), the other 8 and the ray's end each touch a NaN texel with non-zero weight. The segments
    // from the start to the 8th sample (7.5 voxels) count; every segment with a NaN end adds nothing.
    let volume = volume_from(|_, _, z| if z < N / 2 { f32::NAN } else { 1.0 });
    let trace = Reference::new(&volume).trace(&head_on(&volume, SIZE), CENTRE, CENTRE);
    assert_eq!((trace.samples, trace.composited), (16, 8));
    assert_near("opacity", trace.alpha, 1.0 - keep().powf(7.5), 1e-12);
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
    let bg = background_pixel();
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
    let bg = background_pixel();
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

/// Rule 8: compositing happens in linear light and is encoded once, so 50% white over black is sRGB 188, not 128.
#[test]
fn half_white_over_black_is_srgb_188() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.transfer_function = Some(constant_tf([1.0; 3], 0.5));
    s.background = Vec3::ZERO;
    // One voxel of the box along the ray: one sample, whose opacity is the table's 0.5.
    s.set_slab(2, 0.5, 1.0 / 16.0);
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_eq!(trace.samples, 1);
    assert_near("opacity", trace.alpha, 0.5, 1e-12);
    assert_near3("linear output", trace.linear, DVec3::splat(0.5), 1e-12);
    assert_eq!(quantise(trace.output), Rgba([188, 188, 188, 255]));
    assert_eq!(
        *render_reference(&volume, &s).get_pixel(CENTRE, CENTRE),
        Rgba([188, 188, 188, 255])
    );

    // And 50% black over a white background: also half the light, also 188.
    s.transfer_function = Some(constant_tf([0.0; 3], 0.5));
    s.background = Vec3::ONE;
    assert_eq!(
        quantise(reference.trace(&s, CENTRE, CENTRE).output),
        Rgba([188, 188, 188, 255])
    );
}

/// Rule 1, orthographic: rays parallel to the view direction from the plane through the eye, the view as high as
/// the perspective view is at the target's distance.
#[test]
fn orthographic_rays_are_parallel_and_framed_like_perspective_at_the_target() {
    let volume = constant_volume();
    let (width, height) = (15u32, 9u32);
    let mut persp = head_on(&volume, SIZE);
    (persp.width, persp.height) = (width, height);
    persp.camera = Camera::orbit(30.0, 20.0, 3.0, Vec3::new(0.1, 0.0, -0.05));
    persp.camera.fov_y_deg = 40.0;
    let mut ortho = persp.clone();
    ortho.camera.ortho = true;

    let eye = ortho.camera.eye.as_dvec3();
    let target = ortho.camera.target.as_dvec3();
    let d = (target - eye).length();
    let forward = (target - eye) / d;
    let origins: Vec<Vec<DVec3>> = (0..height)
        .map(|y| {
            (0..width)
                .map(|x| {
                    let (origin, dir) = pixel_ray(&ortho, x, y);
                    assert_near3("direction is the view direction", dir, forward, 1e-12);
                    assert_near(
                        "origin on the plane through the eye",
                        (origin - eye).dot(forward),
                        0.0,
                        1e-12,
                    );
                    // Where the perspective ray of the same pixel crosses the target's plane.
                    let (p_origin, p_dir) = pixel_ray(&persp, x, y);
                    let at_target = p_origin + p_dir * (d / p_dir.dot(forward));
                    assert_near3(
                        &format!("pixel ({x}, {y}) at the target"),
                        origin + forward * d,
                        at_target,
                        1e-9,
                    );
                    origin
                })
                .collect()
        })
        .collect();
    // The view is 2·d·tan(fov/2) high and aspect times as wide: pixel centres are that over the size apart.
    let view_h = 2.0 * d * (40f64.to_radians() / 2.0).tan();
    let view_w = view_h * f64::from(width) / f64::from(height);
    let rows = (origins[height as usize - 1][0] - origins[0][0]).length();
    let cols = (origins[0][width as usize - 1] - origins[0][0]).length();
    assert_near(
        "rows span",
        rows,
        view_h * f64::from(height - 1) / f64::from(height),
        1e-9,
    );
    assert_near(
        "columns span",
        cols,
        view_w * f64::from(width - 1) / f64::from(width),
        1e-9,
    );

    // Head-on, every ray inside the front face crosses the whole unit depth: 16 samples each, the same colour, and
    // the silhouette is the face itself, at any distance.
    let reference = Reference::new(&volume);
    for distance in [3.0f32, 7.0] {
        let mut s = head_on(&volume, SIZE);
        s.camera = Camera::looking_at(Vec3::new(0.0, 0.0, distance), Vec3::ZERO);
        s.camera.ortho = true;
        let half_h = f64::from(distance) * 15f64.to_radians().tan();
        let tracer = reference.tracer(&s);
        let centre_trace = tracer.trace(CENTRE, CENTRE);
        for y in 0..SIZE {
            for x in 0..SIZE {
                let world = |i: u32| ((f64::from(i) + 0.5) / f64::from(SIZE) * 2.0 - 1.0) * half_h;
                let inside = world(x).abs() < 0.5 && world(y).abs() < 0.5;
                let trace = tracer.trace(x, y);
                assert_eq!(
                    trace.segment.is_some(),
                    inside,
                    "pixel ({x}, {y}) at distance {distance}"
                );
                if inside {
                    assert_eq!(trace.samples, 16);
                    assert_eq!(trace.output, centre_trace.output);
                }
            }
        }
    }

    // From inside the box every ray starts at the near plane: view depth `near` = distance `near` along it.
    let mut s = head_on(&volume, SIZE);
    s.camera = Camera::looking_at(Vec3::new(0.0, 0.0, 0.2), Vec3::new(0.0, 0.0, -1.0));
    s.camera.ortho = true;
    s.camera.near = 0.05;
    let eye = s.camera.eye.as_dvec3();
    let tracer = reference.tracer(&s);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let segment = tracer.trace(x, y).segment.expect("every ray starts inside the box");
            let depth = (segment.at(segment.t_start) - eye).dot(DVec3::new(0.0, 0.0, -1.0));
            assert_near("view depth of the start", depth, 0.05, 1e-7);
            assert_near("end", segment.at(segment.t_end).z, -0.5, 1e-12);
        }
    }
}

/// The values the centre ray samples on [`z_ramp`] looking down -z: tex_z = 1 − (k + o)/16.
fn ramp_samples(offset: f64) -> Vec<f64> {
    (0..16)
        .map(|k| f64::from(k) + offset)
        .take_while(|&u| u < 16.0)
        .map(|u| (31.0 / 32.0 - u / 16.0).clamp(0.0, 15.0 / 16.0))
        .collect()
}

/// Rule 7 for MIP, MinIP and average: the colour at the max/min/mean of the visible samples, A = 1; with and
/// without jitter, whose offset moves every sample.
#[test]
fn mip_minip_and_average_on_a_linear_ramp() {
    let volume = z_ramp();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.transfer_function = Some(grey_ramp_tf(0.3));
    let mut offsets = Vec::new();
    for jitter in [None, Some(0), Some(1), Some(7), Some(12345), Some(u32::MAX)] {
        s.jitter = jitter;
        let offset = jitter.map_or(0.5, |seed| jitter_offset(CENTRE, CENTRE, seed));
        offsets.push(offset);
        for window in [[0.0f32, 1.0], [0.2, 0.8], [0.25, 0.75], [0.3, 0.31]] {
            s.window = window;
            let [lo, hi] = window.map(f64::from);
            let visible: Vec<f64> = ramp_samples(offset)
                .into_iter()
                .filter(|v| (lo..=hi).contains(v))
                .collect();
            for mode in [CompositeMode::Mip, CompositeMode::MinIp, CompositeMode::Average] {
                s.mode = mode;
                let what = format!("{mode:?}, jitter {jitter:?}, window {window:?}");
                let trace = reference.trace(&s, CENTRE, CENTRE);
                assert_eq!(trace.offset, offset, "{what}");
                assert_eq!(trace.composited as usize, visible.len(), "{what}");
                if visible.is_empty() {
                    assert_eq!(trace.value, None, "{what}");
                    assert_eq!(quantise(trace.output), background_pixel(), "{what}");
                    continue;
                }
                let m = match mode {
                    CompositeMode::Mip => visible.iter().copied().fold(f64::MIN, f64::max),
                    CompositeMode::MinIp => visible.iter().copied().fold(f64::MAX, f64::min),
                    _ => visible.iter().sum::<f64>() / visible.len() as f64,
                };
                assert_near(&what, trace.value.expect("a visible sample"), m, 1e-12);
                assert_near(&format!("{what}: opacity"), trace.alpha, 1.0, 0.0);
                // Grey level v in sRGB, exactly (the reference classifies by the definition, not a table).
                let expected = srgb_to_linear(m);
                assert_near3(&format!("{what}: colour"), trace.color, DVec3::splat(expected), 1e-12);
                let srgb = linear_to_srgb(expected);
                assert_near3(&format!("{what}: output"), trace.output, DVec3::splat(srgb), 1e-6);
            }
        }
    }
    // Without jitter: v_k = (15 − k)/16, so MIP 15/16, MinIP 0, mean 7.5/16.
    s.jitter = None;
    s.window = [0.0, 1.0];
    for (mode, m) in [
        (CompositeMode::Mip, 15.0 / 16.0),
        (CompositeMode::MinIp, 0.0),
        (CompositeMode::Average, 7.5 / 16.0),
    ] {
        s.mode = mode;
        assert_near(
            &format!("{mode:?}"),
            reference.trace(&s, CENTRE, CENTRE).value.unwrap(),
            m,
            1e-15,
        );
    }
    offsets.sort_by(f64::total_cmp);
    offsets.dedup();
    assert_eq!(offsets.len(), 6, "every seed moves the samples: {offsets:?}");
    // NaN samples are never visible.
    let nan = volume_from(|_, _, _| f32::NAN);
    s.mode = CompositeMode::Mip;
    assert_all_background(&render_reference(&nan, &s), "MIP of NaN");
}

/// Rule 2 with jitter: offsets are the hash of pixel and seed, and averaged over seeds the jittered ray's optical
/// depth is the continuous integral, which the midpoint samples miss when the steps don't fit the ray.
#[test]
fn jittered_mean_converges_to_the_integral() {
    // Normalised value along the centre ray, t in voxels from the entry: 0 until 0.5, (t − 0.5)/16 until 15.5,
    // then 15/16; opacity 0.3·v, so the extinction per voxel is −ln(1 − 0.3·v).
    let volume = volume_with([N; 3], [1.0; 3], [0.0, 16.0], |_, _, z| (15 - z) as f32);
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, 1);
    s.transfer_function = Some(TransferFunction {
        opacity: vec![[0.0, 0.0], [1.0, 0.3]],
        ..constant_tf([1.0; 3], 0.0)
    });
    s.step_length = 1.3;
    let u_end: f64 = 0.3 * 15.0 / 16.0;
    let integral = 16.0 / 0.3 * ((1.0 - u_end) * (1.0 - u_end).ln() + u_end) - 0.5 * (1.0 - u_end).ln();

    let depth = |s: &RenderSettings| -(1.0 - reference.trace(s, 0, 0).alpha).ln();
    // Pre-integrated segments cover the whole ray and follow a linear ramp exactly: midpoint samples already
    // give the integral (up to the two segments holding the ramp's kinks).
    let midpoint = depth(&s);
    assert_near("midpoint optical depth", midpoint, integral, 0.015);
    let seeds = 1024;
    let (mut sum, mut offset_sum) = (0.0, 0.0);
    for seed in 0..seeds {
        s.jitter = Some(seed);
        let trace = reference.trace(&s, 0, 0);
        let o = jitter_offset(0, 0, seed);
        assert_eq!(trace.offset, o);
        assert!((0.0..1.0).contains(&o));
        assert_eq!(trace.samples, expected_samples_at(16.0, 1.3, o), "seed {seed}");
        offset_sum += o;
        sum += -(1.0 - trace.alpha).ln();
    }
    let mean = sum / f64::from(seeds);
    assert_near("mean offset", offset_sum / f64::from(seeds), 0.5, 0.03);
    assert_near("mean jittered optical depth", mean, integral, 0.015);
}

/// Rule 7's isosurface on a linear ramp along the ray: the hit is the analytic crossing within step/512 (8
/// bisections of one step, then the midpoint); the first sample at or above the iso value hits at itself; the
/// window is ignored for the search; the colour is the classification's at the iso value clamped into the window,
/// shaded with the default lighting.
#[test]
fn isosurface_hits_the_analytic_crossing() {
    // Looking up +z at z_ramp: t world units into the box, tex_z = t, v = t − 1/32.
    let volume = z_ramp();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.camera = Camera::looking_at(Vec3::new(0.0, 0.0, -3.0), Vec3::ZERO);
    s.mode = CompositeMode::Isosurface;
    s.transfer_function = Some(grey_ramp_tf(0.3));
    // The surface coloured by the classification (the default is a light neutral, below).
    s.iso_color = None;
    for step_length in [0.5f32, 1.0, 1.7, 3.0] {
        for jitter in [None, Some(3), Some(99)] {
            for iso in [0.1f32, 0.37, 0.5, 0.8] {
                for window in [[0.0f32, 1.0], [0.95, 1.0]] {
                    (s.step_length, s.jitter, s.iso_value, s.window) = (step_length, jitter, iso, window);
                    let what = format!("iso {iso}, step {step_length}, jitter {jitter:?}, window {window:?}");
                    let h = f64::from(step_length) / 16.0;
                    let trace = reference.trace(&s, CENTRE, CENTRE);
                    let crossing = 2.5 + f64::from(iso) + 1.0 / 32.0;
                    let hit = trace.hit.unwrap_or_else(|| panic!("{what}: no hit"));
                    assert_near(&what, hit, crossing, h / 512.0 + 1e-12);
                    assert_eq!(trace.alpha, 1.0);
                    // The colour of the iso value clamped into the window: this transfer function's grey is the
                    // value itself, so 0.95 for every iso value below the window [0.95, 1]. Gradient
                    // (0, 0, 1/16) per voxel = (0, 0, 1) per world unit, facing the eye: |n·L| = 1, and the
                    // specular highlight is white.
                    let grey = f64::from(iso.clamp(window[0], window[1]));
                    let lit = srgb_to_linear(grey) * (0.2 + 0.7) + 0.3;
                    assert_near3(&format!("{what}: colour"), trace.color, DVec3::splat(lit), 1e-6);
                }
            }
        }
    }
    // The default material: a light neutral, whatever the classification says.
    s.iso_color = Some(volcast::scene::lighting::NEUTRAL);
    s.iso_value = 0.37;
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_near3(
        "neutral",
        trace.color,
        linear(volcast::scene::lighting::NEUTRAL) * 0.9 + DVec3::splat(0.3),
        1e-6,
    );
    // The first sample already at or above the value: the hit is that sample, exactly.
    s.iso_value = 0.0;
    for jitter in [None, Some(5)] {
        s.jitter = jitter;
        let trace = reference.trace(&s, CENTRE, CENTRE);
        assert_eq!(trace.samples, 1);
        assert_near(
            "first sample",
            trace.hit.unwrap(),
            2.5 + trace.offset * f64::from(s.step_length) / 16.0,
            1e-12,
        );
    }
    // Above every value, or NaN everywhere: no hit, the background.
    (s.iso_value, s.step_length, s.jitter) = (0.95, 1.0, None);
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_eq!((trace.hit, trace.samples), (None, 16));
    assert_all_background(&render_reference(&volume, &s), "iso above the data");
    s.iso_value = 0.0;
    assert_all_background(&render_reference(&volume_from(|_, _, _| f32::NAN), &s), "iso in NaN");
}

/// A planar ramp on a box with anisotropic voxels (1/32 × 1/32 × 1/16 world units): raw 2x + y + 3z over the range
/// [0, 120], so the gradient is (2, 1, 3)/120 per voxel everywhere trilinear filtering is not clamped.
fn planar_ramp() -> Volume {
    volume_with([N; 3], [1.0, 1.0, 2.0], [0.0, 120.0], |x, y, z| {
        (2 * x + y + 3 * z) as f32
    })
}

/// Looking along `-axis_dir` at the box through the centre pixel, the segment kept where the gradient's stencil
/// stays clear of the clamped edges.
fn planar_view(volume: &Volume, eye: Vec3) -> RenderSettings {
    let mut s = head_on(volume, SIZE);
    s.camera = Camera::looking_at(eye, Vec3::ZERO);
    s.transfer_function = Some(constant_tf([0.8, 0.5, 0.3], STEP_ALPHA));
    for axis in 0..3 {
        s.set_slab(axis, 0.5, 0.75);
    }
    s
}

/// Rule 5's lighting on a planar ramp, whose gradient is known exactly: C = lit·A with
/// lit = rgb·(ambient + diffuse·|cos θ|) + specular·|cos θ|^shininess, θ between the world gradient and the view.
#[test]
fn shading_on_a_planar_ramp() {
    let volume = planar_ramp();
    let reference = Reference::new(&volume);
    assert_near3(
        "voxel size",
        reference.placement(&RenderSettings::default()).voxel_sides(),
        DVec3::new(1.0 / 32.0, 1.0 / 32.0, 1.0 / 16.0),
        1e-9,
    );
    let shading = Shading {
        ambient: 0.1,
        diffuse: 0.6,
        specular: 0.4,
        shininess: 8.0,
    };
    let world_gradient = DVec3::new(2.0 * 32.0, 32.0, 3.0 * 16.0) / 120.0;
    let rgb = linear(Vec3::new(0.8, 0.5, 0.3));
    for (eye, view) in [
        (Vec3::new(0.0, 0.0, 3.0), DVec3::Z),
        (Vec3::new(0.0, 0.0, -3.0), -DVec3::Z),
        (Vec3::new(3.0, 0.0, 0.0), DVec3::X),
        (Vec3::new(0.0, -3.0, 0.0), -DVec3::Y),
    ] {
        let mut s = planar_view(&volume, eye);
        s.shading = Some(shading);
        let trace = reference.trace(&s, CENTRE, CENTRE);
        let cos = world_gradient.normalize().dot(view).abs();
        let lit = rgb * (0.1 + 0.6 * cos) + DVec3::splat(0.4 * cos.powi(8));
        let seg = trace.segment.expect("hit");
        let n = expected_samples(seg.length() / reference.step_world(&s) * f64::from(s.step_length), 1.0);
        assert!(n >= 8, "{n} samples");
        assert_eq!(trace.samples, n);
        let alpha = 1.0 - keep().powi(n as i32);
        assert_near(&format!("opacity from {eye}"), trace.alpha, alpha, 1e-12);
        assert_near3(&format!("shaded colour from {eye}"), trace.color, lit * alpha, 1e-6);
        // Without `shading` the colour is unlit.
        s.shading = None;
        assert_near3("unlit", reference.trace(&s, CENTRE, CENTRE).color, rgb * alpha, 1e-6);
    }
    // The gradient itself, in value per voxel.
    let g = reference.gradient(DVec3::new(0.4, 0.55, 0.6));
    assert_near3("gradient", g, DVec3::new(2.0, 1.0, 3.0) / 120.0, 1e-12);

    // A constant volume has no gradient: the colour is kept.
    let constant = constant_volume();
    let mut s = planar_view(&constant, Vec3::new(0.0, 0.0, 3.0));
    s.shading = Some(shading);
    let trace = Reference::new(&constant).trace(&s, CENTRE, CENTRE);
    assert_near3("zero gradient keeps rgb", trace.color, rgb * trace.alpha, 1e-6);
    // A NaN among the six samples zeroes the gradient.
    let half_nan = volume_from(|x, _, _| if x < N / 2 { f32::NAN } else { x as f32 / 8.0 });
    let r = Reference::new(&half_nan);
    assert_eq!(r.gradient(DVec3::new(9.0 / 16.0, 0.5, 0.5)), DVec3::ZERO);
    assert_near3(
        "clear of the NaN",
        r.gradient(DVec3::new(11.0 / 16.0, 0.5, 0.5)),
        DVec3::X / 16.0,
        1e-12,
    );
}

/// Rule 5's gradient opacity: a ← a·min(1, |g|/r), |g| in value per voxel; applied with or without lighting.
#[test]
fn gradient_opacity_scales_alpha_by_the_gradient() {
    let volume = planar_ramp();
    let reference = Reference::new(&volume);
    let g = 14f64.sqrt() / 120.0;
    let a = f64::from(STEP_ALPHA);
    for (r, nominal) in [(g * 2.0, 0.5), (g * 4.0, 0.25), (g / 2.0, 1.0), (g, 1.0)] {
        let r = r as f32;
        // r as the f32 setting holds it: `nominal` up to that rounding.
        let scale = (g / f64::from(r)).min(1.0);
        assert_near("scale", scale, nominal, 1e-6);
        for shading in [None, Some(Shading::default())] {
            let mut s = planar_view(&volume, Vec3::new(0.0, 0.0, 3.0));
            s.gradient_opacity = Some(r);
            s.shading = shading;
            let trace = reference.trace(&s, CENTRE, CENTRE);
            // The extinction is scaled: (1 − a)^scale per voxel, over the segment's 32 voxels per unit.
            let voxels = trace.segment.expect("hit").length() * 32.0;
            let alpha = 1.0 - (1.0 - a).powf(scale * voxels);
            assert_near(
                &format!("opacity with r = {r}, shading {shading:?}"),
                trace.alpha,
                alpha,
                1e-12,
            );
        }
    }
    // No gradient, no opacity.
    let constant = constant_volume();
    let mut s = planar_view(&constant, Vec3::new(0.0, 0.0, 3.0));
    s.gradient_opacity = Some(0.01);
    assert_eq!(Reference::new(&constant).trace(&s, CENTRE, CENTRE).alpha, 0.0);
}

/// Rule 6's density model: the step's opacity a·density·step_length, linear in the density up to 1.
#[test]
fn density_mode_opacity_is_linear_in_density() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.mode = CompositeMode::Density;
    let a = f64::from(STEP_ALPHA);
    // One voxel, one sample: two half-voxel segments, each of opacity a·d/2.
    s.set_slab(2, 0.5, 1.0 / 16.0);
    for density in [0.25f32, 0.5, 1.0, 2.0, 4.0] {
        s.density = density;
        let trace = reference.trace(&s, CENTRE, CENTRE);
        assert_eq!(trace.samples, 1);
        let half = a * f64::from(density) * 0.5;
        assert_near(
            &format!("density {density}"),
            trace.alpha,
            1.0 - (1.0 - half) * (1.0 - half),
            1e-12,
        );
    }
    s.density = 10.0;
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_eq!(trace.alpha, 1.0, "clamped at 1");
    // The whole ray, at several step lengths: A = 1 − (1 − min(1, a·d·s))^n, not the emission model's correction.
    s.slab_lo = Vec3::ZERO;
    s.slab_hi = Vec3::ONE;
    for (density, step_length) in [(0.5f32, 1.0f32), (1.0, 0.5), (2.0, 0.7), (2.0, 2.0)] {
        (s.density, s.step_length) = (density, step_length);
        let sl = f64::from(step_length);
        let n = expected_samples(16.0, sl);
        let keep: f64 = segment_lengths(16.0, sl, 0.5)
            .iter()
            .map(|length| 1.0 - (a * f64::from(density) * length).min(1.0))
            .product();
        let trace = reference.trace(&s, CENTRE, CENTRE);
        assert_eq!(trace.samples, n);
        assert_near(
            &format!("density {density}, step {step_length}"),
            trace.alpha,
            1.0 - keep,
            1e-12,
        );
    }
    s.mode = CompositeMode::Emission;
    (s.density, s.step_length) = (1.0, 0.5);
    assert_near(
        "emission differs",
        reference.trace(&s, CENTRE, CENTRE).alpha,
        1.0 - keep().powf(16.0),
        1e-12,
    );
}

/// Rule 7 with several surfaces: on the z ramp (values rising away from the eye) a translucent red surface at 0.3
/// and an opaque white one at 0.6 are met in that order; the pixel is the first over the second. Seen from the
/// other side (values falling along the ray), the order reverses. Rule 5's directional light: its angle θ to the
/// surface normal gives `rgb·(ambient + diffuse·c·cos θ) + specular·c·cos(θ/2)^shininess`.
#[test]
fn layered_isosurfaces_and_a_directional_light_follow_the_closed_form() {
    let volume = z_ramp();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.camera = Camera::looking_at(Vec3::new(0.0, 0.0, -3.0), Vec3::ZERO);
    s.mode = CompositeMode::Isosurface;
    s.jitter = None;
    let red = Vec3::new(1.0, 0.0, 0.0);
    (s.iso_value, s.iso_color, s.iso_opacity) = (0.6, Some(Vec3::ONE), 1.0);
    s.extra_isosurfaces = vec![volcast::scene::lighting::IsoSurface {
        value: 0.3,
        color: Some(red),
        opacity: 0.4,
    }];
    let lit = |rgb: DVec3| rgb * 0.9 + DVec3::splat(0.3);
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_eq!(trace.composited, 2);
    assert_near(
        "first hit",
        trace.hit.unwrap(),
        2.5 + 0.3 + 1.0 / 32.0,
        1.0 / 16.0 / 256.0,
    );
    let expected = 0.4 * lit(linear(red)) + 0.6 * lit(DVec3::ONE);
    assert_near3("red over white", trace.color, expected, 1e-6);
    assert_near("opacity", trace.alpha, 1.0, 1e-12);
    // From the far side the values fall along the ray: white (0.6) is met first and hides red.
    s.camera = Camera::looking_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_eq!(trace.composited, 1);
    assert_near3("white in front", trace.color, lit(DVec3::ONE), 1e-6);
    // Made translucent, white lets the rest through: the ray starts inside both (white, the innermost, first),
    // then leaves through white and red again as the values fall.
    s.iso_opacity = 0.5;
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_eq!(trace.composited, 4);
    let (mut c, mut a) = (DVec3::ZERO, 0.0);
    for (rgb, alpha) in [
        (DVec3::ONE, 0.5),
        (linear(red), 0.4),
        (DVec3::ONE, 0.5),
        (linear(red), 0.4),
    ] {
        c += (1.0 - a) * alpha * lit(rgb);
        a += (1.0 - a) * alpha;
    }
    assert_near3("white, red, white, red", trace.color, c, 1e-6);
    assert_near("opacity", trace.alpha, a, 1e-7);
    // A directional light at θ = 40° from the normal (the normal faces the eye at −z), coloured and brighter.
    s.camera = Camera::looking_at(Vec3::new(0.0, 0.0, -3.0), Vec3::ZERO);
    s.extra_isosurfaces.clear();
    s.iso_opacity = 1.0;
    let theta = 40f64.to_radians();
    let colour = Vec3::new(1.0, 0.5, 0.25);
    s.light = volcast::scene::lighting::Light {
        direction: Some(Vec3::new(theta.sin() as f32, 0.0, -theta.cos() as f32)),
        color: colour,
        intensity: 2.0,
    };
    let c = linear(colour) * 2.0;
    let trace = reference.trace(&s, CENTRE, CENTRE);
    let expected = DVec3::ONE * (DVec3::splat(0.2) + 0.7 * theta.cos() * c) + 0.3 * (theta / 2.0).cos().powf(20.0) * c;
    assert_near3("directional light", trace.color, expected, 1e-5);
    // Behind the surface the light leaves only the ambient term.
    s.light.direction = Some(Vec3::new(0.0, 0.0, 1.0));
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_near3("back-lit", trace.color, DVec3::splat(0.2), 1e-7);
}
