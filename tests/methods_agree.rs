//! The two ray setups (entry/exit faces and analytic ray/box) agree with each other, and each with the CPU
//! reference (the analytic one also marched in a compute pass, which must match its fragment pass within 1/255), at every built-in viewpoint of `volcast compare` — inside the volume, on a face, grazing, with the
//! near plane cutting the box and inside a slab — for a built-in and a real volume, under validation.
//! Bounds as in gpu_vs_reference.rs: methods agree within mean 0.5/255 and p99 3/255 (compare::AGREE_*); each
//! matches the reference within mean 0.5/255 and p99 3/255, or p99 10/255 for uint8 data (lavapipe's 8-bit
//! filter weights, explained there).

mod common;

use common::compare::{diff, write_failure_images};
use common::reference::Reference;
use volcast::compare::{builtin_views, compare_view};
use volcast::gpu::{Gpu, GpuOptions};
use volcast::headless::Headless;
use volcast::render::VolumeLayout;
use volcast::settings::RenderSettings;
use volcast::volume::{self, Volume};

fn check(volume: &Volume, size: u32, window: [f32; 2]) -> Vec<String> {
    let gpu = Gpu::new(&GpuOptions {
        validation: true,
        ..Default::default()
    })
    .expect("Vulkan with validation");
    let mut headless = Headless::new(&gpu).expect("renderer");
    headless.set_volume(&gpu, volume).expect("upload");
    let reference = Reference::new(volume);
    let mut base = RenderSettings::new(size, size, volume.extent());
    base.window = window;
    let ref_p99 = if headless.renderer.volume_layout() == Some(VolumeLayout::Texture(ash::vk::Format::R8_UNORM)) {
        10.0
    } else {
        3.0
    };
    let mut failures = Vec::new();
    for view in builtin_views(&base, volume.extent()) {
        let c = compare_view(&gpu, &mut headless, &view, 0).expect("render both methods");
        let label = format!("{}-{}", volume.name, view.name);
        eprintln!("{label}: faces vs analytic: {}", c.verdict());
        if !c.diff.agrees() {
            write_failure_images(&format!("{label}-methods"), &c.faces.image, &c.analytic.image);
            failures.push(format!("{label}: {}", c.verdict()));
        }
        let mut cs = view.settings.clone();
        cs.ray_setup = volcast::settings::RaySetup::Analytic;
        cs.compute = true;
        let compute = headless.render(&gpu, &cs).expect("compute march").image;
        // Same rays, same march code, another pipeline stage: at most rounding apart.
        let d = diff(&compute, &c.analytic.image);
        eprintln!("{label}: compute vs analytic fragment: {d}");
        if d.max > 1.0 {
            write_failure_images(&format!("{label}-compute"), &compute, &c.analytic.image);
            failures.push(format!("{label}: compute vs analytic fragment: {d}"));
        }
        let expected = reference.render(&view.settings);
        for (method, image) in [
            ("faces", &c.faces.image),
            ("analytic", &c.analytic.image),
            ("compute", &compute),
        ] {
            let d = diff(image, &expected);
            eprintln!("{label}: {method} vs reference: {d}");
            if d.mean >= 0.5 || d.p99 >= ref_p99 {
                write_failure_images(&format!("{label}-{method}"), image, &expected);
                failures.push(format!("{label}: {method} vs reference: {d}"));
            }
        }
    }
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    let problems = log.problems();
    assert!(problems.is_empty(), "validation layer reported:\n{problems:#?}");
    failures
}

#[test]
fn methods_agree_on_the_helix() {
    let helix = volume::builtin("helix", Some(128)).expect("helix");
    let failures = check(&helix, 112, [0.1, 1.0]);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn methods_agree_on_the_ct_head() {
    let Some(path) = common::shared_data("raw/cranium_ct_256x256x108_int16.raw") else {
        return;
    };
    let opts = volume::RawOptions {
        spacing: Some([0.957031, 0.957031, 1.5]),
        ..Default::default()
    };
    let ct = volume::load_raw(&path, &opts).expect("CT head");
    let failures = check(&ct, 112, [0.3, 1.0]);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
