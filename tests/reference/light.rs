//! Rule 9's light grid in the reference against closed forms: in a uniform medium the shadow falls off as
//! e^(−σ·depth) along the light and the occlusion inside is e^(−4σ); nothing absorbs outside the window or past the
//! box; a slab casts its shadow only below it.

use crate::common;

use common::light::LightGridRef;
use common::reference::Reference;
use glam::Vec3;
use volcast::scene::lighting::Light;
use volcast::scene::settings::{RenderSettings, Shading};
use volcast::volume::{Volume, VoxelData, VoxelType};

const N: u32 = 16;

fn volume(value: impl Fn(u32, u32, u32) -> f32) -> Volume {
    let mut data = Vec::new();
    for z in 0..N {
        for y in 0..N {
            for x in 0..N {
                data.push(value(x, y, z));
            }
        }
    }
    let mut v = Volume::new("light", [N; 3], [1.0; 3], VoxelType::F32, VoxelData::F32(data)).unwrap();
    v.range = [0.0, 1.0];
    v
}

/// A lit frame with the simple model: opacity `a` per voxel everywhere in the window [0.25, 1].
fn frame(v: &Volume, a: f32) -> RenderSettings {
    let mut s = RenderSettings::new(8, 8, v.extent());
    s.lighting.shading = Some(Shading::default());
    s.colour.window = [0.25, 1.0];
    s.colour.step_alpha = a;
    (s.lighting.shadows, s.lighting.ambient_occlusion) = (true, true);
    s.lighting.light = Light {
        direction: Some(Vec3::Z),
        ..Light::default()
    };
    s
}

fn grid(v: &Volume, s: &RenderSettings) -> LightGridRef {
    let r = Reference::new(v);
    LightGridRef::new(&r, s, &r.classifier(s), &r.placement(s))
}

#[test]
fn a_uniform_medium_shadows_exponentially_and_occludes_by_four_cells() {
    let v = volume(|_, _, _| 0.5);
    let s = frame(&v, 0.2);
    let g = grid(&v, &s);
    assert_eq!(g.cells(), [16, 16, 16], "one cell per voxel up to 128");
    let sigma = -(1.0 - f64::from(0.2f32)).ln();
    // The light is straight up (+z): the top slice is lit fully, each slice below loses one voxel's worth.
    for z in 0..16 {
        let expected = (-sigma * (15 - z) as f64).exp();
        for (x, y) in [(0, 0), (7, 9), (15, 15)] {
            let t = g.t_cell([x, y, z]);
            assert!(
                (t - expected).abs() < 1e-12,
                "T at ({x},{y},{z}) = {t}, expected {expected}"
            );
        }
    }
    // Inside, every one of the 14 rays crosses 4 absorbing cells of one voxel's length (a unit cube grid).
    let o = g.o_cell([8, 8, 8]);
    assert!((o - (-4.0 * sigma).exp()).abs() < 1e-12, "O inside {o}");
    // At a corner, the rays leaving the box see nothing past its edge: more open than inside.
    assert!(g.o_cell([0, 0, 0]) > o + 0.2);
}

#[test]
fn values_outside_the_window_neither_shadow_nor_occlude() {
    let v = volume(|_, _, _| 0.1);
    let g = grid(&v, &frame(&v, 0.9));
    for c in [[0, 0, 0], [8, 8, 8], [15, 3, 0]] {
        assert_eq!((g.t_cell(c), g.o_cell(c)), (1.0, 1.0), "{c:?}");
    }
}

#[test]
fn a_slab_casts_its_shadow_below_and_not_above() {
    // An absorbing slab at z = 10..=11, empty elsewhere; the light from +z.
    let v = volume(|_, _, z| if (10..=11).contains(&z) { 1.0 } else { 0.0 });
    let s = frame(&v, 0.5);
    let g = grid(&v, &s);
    let sigma = -(0.5f64).ln();
    for z in 12..16 {
        assert!((g.t_cell([8, 8, z]) - 1.0).abs() < 1e-12, "above the slab, z {z}");
    }
    // Cells sample the trilinear value at their centres, which here are the voxels: the slab's two cells absorb.
    assert!((g.t_cell([8, 8, 11]) - (-sigma).exp()).abs() < 1e-12);
    for z in 0..10 {
        let t = g.t_cell([8, 8, z]);
        assert!((t - (-2.0 * sigma).exp()).abs() < 1e-12, "below the slab, z {z}: {t}");
    }
    // A light from the side (+x) leaves the region below the slab lit where no slab lies between.
    let mut side = s.clone();
    side.lighting.light.direction = Some(Vec3::X);
    let g = grid(&v, &side);
    assert!((g.t_cell([8, 8, 3]) - 1.0).abs() < 1e-12);
    assert!(g.t_cell([0, 8, 10]) < 1e-3, "across the whole slab from the side");
}
