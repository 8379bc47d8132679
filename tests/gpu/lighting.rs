//! Rule 9 on the GPU against the CPU reference: shadows and ambient occlusion from the light grid, in emission,
//! density and iso-surface frames, under validation with synchronization validation.

use crate::common;

use common::bounds::REFERENCE;
use common::cases::ct_head;
use common::compare::against_reference;
use common::gpu::{close, validated_gpu, Judge};
use common::reference::Reference;
use volcast::render::headless::Headless;
use volcast::scene::lighting::{IsoSurface, Light};
use volcast::scene::settings::{CompositeMode, RenderSettings, Shading};
use volcast::transfer::function::TransferFunction;
use volcast::volume::{self, Volume};

/// The frames: emission lit by a directional light with shadows and occlusion, the same under the key light
/// (a headlight with shadows), density with occlusion only, and skin over bone with shadows.
fn frames(v: &Volume, ct: bool) -> Vec<(String, RenderSettings)> {
    let mut base = RenderSettings::for_volume(96, 96, v);
    base.lighting.shading = Some(Shading::default());
    if ct {
        base.colour.transfer_function = Some(TransferFunction::preset("ct-bone").unwrap());
        base.colour.window = [0.0, 1.0];
    } else {
        base.colour.step_alpha = 0.3;
    }
    let mut out = Vec::new();
    let mut s = base.clone();
    (s.lighting.shadows, s.lighting.ambient_occlusion) = (true, true);
    s.lighting.light = Light::from_angles(-50.0, 35.0);
    out.push(("emission-shadows-occlusion".to_string(), s.clone()));
    s.lighting.light = Light::default();
    out.push(("emission-key-light-shadows".to_string(), s.clone()));
    let mut d = base.clone();
    d.compositing.mode = CompositeMode::Density;
    d.compositing.density = 2.0;
    d.lighting.ambient_occlusion = true;
    out.push(("density-occlusion".to_string(), d));
    let mut iso = base.clone();
    iso.compositing.mode = CompositeMode::Isosurface;
    iso.compositing.iso_value = if ct { 0.45 } else { 0.5 };
    iso.compositing.extra_isosurfaces = vec![IsoSurface {
        value: if ct { 0.2 } else { 0.25 },
        color: Some(glam::Vec3::new(0.9, 0.6, 0.5)),
        opacity: 0.35,
    }];
    (iso.lighting.shadows, iso.lighting.ambient_occlusion) = (true, true);
    iso.lighting.light = Light::from_angles(30.0, 50.0);
    out.push(("iso-layers-shadows-occlusion".to_string(), iso));
    out
}

#[test]
fn shadows_and_occlusion_match_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut volumes = vec![(volume::builtin("helix", Some(64)).unwrap(), false)];
    volumes.extend(ct_head().map(|v| (v, true)));
    let mut judge = Judge::default();
    let mut unchanged = Vec::new();
    for (v, ct) in &volumes {
        headless.set_volume(&gpu, v).unwrap();
        let reference = Reference::new(v);
        for (label, s) in frames(v, *ct) {
            let actual = headless.render(&gpu, &s).unwrap().image;
            let expected = reference.render_full(&s);
            judge.against(
                "reference",
                format!("{}-{label}", v.name),
                &actual,
                &expected,
                &s,
                REFERENCE,
            );
            // The light grid must matter: without it the image is clearly different.
            let mut plain = s.clone();
            (plain.lighting.shadows, plain.lighting.ambient_occlusion) = (false, false);
            let d = against_reference(&headless.render(&gpu, &plain).unwrap().image, &expected, s.background);
            eprintln!("{}-{label}: without the light grid {d}", v.name);
            if d.mean < 1.0 {
                unchanged.push(format!(
                    "{}-{label}: the light grid changed the image by only {d}",
                    v.name
                ));
            }
        }
        // MIP is never lit: shadows and occlusion leave it as it was.
        let mut mip = RenderSettings::for_volume(64, 64, v);
        mip.compositing.mode = CompositeMode::Mip;
        let plain = headless.render(&gpu, &mip).unwrap().image;
        (mip.lighting.shadows, mip.lighting.ambient_occlusion) = (true, true);
        assert_eq!(plain, headless.render(&gpu, &mip).unwrap().image, "MIP with shadows");
    }
    close(gpu, headless);
    judge.assert_all();
    assert!(unchanged.is_empty(), "{}", unchanged.join("\n"));
}
