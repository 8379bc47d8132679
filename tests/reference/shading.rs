//! Rule 5 in the reference: lighting and gradient opacity on a planar ramp with anisotropic voxels, whose gradient
//! is known exactly.

use crate::common;

use super::scenes::{
    assert_near, assert_near3, constant_tf, constant_volume, expected_samples, head_on, keep, linear, volume_from,
    volume_with, CENTRE, N, SIZE, STEP_ALPHA,
};
use common::reference::Reference;
use glam::{DVec3, Vec3};
use volcast::scene::camera::Camera;
use volcast::scene::settings::{RenderSettings, Shading};
use volcast::volume::Volume;

/// A planar ramp on a box with anisotropic voxels (1/32 × 1/32 × 1/16 world units): raw 2x + y + 3z over the range
/// [0, 120], so the gradient is (2, 1, 3)/120 per voxel everywhere trilinear filtering is not clamped.
fn planar_ramp() -> Volume {
    volume_with([N; 3], [1.0, 1.0, 2.0], [0.0, 120.0], |x, y, z| {
        (2 * x + y + 3 * z) as f32
    })
}

/// Looking from `eye` at the box's centre through the centre pixel, the segment kept where the gradient's stencil
/// stays clear of the clamped edges.
fn planar_view(volume: &Volume, eye: Vec3) -> RenderSettings {
    let mut s = head_on(volume, SIZE);
    s.camera = Camera::looking_at(eye, Vec3::ZERO);
    s.colour.transfer_function = Some(constant_tf([0.8, 0.5, 0.3], STEP_ALPHA));
    for axis in 0..3 {
        s.cut.set_slab(axis, 0.5, 0.75);
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
        s.lighting.shading = Some(shading);
        let trace = reference.trace(&s, CENTRE, CENTRE);
        let cos = world_gradient.normalize().dot(view).abs();
        let lit = rgb * (0.1 + 0.6 * cos) + DVec3::splat(0.4 * cos.powi(8));
        let seg = trace.segment.expect("hit");
        let n = expected_samples(
            seg.length() / reference.step_world(&s) * f64::from(s.sampling.step_length),
            1.0,
        );
        assert!(n >= 8, "{n} samples");
        assert_eq!(trace.samples, n);
        let alpha = 1.0 - keep().powi(n as i32);
        assert_near(&format!("opacity from {eye}"), trace.alpha, alpha, 1e-12);
        assert_near3(&format!("shaded colour from {eye}"), trace.color, lit * alpha, 1e-6);
        // Without `shading` the colour is unlit.
        s.lighting.shading = None;
        assert_near3("unlit", reference.trace(&s, CENTRE, CENTRE).color, rgb * alpha, 1e-6);
    }
    // The gradient itself, in value per voxel.
    let g = reference.gradient(DVec3::new(0.4, 0.55, 0.6));
    assert_near3("gradient", g, DVec3::new(2.0, 1.0, 3.0) / 120.0, 1e-12);

    // A constant volume has no gradient: the colour is kept.
    let constant = constant_volume();
    let mut s = planar_view(&constant, Vec3::new(0.0, 0.0, 3.0));
    s.lighting.shading = Some(shading);
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
            s.lighting.gradient_opacity = Some(r);
            s.lighting.shading = shading;
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
    s.lighting.gradient_opacity = Some(0.01);
    assert_eq!(Reference::new(&constant).trace(&s, CENTRE, CENTRE).alpha, 0.0);
}
