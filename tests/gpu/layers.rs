//! Rule 13's layers against the CPU reference under validation: depth order whichever volume holds the nearer
//! thing, overlays on their own (coarser, shifted) grid, a sparse-id label map sampled at the nearest voxel, and
//! label maps lit as surfaces.

use crate::common;

use common::bounds::REFERENCE;
use common::gpu::{finish, validated_gpu, Judge};
use common::layers::RefLayer;
use common::reference::Reference;
use glam::{DMat4, DVec3, Vec3};
use volcast::gpu::Gpu;
use volcast::render::headless::Headless;
use volcast::render::layers::LayerInput;
use volcast::scene::camera::Camera;
use volcast::scene::layers::{Blend, LayerStyle};
use volcast::scene::settings::RenderSettings;
use volcast::transfer::Colormap;
use volcast::volume::geometry::Geometry;
use volcast::volume::labels::{LabelMap, LabelTable};
use volcast::volume::{Volume, VoxelData, VoxelType};

/// A volume's values by position.
type Field = Box<dyn Fn(DVec3) -> f32>;

/// The base's side (voxels of 1 mm) and a layer's (voxels of 2 mm over the same box, shifted by a quarter voxel).
const BASE: u32 = 32;
const LAYER: u32 = 16;

/// A volume of `side`³ voxels of `mm` whose voxel centres start at `origin` mm, valued `f(p)` at the point p
/// of the base's box in [−½, ½]³ (the base's voxel centres span it).
fn volume(name: &str, side: u32, mm: f64, origin: f64, f: impl Fn(DVec3) -> f32) -> Volume {
    let mut data = Vec::with_capacity((side * side * side) as usize);
    let extent = f64::from(BASE);
    for z in 0..side {
        for y in 0..side {
            for x in 0..side {
                let centre = DVec3::new(f64::from(x), f64::from(y), f64::from(z)) * mm + origin;
                data.push(f((centre + 0.5) / extent - 0.5));
            }
        }
    }
    let v = Volume::new(name, [side; 3], [mm as f32; 3], VoxelType::F32, VoxelData::F32(data)).expect("volume");
    let affine = DMat4::from_translation(DVec3::splat(origin)) * DMat4::from_scale(DVec3::splat(mm));
    v.with_geometry(Geometry {
        affine,
        anatomical: false,
    })
    .expect("placed")
}

/// 1 within `core` of 0, falling linearly to 0 at `core + soft` (smooth enough that half a millimetre of the
/// position targets' rounding changes a point-sampled layer's colour by little).
fn soft(d: f64, core: f64, soft: f64) -> f32 {
    (1.0 - (d.abs() - core) / soft).clamp(0.0, 1.0) as f32
}

/// An opaque slab across the view, nearer the eye (`front`) or farther, about 0.12 thick.
fn slab(eye: DVec3, front: bool) -> impl Fn(DVec3) -> f32 {
    let at = if front { 0.25 } else { -0.25 };
    move |p| soft(p.dot(eye) - at, 0.03, 0.06)
}

/// A ball at the centre, radius about 0.15.
fn ball(p: DVec3) -> f32 {
    soft(p.length(), 0.1, 0.1)
}

/// The view straight along an axis, with the base in white (grayscale at 1), opaque per voxel.
fn view(base: &Volume) -> RenderSettings {
    let mut s = RenderSettings::for_volume(64, 64, base);
    s.camera = Camera::orbit(0.0, 0.0, 2.2, Vec3::ZERO);
    s.colour.colormap = Colormap::Grayscale;
    s.colour.window = [0.5, 1.0];
    s.colour.step_alpha = 0.95;
    s.colour.transfer_function = None;
    s.lighting.shading = None;
    s.background = Vec3::ZERO;
    // Rays go on through what is opaque, so a march that put a layer over the base whole, after its own march,
    // would show the layer behind the slab rather than stop at it.
    s.compositing.early_termination = 1.0;
    s
}

