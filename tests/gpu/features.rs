//! The march's optional features, each proven against the reference or an invariant rather than against itself:
//! empty-space skipping takes fewer samples and leaves the image unchanged; the march visits exactly the samples
//! rule 2 names; adaptive steps stay within their documented bound of the reference while taking fewer samples;
//! the gradient texture renders what the reference renders with the same (grid-gradient) rule; jitter averages
//! towards the finely sampled image. All under validation.

use crate::common;

use common::bounds::{REFERENCE, STRIDES};
use common::cases::{ct_head, marschner_lobb_as, mirrored, oblique, quality_cases, standard_cases, with};
use common::compare::{against_reference, diff, write_failure_images};
use common::gpu::{close, gpu_sample_counts, validated_gpu, Judge};
use common::reference::Reference;
use volcast::render::headless::Headless;
use volcast::scene::settings::{CompositeMode, RaySetup, RenderSettings, Shading};
use volcast::transfer::function::TransferFunction;
use volcast::transfer::Colormap;
use volcast::volume::{self, Volume, VoxelType};

fn total(counts: &[u32]) -> u64 {
    counts.iter().map(|&c| u64::from(c)).sum()
}

/// With skipping off, the march visits exactly rule 2's samples: per pixel the reference's count, give or take
/// one where f32 and f64 place the segment's end on either side of a sample (and on silhouette pixels, where the
/// two decide differently whether the ray meets the box at all). With skipping on, it visits fewer — never more
/// on any pixel — and the image is unchanged: skipping leaps over bricks without moving the sample grid.
#[test]
fn empty_space_skipping_takes_fewer_samples_and_keeps_the_image() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    // Whether the volume has empty space to leap over: Marschner–Lobb fills its whole box with visible values.
    let helix = volume::builtin("helix", Some(96)).unwrap();
    let mut volumes = vec![
        (mirrored(&helix), true),
        (helix, true),
        (oblique(&marschner_lobb_as(VoxelType::F32)), false),
    ];
    volumes.extend(ct_head().map(|v| (v, true)));
    let mut failures = Vec::new();
    for (v, has_empty_space) in &volumes {
        headless.set_volume(&gpu, v).unwrap();
        let reference = Reference::new(v);
        let mut cases = standard_cases(v, 80);
        cases.extend(quality_cases(v, 80));
        let (mut taken_all, mut taken_skipped) = (0u64, 0u64);
        for case in cases {
            let expected = reference.render_full(&case.settings);
            for method in [RaySetup::Faces, RaySetup::Analytic] {
                let label = format!("{}-{}-{:?}", v.name, case.name, method).to_lowercase();
                let mut s = case.settings.clone();
                s.pipeline.ray_setup = method;
                s.sampling.skip_empty = false;
                let full = headless.render(&gpu, &s).unwrap().image;
                let counts_full = gpu_sample_counts(&gpu, &mut headless, &s);
                s.sampling.skip_empty = true;
                let skipped = headless.render(&gpu, &s).unwrap().image;
                let counts_skipped = gpu_sample_counts(&gpu, &mut headless, &s);

                let d = diff(&skipped, &full);
                if d.max > 0.0 {
                    write_failure_images(&format!("{label}-skipping"), &skipped, &full);
                    failures.push(format!("{label}: skipping changed the image: {d}"));
                }
                // Rule 2 against the reference, pixel by pixel.
                let off = common::gpu::counts_off(&counts_full, &expected.samples);
                if off.len() > 12 {
                    failures.push(format!(
                        "{label}: {} pixels visit other samples than rule 2's (pixel, GPU, reference): {:?}",
                        off.len(),
                        &off[..off.len().min(8)]
                    ));
                }
                let (all, some) = (total(&counts_full), total(&counts_skipped));
                let tol = (total(&expected.samples) / 200).max(8);
                if all.abs_diff(total(&expected.samples)) > tol {
                    failures.push(format!(
                        "{label}: {all} samples taken, rule 2 names {}",
                        total(&expected.samples)
                    ));
                }
                if let Some(i) = (0..counts_full.len()).find(|&i| counts_skipped[i] > counts_full[i]) {
                    failures.push(format!(
                        "{label}: pixel {i} takes {} samples skipping, {} without",
                        counts_skipped[i], counts_full[i]
                    ));
                }
                taken_all += all;
                taken_skipped += some;
            }
        }
        let share = taken_skipped as f64 / taken_all.max(1) as f64;
        eprintln!(
            "{}: skipping takes {taken_skipped} of {taken_all} samples ({:.1}%)",
            v.name,
            share * 100.0
        );
        // Measured: the helix 24%, the CT head 38% of the samples taken.
        if *has_empty_space && share > 0.6 {
            failures.push(format!(
                "{}: skipping took {:.1}% of the samples; it should leap over the empty space",
                v.name,
                share * 100.0
            ));
        }
    }
    close(gpu, headless);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Brick strides (rule 2): faint bricks take every second or fourth sample. The reference implements the rule
