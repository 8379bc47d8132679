//! Rule 10's clipping plane in the CPU reference against closed forms (no GPU): where a ray's segment ends on the
//! plane, the extremum a MIP/MinIP frame then finds on a ramp, iso-surfaces cut open rather than capped, and the
//! planes beyond the box.

use crate::common;

use common::reference::{background_pixel, Reference};
use glam::Vec3;
use volcast::scene::camera::Camera;
use volcast::scene::clip::ClipPlane;
use volcast::scene::settings::{CompositeMode, RenderSettings};
use volcast::volume::{Volume, VoxelData, VoxelType};

/// `dims` voxels of 1 mm (float32) with value `f(i, j, k)`.
fn volume(dims: [u32; 3], f: impl Fn(u32, u32, u32) -> f32) -> Volume {
    let mut values = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                values.push(f(i, j, k));
            }
        }
    }
    Volume::new("clip-test", dims, [1.0; 3], VoxelType::F32, VoxelData::F32(values)).expect("volume")
}

/// A 9×9 orthographic frame looking along +x: pixel (4, 4)'s ray runs along the x axis through the box's centre.
fn along_x(v: &Volume) -> RenderSettings {
    let mut s = RenderSettings::new(9, 9, v.extent());
    s.camera = Camera::looking_at(Vec3::new(-2.0, 0.0, 0.0), Vec3::ZERO);
    s.camera.ortho = true;
    s.sampling.jitter = None;
    s
}

fn plane(normal: Vec3, offset: f32) -> Option<ClipPlane> {
    Some(ClipPlane::new(normal, offset).expect("valid plane"))
}

/// The ramp v = i/31 along x (32 voxels, voxel i at x = i − 15.5 mm from the centre), so v(x) = (x + 15.5)/31.
/// Keeping x ≤ 5 mm (normal −x, offset −5) ends the centre ray exactly on the plane, and its MIP is the last
/// sample before it: within one step (1 voxel, 1/31 of value) below v(5). The flipped plane starts the ray there,
/// and MinIP is within a step above v(5).
#[test]
fn a_plane_ends_the_segment_exactly_and_bounds_the_extremum() {
    let v = volume([32, 8, 8], |i, _, _| i as f32);
    let reference = Reference::new(&v);
    let world_per_mm = 1.0 / 32.0;
    let ramp = |x_mm: f64| (x_mm + 15.5) / 31.0;
    let keep_low = plane(-Vec3::X, -5.0);
    let mut s = along_x(&v);
    s.compositing.mode = CompositeMode::Mip;
    s.colour.window = [0.0, 1.0];
    s.cut.clip_plane = keep_low;
    let t = reference.trace(&s, 4, 4);
    let seg = t.segment.expect("a segment");
    assert!((seg.at(seg.t_end).x / world_per_mm - 5.0).abs() < 1e-9, "{seg:?}");
    assert!((seg.at(seg.t_start).x / world_per_mm + 16.0).abs() < 1e-9, "{seg:?}");
    assert!(!seg.clipped_start);
    let m = t.value.expect("a visible sample");
    assert!(
        m <= ramp(5.0) && m > ramp(5.0) - 1.0 / 31.0,
        "MIP {m} vs v(5) {}",
        ramp(5.0)
    );

    s.cut.clip_plane = keep_low.map(ClipPlane::flipped);
    s.compositing.mode = CompositeMode::MinIp;
    let t = reference.trace(&s, 4, 4);
    let seg = t.segment.expect("a segment");
    assert!((seg.at(seg.t_start).x / world_per_mm - 5.0).abs() < 1e-9, "{seg:?}");
    assert!(seg.clipped_start);
    let m = t.value.expect("a visible sample");
    assert!(
        m >= ramp(5.0) && m < ramp(5.0) + 1.0 / 31.0,
        "MinIP {m} vs v(5) {}",
        ramp(5.0)
    );
}

/// A solid cube (value 1 on voxels 4..=11 of 16, 0 elsewhere; voxel i at x = i − 7.5 mm) under an iso-surface at
/// 0.5, its faces at x = ±4 mm. The slab box cut at the centre caps the solid: the ray's first sample is inside,
/// so the surface is met there (x = 0.5 mm, the first sample). The plane through the centre cuts it open: the
/// ray meets the surface only where it leaves the solid, at x = 4 mm (8 bisection steps: within 1/256 mm).
#[test]
fn iso_surfaces_are_cut_open_by_the_plane_and_capped_by_the_slab() {
    let inside = |i: u32| (4..12).contains(&i);
    let v = volume([16; 3], |i, j, k| {
        f32::from(u8::from(inside(i) && inside(j) && inside(k)))
    });
    let reference = Reference::new(&v);
    let world_per_mm = 1.0 / 16.0;
    let mut s = along_x(&v);
    s.compositing.mode = CompositeMode::Isosurface;
    s.compositing.iso_value = 0.5;

    let mut capped = s.clone();
    capped.cut.set_slab(0, 0.75, 0.5);
    let t = reference.trace(&capped, 4, 4);
    let hit = t.hit.expect("the cap") / world_per_mm;
    let start = t.segment.expect("a segment").t_start / world_per_mm;
    assert!(
        (hit - start - 0.5).abs() < 1e-9,
        "capped at the first sample: {hit} from {start}"
    );

    s.cut.clip_plane = plane(Vec3::X, 0.0);
    let t = reference.trace(&s, 4, 4);
    let seg = t.segment.expect("a segment");
    assert!(seg.clipped_start);
    let x = seg.at(t.hit.expect("the far face")).x / world_per_mm;
    assert!(
        (x - 4.0).abs() < 1.0 / 256.0,
        "the surface is met leaving the solid, at x = {x}"
    );
}

/// Beyond the box (its half-diagonal is under 30 mm): keeping everything is the frame without a plane, and
/// removing everything leaves the background.
#[test]
fn planes_beyond_the_box() {
    let v = volume([12, 10, 8], |i, j, k| (i * j + k) as f32);
    let reference = Reference::new(&v);
    let mut s = RenderSettings::new(24, 20, v.extent());
    s.colour.step_alpha = 0.4;
    let plain = reference.render(&s);
    for normal in [Vec3::new(0.3, -0.2, 0.9), Vec3::Y] {
        s.cut.clip_plane = plane(normal, -30.0);
        assert!(
            reference.render(&s) == plain,
            "{normal}: keeping everything changed the frame"
        );
        s.cut.clip_plane = plane(normal, 30.0);
        let bg = background_pixel(s.background);
        assert!(reference.render(&s).pixels().all(|p| *p == bg), "{normal}");
    }
}