/// An overlay shown yellow (plasma's top) where it is at least 0.5, opaque per voxel.
fn yellow() -> LayerStyle {
    LayerStyle {
        window: [0.0, 0.5],
        threshold: Some(0.5),
        colormap: Colormap::Plasma,
        opacity: 0.95,
        ..LayerStyle::default()
    }
}

fn overlay_input(volume: &Volume) -> LayerInput<'_> {
    LayerInput { volume, labels: None }
}

/// The frame of `s` without its layers (the renderer keeps them).
fn base_alone(gpu: &Gpu, headless: &mut Headless, s: &RenderSettings) -> image::RgbaImage {
    let alone = RenderSettings {
        layers: Vec::new(),
        ..s.clone()
    };
    headless.render(gpu, &alone).expect("render").image
}

fn render_layered(
    gpu: &Gpu,
    headless: &mut Headless,
    base: &Volume,
    inputs: &[LayerInput],
    s: &RenderSettings,
) -> image::RgbaImage {
    headless.set_volume(gpu, base).expect("upload");
    headless.renderer.set_layers(gpu, inputs).expect("layers");
    headless.render(gpu, s).expect("render").image
}

/// The centre pixel: grey (the base's colour: blue as strong as red) or yellow (the overlay's: little blue).
fn centre_is_white(image: &image::RgbaImage) -> bool {
    let p = image.get_pixel(32, 32);
    assert!(p[0] > 80, "the centre shows something: {p:?}");
    2 * u32::from(p[2]) > u32::from(p[0])
}

#[test]
fn what_is_nearer_hides_what_is_behind_whichever_volume_holds_it() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let probe = volume("probe", BASE, 1.0, 0.0, |_| 0.0);
    let eye = view(&probe).camera.eye.as_dvec3().normalize();
    for front in [true, false] {
        for slab_is_base in [true, false] {
            let (base_f, layer_f): (Field, Field) = if slab_is_base {
                (Box::new(slab(eye, front)), Box::new(ball))
            } else {
                (Box::new(ball), Box::new(slab(eye, front)))
            };
            let base = volume("base", BASE, 1.0, 0.0, base_f);
            // The layer on its own grid: 2 mm voxels, shifted so its box matches the base's.
            let layer = volume("layer", LAYER, 2.0, 0.5, layer_f);
            let mut s = view(&base);
            s.layers = vec![yellow()];
            let inputs = [LayerInput {
                volume: &layer,
                labels: None,
            }];
            let actual = render_layered(&gpu, &mut headless, &base, &inputs, &s);
            let reference = Reference::new(&base).with_layers(vec![RefLayer::overlay(&layer)]);
            let label = format!(
                "slab-{}-in-{}",
                if front { "front" } else { "behind" },
                if slab_is_base { "base" } else { "layer" }
            );
            judge.against(
                "layers",
                label.clone(),
                &actual,
                &reference.render_full(&s),
                &s,
                REFERENCE,
            );
            // The slab in front hides the ball; behind, the ball shows. White is the base's colour.
            let shows_slab = front;
            assert_eq!(centre_is_white(&actual), shows_slab == slab_is_base, "{label}");
        }
    }
    finish(gpu, headless, judge);
}

