//! The brick pool and its page table (src/render/pool.rs, shaders/volume.glsl `brick_at`, walk.glsl's spans)
//! against the CPU reference. Volumes are cut into small bricks (`Renderer::brick_side`), so that rays cross many
//! bricks, spans end at brick faces, samples and gradients read slot borders, segments start and end in other
//! bricks than their samples, and bisection, light-grid and resample reads look bricks up on their own. With
//! every brick at level 0 the image must match the reference within the unbricked bounds: the pool is invisible.

use crate::common;

use common::bounds::REFERENCE;
use common::cases::{gradient_cases, marschner_lobb_as, quality_cases, settings_cases, standard_cases, with};
use common::gpu::{finish, validated_gpu, Judge, METHODS};
use common::reference::Reference;
use volcast::gpu::Gpu;
use volcast::render::headless::Headless;
use volcast::render::TexelPolicy;
use volcast::scene::lighting::Light;
use volcast::scene::settings::{RaySetup, Shading};
use volcast::volume::{self, Volume, VoxelType};

/// Uploads `volume` cut into bricks of `side` and checks that it was cut (more than one brick along each axis).
fn set_bricked(gpu: &Gpu, headless: &mut Headless, volume: &Volume, side: u32) {
    headless.renderer.brick_side = Some(side);
    headless.set_volume(gpu, volume).expect("upload volume");
    let pool = headless.renderer.pool().expect("a pool");
    assert_eq!(
        pool.brick,
        volume.dims.map(|d| side.min(d)),
        "{}: brick size",
        volume.name
    );
    assert!(
        pool.grid.iter().all(|&g| g > 1),
        "{}: not cut into bricks: {:?}",
        volume.name,
        pool.grid
    );
    assert!(
        pool.slots.iter().filter(|&&s| s > 1).count() >= 2,
        "{}: slots {:?}",
        volume.name,
        pool.slots
    );
}

#[test]
fn bricked_volumes_match_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    // Every compositing family and setting on the helix (8-bit corners on lavapipe), in bricks of 16.
    let helix = volume::builtin("helix", Some(64)).expect("helix");
    let mut cases = standard_cases(&helix, 72);
    cases.extend(settings_cases(&helix, 72));
    cases.extend(quality_cases(&helix, 72));
    set_bricked(&gpu, &mut headless, &helix, 16);
    judge.run_cases(("reference", REFERENCE), &gpu, &mut headless, &helix, cases, METHODS);
    // Marschner-Lobb, whose values change every voxel, through each layout, in bricks of 8 (rays cross a brick
    // face every few samples), shaded with six samples and with the gradient texture.
    for (ty, policy) in [
        (VoxelType::U8, TexelPolicy::Corners),
        (VoxelType::U16, TexelPolicy::Native),
        (VoxelType::F32, TexelPolicy::Native),
    ] {
        headless.renderer.texel_policy = policy;
        let v = marschner_lobb_as(ty);
        set_bricked(&gpu, &mut headless, &v, 8);
        let mut cases = standard_cases(&v, 64);
        cases.extend(gradient_cases(&v, 64));
        // Steps longer than a brick's border: the point before a leap (a segment's start) and a segment's
        // midpoint lie in other bricks than the sample after them.
        cases.push(with(&v, 64, "step-3", |s| s.sampling.step_length = 3.0));
        cases.push(with(&v, 64, "step-3-shaded", |s| {
            s.sampling.step_length = 3.0;
            s.lighting.shading = Some(Shading::default());
        }));
        judge.run_cases(("reference", REFERENCE), &gpu, &mut headless, &v, cases, METHODS);
    }
    headless.renderer.texel_policy = TexelPolicy::Auto;
    // The helix's empty space in bricks of 8 at long steps: after each leap the segment starts at the last sample
    // leapt over, up to a step outside the brick of the sample after it.
    // Its empty space holds a faint ramp below the window (a segment's integral depends on its invisible start).
    let mut small = volume::builtin("helix", Some(48)).expect("helix");
    if let volcast::volume::VoxelData::U8(v) = &mut small.data {
        for (i, x) in v.iter_mut().enumerate() {
            if *x == 0 {
                *x = (i % 48 + i / 48 % 48 + i / 2304) as u8 % 20;
            }
        }
    }
    set_bricked(&gpu, &mut headless, &small, 8);
    let cases = [3.0, 4.0]
        .map(|step| with(&small, 72, &format!("step-{step}"), |s| s.sampling.step_length = step))
        .to_vec();
    judge.run_cases(("reference", REFERENCE), &gpu, &mut headless, &small, cases, METHODS);
    // The compute march the same way.
    let ml = volume::builtin("marschner-lobb", None).expect("marschner-lobb");
    set_bricked(&gpu, &mut headless, &ml, 8);
    let compute = &[(RaySetup::Analytic, true)];
    let mut cases = quality_cases(&ml, 64);
    cases.extend(gradient_cases(&ml, 64));
    judge.run_cases(("reference", REFERENCE), &gpu, &mut headless, &ml, cases, compute);
    finish(gpu, headless, judge);
}

/// Rule 9's light grid is filled by a compute pass that reads the volume through `sample_value`, a lookup per
/// read: shadows and occlusion over a bricked volume match the reference.
#[test]
fn the_light_grid_reads_bricked_volumes() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let helix = volume::builtin("helix", Some(64)).expect("helix");
    set_bricked(&gpu, &mut headless, &helix, 16);
    let reference = Reference::new(&helix);
    let mut s = volcast::scene::settings::RenderSettings::for_volume(80, 80, &helix);
    s.lighting.shading = Some(Shading::default());
    s.colour.step_alpha = 0.3;
    (s.lighting.shadows, s.lighting.ambient_occlusion) = (true, true);
    s.lighting.light = Light::from_angles(-50.0, 35.0);
    let actual = headless.render(&gpu, &s).expect("render").image;
    let expected = reference.render_full(&s);
    judge.against(
        "reference",
        "helix-bricked-shadows".into(),
        &actual,
        &expected,
        &s,
        REFERENCE,
    );
    finish(gpu, headless, judge);
}
