//! Rules 0 and 1 in the reference: the box placed and the rays built as `RenderSettings`'s docs say, checked
//! against `Camera`'s own matrices (the GPU's convention) and closed forms: the segment inside the slab box and
//! past the near plane, the image's orientation, the silhouette, orthographic rays, and the slab test itself.

use crate::common;

use super::scenes::{
    assert_near, assert_near3, background_pixel, constant_volume, expected_samples, head_on, keep, volume_from,
    BACKGROUND, CENTRE, N, SIZE,
};
use common::rays::{pixel_ray, ray_segment};
use common::reference::{quantise, render_reference, Reference};
use glam::{DVec3, Vec3};
use image::Rgba;
use volcast::scene::camera::Camera;
use volcast::scene::settings::RenderSettings;

#[test]
fn slab_restricts_the_segment() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.cut.set_slab(2, 0.25, 0.5);
    let trace = reference.trace(&s, CENTRE, CENTRE);
    let segment = trace.segment.expect("the slab still holds the centre ray");
    assert_near("segment start at the slab's top", segment.t_start, 3.0, 1e-12);
    assert_near("segment length", segment.length(), 0.5, 1e-12);
    assert_eq!(trace.samples, 8, "half the box, half the samples");
    assert_near("opacity", trace.alpha, 1.0 - keep().powi(8), 1e-12);

    // A slab beside the centre ray leaves it without a segment.
    let mut s = head_on(&volume, SIZE);
    s.cut.set_slab(0, 0.9, 0.2);
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

/// Screen orientation: row 0 is the top (+z seen from +y) and screen right is world -x (from `Camera`'s docs).
#[test]
fn image_orientation_follows_the_camera() {
    // Value 1 (v = 0.5) only where x < 0 and z > 0; the window [0.25, 1] keeps samples with v ≥ 0.25, which
    // trilinear blending across the planes x = 0 and z = 0 reaches only up to those planes themselves.
    let volume = volume_from(|x, _, z| if x < N / 2 && z >= N / 2 { 1.0 } else { 0.0 });
    let mut s = RenderSettings::new(33, 33, volume.extent());
    s.camera = Camera::orbit(0.0, 0.0, 3.0, Vec3::ZERO);
    s.colour.window = [0.25, 1.0];
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
    s.colour.step_alpha = 0.5;
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
