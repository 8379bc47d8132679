use super::*;
use crate::volume::{VoxelData, VoxelType};
use glam::DVec4;

/// A float volume whose value at each voxel is a linear function of its world (RAS) position, placed obliquely-free
/// but flipped and anisotropic: stored L→R along i (LAS), 1.5 mm voxels along j.
fn linear_volume(f: impl Fn(DVec3) -> f64) -> (Volume, DMat4) {
    let dims = [12u32, 10, 8];
    let affine = DMat4::from_cols(
        DVec4::new(-1.0, 0.0, 0.0, 0.0),
        DVec4::new(0.0, 1.5, 0.0, 0.0),
        DVec4::new(0.0, 0.0, 2.0, 0.0),
        DVec4::new(20.0, -5.0, 3.0, 1.0),
    );
    let mut data = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let w = affine.transform_point3(DVec3::new(f64::from(i), f64::from(j), f64::from(k)));
                data.push(f(w) as f32);
            }
        }
    }
    let v = Volume::new("linear", dims, [1.0; 3], VoxelType::F32, VoxelData::F32(data))
        .and_then(|v| v.with_geometry(Geometry::anatomical(affine)))
        .expect("valid volume");
    (v, affine)
}

#[test]
fn samples_equal_voxels_at_centres_and_interpolate_linear_fields_exactly() {
    let (v, affine) = linear_volume(|w| 3.0 * w.x - 2.0 * w.y + 0.5 * w.z);
    let inv = affine.inverse();
    for (i, j, k) in [(0, 0, 0), (11, 9, 7), (5, 3, 2)] {
        let w = affine.transform_point3(DVec3::new(f64::from(i), f64::from(j), f64::from(k)));
        let s = sample(&v, inv, w).expect("inside");
        assert!((s - v.value(i, j, k)).abs() < 1e-4, "{s} vs {}", v.value(i, j, k));
    }
    // Between centres a linear field is reproduced exactly by trilinear interpolation.
    let w = affine.transform_point3(DVec3::new(4.3, 6.7, 1.2));
    let expect = 3.0 * w.x - 2.0 * w.y + 0.5 * w.z;
    assert!((sample(&v, inv, w).unwrap() - expect).abs() < 1e-3);
    // Outside the voxels' outer faces there is nothing.
    assert!(sample(&v, inv, affine.transform_point3(DVec3::new(-0.6, 0.0, 0.0))).is_none());
    assert!(sample(&v, inv, affine.transform_point3(DVec3::new(11.4, 9.0, 7.0))).is_some());
}

#[test]
fn views_are_oriented_as_slicer_shows_them() {
    // Value = the RAS coordinate along each axis in turn; read which way it grows across each view.
    for axis in 0..3 {
        let (v, affine) = linear_volume(move |w| w[axis]);
        let centre = affine.transform_point3(DVec3::new(5.5, 4.5, 3.5));
        for view in SliceView::ALL {
            let frame = SliceFrame::new(view, true, affine, v.dims, centre, 512);
            let inv = affine.inverse();
            let at = |x: f64, y: f64| {
                sample(
                    &v,
                    inv,
                    frame.world(DVec2::new(x * f64::from(frame.width), y * f64::from(frame.height))),
                )
                .unwrap()
            };
            let rightward = at(0.7, 0.5) - at(0.3, 0.5);
            let downward = at(0.5, 0.7) - at(0.5, 0.3);
            // Right on screen is the patient's left (R decreases) in axial and coronal; posterior in sagittal.
            // Down is posterior (axial) or inferior.
            let (right_axis, right_sign, down_axis, down_sign) = match view {
                SliceView::Axial => (0, -1.0, 1, -1.0),
                SliceView::Coronal => (0, -1.0, 2, -1.0),
                SliceView::Sagittal => (1, -1.0, 2, -1.0),
            };
            let expect_right = if axis == right_axis { right_sign } else { 0.0 };
            let expect_down = if axis == down_axis { down_sign } else { 0.0 };
            assert_eq!(
                rightward.signum() * (rightward.abs() > 1e-6) as i32 as f64,
                expect_right,
                "{view:?} {axis}"
            );
            assert_eq!(
                downward.signum() * (downward.abs() > 1e-6) as i32 as f64,
                expect_down,
                "{view:?} {axis}"
            );
            // The view's own axis is constant on it: the crosshair's coordinate.
            if axis == view.normal_axis() {
                assert!((at(0.5, 0.5) - centre[axis]).abs() < 1e-3);
            }
        }
    }
}

