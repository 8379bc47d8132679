//! The GPU image against the independent CPU reference (tests/common/reference.rs), case by case, under the
//! Khronos validation layer with synchronization validation. One GPU serves all cases (lavapipe compiles each
//! pipeline on first use, ~0.5 s); at the end the GPU is dropped and the test asserts that the layer said
//! nothing, leaked objects and allocations included.
//!
//! Tolerances (units of 1/255, per pixel the largest RGB channel error):
//! - mean < 0.5 and 99th percentile < 3: the foundation's target. Sources of error that remain: lavapipe filters
//!   in f32 (the reference in f64), position targets hold f32 positions, the rasteriser and the analytic slab
//!   test disagree on exact silhouette pixels, and a ray whose opacity lands on the early-termination
//!   threshold can stop one sample apart. Measured on lavapipe: worst mean 0.07/255, worst p99 1/255.
//! - uint8 volumes (R8_UNORM textures): p99 < 10. lavapipe filters 8-bit UNORM textures with 8-bit fixed-point
//!   weights, so a trilinear sample can be off by up to ~1/256 of the value range; where the data is steep
//!   (the Marschner–Lobb rings, the helix's edges) that moves samples across the window edge and the error
//!   compounds along the ray. Measured: p99 up to 9/255, mean < 0.4/255. Uploading the same data as R16_UNORM
//!   brought it to p99 1/255 (mean 0.07/255), which shows the shader itself is exact. On CPU devices volcast
//!   now widens 8- and 16-bit data to R32_SFLOAT by default (`TexelPolicy::Auto`: faster there, and exact), so
//!   the looser bound applies only where a test asks for the native R8 texture (`TexelPolicy::Native`).

mod common;

use common::compare::{diff, write_failure_images, ImageDiff};
use common::reference::Reference;
use glam::Vec3;
use volcast::camera::Camera;
use volcast::gpu::{Gpu, GpuOptions};
use volcast::headless::Headless;
use volcast::render::{TexelPolicy, VolumeLayout};
use volcast::settings::{CompositeMode, RaySetup, RenderSettings, Shading};
use volcast::tf::TransferFunction;
use volcast::transfer::Colormap;
use volcast::volume::{self, Volume, VoxelData, VoxelType};

const MAX_MEAN: f64 = 0.5;
const MAX_P99: f64 = 3.0;
const MAX_P99_UINT8: f64 = 10.0;

#[derive(Clone)]
struct Case {
    name: String,
    settings: RenderSettings,
}

fn base(volume: &Volume, size: u32) -> RenderSettings {
    RenderSettings::new(size, size, volume.extent())
}

fn with(volume: &Volume, size: u32, name: &str, f: impl FnOnce(&mut RenderSettings)) -> Case {
    let mut s = base(volume, size);
    f(&mut s);
    Case {
        name: name.to_string(),
        settings: s,
    }
}

/// Cases every volume goes through.
fn standard_cases(v: &Volume, size: u32) -> Vec<Case> {
    let e = v.extent();
    vec![
        with(v, size, "oblique", |_| {}),
        with(v, size, "axis-x", |s| {
            s.camera = Camera::orbit(90.0, 0.0, 2.5, Vec3::ZERO)
        }),
        with(v, size, "axis-z-top", |s| {
            s.camera = Camera::orbit(0.0, 90.0, 2.5, Vec3::ZERO)
        }),
        with(v, size, "inside", |s| {
            s.camera = Camera::looking_at(Vec3::new(0.05, -0.1, 0.02) * e, Vec3::new(0.3, 0.4, 0.1) * e);
        }),
        with(v, size, "on-face", |s| {
            s.camera = Camera::looking_at(Vec3::new(0.0, 0.5 * e.y, 0.0), Vec3::ZERO)
        }),
        with(v, size, "multiplied-viridis", |s| {
            s.multiplied_alpha = true;
            s.step_alpha = 0.5;
            s.colormap = Colormap::Viridis;
        }),
    ]
}

