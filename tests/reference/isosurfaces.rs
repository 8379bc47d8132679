//! Rule 7's iso-surfaces in the reference: the crossing found by bisection within its bound, several surfaces met
//! in the order the ray crosses them, and their shading under a directional light (rule 5).

use crate::common;

use super::scenes::{
    assert_all_background, assert_near, assert_near3, grey_ramp_tf, head_on, linear, volume_from, z_ramp, CENTRE, SIZE,
};
use common::classify::srgb_to_linear;
use common::reference::{render_reference, Reference};
use glam::{DVec3, Vec3};
use volcast::scene::camera::Camera;
use volcast::scene::settings::CompositeMode;

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
    s.compositing.mode = CompositeMode::Isosurface;
    s.colour.transfer_function = Some(grey_ramp_tf(0.3));
    // The surface coloured by the classification (the default is a light neutral, below).
    s.compositing.iso_color = None;
    for step_length in [0.5f32, 1.0, 1.7, 3.0] {
        for jitter in [None, Some(3), Some(99)] {
            for iso in [0.1f32, 0.37, 0.5, 0.8] {
                for window in [[0.0f32, 1.0], [0.95, 1.0]] {
                    (
                        s.sampling.step_length,
                        s.sampling.jitter,
                        s.compositing.iso_value,
                        s.colour.window,
                    ) = (step_length, jitter, iso, window);
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
    s.compositing.iso_color = Some(volcast::scene::lighting::NEUTRAL);
    s.compositing.iso_value = 0.37;
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_near3(
        "neutral",
        trace.color,
        linear(volcast::scene::lighting::NEUTRAL) * 0.9 + DVec3::splat(0.3),
        1e-6,
    );
    // The first sample already at or above the value: the hit is that sample, exactly.
    s.compositing.iso_value = 0.0;
    for jitter in [None, Some(5)] {
        s.sampling.jitter = jitter;
        let trace = reference.trace(&s, CENTRE, CENTRE);
        assert_eq!(trace.samples, 1);
        assert_near(
            "first sample",
            trace.hit.unwrap(),
            2.5 + trace.offset * f64::from(s.sampling.step_length) / 16.0,
            1e-12,
        );
    }
    // Above every value, or NaN everywhere: no hit, the background.
    (s.compositing.iso_value, s.sampling.step_length, s.sampling.jitter) = (0.95, 1.0, None);
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_eq!((trace.hit, trace.samples), (None, 16));
    assert_all_background(&render_reference(&volume, &s), "iso above the data");
    s.compositing.iso_value = 0.0;
    assert_all_background(&render_reference(&volume_from(|_, _, _| f32::NAN), &s), "iso in NaN");
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
    s.compositing.mode = CompositeMode::Isosurface;
    s.sampling.jitter = None;
    let red = Vec3::new(1.0, 0.0, 0.0);
    (
        s.compositing.iso_value,
        s.compositing.iso_color,
        s.compositing.iso_opacity,
    ) = (0.6, Some(Vec3::ONE), 1.0);
    s.compositing.extra_isosurfaces = vec![volcast::scene::lighting::IsoSurface {
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
    s.compositing.iso_opacity = 0.5;
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
    s.compositing.extra_isosurfaces.clear();
    s.compositing.iso_opacity = 1.0;
    let theta = 40f64.to_radians();
    let colour = Vec3::new(1.0, 0.5, 0.25);
    s.lighting.light = volcast::scene::lighting::Light {
        direction: Some(Vec3::new(theta.sin() as f32, 0.0, -theta.cos() as f32)),
        color: colour,
        intensity: 2.0,
    };
    let c = linear(colour) * 2.0;
    let trace = reference.trace(&s, CENTRE, CENTRE);
    let expected = DVec3::ONE * (DVec3::splat(0.2) + 0.7 * theta.cos() * c) + 0.3 * (theta / 2.0).cos().powf(20.0) * c;
    assert_near3("directional light", trace.color, expected, 1e-5);
    // Behind the surface the light leaves only the ambient term.
    s.lighting.light.direction = Some(Vec3::new(0.0, 0.0, 1.0));
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_near3("back-lit", trace.color, DVec3::splat(0.2), 1e-7);
}
