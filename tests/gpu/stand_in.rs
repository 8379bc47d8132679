//! Stand-ins keep the optical depth (rule 6, `Volume::source_voxels`): a preview of every k-th voxel, a level read
//! under a budget and a volume reduced by `--max-dim` show the same transfer function as the volume itself, whose
//! opacity is per voxel of the file. Seen in issue 60: a 128³ preview of a large file showed a translucent shell with
//! bright blobs inside, and the refined picture an opaque shell that hides them.
//!
//! The scene is that file in small: a thick shell around four bright blobs, 128³, written as a raw file and read
//! back in place. Each stand-in's picture agrees with the full volume's within a small mean difference, and the same
//! stand-in marched per voxel of its own (the rule dropped) is several times further off; each stand-in also
//! matches the CPU reference, which takes the rule from the volume independently.

use crate::common;

use common::bounds::REFERENCE;
use common::gpu::{finish, validated_gpu, Judge, METHODS};
use common::reference::background_pixel;
use image::RgbaImage;
use volcast::formats::OpenOptions;
use volcast::gpu::Gpu;
use volcast::pyramid::budget::Budgets;
use volcast::render::headless::Headless;
use volcast::scene::camera::Camera;
use volcast::scene::settings::RenderSettings;
use volcast::volume::Volume;

const SIDE: u32 = 128;

/// A smooth shell (value 90 at 0.68 of the half side, falling off over 0.1) around four smooth blobs (250 at their
/// centres): the shell is faint per voxel and nearly opaque over its thickness, and smooth enough that a coarser
/// grid of it differs in optical depth, not in shape.
fn shell_with_blobs() -> Vec<u8> {
    let c = f64::from(SIDE) / 2.0;
    // Centred on voxels a multiple of 4 apart, so that a preview of every 4th voxel holds their peaks (and the
    // file's range).
    let blobs =
        [[48, 48, 64], [80, 48, 64], [48, 80, 64], [80, 80, 64]].map(|b| b.map(|i| (f64::from(i) + 0.5 - c) / c));
    let mut out = Vec::with_capacity((SIDE * SIDE * SIDE) as usize);
    for z in 0..SIDE {
        for y in 0..SIDE {
            for x in 0..SIDE {
                let p = [x, y, z].map(|i| (f64::from(i) + 0.5 - c) / c);
                let r = p.iter().map(|a| a * a).sum::<f64>().sqrt();
                let shell = 90.0 * plateau((r - 0.66).abs());
                let blob = blobs
                    .iter()
                    .map(|b| 250.0 * (-(0..3).map(|a| (p[a] - b[a]).powi(2)).sum::<f64>() / 0.02).exp())
                    .fold(0.0, f64::max);
                out.push(shell.max(blob).round() as u8);
            }
        }
    }
    out
}

/// 1 within 0.06 of the centre, falling smoothly to 0 at 0.26.
fn plateau(d: f64) -> f64 {
    let t = ((d - 0.06) / 0.2).clamp(0.0, 1.0);
    0.5 + 0.5 * (std::f64::consts::PI * t).cos()
}

/// The view, from inside the shell's outline (so that every block compared is the shell's depth, not an edge a
/// coarser grid moves): the default transfer function over a window that leaves the shell faint per voxel.
fn view(v: &Volume) -> RenderSettings {
    let mut s = RenderSettings::for_volume(96, 96, v);
    s.camera = Camera::orbit(30.0, 20.0, 1.0, glam::Vec3::ZERO);
    s.colour.window = [0.2, 1.0];
    s.lighting.shading = None;
    s
}