/// Cases that exercise one setting each, on one volume.
fn settings_cases(v: &Volume, size: u32) -> Vec<Case> {
    vec![
        with(v, size, "window", |s| s.window = [0.3, 0.7]),
        with(v, size, "slab", |s| {
            s.set_slab(0, 0.5, 0.4);
            s.set_slab(2, 0.3, 0.5);
        }),
        with(v, size, "slab-inside", |s| {
            s.set_slab(1, 0.6, 0.3);
            s.camera = Camera::looking_at(Vec3::new(0.1, 0.0, 0.05), Vec3::new(-0.2, 0.5, 0.0));
        }),
        with(v, size, "half-step", |s| {
            s.step_length = 0.5;
            s.colormap = Colormap::Plasma;
        }),
        with(v, size, "double-step-gnuplot", |s| {
            s.step_length = 2.0;
            s.colormap = Colormap::Gnuplot;
        }),
        with(v, size, "no-early-stop-rainbow", |s| {
            s.early_termination = 1.0;
            s.step_alpha = 0.05;
            s.colormap = Colormap::Rainbow;
        }),
        with(v, size, "background-grayscale", |s| {
            // Channels chosen off the .5 rounding ties (0.3 × 255 = 76.5 would round either way).
            s.background = Vec3::new(0.2, 0.35, 0.45);
            s.colormap = Colormap::Grayscale;
        }),
        with(v, size, "wide-angle-close", |s| {
            s.camera = Camera::orbit(-60.0, -30.0, 1.2, Vec3::ZERO);
            s.camera.fov_y_deg = 70.0;
        }),
        with(v, size, "non-square", |s| {
            s.width = size + 37;
            s.height = size - 21;
        }),
        with(v, size, "no-jitter", |s| s.jitter = None),
        with(v, size, "jitter-seed-7", |s| s.jitter = Some(7)),
        with(v, size, "orthographic", |s| s.camera.ortho = true),
        with(v, size, "orthographic-inside", |s| {
            s.camera = Camera::looking_at(Vec3::new(0.1, -0.2, 0.05), Vec3::new(0.3, 0.4, 0.1));
            s.camera.ortho = true;
        }),
    ]
}

/// One case per compositing mode, shading and classification option (issue 6's rules), on one volume.
fn quality_cases(v: &Volume, size: u32) -> Vec<Case> {
    vec![
        with(v, size, "mip", |s| s.mode = CompositeMode::Mip),
        with(v, size, "minip", |s| {
            s.mode = CompositeMode::MinIp;
            s.window = [0.2, 1.0];
        }),
        with(v, size, "average", |s| s.mode = CompositeMode::Average),
        with(v, size, "iso", |s| {
            s.mode = CompositeMode::Isosurface;
            s.iso_value = 0.4;
        }),
        with(v, size, "iso-ortho-phong", |s| {
            s.mode = CompositeMode::Isosurface;
            s.iso_value = 0.6;
            s.camera.ortho = true;
            s.shading = Some(Shading {
                ambient: 0.1,
                diffuse: 0.6,
                specular: 0.6,
                shininess: 40.0,
            });
        }),
        with(v, size, "density", |s| {
            s.mode = CompositeMode::Density;
            s.density = 2.5;
        }),
        with(v, size, "shaded", |s| s.shading = Some(Shading::default())),
        with(v, size, "shaded-gradient-opacity", |s| {
            s.shading = Some(Shading::default());
            s.gradient_opacity = Some(0.05);
            s.step_alpha = 0.4;
        }),
        with(v, size, "tf-mr-default", |s| {
            s.transfer_function = Some(TransferFunction::preset("mr-default").unwrap());
            s.window = [0.0, 1.0];
        }),
        with(v, size, "tf-qt-example-multiplied-off", |s| {
            s.transfer_function = Some(TransferFunction::preset("qt-example").unwrap());
            s.window = [0.0, 1.0];
        }),
    ]
}