#[test]
fn a_signed_overlay_and_sparse_labels_on_their_own_grids_match_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    // A faint base, a signed overlay on a shifted 2 mm grid and a label map with sparse ids on another, both over
    // a part of the base only: where they show nothing, the base keeps its strides.
    let base = volume("base", BASE, 1.0, 0.0, |p| soft(p.abs().max_element(), 0.3, 0.05));
    let z = volume("z", LAYER, 2.0, 1.5, |p| {
        if p.x > 0.1 {
            (8.0 * (p.y * 9.0).sin() * (0.45 - p.length()).max(0.0)) as f32
        } else {
            0.0
        }
    });
    let ids = volume("ids", LAYER, 2.0, 0.75, |p| {
        if p.y > 0.3 {
            70_000.0
        } else if p.x > 0.35 && p.z > 0.2 {
            5.0
        } else {
            0.0
        }
    });
    let map = LabelMap::of(&ids).expect("labels");
    assert_eq!(map.ids, [0, 5, 70_000]);
    let table = LabelTable::default();
    let rgba: Vec<[u8; 4]> = map.ids.iter().map(|&id| table.rgba(id)).collect();
    let mut s = view(&base);
    s.colour.step_alpha = 0.03;
    s.colour.window = [0.05, 1.0];
    s.camera = Camera::orbit(30.0, 20.0, 2.2, Vec3::ZERO);
    // Rule 2's strides in the faint base, and every sample where a layer may show something (rule 13).
    (s.sampling.step_length, s.sampling.max_stride) = (0.4, 4);
    let mut zs = LayerStyle::overlay([-8.0, 8.0], Some(0.6));
    zs.opacity = 0.4;
    let mut ls = LayerStyle::labels();
    ls.opacity = 0.3;
    s.layers = vec![zs, ls];
    let inputs = [
        LayerInput {
            volume: &z,
            labels: None,
        },
        LayerInput {
            volume: &ids,
            labels: Some((&map, rgba)),
        },
    ];
    let actual = render_layered(&gpu, &mut headless, &base, &inputs, &s);
    let reference = Reference::new(&base).with_layers(vec![
        RefLayer::overlay(&z),
        RefLayer::labels(&ids, move |id| table.rgba(id)),
    ]);
    let expected = reference.render_full(&s);
    // The strides are in play: fewer samples than with every one taken.
    let mut every = s.clone();
    every.sampling.max_stride = 1;
    let (strided, all) = (expected.stats.samples, reference.render_full(&every).stats.samples);
    assert!(strided < all, "the base takes strides: {strided} of {all} samples");
    eprintln!("strides take {strided} of {all} samples");
    judge.against("layers", "signed-and-labels".into(), &actual, &expected, &s, REFERENCE);
    finish(gpu, headless, judge);
}

/// Rule 13's other blends: an overlay blended by addition and one by maximum, each on its own grid, match the
/// reference; neither absorbs (every pixel is at least the base's alone), and the maximum of a ball behind an
/// opaque slab is hidden by it, as depth demands.
#[test]
fn overlays_blended_by_maximum_and_addition_match_the_reference_and_absorb_nothing() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let base = volume("base", BASE, 1.0, 0.0, |p| soft(p.abs().max_element(), 0.3, 0.05));
    let shifted = |dx: f64| move |p: DVec3| 4.0 * ball(p - DVec3::new(dx, 0.0, 0.0));
    let added = volume("added", LAYER, 2.0, 1.5, shifted(0.12));
    let peak = volume("peak", LAYER, 2.0, 0.75, shifted(-0.12));
    let mut s = view(&base);
    (s.colour.step_alpha, s.colour.window) = (0.03, [0.05, 1.0]);
    s.camera = Camera::orbit(30.0, 20.0, 2.2, Vec3::ZERO);
    let blended = |blend, opacity, colormap| LayerStyle {
        blend,
        opacity,
        colormap,
        ..LayerStyle::overlay([0.0, 4.0], Some(0.5))
    };
    s.layers = vec![
        LayerStyle {
            tint: Some([40, 255, 90]),
            ..blended(Blend::Add, 0.15, Colormap::Viridis)
        },
        blended(Blend::Max, 0.8, Colormap::Plasma),
    ];
    let actual = render_layered(
        &gpu,
        &mut headless,
        &base,
        &[overlay_input(&added), overlay_input(&peak)],
        &s,
    );
    let reference = Reference::new(&base).with_layers(vec![RefLayer::overlay(&added), RefLayer::overlay(&peak)]);
    judge.against(
        "layers",
        "add-and-max".into(),
        &actual,
        &reference.render_full(&s),
        &s,
        REFERENCE,
    );
    let alone = base_alone(&gpu, &mut headless, &s);
    let lit = actual
        .pixels()
        .zip(alone.pixels())
        .filter(|(a, b)| a[1] > b[1] + 8)
        .count();
    assert!(lit > 100, "the blended balls show: {lit} pixels brighter");
    for (a, b) in actual.pixels().zip(alone.pixels()) {
        assert!(
            (0..3).all(|c| u16::from(a[c]) + 1 >= u16::from(b[c])),
            "a blend absorbed: {a:?} under {b:?} alone"
        );
    }
    // Depth: an opaque slab in front hides the maximum of the ball behind it; behind it, the ball shows.
    let eye = view(&base).camera.eye.as_dvec3().normalize();
    for front in [true, false] {
        let slab_base = volume("slab", BASE, 1.0, 0.0, slab(eye, front));
        let ball_layer = volume("ball", LAYER, 2.0, 0.5, |p| 4.0 * ball(p));
        // A red slab (cool-warm's top: little green), so that the ball's yellow light added over it shows.
        let mut s = view(&slab_base);
        s.colour.colormap = Colormap::CoolWarm;
        s.layers = vec![blended(Blend::Max, 0.95, Colormap::Plasma)];
        let actual = render_layered(&gpu, &mut headless, &slab_base, &[overlay_input(&ball_layer)], &s);
        let reference = Reference::new(&slab_base).with_layers(vec![RefLayer::overlay(&ball_layer)]);
        let label = format!("max-{}-slab", if front { "behind" } else { "before" });
        judge.against(
            "layers",
            label.clone(),
            &actual,
            &reference.render_full(&s),
            &s,
            REFERENCE,
        );
        let alone = base_alone(&gpu, &mut headless, &s);
        let (a, b) = (actual.get_pixel(32, 32), alone.get_pixel(32, 32));
        let brighter = i32::from(a[1]) - i32::from(b[1]);
        assert!(
            if front { brighter <= 12 } else { brighter >= 40 },
            "{label}: {a:?} over {b:?} alone"
        );
    }
    finish(gpu, headless, judge);
}

