//! The GPU image against the independent CPU reference (tests/common/reference.rs), case by case, under the
//! Khronos validation layer with synchronization validation. One GPU serves each test (lavapipe compiles each
//! pipeline on first use, ~0.5 s); at the end the GPU is dropped and the test asserts that the layer said
//! nothing, leaked objects and allocations included. Bounds per family: tests/common/bounds.rs.

use crate::common;

use common::bounds::{REFERENCE, REFERENCE_R8};
use common::cases::{
    gradient_cases, marschner_lobb_as, marschner_lobb_sized, mask_as, mirrored, oblique, quality_cases, settings_cases,
    sheared, standard_cases, with,
};
use common::compare::Bounds;
use common::gpu::{finish, validated_gpu, Judge, METHODS};
use volcast::formats;
use volcast::gpu::Gpu;
use volcast::render::headless::Headless;
use volcast::render::{TexelPolicy, VolumeLayout};
use volcast::scene::settings::{CompositeMode, RaySetup, Shading};
use volcast::transfer::function::TransferFunction;
use volcast::volume::{self, Volume, VoxelType};

/// The bounds for the layout the renderer chose for the volume just set.
fn bounds_for(headless: &Headless) -> (&'static str, Bounds) {
    if headless.renderer.volume_layout() == Some(VolumeLayout::Texture(ash::vk::Format::R8_UNORM)) {
        ("reference-r8", REFERENCE_R8)
    } else {
        ("reference", REFERENCE)
    }
}

fn run(
    judge: &mut Judge,
    gpu: &Gpu,
    headless: &mut Headless,
    volume: &Volume,
    cases: Vec<common::cases::Case>,
    methods: &[(RaySetup, bool)],
) {
    headless.set_volume(gpu, volume).expect("upload volume");
    judge.run_cases(bounds_for(headless), gpu, headless, volume, cases, methods);
}

#[test]
fn builtins_match_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let helix = volume::builtin("helix", Some(96)).expect("helix");
    let mut cases = standard_cases(&helix, 96);
    cases.extend(settings_cases(&helix, 96));
    cases.extend(quality_cases(&helix, 96));
    run(&mut judge, &gpu, &mut headless, &helix, cases, METHODS);
    let ml = volume::builtin("marschner-lobb", None).expect("marschner-lobb");
    let mut cases = standard_cases(&ml, 80);
    cases.extend(quality_cases(&ml, 80));
    run(&mut judge, &gpu, &mut headless, &ml, cases, METHODS);
    for name in ["box", "colormap"] {
        let v = volume::builtin(name, Some(64)).expect("built-in");
        let cases = standard_cases(&v, 64).into_iter().take(2).collect();
        run(&mut judge, &gpu, &mut headless, &v, cases, METHODS);
    }
    // Label masks: whole regions at exactly the data's maximum, the top of the default window.
    for ty in [VoxelType::U8, VoxelType::U16, VoxelType::F32] {
        let mask = mask_as(ty);
        let cases = vec![
            with(&mask, 72, "emission", |_| {}),
            with(&mask, 72, "mip", |s| s.compositing.mode = CompositeMode::Mip),
            with(&mask, 72, "minip-low-window", |s| {
                s.compositing.mode = CompositeMode::MinIp;
                s.colour.window = [0.0, 0.5];
            }),
        ];
        run(&mut judge, &gpu, &mut headless, &mask, cases, METHODS);
    }
    // The same rules under an oblique, a mirrored (left-handed) and a sheared placement.
    let small = volume::builtin("helix", Some(64)).expect("helix");
    for placed in [oblique(&small), mirrored(&small), sheared(&small)] {
        let mut cases = standard_cases(&placed, 80);
        cases.extend(quality_cases(&placed, 80));
        cases.extend(
            settings_cases(&placed, 80)
                .into_iter()
                .filter(|c| c.name.starts_with("slab") || c.name.starts_with("orthographic")),
        );
        run(&mut judge, &gpu, &mut headless, &placed, cases, METHODS);
    }
    finish(gpu, headless, judge);
}