/// A synthetic volume of `ty` built from the Marschner–Lobb function, for data types no built-in has.
fn marschner_lobb_as(ty: VoxelType) -> Volume {
    let ml = volume::builtin("marschner-lobb", Some(33)).expect("built-in");
    let values: Vec<f64> = (0..33u32 * 33 * 33)
        .map(|i| ml.value(i % 33, (i / 33) % 33, i / (33 * 33)))
        .collect();
    let data = match ty {
        VoxelType::U16 => VoxelData::U16(values.iter().map(|v| (v * 4095.0).round() as u16).collect()),
        // int16 is stored biased (+32768) on the GPU; this range straddles zero like CT data.
        VoxelType::I16 => VoxelData::U16(
            values
                .iter()
                .map(|v| ((v * 3000.0 - 1000.0).round() as i32 + 32768) as u16)
                .collect(),
        ),
        VoxelType::U8 => VoxelData::U8(values.iter().map(|v| (v * 255.0).round() as u8).collect()),
        _ => VoxelData::F32(values.iter().map(|&v| v as f32).collect()),
    };
    Volume::new(format!("ml-{}", ty.name()), [33, 33, 33], [1.0, 1.2, 0.8], ty, data).expect("valid volume")
}

struct Outcome {
    label: String,
    diff: ImageDiff,
    max_p99: f64,
}

impl Outcome {
    fn failed(&self) -> bool {
        self.diff.mean > MAX_MEAN || self.diff.p99 > self.max_p99
    }
}

/// The two ray setups; the compute march (the analytic setup in a compute pass) has a test of its own.
const METHODS: &[(RaySetup, bool)] = &[(RaySetup::Faces, false), (RaySetup::Analytic, false)];

fn run_cases(gpu: &Gpu, headless: &mut Headless, volume: &Volume, cases: Vec<Case>, out: &mut Vec<Outcome>) {
    run_cases_with(gpu, headless, volume, cases, METHODS, out)
}

fn run_cases_with(
    gpu: &Gpu,
    headless: &mut Headless,
    volume: &Volume,
    cases: Vec<Case>,
    methods: &[(RaySetup, bool)],
    out: &mut Vec<Outcome>,
) {
    headless.set_volume(gpu, volume).expect("upload volume");
    let reference = Reference::new(volume);
    // The looser uint8 bound is for R8_UNORM textures only (lavapipe's 8-bit filter weights); 8-bit data
    // widened to float (TexelPolicy) is held to the common bound.
    let max_p99 = if headless.renderer.volume_layout() == Some(VolumeLayout::Texture(ash::vk::Format::R8_UNORM)) {
        MAX_P99_UINT8
    } else {
        MAX_P99
    };
    for case in cases {
        let expected = reference.render(&case.settings);
        for &(method, compute) in methods {
            let mut s = case.settings.clone();
            s.ray_setup = method;
            s.compute = compute;
            let suffix = if compute { "-compute" } else { "" };
            let label = format!("{}-{}-{:?}{suffix}", volume.name, case.name, method).to_lowercase();
            let actual = headless.render(gpu, &s).expect("render").image;
            let d = diff(&actual, &expected);
            eprintln!("{label}: {d}");
            let outcome = Outcome {
                label,
                diff: d,
                max_p99,
            };
            if outcome.failed() {
                write_failure_images(&outcome.label, &actual, &expected);
            }
            out.push(outcome);
        }
    }
}

fn validated_gpu() -> Gpu {
    Gpu::new(&GpuOptions {
        validation: true,
        ..Default::default()
    })
    .expect("a Vulkan device with the validation layer (apt-get install mesa-vulkan-drivers vulkan-validationlayers)")
}

/// Tears down and asserts the validation layer said nothing, leaks at device destruction included.
fn close(gpu: Gpu, headless: Headless) {
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    assert!(
        log.problems().is_empty(),
        "validation layer reported:\n{:#?}",
        log.problems()
    );
}

