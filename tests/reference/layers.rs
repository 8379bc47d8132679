//! Rule 13 in the reference: label surfaces are lit along a normal that follows the surface the ids sample, not the
//! staircase of their voxel faces.

use crate::common;

use common::layers::RefLayer;
use glam::DVec3;
use volcast::volume::{Volume, VoxelData, VoxelType};

const SIDE: u32 = 24;
const RADIUS: f64 = 8.3;

/// A ball of id 3 (radius 8.3 voxels, centred in a 24³ map of 1 mm voxels), 0 around it.
fn ball() -> Volume {
    let c = f64::from(SIDE - 1) / 2.0;
    let mut ids = Vec::new();
    for z in 0..SIDE {
        for y in 0..SIDE {
            for x in 0..SIDE {
                let d = (DVec3::new(f64::from(x), f64::from(y), f64::from(z)) - c).length();
                ids.push(if d <= RADIUS { 3u8 } else { 0 });
            }
        }
    }
    Volume::new("ball", [SIDE; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(ids)).expect("volume")
}

/// Where a ray from outside towards the centre along −dir first meets id 3 at the nearest voxel (as a march does,
/// in steps of 0.02 voxels): the point, and the face of the voxel grid it crossed (the staircase's normal).
fn first_hit(dir: DVec3) -> (DVec3, DVec3) {
    let c = DVec3::splat(f64::from(SIDE - 1) / 2.0);
    let inside = |p: DVec3| (p + 0.5).floor() - c;
    let mut p = c + dir * (RADIUS + 2.0);
    loop {
        let next = p - dir * 0.02;
        if inside(next).length() <= RADIUS {
            let crossed = (next + 0.5).floor() - (p + 0.5).floor();
            return (next, crossed.normalize());
        }
        p = next;
    }
}

/// On a voxelised ball, the label normal at the first sample a ray takes inside it lies within a few degrees of
/// the true (radial) one on average, where the faces' staircase is off by about 38°.
#[test]
fn label_normals_follow_the_surface_not_the_voxel_faces() {
    let layer = RefLayer::labels(&ball(), |_| [255; 4]);
    let (mut smooth, mut stairs, mut worst) = (0.0, 0.0, 0.0f64);
    let n = 400;
    for k in 0..n {
        // A Fibonacci sphere of directions.
        let z = 1.0 - 2.0 * (f64::from(k) + 0.5) / f64::from(n);
        let phi = f64::from(k) * 2.399_963_229_728_653;
        let dir = DVec3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z);
        let (p, face) = first_hit(dir);
        let radial = (p - DVec3::splat(f64::from(SIDE - 1) / 2.0)).normalize();
        let g = -layer.label_gradient(p, 3);
        assert!(g.length() > 0.0, "no normal at {p}");
        let angle = g.normalize().dot(radial).clamp(-1.0, 1.0).acos().to_degrees();
        smooth += angle / f64::from(n);
        stairs += face.dot(radial).abs().clamp(-1.0, 1.0).acos().to_degrees() / f64::from(n);
        worst = worst.max(angle);
    }
    eprintln!("label normal off the radial one: mean {smooth:.1}°, worst {worst:.1}°; voxel faces: mean {stairs:.1}°");
    assert!(
        smooth < 12.0 && stairs > 3.0 * smooth,
        "mean {smooth:.1}° against the faces' {stairs:.1}°"
    );
    assert!(worst < 35.0, "worst {worst:.1}°");
}