/// from its definition, so the GPU must match it within the common bound. Against every step (the reference
/// again) the strided image must stay within [`STRIDES`]; strides must never take more samples than every step,
/// and must take fewer on each volume (its faint bricks: the CT head's and Marschner–Lobb's faint tables, the
/// helix's MR preset; the helix's sharp edges keep its faint tables at stride 1).
#[test]
fn brick_strides_follow_the_reference_rule() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut volumes = vec![
        volume::builtin("helix", Some(128)).unwrap(),
        volume::builtin("marschner-lobb", None).unwrap(),
    ];
    volumes.extend(ct_head());
    let mut judge = Judge::default();
    let mut failures = Vec::new();
    for v in &volumes {
        headless.set_volume(&gpu, v).unwrap();
        let reference = Reference::new(v);
        let strided = |s: &mut RenderSettings| {
            s.sampling.step_length = 0.4;
            s.sampling.max_stride = 4;
        };
        let cases = vec![
            with(v, 112, "default", strided),
            with(v, 112, "faint", |s| {
                strided(s);
                s.colour.step_alpha = 0.03;
            }),
            with(v, 112, "faint-lit", |s| {
                strided(s);
                s.colour.step_alpha = 0.03;
                s.lighting.shading = Some(Shading::default());
            }),
            with(v, 112, "mr-default-shaded", |s| {
                strided(s);
                s.colour.transfer_function = Some(TransferFunction::preset("mr-default").unwrap());
                s.colour.window = [0.0, 1.0];
                s.lighting.shading = Some(Shading::default());
            }),
            with(v, 112, "density", |s| {
                strided(s);
                s.compositing.mode = CompositeMode::Density;
                s.colour.step_alpha = 0.02;
            }),
            // Draft's tolerance (Quality::stride_tolerance): bounds four times looser, more bricks stride.
            with(v, 112, "faint-tolerant", |s| {
                strided(s);
                s.colour.step_alpha = 0.03;
                s.sampling.stride_tolerance = 4.0;
            }),
        ];
        let (mut full_samples, mut strided_samples) = (0, 0);
        for case in cases {
            let mut s = case.settings.clone();
            let image = headless.render(&gpu, &s).unwrap().image;
            let taken = total(&gpu_sample_counts(&gpu, &mut headless, &s));
            let label = format!("{}-{}-strides", v.name, case.name).to_lowercase();
            let strided = reference.render_full(&s);
            judge.against("reference", label.clone(), &image, &strided, &s, REFERENCE);
            // Rule 2 pixel by pixel: every sample counted (skipping would leave out the empty bricks').
            let counts = gpu_sample_counts(
                &gpu,
                &mut headless,
                &RenderSettings {
                    sampling: volcast::scene::settings::Sampling {
                        skip_empty: false,
                        ..s.sampling.clone()
                    },
                    ..s.clone()
                },
            );
            let off = common::gpu::counts_off(&counts, &strided.samples).len();
            // (A brick whose bound the f32 table and the f64 reference put on either side takes another stride.)
            if off > counts.len() / 100 {
                failures.push(format!(
                    "{label}: {off} pixels take other samples than rule 2's strides"
                ));
            }
            s.sampling.max_stride = 1;
            let every = total(&gpu_sample_counts(&gpu, &mut headless, &s));
            (strided_samples, full_samples) = (strided_samples + taken, full_samples + every);
            // What rule 2 gives up is bounded at its own tolerance; a looser one is draft's, whose error the bench
            // measures against its target (docs/performance.md, Quality levels).
            if s.sampling.stride_tolerance == 1.0 {
                judge.against(
                    "strides",
                    label,
                    &strided.image,
                    &reference.render_full(&s),
                    &s,
                    STRIDES,
                );
            }
            eprintln!("{}: {taken} of {every} samples", case.name);
        }
        // The same classification unlit, then lit: lighting halves the depth bound, so the renderer must classify
        // its bricks again (a kept occupancy would stride as for the unlit frame).
        let mut s = with(v, 112, "faint-lit", |_| {}).settings;
        (s.sampling.step_length, s.sampling.max_stride, s.colour.step_alpha) = (0.4, 4, 0.03);
        headless.render(&gpu, &s).unwrap();
        s.lighting.shading = Some(Shading::default());
        let lit = headless.render(&gpu, &s).unwrap().image;
        let label = format!("{}-faint-lit-after-unlit", v.name).to_lowercase();
        judge.against("reference", label, &lit, &reference.render_full(&s), &s, REFERENCE);
        eprintln!("{}: strides take {strided_samples} of {full_samples} samples", v.name);
        if strided_samples >= full_samples {
            failures.push(format!(
                "{}: strides took {strided_samples} samples, every step {full_samples}",
                v.name
            ));
        }
    }
    let log = gpu.log.clone();
    headless.destroy(&gpu);
    drop(gpu);
    judge.assert_all();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(log.problems().is_empty(), "{:#?}", log.problems());
}