/// Rule 13's label surfaces: with shading on, a label map (a ball of one id and a box of another, on a 2 mm grid
/// shifted from the base's) is lit along its smoothed indicator's normal, as the reference lights it; the ball's
/// middle faces the headlight and is brighter than its rim.
#[test]
fn label_maps_are_lit_as_smooth_surfaces_as_the_reference_lights_them() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let base = volume("base", BASE, 1.0, 0.0, |p| soft(p.abs().max_element(), 0.3, 0.05));
    let ids = volume("ids", LAYER, 2.0, 0.75, |p| {
        if p.length() < 0.28 {
            9.0
        } else if p.x > 0.3 && p.y < -0.1 {
            4.0
        } else {
            0.0
        }
    });
    let map = LabelMap::of(&ids).expect("labels");
    let table = LabelTable::default();
    let rgba: Vec<[u8; 4]> = map.ids.iter().map(|&id| table.rgba(id)).collect();
    let mut s = view(&base);
    (s.colour.step_alpha, s.colour.window) = (0.02, [0.05, 1.0]);
    s.camera = Camera::orbit(25.0, 15.0, 2.2, Vec3::ZERO);
    s.lighting.shading = Some(Default::default());
    s.compositing.early_termination = 0.99;
    s.layers = vec![LayerStyle::labels()];
    let inputs = [LayerInput {
        volume: &ids,
        labels: Some((&map, rgba)),
    }];
    let actual = render_layered(&gpu, &mut headless, &base, &inputs, &s);
    let reference = Reference::new(&base).with_layers(vec![RefLayer::labels(&ids, move |id| table.rgba(id))]);
    judge.against(
        "layers",
        "lit-labels".into(),
        &actual,
        &reference.render_full(&s),
        &s,
        REFERENCE,
    );
    let brightness = |x: u32| {
        actual.get_pixel(x, 32).0[..3]
            .iter()
            .map(|&c| u32::from(c))
            .sum::<u32>()
    };
    let (middle, rim) = (brightness(32), brightness(32 - 17));
    assert!(
        middle > rim + 60,
        "the ball's middle ({middle}) is lit more than its rim ({rim})"
    );
    finish(gpu, headless, judge);
}
