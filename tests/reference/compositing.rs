//! Rules 6 to 8 in the reference: pre-integrated segments with opacity corrected to their length, the density
//! model, front-to-back compositing with early termination, MIP/MinIP/average, and the output composited in
//! linear light over the background and encoded to sRGB once.

use crate::common;

use super::scenes::{
    assert_all_background, assert_near, assert_near3, background_pixel, constant_tf, constant_volume, expected_samples,
    grey_ramp_tf, head_on, keep, linear, segment_lengths, table_rgb, volume_from, z_ramp, BACKGROUND, CENTRE, SIZE,
    STEP_ALPHA,
};
use common::classify::{jitter_offset, linear_to_srgb, srgb_to_linear};
use common::reference::{quantise, render_reference, Reference};
use glam::{DVec3, Vec3};
use image::Rgba;
use volcast::scene::settings::CompositeMode;

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
fn opacity_correction_keeps_opacity_per_distance() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let at_one_voxel = 1.0 - keep().powi(16);
    for step_length in [0.25f32, 0.5, 0.7, 1.0, 1.3, 2.0, 4.0] {
        let mut s = head_on(&volume, SIZE);
        s.sampling.step_length = step_length;
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
    s.colour.step_alpha = 0.5;
    // After sample j (from 1) the ray has crossed j − 0.5 voxels; without termination all 16.
    for (threshold, samples, depth) in [(0.9f32, 4, 3.5), (0.99, 8, 7.5), (0.5, 2, 1.5), (1.0, 16, 16.0)] {
        s.compositing.early_termination = threshold;
        let trace = reference.trace(&s, CENTRE, CENTRE);
        assert_eq!(trace.samples, samples, "termination at {threshold}");
        assert_near("opacity", trace.alpha, 1.0 - 0.5f64.powf(depth), 1e-12);
        assert_eq!(trace.terminated_early, threshold < 1.0);
        assert_near3("colour", trace.color, table_rgb(&volume, &s, 0.5) * trace.alpha, 1e-7);
    }
}

/// Rule 6's density model: the step's opacity a·density·step_length, linear in the density up to 1.
#[test]
fn density_mode_opacity_is_linear_in_density() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.compositing.mode = CompositeMode::Density;
    let a = f64::from(STEP_ALPHA);
    // One voxel, one sample: two half-voxel segments, each of opacity a·d/2.
    s.cut.set_slab(2, 0.5, 1.0 / 16.0);
    for density in [0.25f32, 0.5, 1.0, 2.0, 4.0] {
        s.compositing.density = density;
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
    s.compositing.density = 10.0;
    let trace = reference.trace(&s, CENTRE, CENTRE);
    assert_eq!(trace.alpha, 1.0, "clamped at 1");
    // The whole ray, at several step lengths: A = 1 − (1 − min(1, a·d·s))^n, not the emission model's correction.
    s.cut.slab_lo = Vec3::ZERO;
    s.cut.slab_hi = Vec3::ONE;
    for (density, step_length) in [(0.5f32, 1.0f32), (1.0, 0.5), (2.0, 0.7), (2.0, 2.0)] {
        (s.compositing.density, s.sampling.step_length) = (density, step_length);
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
    s.compositing.mode = CompositeMode::Emission;
    (s.compositing.density, s.sampling.step_length) = (1.0, 0.5);
    assert_near(
        "emission differs",
        reference.trace(&s, CENTRE, CENTRE).alpha,
        1.0 - keep().powf(16.0),
        1e-12,
    );
}

/// Rule 8: compositing happens in linear light and is encoded once, so 50% white over black is sRGB 188, not 128.
#[test]
fn half_white_over_black_is_srgb_188() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.colour.transfer_function = Some(constant_tf([1.0; 3], 0.5));
    s.background = Vec3::ZERO;
    // One voxel of the box along the ray: one sample, whose opacity is the table's 0.5.
    s.cut.set_slab(2, 0.5, 1.0 / 16.0);
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
    s.colour.transfer_function = Some(constant_tf([0.0; 3], 0.5));
    s.background = Vec3::ONE;
    assert_eq!(
        quantise(reference.trace(&s, CENTRE, CENTRE).output),
        Rgba([188, 188, 188, 255])
    );
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
    s.colour.transfer_function = Some(grey_ramp_tf(0.3));
    let mut offsets = Vec::new();
    for jitter in [None, Some(0), Some(1), Some(7), Some(12345), Some(u32::MAX)] {
        s.sampling.jitter = jitter;
        let offset = jitter.map_or(0.5, |seed| jitter_offset(CENTRE, CENTRE, seed));
        offsets.push(offset);
        for window in [[0.0f32, 1.0], [0.2, 0.8], [0.25, 0.75], [0.3, 0.31]] {
            s.colour.window = window;
            let [lo, hi] = window.map(f64::from);
            let visible: Vec<f64> = ramp_samples(offset)
                .into_iter()
                .filter(|v| (lo..=hi).contains(v))
                .collect();
            for mode in [CompositeMode::Mip, CompositeMode::MinIp, CompositeMode::Average] {
                s.compositing.mode = mode;
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
    s.sampling.jitter = None;
    s.colour.window = [0.0, 1.0];
    for (mode, m) in [
        (CompositeMode::Mip, 15.0 / 16.0),
        (CompositeMode::MinIp, 0.0),
        (CompositeMode::Average, 7.5 / 16.0),
    ] {
        s.compositing.mode = mode;
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
    s.compositing.mode = CompositeMode::Mip;
    assert_all_background(&render_reference(&nan, &s), "MIP of NaN");
}