/// The precomputed gradient texture shades with the grid's filtered gradients (Sobel for float data, a Gaussian
/// derivative for integer data), interpolated trilinearly (`RenderSettings::gradient_texture`, rule 5); the
/// reference implements that rule too. The GPU must match it within the common bound, in emission and on
/// iso-surfaces — and on Marschner–Lobb (sampled near its Nyquist limit) the rule visibly differs from central
/// differences of the interpolant, so an unused texture would fail; on its 16-bit copy Sobel and the Gaussian
/// differ, so the wrong filter would fail.
#[test]
fn gradient_texture_matches_the_reference_rule() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut volumes = vec![
        volume::builtin("marschner-lobb", None).unwrap(),
        volume::builtin("helix", Some(128)).unwrap(),
        oblique(&marschner_lobb_as(VoxelType::U16)),
    ];
    volumes.extend(ct_head());
    let mut judge = Judge::default();
    let mut differs = Vec::new();
    for v in &volumes {
        headless.set_volume(&gpu, v).unwrap();
        headless.renderer.enable_gradient_texture(&gpu, v).unwrap();
        let reference = Reference::new(v);
        let mut s = RenderSettings::new(96, 96, v.extent());
        s.lighting.shading = Some(Shading::default());
        s.colour.step_alpha = 0.3;
        let central = reference.render_full(&s);
        s.lighting.gradient_texture = true;
        let expected = reference.render_full(&s);
        for method in [RaySetup::Faces, RaySetup::Analytic] {
            s.pipeline.ray_setup = method;
            let textured = headless.render(&gpu, &s).unwrap().image;
            let label = format!("{}-gradient-texture-{method:?}", v.name).to_lowercase();
            judge.against("reference", label, &textured, &expected, &s, REFERENCE);
        }
        // Gradient-modulated opacity reads the gradient's length (shading only its direction).
        let mut g = s.clone();
        g.lighting.gradient_opacity = Some(0.08);
        g.colour.step_alpha = 0.6;
        let expected = reference.render_full(&g);
        let textured = headless.render(&gpu, &g).unwrap().image;
        let label = format!("{}-gradient-texture-opacity", v.name).to_lowercase();
        judge.against("reference", label, &textured, &expected, &g, REFERENCE);
        // Iso-surface normals from the same texture.
        let mut iso = s.clone();
        iso.compositing.mode = CompositeMode::Isosurface;
        iso.compositing.iso_value = 0.45;
        let expected_iso = reference.render_full(&iso);
        let textured = headless.render(&gpu, &iso).unwrap().image;
        let label = format!("{}-gradient-texture-iso", v.name).to_lowercase();
        judge.against("reference", label, &textured, &expected_iso, &iso, REFERENCE);
        differs.push((
            v.name.clone(),
            against_reference(&expected.image, &central, s.background),
        ));
    }
    close(gpu, headless);
    judge.assert_all();
    // A GPU that ignored the texture (central differences) would fail the bound the texture is held to.
    let (name, d) = &differs[0];
    eprintln!("{name}: grid gradients vs central differences (reference): {d}");
    assert!(
        REFERENCE.check(d).is_err(),
        "{name}: the two gradient rules should differ beyond the bound here, but differ by {d}"
    );
}