fn finish(gpu: Gpu, headless: Headless, outcomes: Vec<Outcome>) {
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    let problems = log.problems();
    let failed: Vec<&Outcome> = outcomes.iter().filter(|o| o.failed()).collect();
    let worst_mean = outcomes.iter().map(|o| o.diff.mean).fold(0.0, f64::max);
    let worst_p99 = outcomes.iter().map(|o| o.diff.p99).fold(0.0, f64::max);
    eprintln!(
        "{} comparisons; worst mean {worst_mean:.3}/255, worst p99 {worst_p99:.0}/255",
        outcomes.len()
    );
    assert!(
        failed.is_empty(),
        "{} of {} images differ from the CPU reference beyond mean {MAX_MEAN}/255 or their p99 bound:\n{}",
        failed.len(),
        outcomes.len(),
        failed
            .iter()
            .map(|o| format!("  {}: {} (p99 bound {})", o.label, o.diff, o.max_p99))
            .collect::<Vec<_>>()
            .join("\n")
    );
    assert!(
        problems.is_empty(),
        "validation layer reported {} problem(s):\n{:#?}",
        problems.len(),
        problems
    );
}

#[test]
fn builtins_match_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut outcomes = Vec::new();
    let helix = volume::builtin("helix", Some(96)).expect("helix");
    let mut cases = standard_cases(&helix, 96);
    cases.extend(settings_cases(&helix, 96));
    cases.extend(quality_cases(&helix, 96));
    run_cases(&gpu, &mut headless, &helix, cases, &mut outcomes);
    let ml = volume::builtin("marschner-lobb", None).expect("marschner-lobb");
    let mut cases = standard_cases(&ml, 80);
    cases.extend(quality_cases(&ml, 80));
    run_cases(&gpu, &mut headless, &ml, cases, &mut outcomes);
    for name in ["box", "colormap"] {
        let v = volume::builtin(name, Some(64)).expect("built-in");
        run_cases(
            &gpu,
            &mut headless,
            &v,
            standard_cases(&v, 64).into_iter().take(2).collect(),
            &mut outcomes,
        );
    }
    finish(gpu, headless, outcomes);
}

/// The compute march (`--method compute`) against the reference: every shader variant (compositing families,
/// shading, gradient opacity) and the settings that change the rays (slabs, inside, orthographic, non-square
/// images, whose sizes are not multiples of the 8×8 workgroup), on the helix and the Marschner–Lobb volume.
#[test]
fn compute_march_matches_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut outcomes = Vec::new();
    let compute = &[(RaySetup::Analytic, true)];
    let helix = volume::builtin("helix", Some(96)).expect("helix");
    let mut cases = standard_cases(&helix, 96);
    cases.extend(settings_cases(&helix, 93));
    cases.extend(quality_cases(&helix, 96));
    run_cases_with(&gpu, &mut headless, &helix, cases, compute, &mut outcomes);
    let ml = volume::builtin("marschner-lobb", None).expect("marschner-lobb");
    run_cases_with(&gpu, &mut headless, &ml, quality_cases(&ml, 80), compute, &mut outcomes);
    finish(gpu, headless, outcomes);
}

#[test]
fn every_data_type_matches_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut outcomes = Vec::new();
    for ty in [VoxelType::U8, VoxelType::U16, VoxelType::I16, VoxelType::F32] {
        let v = marschner_lobb_as(ty);
        // Each layout the data can go to the GPU in: the native texture (R8/R16_UNORM), a float texture and a
        // corner buffer (8/16-bit data; TexelPolicy::Auto's choice on CPU devices like lavapipe).
        for policy in [TexelPolicy::Native, TexelPolicy::Float, TexelPolicy::Corners] {
            headless.renderer.texel_policy = policy;
            let mut v = v.clone();
            v.name = format!("{}-{policy:?}", v.name);
            run_cases(&gpu, &mut headless, &v, standard_cases(&v, 72), &mut outcomes);
        }
    }
    headless.renderer.texel_policy = TexelPolicy::Auto;
    finish(gpu, headless, outcomes);
}

