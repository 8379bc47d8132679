//! The two ray setups (entry/exit faces and analytic ray/box) agree with each other, and each with the CPU
//! reference (the analytic one also marched in a compute pass, which must match its fragment pass within 1/255),
//! at every built-in viewpoint of `volcast compare` — inside the volume, on a face, grazing, with the near plane
//! cutting the box and inside a slab — for a built-in and a real volume, under validation.
//! The methods agree within `compare::AGREE_*` over the object pixels; each matches the reference within the
//! bounds of tests/common/bounds.rs.

use crate::common;

use common::bounds::{METHODS, REFERENCE, REFERENCE_R8};
use common::compare::{between, diff, write_failure_images};
use common::gpu::{validated_gpu, Judge};
use common::reference::Reference;
use volcast::formats;
use volcast::measure::compare::{builtin_views, compare_view};
use volcast::render::headless::Headless;
use volcast::render::VolumeLayout;
use volcast::scene::settings::{RaySetup, RenderSettings};
use volcast::volume::{self, Volume};

fn check(volume: &Volume, size: u32, window: [f32; 2]) {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    headless.set_volume(&gpu, volume).expect("upload");
    let reference = Reference::new(volume);
    let mut base = RenderSettings::new(size, size, volume.extent());
    base.colour.window = window;
    let (family, bounds) =
        if headless.renderer.volume_layout() == Some(VolumeLayout::Texture(ash::vk::Format::R8_UNORM)) {
            ("reference-r8", REFERENCE_R8)
        } else {
            ("reference", REFERENCE)
        };
    let mut judge = Judge::default();
    let mut failures = Vec::new();
    for view in builtin_views(&base, volume.extent()) {
        let c = compare_view(&gpu, &mut headless, &view, 0).expect("render both methods");
        let label = format!("{}-{}", volume.name, view.name);
        eprintln!("{label}: faces vs analytic: {}", c.verdict());
        if !c.diff.agrees() {
            failures.push(format!("{label}: `compare` says {}", c.verdict()));
        }
        // The same comparison over the object pixels, held to the measured bound.
        let expected = reference.render_full(&view.settings);
        let methods = between(&c.faces.image, &c.analytic.image, &expected, view.settings.background);
        let images = (&c.faces.image, &c.analytic.image);
        judge.record(
            "methods",
            format!("{label}-faces-vs-analytic"),
            methods,
            METHODS,
            images,
        );
        let mut cs = view.settings.clone();
        cs.pipeline.ray_setup = RaySetup::Analytic;
        cs.pipeline.compute = true;
        let compute = headless.render(&gpu, &cs).expect("compute march").image;
        // Same rays, same march code, another pipeline stage: at most rounding apart.
        let d = diff(&compute, &c.analytic.image);
        if d.max > 1.0 {
            write_failure_images(&format!("{label}-compute"), &compute, &c.analytic.image);
            failures.push(format!("{label}: compute vs analytic fragment: {d}"));
        }
        for (method, image) in [
            ("faces", &c.faces.image),
            ("analytic", &c.analytic.image),
            ("compute", &compute),
        ] {
            let label = format!("{label}-{method}");
            judge.against(family, label, image, &expected, &view.settings, bounds);
        }
    }
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    judge.assert_all();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let problems = log.problems();
    assert!(problems.is_empty(), "validation layer reported:\n{problems:#?}");
}

#[test]
fn methods_agree_on_the_helix() {
    let helix = volume::builtin("helix", Some(128)).expect("helix");
    check(&helix, 112, [0.1, 1.0]);
}

#[test]
fn methods_agree_on_the_ct_head() {
    let Some(path) = common::shared_data("raw/cranium_ct_256x256x108_int16.raw") else {
        return;
    };
    let opts = formats::RawOptions {
        spacing: Some([0.957031, 0.957031, 1.5]),
        ..Default::default()
    };
    let ct = formats::load_raw(&path, &opts).expect("CT head");
    check(&ct, 112, [0.3, 1.0]);
}

/// Under an oblique and a mirrored placement the entry/exit faces wind the other way (mirrored) or meet the near
/// plane at an angle; both setups still agree, and each matches the reference.
#[test]
fn methods_agree_on_placed_volumes() {
    let helix = volume::builtin("helix", Some(64)).expect("helix");
    check(&common::cases::oblique(&helix), 96, [0.1, 1.0]);
    check(&common::cases::mirrored(&helix), 96, [0.1, 1.0]);
}