/// Jitter trades banding for noise that averages out: the mean of several jittered frames at a coarse step is
/// closer to a finely sampled reference than the un-jittered frame at that step. Pre-integration already removes
/// the transfer function's share of the banding, so what jitter averages is the data's own detail between samples:
/// measured 1.95/255 unjittered, 1.64/255 for the mean of 16 seeds (a seed-independent offset would give 1.0×).
#[test]
fn jitter_averages_towards_the_finely_sampled_image() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let ml = volume::builtin("marschner-lobb", Some(64)).expect("marschner-lobb");
    headless.set_volume(&gpu, &ml).expect("upload");
    let mut coarse = RenderSettings::new(96, 96, ml.extent());
    coarse.sampling.step_length = 3.0;
    coarse.colour.step_alpha = 0.15;
    coarse.colour.colormap = Colormap::Viridis;
    coarse.sampling.jitter = None;
    let mut fine = coarse.clone();
    fine.sampling.step_length = 0.25;
    let truth = Reference::new(&ml).render(&fine);
    let unjittered = headless.render(&gpu, &coarse).expect("render").image;
    let seeds = 16u32;
    let mut sum = vec![0.0f64; (96 * 96 * 4) as usize];
    for seed in 0..seeds {
        let mut s = coarse.clone();
        s.sampling.jitter = Some(seed);
        let img = headless.render(&gpu, &s).expect("render").image;
        for (acc, &p) in sum.iter_mut().zip(img.as_raw()) {
            *acc += p as f64;
        }
    }
    let mean_img = image::RgbaImage::from_raw(96, 96, sum.iter().map(|v| (v / seeds as f64).round() as u8).collect())
        .expect("image");
    let e_unjittered = diff(&unjittered, &truth).mean;
    let e_jittered = diff(&mean_img, &truth).mean;
    eprintln!("mean error vs step-0.25 reference: unjittered {e_unjittered:.3}/255, mean of {seeds} jittered {e_jittered:.3}/255");
    close(gpu, headless);
    assert!(
        e_jittered < 0.9 * e_unjittered,
        "jittered mean {e_jittered:.3} should beat unjittered {e_unjittered:.3} clearly"
    );
}

/// Pre-integrated segments cover each ray from its start to its end (rule 6), so a constant volume shows the same
/// image at any step length, jittered or not: the opacity of the ray's length through the box, 1 − (1 − a)^L. A
/// march that took its first or last segment (or a double step) as one step long would change with the step.
#[test]
fn a_constant_volume_looks_the_same_at_every_step() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let data = vec![1.0f32; 24 * 24 * 24];
    let mut v = Volume::new(
        "constant",
        [24; 3],
        [1.0; 3],
        VoxelType::F32,
        volume::VoxelData::F32(data),
    )
    .expect("a valid volume");
    v.range = [0.0, 2.0];
    headless.set_volume(&gpu, &v).expect("upload");
    let reference = Reference::new(&v);
    let mut judge = Judge::default();
    let mut base = RenderSettings::new(64, 64, v.extent());
    base.colour.step_alpha = 0.15;
    let mut images = Vec::new();
    for (step, jitter) in [(1.0f32, None), (0.7, Some(3)), (1.3, None), (2.5, Some(7)), (3.7, None)] {
        let mut s = base.clone();
        s.sampling.step_length = step;
        s.sampling.jitter = jitter;
        let actual = headless.render(&gpu, &s).expect("render").image;
        let expected = reference.render_full(&s);
        judge.against(
            "reference",
            format!("constant-step-{step}"),
            &actual,
            &expected,
            &s,
            REFERENCE,
        );
        images.push((step, actual));
    }
    close(gpu, headless);
    judge.assert_all();
    for (step, image) in &images[1..] {
        let d = diff(image, &images[0].1);
        assert!(d.max <= 1.0, "step {step} against step 1: {d}");
    }
}