#[test]
fn frames_cover_the_box_pass_through_the_point_and_map_back() {
    let (v, affine) = linear_volume(|w| w.x);
    let p = affine.transform_point3(DVec3::new(2.0, 7.0, 5.0));
    let corners = box_corners_mm(affine, v.dims);
    for view in SliceView::ALL {
        let frame = SliceFrame::new(view, true, affine, v.dims, p, 512);
        // The point lies on the plane, and image ↔ world round-trips.
        let back = frame.world(frame.image(p));
        assert!(back.distance(p) < 1e-9, "{view:?}");
        // Pixels are the smallest voxel side (1 mm) and the image spans the box: 12 × 15 × 16 mm.
        assert_eq!(frame.pixel, 1.0);
        let sides = match view {
            SliceView::Axial => (12, 15),
            SliceView::Coronal => (12, 16),
            SliceView::Sagittal => (15, 16),
        };
        assert_eq!((frame.width, frame.height), sides, "{view:?}");
        // An axis-aligned box's section is the whole image.
        let section = frame.section(&corners);
        assert_eq!(section.len(), 4, "{view:?}: {section:?}");
        for q in &section {
            assert!(q.x.abs() < 1e-6 || (q.x - f64::from(frame.width)).abs() < 1e-6);
            assert!(q.y.abs() < 1e-6 || (q.y - f64::from(frame.height)).abs() < 1e-6);
        }
        // A large volume is shown with coarser pixels.
        let small = SliceFrame::new(view, true, affine, v.dims, p, 6);
        assert!(small.width <= 6 && small.height <= 6 && small.pixel > 1.0);
    }
}

#[test]
fn a_plane_crosses_a_slice_along_a_line_on_that_plane() {
    let (v, affine) = linear_volume(|w| w.x);
    let centre = affine.transform_point3(DVec3::new(5.5, 4.5, 3.5));
    let frame = SliceFrame::new(SliceView::Axial, true, affine, v.dims, centre, 512);
    let normal = DVec3::new(1.0, 1.0, 0.5).normalize();
    let point = centre + DVec3::new(1.0, -2.0, 0.0);
    let (a, b) = frame.line_of_plane(point, normal).expect("not parallel");
    for t in [0.0, 0.3, 1.0] {
        let w = frame.world(a + (b - a) * t);
        assert!((w - point).dot(normal).abs() < 1e-6, "on the plane");
    }
    // A plane parallel to the slice has no line.
    assert!(frame.line_of_plane(point, DVec3::Z).is_none());
}

#[test]
fn window_level_maps_data_units_and_drags() {
    let wl = WindowLevel {
        window: 400.0,
        level: 40.0,
    };
    assert_eq!(wl.grey(-160.0), 0.0);
    assert_eq!(wl.grey(240.0), 1.0);
    assert!((wl.grey(40.0) - 0.5).abs() < 1e-12);
    assert_eq!(wl.grey(f64::NAN), 0.0);
    let d = wl.dragged(10.0, -5.0, [-1024.0, 3071.0]);
    assert!(d.window > wl.window && d.level < wl.level);
    // The window never collapses.
    assert!(wl.dragged(-1e6, 0.0, [0.0, 1.0]).window > 0.0);
}

#[test]
fn rendered_slices_show_the_window_and_nothing_outside() {
    let (v, affine) = linear_volume(|w| w.x);
    let centre = affine.transform_point3(DVec3::new(5.5, 4.5, 3.5));
    let frame = SliceFrame::new(SliceView::Axial, true, affine, v.dims, centre, 512);
    let wl = WindowLevel {
        window: 11.0,
        level: 14.5,
    };
    let rgba = render(&v, affine, &frame, wl);
    assert_eq!(rgba.len(), (frame.width * frame.height * 4) as usize);
    // Left edge: the patient's right (x = 20, above the window: white); right edge: x = 9 (black).
    let px = |x: u32, y: u32| rgba[((y * frame.width + x) * 4) as usize];
    assert_eq!(px(0, 3), 255);
    assert_eq!(px(frame.width - 1, 3), 0);
    assert!(
        rgba.chunks(4).all(|p| p[3] == 255),
        "the box fills an axis-aligned slice"
    );
    // Through a point outside the volume, the slice is empty.
    let outside = SliceFrame::new(SliceView::Axial, true, affine, v.dims, centre + DVec3::Z * 100.0, 512);
    assert!(render(&v, affine, &outside, wl).iter().all(|&b| b == 0));
}

#[test]
fn a_plane_cuts_a_box_in_an_ordered_polygon() {
    let corners: [DVec3; 8] =
        std::array::from_fn(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64));
    // z = 0.5: the unit square, its corners in order (each next to the last).
    let square = plane_section(&corners, DVec3::Z, 0.5);
    assert_eq!(square.len(), 4);
    for (k, p) in square.iter().enumerate() {
        assert!((p.z - 0.5).abs() < 1e-12);
        assert!((p.distance(square[(k + 1) % 4]) - 1.0).abs() < 1e-12, "{square:?}");
    }
    // x + y + z = 1.5: a regular hexagon of side √2/2.
    let hexagon = plane_section(&corners, DVec3::ONE, 1.5);
    assert_eq!(hexagon.len(), 6);
    for (k, p) in hexagon.iter().enumerate() {
        assert!((p.element_sum() - 1.5).abs() < 1e-12);
        assert!(
            (p.distance(hexagon[(k + 1) % 6]) - 0.5f64.sqrt()).abs() < 1e-12,
            "{hexagon:?}"
        );
    }
    // Missing the box, or touching only a corner: nothing.
    assert!(plane_section(&corners, DVec3::Z, 2.0).is_empty());
    assert!(plane_section(&corners, DVec3::ONE, 3.0).is_empty());
}
