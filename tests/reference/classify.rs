//! Rule 4 in the reference: its classification (tests/common/classify.rs) against published values and closed
//! forms, multiplied alpha on a head-on ray, and the library's table (`function::bake`, what the GPU reads)
//! against the reference.

use crate::common;

use super::scenes::{assert_near, assert_near3, constant_volume, head_on, table_rgb, CENTRE, SIZE, STEP_ALPHA};
use common::classify::{colormap_srgb, jitter_offset, linear, srgb_to_linear, Classifier};
use common::reference::Reference;
use glam::DVec3;
use volcast::scene::settings::RenderSettings;
use volcast::transfer::colormap::tables::{COOL_WARM, PLASMA, VIRIDIS};
use volcast::transfer::function::{self as tf, TfUnits, TransferFunction, PRESET_NAMES};
use volcast::transfer::Colormap;

/// The tabulated maps' control points against their sources.
#[test]
fn colormap_control_points_match_their_published_values() {
    // matplotlib 3.11.2, `matplotlib.colormaps[name].colors[k]` (identical to all 256 entries when checked).
    /// A table, its name, entries at five indices and the sums of its three channels.
    type Published<'a> = (&'a [[f32; 3]; 256], &'a str, [(usize, [f64; 3]); 5], [f64; 3]);
    let published: [Published; 2] = [
        (
            &VIRIDIS,
            "viridis",
            [
                (0, [0.267004, 0.004874, 0.329415]),
                (64, [0.229739, 0.322361, 0.545706]),
                (128, [0.127568, 0.566949, 0.550556]),
                (192, [0.369214, 0.788888, 0.382914]),
                (255, [0.993248, 0.906157, 0.143936]),
            ],
            // numpy: colors.sum(axis=0)
            [83.743425, 137.734004, 110.223089],
        ),
        (
            &PLASMA,
            "plasma",
            [
                (0, [0.050383, 0.029803, 0.527975]),
                (64, [0.494877, 0.01199, 0.657865]),
                (128, [0.798216, 0.280197, 0.469538]),
                (192, [0.973416, 0.585761, 0.25154]),
                (255, [0.940015, 0.975158, 0.131326]),
            ],
            [180.594634, 86.231843, 110.994049],
        ),
    ];
    for (table, name, points, sums) in published {
        for (k, rgb) in points {
            for c in 0..3 {
                assert!(
                    (f64::from(table[k][c]) - rgb[c]).abs() < 1e-6,
                    "{name}[{k}]: {:?} vs {rgb:?}",
                    table[k]
                );
            }
        }
        for (c, sum) in sums.iter().enumerate() {
            let ours: f64 = table.iter().map(|e| f64::from(e[c])).sum();
            assert!(
                (ours - sum).abs() < 1e-4,
                "{name} channel {c} sums to {ours}, matplotlib {sum}"
            );
        }
    }
    // Moreland's endpoints, RGB (0.230, 0.299, 0.754) and (0.706, 0.016, 0.150) in bytes, and his Msh
    // interpolation between them as VTK 9.7.2 computes it (vtkColorTransferFunction, SetColorSpaceToDiverging,
    // GetColor(k/32) × 255 rounded): the table agrees within one 8-bit step everywhere (checked at all 33).
    let vtk: [(usize, [u8; 3]); 9] = [
        (0, [59, 76, 192]),
        (2, [78, 104, 216]),
        (4, [98, 130, 234]),
        (8, [141, 176, 254]),
        (12, [184, 208, 249]),
        (16, [221, 221, 221]),
        (20, [245, 196, 173]),
        (30, [203, 62, 56]),
        (32, [180, 4, 38]),
    ];
    for (k, rgb) in vtk {
        for c in 0..3 {
            assert!(
                COOL_WARM[k][c].abs_diff(rgb[c]) <= 1,
                "cool-warm anchor {k}: {:?} vs {rgb:?}",
                COOL_WARM[k]
            );
        }
    }
}

