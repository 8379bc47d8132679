//! Rule 10's clipping plane on the GPU against the CPU reference, under validation with synchronization
//! validation: oblique, axis-aligned and flipped planes, a plane with the slab box, planes that keep everything
//! and remove everything, in emission, iso-surface and MIP frames, through both ray setups (and the compute
//! march), on volumes placed obliquely with anisotropic voxels and mirrored. The reference clips the world ray
//! itself (tests/common/march.rs); the GPU clips the texture-space segment (shaders/clip.glsl).

use crate::common;

use common::bounds::REFERENCE;
use common::cases::{mirrored, oblique, with, Case};
use common::compare::diff;
use common::gpu::{finish, validated_gpu, Judge, METHODS};
use common::reference::{background_pixel, Reference};
use glam::Vec3;
use volcast::render::headless::Headless;
use volcast::scene::camera::Camera;
use volcast::scene::clip::ClipPlane;
use volcast::scene::lighting::Light;
use volcast::scene::settings::{CompositeMode, RaySetup, RenderSettings, Shading};
use volcast::volume::{self, Volume};

const SIZE: u32 = 80;

fn plane(normal: [f32; 3], offset: f32) -> Option<ClipPlane> {
    Some(ClipPlane::new(Vec3::from_array(normal), offset).expect("a valid plane"))
}

/// An oblique plane a little off the box's centre (mm), through the helix's tube.
fn oblique_plane() -> Option<ClipPlane> {
    plane([0.6, -0.5, 0.4], 4.0)
}

/// How a case sets its plane (and what goes with it).
type SetPlane = Box<dyn Fn(&mut RenderSettings)>;

/// The planes, each in emission, iso-surface and MIP frames.
fn plane_cases(v: &Volume) -> Vec<Case> {
    let planes: Vec<(&str, SetPlane)> = vec![
        ("oblique", Box::new(|s| s.cut.clip_plane = oblique_plane())),
        ("axis-z", Box::new(|s| s.cut.clip_plane = plane([0.0, 0.0, -1.0], 4.0))),
        (
            "flipped",
            Box::new(|s| s.cut.clip_plane = oblique_plane().map(ClipPlane::flipped)),
        ),
        (
            "with-slab",
            Box::new(|s| {
                s.cut.clip_plane = oblique_plane();
                s.cut.set_slab(0, 0.45, 0.5);
                s.cut.set_slab(2, 0.6, 0.7);
            }),
        ),
        (
            "inside-no-jitter",
            Box::new(|s| {
                // The eye inside the volume, on a plane along the view: the plane halves the image.
                s.camera = Camera::looking_at(Vec3::new(0.1, -0.15, 0.05), Vec3::new(-0.2, 0.3, 0.0));
                s.cut.clip_plane = plane([0.45, 0.3, 0.0], 0.0);
                s.sampling.jitter = None;
            }),
        ),
        (
            "orthographic-no-skip",
            Box::new(|s| {
                s.camera.ortho = true;
                s.sampling.skip_empty = false;
                s.cut.clip_plane = plane([0.2, 1.0, -0.3], 2.0);
            }),
        ),
    ];
    let mut cases = Vec::new();
    for (name, set) in &planes {
        cases.push(with(v, SIZE, &format!("{name}-emission"), |s| {
            s.colour.step_alpha = 0.3;
            set(s);
        }));
        cases.push(with(v, SIZE, &format!("{name}-iso"), |s| {
            s.compositing.mode = CompositeMode::Isosurface;
            s.compositing.iso_value = 0.4;
            set(s);
        }));
        cases.push(with(v, SIZE, &format!("{name}-mip"), |s| {
            s.compositing.mode = CompositeMode::Mip;
            set(s);
        }));
    }
    // Layered iso-surfaces (every sample marched, translucent outer surface) and lit frames with rule 9's light
    // grid, which keeps the material the plane removes (it shadows what is kept).
    cases.push(with(v, SIZE, "oblique-iso-layers", |s| {
        s.compositing.mode = CompositeMode::Isosurface;
        s.compositing.iso_value = 0.6;
        s.compositing.iso_opacity = 0.5;
        s.compositing.extra_isosurfaces = vec![volcast::scene::lighting::IsoSurface {
            value: 0.3,
            color: Some(Vec3::new(0.9, 0.5, 0.3)),
            opacity: 0.4,
        }];
        s.cut.clip_plane = oblique_plane();
    }));
    cases.push(with(v, SIZE, "oblique-shaded-shadows", |s| {
        s.colour.step_alpha = 0.3;
        s.lighting.shading = Some(Shading::default());
        (s.lighting.shadows, s.lighting.ambient_occlusion) = (true, true);
        s.lighting.light = Light::from_angles(-50.0, 35.0);
        s.cut.clip_plane = oblique_plane();
    }));
    cases.push(with(v, SIZE, "oblique-iso-shadows", |s| {
        s.compositing.mode = CompositeMode::Isosurface;
        s.compositing.iso_value = 0.4;
        (s.lighting.shadows, s.lighting.ambient_occlusion) = (true, true);
        s.lighting.light = Light::from_angles(30.0, 50.0);
        s.cut.clip_plane = oblique_plane().map(ClipPlane::flipped);
    }));
    cases
}

