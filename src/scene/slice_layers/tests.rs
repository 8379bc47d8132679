use super::*;
use crate::scene::slice::{mm_from_index, SliceView};
use crate::volume::labels::{LabelEntry, LabelMap, LabelTable};
use crate::volume::{Volume, VoxelData, VoxelType};

const GREY: u8 = 100;

/// The base: 8³ voxels of 1 mm; its axial slice through the middle, grey.
fn base() -> (Geometry, DMat4, SliceFrame, Vec<u8>) {
    let geometry = Geometry::from_spacing([1.0; 3]);
    let mm = mm_from_index(&geometry, false);
    let frame = SliceFrame::new(SliceView::Axial, false, mm, [8; 3], DVec3::new(3.5, 3.5, 3.5), 64);
    let rgba = [GREY, GREY, GREY, 255].repeat((frame.width * frame.height) as usize);
    (geometry, mm, frame, rgba)
}

/// A label map of 4³ voxels of 2 mm (its own grid, not the base's) holding id 7 at voxels 1–2 across x and y.
fn labels() -> Layers {
    let mut ids = vec![0u8; 64];
    for z in 0..4 {
        for y in 1..3 {
            for x in 1..3 {
                ids[x + 4 * (y + 4 * z)] = 7;
            }
        }
    }
    let v = Volume::new("atlas", [4; 3], [2.0; 3], VoxelType::U8, VoxelData::U8(ids)).expect("volume");
    let map = LabelMap::of(&v).expect("labels");
    let table = LabelTable {
        entries: vec![LabelEntry {
            id: 7,
            name: "Thalamus".into(),
            rgba: [255, 0, 0, 255],
        }],
    };
    let mut layers = Layers::default();
    layers
        .add_labels(v, map, table, "atlas.nii", &Default::default())
        .expect("added");
    layers
}

#[test]
fn labels_are_filled_at_their_opacity_and_outlined_on_their_own_grid() {
    let (geometry, mm, frame, mut rgba) = base();
    let layers = labels();
    let mut styles = layers.styles.clone();
    styles[0].opacity = 0.5;
    paint(&mut rgba, &geometry, mm, &frame, &layers, &styles);
    let (mut filled, mut outlined) = (0, 0);
    for y in 0..frame.height {
        for x in 0..frame.width {
            let w = frame.world(DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5));
            // The base's index is its millimetres; the atlas's nearest voxel is floor(mm/2 + ½).
            let inside = [w.x, w.y]
                .iter()
                .all(|&c| (1.0..=2.0).contains(&(c / 2.0 + 0.5).floor()));
            let i = ((y * frame.width + x) * 4) as usize;
            let p = &rgba[i..i + 3];
            match (inside, p) {
                (false, p) => assert_eq!(p, [GREY; 3], "outside the label at {w}"),
                (true, [255, 0, 0]) => outlined += 1,
                (true, [r, g, b]) => {
                    assert_eq!((*r, *g, *b), (178, 50, 50), "half red over grey at {w}");
                    filled += 1;
                }
                _ => unreachable!(),
            }
        }
    }
    // Base voxels 1–4 on each axis are labelled: a 4×4 square whose 12 rim pixels are its outline.
    assert_eq!((filled, outlined), (4, 12));
}

#[test]
fn hidden_layers_and_ids_show_nothing() {
    let (geometry, mm, frame, mut rgba) = base();
    let layers = labels();
    let mut styles = layers.styles.clone();
    styles[0].visible = false;
    paint(&mut rgba, &geometry, mm, &frame, &layers, &styles);
    assert!(rgba.chunks(4).all(|p| p[..3] == [GREY; 3]));
    let mut hidden = labels();
    let looks = crate::scene::layer_set::Looks {
        label_ids: vec![3],
        ..Default::default()
    };
    let (v, map, table) = (
        hidden.volumes.remove(0),
        hidden.labels.remove(0).expect("labels").0,
        hidden.tables.remove(0),
    );
    let mut layers = Layers::default();
    layers.add_labels(v, map, table, "atlas", &looks).expect("added");
    paint(&mut rgba, &geometry, mm, &frame, &layers, &layers.styles.clone());
    assert!(
        rgba.chunks(4).all(|p| p[..3] == [GREY; 3]),
        "id 7 is not among --label-ids 3"
    );
}

#[test]
fn a_signed_overlay_shows_beyond_its_threshold_on_both_sides() {
    let (geometry, mm, frame, mut rgba) = base();
    let values: Vec<f32> = (0..512).map(|i| (i % 8) as f32 - 4.0).collect();
    let v = Volume::new("z", [8; 3], [1.0; 3], VoxelType::F32, VoxelData::F32(values)).expect("volume");
    let mut layers = Layers::default();
    let looks = crate::scene::layer_set::Looks {
        threshold: Some(2.5),
        ..Default::default()
    };
    layers.add_overlay(v, "z.nii", &looks).expect("added");
    assert!(layers.styles[0].signed);
    paint(&mut rgba, &geometry, mm, &frame, &layers, &layers.styles.clone());
    for y in 0..frame.height {
        for x in 0..frame.width {
            let w = frame.world(DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5));
            let z = w.x.clamp(0.0, 7.0) - 4.0;
            let i = ((y * frame.width + x) * 4) as usize;
            let grey = rgba[i..i + 3] == [GREY; 3];
            assert_eq!(grey, z.abs() < 2.5, "z {z} at {w}: {:?}", &rgba[i..i + 3]);
        }
    }
    let probe = values_at(&geometry, mm, DVec3::new(7.0, 3.0, 3.0), &layers);
    assert_eq!(probe, vec!["z.nii: 3.000".to_string()]);
}

#[test]
fn the_probe_names_the_label_under_the_cursor() {
    let (geometry, mm, _, _) = base();
    let layers = labels();
    let at = |x: f64| values_at(&geometry, mm, DVec3::new(x, 3.0, 3.0), &layers);
    assert_eq!(at(3.0), vec!["atlas.nii: 7 Thalamus".to_string()]);
    assert_eq!(at(6.0), vec!["atlas.nii: 0 none".to_string()]);
    assert!(at(20.0).is_empty(), "outside the atlas's box");
}