/// Three Gaussian blobs: a smooth field, as float32 and stored in 100 levels as uint8 (like an 8-bit MRI).
fn blobs(n: u32, quantised: bool) -> Volume {
    let c = [(0.38, 0.5, 0.5, 0.16), (0.64, 0.5, 0.5, 0.2), (0.45, 0.42, 0.62, 0.1)];
    let mut f = Vec::with_capacity((n * n * n) as usize);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = [x, y, z].map(|i| (f64::from(i) + 0.5) / f64::from(n));
                let v: f64 = c
                    .iter()
                    .map(|(cx, cy, cz, r)| {
                        let d2 = (p[0] - cx).powi(2) + (p[1] - cy).powi(2) + (p[2] - cz).powi(2);
                        (-d2 / (2.0 * r * r)).exp()
                    })
                    .sum::<f64>()
                    .min(1.0);
                f.push(v);
            }
        }
    }
    let dims = [n; 3];
    if quantised {
        let q = f.iter().map(|v| (v * 99.0).round() as u8).collect();
        Volume::new("blobs-u8", dims, [1.0; 3], VoxelType::U8, volume::VoxelData::U8(q)).unwrap()
    } else {
        let q = f.iter().map(|v| *v as f32).collect();
        Volume::new("blobs-f32", dims, [1.0; 3], VoxelType::F32, volume::VoxelData::F32(q)).unwrap()
    }
}

/// Rule 5's filter reconstructs a quantised field's smooth gradient: the 100-level uint8 copy's iso-surface and
/// shaded emission stay close to its float32 original (docs/rendering.md, Gradients; the goal is a mean of 1/255
/// and p99 8/255 over object pixels), where central differences shade every terrace.
#[test]
fn a_quantised_field_shades_like_its_float_original() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let (float, quantised) = (blobs(96, false), blobs(96, true));
    let mut iso = RenderSettings::new(240, 240, float.extent());
    iso.compositing.mode = CompositeMode::Isosurface;
    iso.compositing.iso_value = 0.3;
    let mut emission = RenderSettings::new(240, 240, float.extent());
    emission.lighting.shading = Some(Shading::default());
    emission.colour.window = [0.2, 1.0];
    emission.colour.step_alpha = 0.3;
    let mut failures = Vec::new();
    for (label, s) in [("iso", iso), ("emission", emission)] {
        let mut images = Vec::new();
        for (v, texture) in [(&float, true), (&quantised, true), (&quantised, false)] {
            headless.set_volume(&gpu, v).unwrap();
            let mut s = s.clone();
            volcast::scene::quality::Quality::Normal.apply(&mut s, v.range);
            s.lighting.gradient_texture = texture;
            if texture {
                headless.renderer.enable_gradient_texture(&gpu, v).unwrap();
            }
            images.push(headless.render(&gpu, &s).unwrap().image);
        }
        let bg = volcast::measure::image_diff::background_u8(&s);
        let smoothed = volcast::measure::image_diff::diff_stats(&images[1], &images[0], bg);
        let central = volcast::measure::image_diff::diff_stats(&images[2], &images[0], bg);
        eprintln!("{label}: uint8 vs float32, filtered {smoothed:?}; central differences {central:?}");
        if smoothed.mean > 1.0 || smoothed.p99 > 8.0 {
            failures.push(format!("{label}: filtered gradients {smoothed:?}"));
        }
        if central.mean < 2.0 * smoothed.mean {
            failures.push(format!("{label}: central differences {central:?} should be far off"));
        }
    }
    close(gpu, headless);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