/// Each plane case against the reference, and each must differ from the unclipped frame (the plane matters).
#[test]
fn clipped_frames_match_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let helix = volume::builtin("helix", Some(64)).expect("helix");
    let compute = &[(RaySetup::Analytic, true)];
    for placed in [oblique(&helix), mirrored(&helix)] {
        headless.set_volume(&gpu, &placed).expect("upload volume");
        let cases = plane_cases(&placed);
        let reference = Reference::new(&placed);
        for case in &cases {
            let mut unclipped = case.settings.clone();
            unclipped.cut.clip_plane = None;
            let d = diff(&reference.render(&case.settings), &reference.render(&unclipped));
            assert!(
                d.above(8) > 40,
                "{}-{}: the plane hardly changes the image ({d})",
                placed.name,
                case.name
            );
        }
        judge.run_cases(
            ("reference", REFERENCE),
            &gpu,
            &mut headless,
            &placed,
            cases.clone(),
            METHODS,
        );
        let some: Vec<Case> = cases.into_iter().filter(|c| c.name.starts_with("oblique")).collect();
        judge.run_cases(("reference", REFERENCE), &gpu, &mut headless, &placed, some, compute);
    }
    finish(gpu, headless, judge);
}

/// A plane beyond the box on its normal's side removes everything: every pixel is the background, on the GPU and
/// in the reference. One beyond the other side keeps everything: the very image of no plane (the segment is left
/// untouched, bit for bit).
#[test]
fn planes_beyond_the_box_keep_everything_or_nothing() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let placed = oblique(&volume::builtin("helix", Some(48)).expect("helix"));
    headless.set_volume(&gpu, &placed).expect("upload volume");
    let reference = Reference::new(&placed);
    let mut judge = Judge::default();
    for mode in [CompositeMode::Emission, CompositeMode::Isosurface, CompositeMode::Mip] {
        for &(method, compute) in &[
            (RaySetup::Faces, false),
            (RaySetup::Analytic, false),
            (RaySetup::Analytic, true),
        ] {
            let mut s = with(&placed, 64, "beyond", |s| s.compositing.mode = mode).settings;
            // Channels off the .5 rounding ties of 8-bit output.
            s.background = Vec3::new(0.2, 0.35, 0.45);
            (s.pipeline.ray_setup, s.pipeline.compute) = (method, compute);
            let label = format!("{}-{}-{method:?}-compute-{compute}", placed.name, mode.name());
            let plain = headless.render(&gpu, &s).expect("render").image;
            // The box's half-diagonal is under 60 mm: 1000 mm is beyond it along any normal.
            for normal in [[0.6, -0.5, 0.4], [0.0, 0.0, -1.0]] {
                s.cut.clip_plane = plane(normal, -1000.0);
                let kept = headless.render(&gpu, &s).expect("render").image;
                assert!(kept == plain, "{label}: a plane keeping everything changed the image");
                s.cut.clip_plane = plane(normal, 1000.0);
                let removed = headless.render(&gpu, &s).expect("render").image;
                let bg = background_pixel(s.background);
                let left: Vec<_> = removed.pixels().filter(|p| **p != bg).take(4).collect();
                assert!(
                    left.is_empty(),
                    "{label}: a plane removing everything left pixels {left:?} (background {bg:?})"
                );
                let expected = reference.render_full(&s);
                assert!(
                    expected.object.iter().all(|o| !o),
                    "{label}: the reference kept something"
                );
                judge.against(
                    "reference",
                    format!("{label}-removed"),
                    &removed,
                    &expected,
                    &s,
                    REFERENCE,
                );
            }
            let bg = background_pixel(s.background);
            let shown = plain.pixels().filter(|p| **p != bg).count();
            assert!(
                shown > 100,
                "{label}: the frame without a plane shows only {shown} pixels"
            );
        }
    }
    finish(gpu, headless, judge);
}