/// How far apart two pictures are as a coarse look sees them: the mean absolute difference (in 1/255, over the
/// three channels) of their 8×8-pixel block means, over the blocks where either shows the volume. A stand-in's
/// coarser grid moves edges by a voxel of its own; its optical depth moves every block.
fn apart(a: &RgbaImage, b: &RgbaImage, s: &RenderSettings) -> f64 {
    let bg = background_pixel(s.background);
    let (w, h) = (a.width() / 8, a.height() / 8);
    let mut blocks = Vec::new();
    for (bx, by) in (0..w * h).map(|i| (i % w, i / w)) {
        let pixels = (0..64).map(|i| (bx * 8 + i % 8, by * 8 + i / 8));
        let (mut sum, mut shows) = ([0.0f64; 3], false);
        for (x, y) in pixels {
            let (p, q) = (a.get_pixel(x, y), b.get_pixel(x, y));
            shows |= *p != bg || *q != bg;
            for (c, total) in sum.iter_mut().enumerate() {
                *total += f64::from(p[c]) - f64::from(q[c]);
            }
        }
        if shows {
            blocks.push(sum.iter().map(|d| d.abs() / 64.0).sum::<f64>() / 3.0);
        }
    }
    blocks.iter().sum::<f64>() / blocks.len().max(1) as f64
}

fn render(gpu: &Gpu, headless: &mut Headless, v: &Volume, s: &RenderSettings) -> RgbaImage {
    headless.set_volume(gpu, v).expect("upload");
    headless.render(gpu, s).expect("render").image
}

/// Each stand-in against the full picture, with the rule and without it (`source_voxels` set back to 1).
fn stand_ins(path: &std::path::Path, full: &Volume) -> Vec<(&'static str, Volume)> {
    let place = volcast::formats::in_place::in_place(path, &OpenOptions::default())
        .expect("in place")
        .expect("a raw file is read in place");
    let preview = volcast::scale::preview::strided(&place, 4).expect("preview");
    let budgets = Budgets {
        // One byte short of level 1 (64³ one-byte voxels): level 2 is read.
        host: 64 * 64 * 64 - 1,
        gpu: None,
    };
    let level = volcast::scale::open(path, &OpenOptions::default(), budgets, None, &mut |_| {}).expect("level");
    let reduced = volcast::pyramid::max_dim::downsample_to(full.clone(), 32);
    assert_eq!((preview.dims, level.dims, reduced.dims), ([32; 3], [32; 3], [32; 3]));
    vec![("preview", preview), ("budget level", level), ("max-dim", reduced)]
}

#[test]
fn stand_ins_keep_the_optical_depth_of_the_volume() {
    let dir = common::scratch::scratch("stand-in");
    let path = dir.write("shell_128x128x128_uint8.raw", &shell_with_blobs());
    let full = volcast::formats::open(&path, &OpenOptions::default()).expect("open");
    assert_eq!(full.dims, [SIDE; 3]);
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let s = view(&full);
    let truth = render(&gpu, &mut headless, &full, &s);
    for (name, v) in stand_ins(&path, &full) {
        assert!(
            (v.source_voxels - 4.0).abs() < 1e-9,
            "{name}: {} source voxels",
            v.source_voxels
        );
        let kept = apart(&render(&gpu, &mut headless, &v, &s), &truth, &s);
        let mut dropped = v.clone();
        dropped.source_voxels = 1.0;
        let lost = apart(&render(&gpu, &mut headless, &dropped, &s), &truth, &s);
        println!("{name}: {kept:.2}/255 from the volume's picture with the rule, {lost:.2}/255 without it");
        assert!(kept < 5.0, "{name}: {kept:.2}/255 from the volume's picture");
        assert!(
            lost > 3.0 * kept,
            "{name}: without the rule only {lost:.2}/255 (with it {kept:.2}/255)"
        );
        headless.set_volume(&gpu, &v).expect("upload");
        let cases = vec![common::cases::Case {
            name: name.replace(' ', "-"),
            settings: s.clone(),
        }];
        judge.run_cases(("reference", REFERENCE), &gpu, &mut headless, &v, cases, &METHODS[..1]);
    }
    finish(gpu, headless, judge);
}