/// The compute march (`--method compute`) against the reference: every shader variant (compositing families,
/// shading, gradient opacity) and the settings that change the rays (slabs, inside, orthographic, non-square
/// images, whose sizes are not multiples of the 8×8 workgroup), on the helix and the Marschner–Lobb volume.
#[test]
fn compute_march_matches_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let compute = &[(RaySetup::Analytic, true)];
    let helix = volume::builtin("helix", Some(96)).expect("helix");
    let mut cases = standard_cases(&helix, 96);
    cases.extend(settings_cases(&helix, 93));
    cases.extend(quality_cases(&helix, 96));
    run(&mut judge, &gpu, &mut headless, &helix, cases, compute);
    let ml = volume::builtin("marschner-lobb", None).expect("marschner-lobb");
    run(&mut judge, &gpu, &mut headless, &ml, quality_cases(&ml, 80), compute);
    for placed in [oblique(&ml), mirrored(&ml)] {
        let mut cases = standard_cases(&placed, 72);
        cases.extend(gradient_cases(&placed, 72));
        run(&mut judge, &gpu, &mut headless, &placed, cases, compute);
    }
    finish(gpu, headless, judge);
}

/// Every voxel type, made synthetically on non-cubic voxels (1 × 1.2 × 0.8), through each layout its data can go
/// to the GPU in — the native texture (R8/R16_UNORM or R32F), a float texture and a corner texture (8/16-bit
/// data) — from the standard viewpoints, and shaded, iso-surfaced and gradient-modulated on its default layout.
#[test]
fn every_data_type_matches_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    for ty in VoxelType::ALL {
        let v = marschner_lobb_as(ty);
        let policies: &[TexelPolicy] = if ty.size() <= 2 {
            &[TexelPolicy::Native, TexelPolicy::Float, TexelPolicy::Corners]
        } else {
            &[TexelPolicy::Native]
        };
        for &policy in policies {
            headless.renderer.texel_policy = policy;
            let mut v = v.clone();
            v.name = format!("{}-{policy:?}", v.name);
            run(&mut judge, &gpu, &mut headless, &v, standard_cases(&v, 72), METHODS);
        }
        // On CPU devices volumes are written in place (Image::new_host_written): 33 × 29 voxels through the padded
        // rows and slices lavapipe gives linear images, 64 × 32 packed as tightly as the data. Each layout again
        // at that size, and on a CPU device both must have been written in place.
        let tight = marschner_lobb_sized(ty, [64, 32, 25]);
        for &policy in policies {
            headless.renderer.texel_policy = policy;
            let mut w = tight.clone();
            w.name = format!("{}-64x32-{policy:?}", w.name);
            let cases = standard_cases(&w, 64).into_iter().take(2).collect();
            run(&mut judge, &gpu, &mut headless, &w, cases, METHODS);
            if gpu.properties.device_type == ash::vk::PhysicalDeviceType::CPU {
                for volume in [&v, &w] {
                    headless.set_volume(&gpu, volume).unwrap();
                    assert!(
                        headless.renderer.volume_is_host_written(),
                        "{}: staged on a CPU device",
                        volume.name
                    );
                }
            }
        }
        headless.renderer.texel_policy = TexelPolicy::Auto;
        run(&mut judge, &gpu, &mut headless, &v, gradient_cases(&v, 72), METHODS);
        // Shading normals follow the placement: an oblique and a mirrored one for each type.
        for placed in [oblique(&v), mirrored(&v)] {
            let cases = gradient_cases(&placed, 64).into_iter().take(3).collect();
            run(&mut judge, &gpu, &mut headless, &placed, cases, METHODS);
        }
    }
    finish(gpu, headless, judge);
}

