//! Rules 2 and 3 in the reference: where a ray samples (jittered offsets, whose mean converges to the integral)
//! and what a sample reads (trilinear between texel centres, clamped at the edges; NaN and values outside the
//! window skipped).

use crate::common;

use super::scenes::{
    assert_all_background, assert_near, constant_tf, constant_volume, expected_samples_at, head_on, keep, volume_from,
    volume_with, CENTRE, N, SIZE, STEP_ALPHA,
};
use common::classify::jitter_offset;
use common::reference::{render_reference, Reference};
use glam::DVec3;
use volcast::scene::settings::RenderSettings;
use volcast::transfer::function::TransferFunction;

#[test]
fn window_excluding_every_value_gives_the_background() {
    let volume = constant_volume();
    let mut s = head_on(&volume, SIZE);
    s.colour.window = [0.6, 1.0];
    assert_all_background(&render_reference(&volume, &s), "window above the value");
    s.colour.window = [0.0, 0.4];
    assert_all_background(&render_reference(&volume, &s), "window below the value");
    // A window whose edge is the value itself still includes it, at full opacity (the rule excludes only v < lo
    // or v > hi).
    s.colour.window = [0.5, 1.0];
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

/// Rule 2 with jitter: offsets are the hash of pixel and seed, and averaged over seeds the jittered ray's optical
/// depth is the continuous integral, which the midpoint samples miss when the steps don't fit the ray.
#[test]
fn jittered_mean_converges_to_the_integral() {
    // Normalised value along the centre ray, t in voxels from the entry: 0 until 0.5, (t − 0.5)/16 until 15.5,
    // then 15/16; opacity 0.3·v, so the extinction per voxel is −ln(1 − 0.3·v).
    let volume = volume_with([N; 3], [1.0; 3], [0.0, 16.0], |_, _, z| (15 - z) as f32);
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, 1);
    s.colour.transfer_function = Some(TransferFunction {
        opacity: vec![[0.0, 0.0], [1.0, 0.3]],
        ..constant_tf([1.0; 3], 0.0)
    });
    s.sampling.step_length = 1.3;
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
        s.sampling.jitter = Some(seed);
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