#[test]
fn real_volumes_match_the_reference() {
    let files = [
        "raw/cranium_ct_256x256x108_int16.raw",
        "raw/dwi_b0_ascm_58x58x24_float64.raw",
        "raw/dwi_s0_10slices_128x128x10_uint16.raw",
        "raw/motor_zmap_53x63x46_float32.raw",
    ];
    let paths: Vec<_> = files.iter().filter_map(|f| common::shared_data(f)).collect();
    if paths.is_empty() {
        return;
    }
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut outcomes = Vec::new();
    for path in paths {
        let v = volume::load_raw(&path, &Default::default()).expect("load real volume");
        let mut cases = standard_cases(&v, 80);
        if v.name.starts_with("cranium") {
            // A CT bone window, at the CT's true (non-cubic) aspect.
            cases.push(with(&v, 96, "bone-window", |s| s.window = [0.45, 1.0]));
            // The presets in Hounsfield units, shaded, on real CT data.
            for preset in ["ct-bone", "ct-soft-tissue", "ct-lung"] {
                cases.push(with(&v, 96, &format!("{preset}-shaded"), |s| {
                    s.transfer_function = Some(TransferFunction::preset(preset).unwrap());
                    s.window = [0.0, 1.0];
                    s.shading = Some(Shading::default());
                }));
            }
        }
        if v.name.starts_with("motor") {
            // The fMRI activation map: MIP shows the blobs.
            cases.push(with(&v, 96, "mip-activation", |s| {
                s.mode = CompositeMode::Mip;
                s.window = [0.55, 1.0];
            }));
        }
        run_cases(&gpu, &mut headless, &v, cases, &mut outcomes);
    }
    finish(gpu, headless, outcomes);
}

/// Jitter trades banding for noise that averages out: the mean of several jittered frames at a coarse step is
/// closer to a finely sampled reference than the un-jittered frame at that step.
#[test]
fn jitter_averages_towards_the_finely_sampled_image() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let ml = volume::builtin("marschner-lobb", Some(64)).expect("marschner-lobb");
    headless.set_volume(&gpu, &ml).expect("upload");
    let mut coarse = RenderSettings::new(96, 96, ml.extent());
    coarse.step_length = 3.0;
    coarse.step_alpha = 0.15;
    coarse.colormap = Colormap::Viridis;
    coarse.jitter = None;
    let mut fine = coarse.clone();
    fine.step_length = 0.25;
    let truth = Reference::new(&ml).render(&fine);
    let unjittered = headless.render(&gpu, &coarse).expect("render").image;
    let seeds = 16u32;
    let mut sum = vec![0.0f64; (96 * 96 * 4) as usize];
    for seed in 0..seeds {
        let mut s = coarse.clone();
        s.jitter = Some(seed);
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
        e_jittered < 0.8 * e_unjittered,
        "jittered mean {e_jittered:.3} should beat unjittered {e_unjittered:.3} clearly"
    );
}

/// Empty-space skipping leaps over bricks without moving the sample grid, so it may only change which samples are
/// taken, never the image: skipped and unskipped frames must agree to 1/255 (in practice they are identical).
#[test]
fn empty_space_skipping_does_not_change_the_image() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut volumes = vec![
        volume::builtin("helix", Some(96)).unwrap(),
        marschner_lobb_as(VoxelType::F32),
    ];
    if let Some(path) = common::shared_data("raw/cranium_ct_256x256x108_int16.raw") {
        volumes.push(volume::load_raw(&path, &Default::default()).unwrap());
    }
    let mut failures = Vec::new();
    for v in &volumes {
        headless.set_volume(&gpu, v).unwrap();
        let mut cases = standard_cases(v, 80);
        cases.extend(quality_cases(v, 80));
        for case in cases {
            for method in [RaySetup::Faces, RaySetup::Analytic] {
                let mut s = case.settings.clone();
                s.ray_setup = method;
                s.skip_empty = true;
                let skipped = headless.render(&gpu, &s).unwrap().image;
                s.skip_empty = false;
                let full = headless.render(&gpu, &s).unwrap().image;
                let d = diff(&skipped, &full);
                if d.max > 1.0 {
                    let label = format!("{}-{}-{:?}-skipping", v.name, case.name, method).to_lowercase();
                    write_failure_images(&label, &skipped, &full);
                    failures.push(format!("{label}: {d}"));
                }
            }
        }
    }
    close(gpu, headless);
    assert!(
        failures.is_empty(),
        "skipping changed the image:\n{}",
        failures.join("\n")
    );
}