/// The reference's colormaps at points where their definitions give known colours.
#[test]
fn reference_colormaps_follow_their_definitions() {
    let c = |map, x| colormap_srgb(map, x);
    assert_near3(
        "rainbow at 0: blue",
        c(Colormap::Rainbow, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
        1e-12,
    );
    assert_near3(
        "rainbow at 1/4: cyan",
        c(Colormap::Rainbow, 0.25),
        DVec3::new(0.0, 1.0, 1.0),
        1e-12,
    );
    assert_near3(
        "rainbow at 1/2: green",
        c(Colormap::Rainbow, 0.5),
        DVec3::new(0.0, 1.0, 0.0),
        1e-12,
    );
    assert_near3(
        "rainbow at 5/8",
        c(Colormap::Rainbow, 0.625),
        DVec3::new(0.5, 1.0, 0.0),
        1e-12,
    );
    assert_near3(
        "rainbow at 1: red",
        c(Colormap::Rainbow, 1.0),
        DVec3::new(1.0, 0.0, 0.0),
        1e-12,
    );
    assert_near3(
        "gnuplot at 1/4",
        c(Colormap::Gnuplot, 0.25),
        DVec3::new(0.5, 1.0 / 64.0, 1.0),
        1e-12,
    );
    assert_near3(
        "gnuplot at 3/4: blue clipped",
        c(Colormap::Gnuplot, 0.75),
        DVec3::new(0.75f64.sqrt(), 0.421875, 0.0),
        1e-12,
    );
    assert_near3("grayscale", c(Colormap::Grayscale, 0.3), DVec3::splat(0.3), 1e-12);
    assert_near3(
        "cool-warm at 1/2",
        c(Colormap::CoolWarm, 0.5),
        DVec3::splat(221.0 / 255.0),
        1e-12,
    );
    // Halfway between viridis entries 10 and 11.
    let mid = (10.5 / 255.0, (VIRIDIS[10], VIRIDIS[11]));
    let expected = DVec3::from_array(std::array::from_fn(|k| {
        (f64::from(mid.1 .0[k]) + f64::from(mid.1 .1[k])) / 2.0
    }));
    assert_near3("viridis between entries", c(Colormap::Viridis, mid.0), expected, 1e-7);
    assert_near3(
        "clamped below",
        c(Colormap::Plasma, -3.0),
        c(Colormap::Plasma, 0.0),
        0.0,
    );
}

fn settings(f: impl FnOnce(&mut RenderSettings)) -> RenderSettings {
    let mut s = RenderSettings::new(8, 8, glam::Vec3::ONE);
    f(&mut s);
    s
}

/// Rule 4 by hand: the colour follows the position in the window, opacity the model.
#[test]
fn reference_classification_by_hand() {
    let s = settings(|s| {
        s.colour.window = [0.2, 0.6];
        s.colour.colormap = Colormap::Grayscale;
        s.colour.step_alpha = 0.4;
    });
    let k = Classifier::new(&s, [0.0, 1.0]);
    // v = 0.3 sits a quarter into the window: grey 0.25, not 0.3.
    let (rgb, a) = k.at(0.3);
    assert_near3(
        "colour by window position",
        rgb,
        DVec3::splat(srgb_to_linear(0.25)),
        1e-7,
    );
    assert!((a - 0.4).abs() < 1e-7);
    assert_eq!(k.at(0.19), (DVec3::ZERO, 0.0), "below the window");
    assert_eq!(k.at(0.61), (DVec3::ZERO, 0.0), "above the window");
    assert_eq!(k.at(f64::NAN), (DVec3::ZERO, 0.0));
    assert!((k.at(0.6).1 - 0.4).abs() < 1e-7, "the window's edges are inside it");

    let s = settings(|s| {
        s.colour.window = [0.2, 0.6];
        s.colour.multiplied_alpha = true;
        s.colour.step_alpha = 0.4;
    });
    assert!((Classifier::new(&s, [0.0, 1.0]).at(0.5).1 - 0.75 * 0.4).abs() < 1e-7);

    // A transfer function in data units on a CT range: opacity 0 at 100 HU rising to 0.8 at 300 HU, colour from
    // red at 0 HU to white at 1000 HU; the window [0, 1] covers the whole range.
    let tf = TransferFunction {
        name: "hand".into(),
        units: TfUnits::Data,
        colors: vec![[0.0, 1.0, 0.0, 0.0], [1000.0, 1.0, 1.0, 1.0]],
        colormap: Colormap::Viridis,
        opacity: vec![[100.0, 0.0], [300.0, 0.8]],
    };
    let s = settings(|s| {
        s.colour.window = [0.0, 1.0];
        s.colour.transfer_function = Some(tf.clone());
    });
    let range = [-1000.0, 3000.0];
    let k = Classifier::new(&s, range);
    let v = |hu: f64| (hu - range[0]) / (range[1] - range[0]);
    let (rgb, a) = k.at(v(200.0));
    assert!((a - 0.4).abs() < 1e-6, "{a}");
    assert_near3("colour at 200 HU", rgb, linear(DVec3::new(1.0, 0.2, 0.2)), 1e-6);
    assert_eq!(k.at(v(-500.0)).1, 0.0, "constant before the first point");
    assert_near3("constant after the last point", k.at(v(2500.0)).0, DVec3::ONE, 1e-6);
    assert!((k.at(v(2500.0)).1 - 0.8).abs() < 1e-6);
    // Without colour points, its colormap spans the window.
    let s = settings(|s| {
        s.colour.window = [0.25, 0.75];
        s.colour.transfer_function = Some(TransferFunction {
            colors: vec![],
            ..tf.clone()
        });
    });
    assert_near3(
        "colormap over the window",
        Classifier::new(&s, range).at(0.5).0,
        linear(colormap_srgb(Colormap::Viridis, 0.5)),
        1e-12,
    );
}

/// The library's 4096-entry table (`function::bake` + `function::lookup`, what the GPU reads) against the reference's
/// definition, for every colormap and alpha model, a window off-centre in the range, and every preset. Away
/// from the window's edges (where the table blends in the zero entry outside) they agree to 1e-3 in linear
/// light: linear interpolation between entries 1/4095 apart cuts the corners of the colormaps' kinks (rainbow's
/// sextants, gnuplot's clipped blue) and of the transfer functions' control points.
#[test]
fn multiplied_alpha_scales_opacity_by_the_windowed_value() {
    let volume = constant_volume();
    let reference = Reference::new(&volume);
    let mut s = head_on(&volume, SIZE);
    s.colour.multiplied_alpha = true;
    s.colour.window = [0.25, 1.0];
    let c = (0.5 - 0.25) / 0.75;
    let trace = reference.trace(&s, CENTRE, CENTRE);
    // The table is linear in c between neighbouring entries, so the lookup gives c × step alpha up to f32 rounding.
    let alpha = 1.0 - (1.0 - c * f64::from(STEP_ALPHA)).powi(16);
    assert_near("opacity", trace.alpha, alpha, 1e-6);
    assert_near3("colour", trace.color, table_rgb(&volume, &s, 0.5) * trace.alpha, 1e-7);
}

#[test]
fn the_library_table_follows_the_reference_definition() {
    let mut cases: Vec<(String, RenderSettings, [f64; 2])> = Vec::new();
    for map in Colormap::ALL {
        for multiplied in [false, true] {
            let s = settings(|s| {
                s.colour.colormap = map;
                s.colour.multiplied_alpha = multiplied;
                s.colour.window = [0.15, 0.7];
                s.colour.step_alpha = 0.35;
            });
            cases.push((format!("{map} multiplied {multiplied}"), s, [0.0, 1.0]));
        }
    }
    for name in PRESET_NAMES {
        let s = settings(|s| {
            s.colour.transfer_function = Some(TransferFunction::preset(name).unwrap());
            s.colour.window = [0.0, 1.0];
        });
        cases.push((format!("preset {name}"), s, [-1024.0, 3071.0]));
    }
    for (what, s, range) in cases {
        let table = tf::bake(&s.classification(), s.colour.window, range);
        let k = Classifier::new(&s, range);
        // Steps the table cannot follow within one entry: the window's edges and a transfer function's points
        // that jump (qt-example's opacity steps from 0 to 0.1 over 0.0001).
        let mut edges: Vec<f64> = s.colour.window.map(f64::from).to_vec();
        if let Some(tf) = &s.colour.transfer_function {
            let to_v = |x: f32| match tf.units {
                TfUnits::Normalized => f64::from(x),
                TfUnits::Data => (f64::from(x) - range[0]) / (range[1] - range[0]),
            };
            edges.extend(tf.opacity.iter().map(|p| to_v(p[0])));
        }
        let [lo, hi] = s.colour.window.map(f64::from);
        for i in 0..=10_000 {
            let v = f64::from(i) / 10_000.0;
            // Outside the window nothing is classified (the table repeats the edges there for interpolation).
            if v < lo || v > hi || edges.iter().any(|e| (v - e).abs() < 2.0 / 4095.0) {
                continue;
            }
            let [r, g, b, a] = tf::lookup(&table, v as f32).map(f64::from);
            let (rgb, alpha) = k.at(v);
            assert_near3(&format!("{what}: colour at {v}"), DVec3::new(r, g, b), rgb, 1e-3);
            assert!((a - alpha).abs() <= 1e-3, "{what}: opacity at {v}: {a} vs {alpha}");
        }
    }
}

/// The reference's own jitter hash and the library's (which the bench's sample counter uses) agree.
#[test]
fn jitter_hashes_agree() {
    for (x, y, seed) in [
        (0, 0, 0),
        (1, 0, 0),
        (511, 300, 7),
        (4000, 17, u32::MAX),
        (12, 9999, 12345),
    ] {
        let ours = jitter_offset(x, y, seed);
        assert!((0.0..1.0).contains(&ours));
        assert_eq!(
            ours,
            f64::from(volcast::scene::settings::jitter_offset(x, y, seed)),
            "({x}, {y}, {seed})"
        );
    }
}