#[test]
fn real_volumes_match_the_reference() {
    // Each with its true voxel size (MANIFEST.txt), so shading and steps see the real geometry.
    let files = [
        ("raw/cranium_ct_256x256x108_int16.raw", [0.957031, 0.957031, 1.5]),
        ("raw/dwi_b0_ascm_58x58x24_float64.raw", [4.0, 4.0, 5.0]),
        ("raw/dwi_s0_10slices_128x128x10_uint16.raw", [2.0, 2.0, 53.1413]),
        ("raw/motor_zmap_53x63x46_float32.raw", [3.0, 3.0, 3.0]),
    ];
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    for (file, spacing) in files {
        let Some(path) = common::shared_data(file) else {
            continue;
        };
        let opts = formats::RawOptions {
            spacing: Some(spacing),
            ..Default::default()
        };
        let v = formats::load_raw(&path, &opts).expect("load real volume");
        let mut cases = standard_cases(&v, 80);
        if v.name.starts_with("cranium") {
            cases.push(with(&v, 96, "bone-window", |s| s.colour.window = [0.45, 1.0]));
            // The presets in Hounsfield units, shaded, on real CT data at its true (non-cubic) aspect.
            for preset in ["ct-bone", "ct-soft-tissue", "ct-lung"] {
                cases.push(with(&v, 96, &format!("{preset}-shaded"), |s| {
                    s.colour.transfer_function = Some(TransferFunction::preset(preset).unwrap());
                    s.colour.window = [0.0, 1.0];
                    s.lighting.shading = Some(Shading::default());
                }));
            }
            cases.push(with(&v, 96, "iso-bone", |s| {
                s.compositing.mode = CompositeMode::Isosurface;
                s.compositing.iso_value = 0.45;
            }));
            // Rule 7's layers (translucent skin over bone, met in order, also falling out of the head) under rule
            // 5's directional, coloured light.
            cases.push(with(&v, 96, "iso-skin-over-bone-lit", |s| {
                s.compositing.mode = CompositeMode::Isosurface;
                s.compositing.iso_value = 0.45;
                s.compositing.extra_isosurfaces = vec![volcast::scene::lighting::IsoSurface {
                    value: 0.2,
                    color: Some(glam::Vec3::new(0.9, 0.6, 0.5)),
                    opacity: 0.3,
                }];
                s.lighting.light = volcast::scene::lighting::Light {
                    direction: Some(glam::Vec3::new(0.6, -0.3, 0.74)),
                    color: glam::Vec3::new(1.0, 0.9, 0.8),
                    intensity: 1.3,
                };
            }));
            cases.push(with(&v, 96, "ct-bone-directional", |s| {
                s.colour.transfer_function = Some(TransferFunction::preset("ct-bone").unwrap());
                s.colour.window = [0.0, 1.0];
                s.lighting.shading = Some(Shading::default());
                s.lighting.light = volcast::scene::lighting::Light::from_angles(-60.0, 40.0);
            }));
        }
        if v.name.starts_with("motor") {
            // The fMRI activation map: MIP shows the blobs.
            cases.push(with(&v, 96, "mip-activation", |s| {
                s.compositing.mode = CompositeMode::Mip;
                s.colour.window = [0.55, 1.0];
            }));
        }
        run(&mut judge, &gpu, &mut headless, &v, cases, METHODS);
    }
    // The native files, placed as their headers say: LAS (motor map), oblique (diffusion b0), sheared (S0), and
    // the tilted DICOM series.
    for native in [
        "native/motor_zmap/image_10426.nii.gz",
        "native/dwi_b0_ascm/ascm_out_test.nii.gz",
        "native/dwi_s0_10slices/S0_10slices.nii.gz",
        "native/brain_pd_mr",
    ] {
        let Some(path) = common::shared_data(native) else {
            continue;
        };
        let v = formats::open(&path, &Default::default()).expect("load a native file");
        let mut cases = standard_cases(&v, 72).into_iter().take(4).collect::<Vec<_>>();
        cases.push(with(&v, 72, "shaded", |s| {
            s.lighting.shading = Some(Shading::default())
        }));
        cases.push(with(&v, 72, "voxel-axes", |s| s.voxel_axes = true));
        run(&mut judge, &gpu, &mut headless, &v, cases, METHODS);
    }
    finish(gpu, headless, judge);
}