/// Adaptive stepping takes every other sample in bricks of faint opacity, correcting opacity for the double
/// step. It is approximate by design; it must stay within the foundation's bound of the full-rate image.
#[test]
fn adaptive_step_stays_within_the_bound() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut volumes = vec![
        volume::builtin("helix", Some(128)).unwrap(),
        volume::builtin("marschner-lobb", None).unwrap(),
    ];
    if let Some(path) = common::shared_data("raw/cranium_ct_256x256x108_int16.raw") {
        volumes.push(volume::load_raw(&path, &Default::default()).unwrap());
    }
    let mut failures = Vec::new();
    for v in &volumes {
        headless.set_volume(&gpu, v).unwrap();
        let mut cases = vec![
            with(v, 112, "default", |_| {}),
            with(v, 112, "faint", |s| s.step_alpha = 0.03),
        ];
        cases.push(with(v, 112, "mr-default-shaded", |s| {
            s.transfer_function = Some(TransferFunction::preset("mr-default").unwrap());
            s.window = [0.0, 1.0];
            s.shading = Some(Shading::default());
        }));
        cases.push(with(v, 112, "density", |s| {
            s.mode = CompositeMode::Density;
            s.step_alpha = 0.02;
        }));
        for case in cases {
            let mut s = case.settings.clone();
            let full = headless.render(&gpu, &s).unwrap().image;
            s.adaptive_step = true;
            let adaptive = headless.render(&gpu, &s).unwrap().image;
            let d = diff(&adaptive, &full);
            let label = format!("{}-{}-adaptive", v.name, case.name).to_lowercase();
            eprintln!("{label}: {d}");
            if d.mean >= MAX_MEAN || d.p99 >= MAX_P99 {
                write_failure_images(&label, &adaptive, &full);
                failures.push(format!("{label}: {d}"));
            }
        }
    }
    close(gpu, headless);
    assert!(
        failures.is_empty(),
        "adaptive stepping left the bound:\n{}",
        failures.join("\n")
    );
}

/// The precomputed gradient texture (one 4-channel sample instead of six) shades like the on-the-fly central
/// differences of rule 5. It differentiates the voxel grid rather than the interpolant, which only matters
/// between voxels where the data change fast: on the CT head and the helix it stays within the foundation's
/// bound; on Marschner-Lobb (sampled near its Nyquist limit on purpose) it was measured at mean 0.88/255,
/// p99 9/255, so that volume gets a bound of mean 1.5 and p99 15 — a regression guard, not a claim of equality.
#[test]
fn gradient_texture_shades_like_central_differences() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut volumes = vec![
        (volume::builtin("marschner-lobb", None).unwrap(), 1.5, 15.0),
        (volume::builtin("helix", Some(128)).unwrap(), MAX_MEAN, MAX_P99),
    ];
    if let Some(path) = common::shared_data("raw/cranium_ct_256x256x108_int16.raw") {
        volumes.push((volume::load_raw(&path, &Default::default()).unwrap(), MAX_MEAN, MAX_P99));
    }
    let mut failures = Vec::new();
    for (v, max_mean, max_p99) in &volumes {
        headless.set_volume(&gpu, v).unwrap();
        headless.renderer.enable_gradient_texture(&gpu, v).unwrap();
        let mut s = RenderSettings::new(96, 96, v.extent());
        s.shading = Some(Shading::default());
        s.step_alpha = 0.3;
        let on_the_fly = headless.render(&gpu, &s).unwrap().image;
        s.gradient_texture = true;
        let textured = headless.render(&gpu, &s).unwrap().image;
        let d = diff(&textured, &on_the_fly);
        eprintln!("{}: gradient texture vs central differences: {d}", v.name);
        if d.mean >= *max_mean || d.p99 >= *max_p99 {
            write_failure_images(&format!("{}-gradient-texture", v.name), &textured, &on_the_fly);
            failures.push(format!("{}: {d}", v.name));
        }
    }
    close(gpu, headless);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
