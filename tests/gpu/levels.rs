//! The resolution pyramid in the brick pool (src/render/levels.rs, resident.rs) against the reference's own
//! pyramid and level rule (tests/common/levels.rs): a level forced everywhere, a cut with a seam between levels,
//! the screen rule within a small pool (coarser bricks where the pool runs out, never a hole), and refinement
//! converging to the full-resolution image.

use crate::common;

use common::bounds::REFERENCE;
use common::cases::{gradient_cases, marschner_lobb_as, quality_cases, standard_cases, Case};
use common::gpu::{finish, validated_gpu, Judge, METHODS};
use common::levels::{screen_cut, Cut as RefCut};
use common::reference::Reference;
use volcast::gpu::Gpu;
use volcast::render::headless::Headless;
use volcast::render::levels::{Cut, LevelChoice};
use volcast::scene::settings::{RenderSettings, Shading};
use volcast::volume::{self, Volume, VoxelType};

/// The reference's form of the renderer's cut.
fn reference_cut(cut: &Cut, brick: [u32; 3]) -> RefCut {
    RefCut {
        brick: brick.map(|b| b as usize),
        grid: cut.grid.map(|g| g as usize),
        level: cut.level.clone(),
        held: 0,
    }
}

/// Renders `cases` with `cut` shown and judges each against the reference for that cut.
fn judge_cut(judge: &mut Judge, gpu: &Gpu, headless: &mut Headless, v: &Volume, cut: &Cut, cases: Vec<Case>) {
    headless.renderer.show_cut(gpu, v, cut).expect("show cut");
    let brick = headless.renderer.pool().unwrap().brick;
    let reference = Reference::with_levels(v, reference_cut(cut, brick));
    for case in cases {
        for &(setup, compute) in METHODS {
            let mut s = case.settings.clone();
            s.pipeline.ray_setup = setup;
            s.pipeline.compute = compute;
            let actual = headless.render(gpu, &s).expect("render").image;
            let expected = reference.render_full(&s);
            let suffix = if compute { "-compute" } else { "" };
            let label = format!("{}-{}-{setup:?}{suffix}", v.name, case.name).to_lowercase();
            judge.against("reference", label, &actual, &expected, &s, REFERENCE);
        }
    }
}

fn bricked(gpu: &Gpu, headless: &mut Headless, v: &Volume, side: u32) -> Cut {
    headless.renderer.brick_side = Some(side);
    headless.set_volume(gpu, v).expect("upload");
    let grid = headless.renderer.pool().unwrap().grid;
    Cut::uniform(grid, 0)
}

/// Levels 1 and 2 everywhere, and a cut with levels 0, 1 and 2 side by side (seams on brick faces), on the helix
/// and on Marschner–Lobb (values that change every voxel, through the 16-bit texture and the 8-bit corners).
#[test]
fn forced_levels_and_seams_match_the_reference() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let helix = volume::builtin("helix", Some(64)).expect("helix");
    let flat = bricked(&gpu, &mut headless, &helix, 16);
    for level in [1, 2] {
        let cases = standard_cases(&helix, 64).into_iter().take(3).collect();
        judge_cut(
            &mut judge,
            &gpu,
            &mut headless,
            &helix,
            &Cut::uniform(flat.grid, level),
            cases,
        );
    }
    // Level 0 in the lower x half, 1 and 2 above it: every brick face between them is a seam.
    let mut mixed = flat.clone();
    for (i, l) in mixed.level.iter_mut().enumerate() {
        let b = flat.brick_of(i);
        *l = if b[0] < 2 {
            0
        } else if b[1] < 2 {
            1
        } else {
            2
        };
    }
    let mut cases = standard_cases(&helix, 72);
    cases.extend(quality_cases(&helix, 72));
    judge_cut(&mut judge, &gpu, &mut headless, &helix, &mixed, cases);
    for (ty, policy) in [
        (VoxelType::U16, volcast::render::TexelPolicy::Native),
        (VoxelType::U8, volcast::render::TexelPolicy::Corners),
    ] {
        headless.renderer.texel_policy = policy;
        let ml = marschner_lobb_as(ty);
        let flat = bricked(&gpu, &mut headless, &ml, 8);
        let mut mixed = flat.clone();
        for (i, l) in mixed.level.iter_mut().enumerate() {
            let b = flat.brick_of(i);
            *l = (b[0] + b[2]) % 3;
        }
        let mut cases = standard_cases(&ml, 64);
        cases.extend(gradient_cases(&ml, 64));
        judge_cut(&mut judge, &gpu, &mut headless, &ml, &mixed, cases);
    }
    finish(gpu, headless, judge);
}

/// Thin bright planes three voxels before a skip brick's face, all else empty: level 2 averages each plane into a
/// voxel whose trilinear reach crosses that face, into skip bricks whose level-0 values (apron included) are all
/// zero. Skipping must take the coarser level's ranges too, or those bricks are leapt over and the glow is lost.
#[test]
fn skipping_keeps_what_coarser_levels_show() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let n = 64usize;
    let data: Vec<u8> = (0..n * n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n % n);
            if x % 32 == 13 || y % 32 == 21 {
                255
            } else {
                0
            }
        })
        .collect();
    let planes = Volume::new(
        "planes",
        [64; 3],
        [1.0; 3],
        VoxelType::U8,
        volcast::volume::VoxelData::U8(data),
    )
    .expect("planes");
    let flat = bricked(&gpu, &mut headless, &planes, 16);
    let mut cases = standard_cases(&planes, 64);
    for case in &mut cases {
        case.settings.colour.window = [0.02, 1.0];
    }
    judge_cut(
        &mut judge,
        &gpu,
        &mut headless,
        &planes,
        &Cut::uniform(flat.grid, 2),
        cases,
    );
    finish(gpu, headless, judge);
}

/// The gradient texture of a pool of mixed levels: each level's own grid gradients, per level-0 voxel.
#[test]
fn the_gradient_texture_follows_the_levels() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let ml = marschner_lobb_as(VoxelType::U16);
    let flat = bricked(&gpu, &mut headless, &ml, 8);
    headless.renderer.enable_gradient_texture(&gpu, &ml).unwrap();
    let mut mixed = flat.clone();
    for (i, l) in mixed.level.iter_mut().enumerate() {
        *l = (flat.brick_of(i)[1] % 2) + 1;
    }
    let cases = ["shaded", "shaded-gradient-opacity", "iso"]
        .into_iter()
        .map(|name| {
            let mut case = gradient_cases(&ml, 64).into_iter().find(|c| c.name == name).unwrap();
            case.settings.lighting.gradient_texture = true;
            case
        })
        .collect();
    judge_cut(&mut judge, &gpu, &mut headless, &ml, &mixed, cases);
    assert!(
        headless.renderer.has_gradient_texture(),
        "the texture is made again for the new pool"
    );
    finish(gpu, headless, judge);
}

/// A close view of a 128³ helix in 16³ bricks (512 at level 0): the screen rule without a bound equals the
/// reference's; within a pool of 40 bricks the bricks that cannot be refined stay coarser (never finer than the
/// rule asks, never a hole), and the image matches the reference for that cut; with room for everything and a
/// tiny factor, refinement reaches level 0 everywhere and the image equals the full-resolution one.
#[test]
fn the_screen_rule_within_a_small_pool() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let helix = volume::builtin("helix", Some(128)).expect("helix");
    bricked(&gpu, &mut headless, &helix, 16);
    let mut s = RenderSettings::for_volume(48, 48, &helix);
    s.camera.eye = s.camera.target + (s.camera.eye - s.camera.target) * 0.5;
    s.lighting.shading = Some(Shading::default());
    let finest = headless.render(&gpu, &s).unwrap().image;
    let reference = Reference::new(&helix);
    let brick = [16usize; 3];
    let free = headless
        .renderer
        .show_levels(
            &gpu,
            &helix,
            &s,
            LevelChoice::Screen {
                factor: 1.0,
                bricks: usize::MAX,
            },
        )
        .unwrap();
    let expected = screen_cut([128; 3], brick, 3, &reference.placement(&s), &s, 1.0);
    assert_eq!(reference_cut(&free, [16; 3]), expected, "the rule without a bound");
    let mut histogram = [0; 4];
    for &l in &free.level {
        histogram[l as usize] += 1;
    }
    eprintln!("level-0 bricks per level: {histogram:?}");
    assert!(
        histogram.iter().filter(|&&n| n > 0).count() >= 2,
        "the view needs more than one level"
    );
    let tight = headless
        .renderer
        .show_levels(
            &gpu,
            &helix,
            &s,
            LevelChoice::Screen {
                factor: 1.0,
                bricks: 40,
            },
        )
        .unwrap();
    let shown = tight.shown().len();
    assert!(shown <= 40 && shown < free.shown().len(), "{shown} bricks shown");
    for (i, (&t, &f)) in tight.level.iter().zip(&free.level).enumerate() {
        assert!(t >= f, "brick {i}: level {t} is finer than the rule's {f}");
    }
    // A brick left coarser than the rule asks stays so only because its children do not fit beside the rest.
    for (l, b) in tight.shown() {
        let under = (0..tight.level.len()).filter(|&i| tight.brick_of(i).map(|v| v >> l) == b);
        if under.clone().all(|i| free.level[i] >= l) {
            continue;
        }
        let g = volcast::pyramid::bricks::grid_at([128; 3], [16; 3], l - 1);
        let children = (0..8u32)
            .filter(|i| (0..3).all(|a| 2 * b[a] + (i >> a & 1) < g[a]))
            .count();
        assert!(
            shown - 1 + children > 40,
            "level-{l} brick {b:?} could have been refined"
        );
    }
    let actual = headless.render(&gpu, &s).unwrap().image;
    let want = Reference::with_levels(&helix, reference_cut(&tight, [16; 3])).render_full(&s);
    judge.against(
        "reference",
        "helix-128-screen-40-bricks".into(),
        &actual,
        &want,
        &s,
        REFERENCE,
    );
    // Refinement converges: everything at level 0 shows the full-resolution image, bit for bit.
    let all = headless
        .renderer
        .show_levels(
            &gpu,
            &helix,
            &s,
            LevelChoice::Screen {
                factor: 1e-6,
                bricks: usize::MAX,
            },
        )
        .unwrap();
    assert!(all.level.iter().all(|&l| l == 0));
    assert_eq!(headless.render(&gpu, &s).unwrap().image, finest, "refined to level 0");
    finish(gpu, headless, judge);
}

/// Rule 2's level strides: in a cut of levels 0, 1 and 2 side by side, each brick is sampled at the step's length
/// in voxels of its own level. The GPU visits, pixel by pixel, the samples the reference names (faint strided
/// settings and strong ones alike), and the coarse half takes fewer samples than the same view at level 0.
#[test]
fn level_strides_sample_each_brick_at_its_own_voxel() {
    use common::gpu::gpu_sample_counts;
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let helix = volume::builtin("helix", Some(64)).expect("helix");
    let flat = bricked(&gpu, &mut headless, &helix, 16);
    let mut mixed = flat.clone();
    for (i, l) in mixed.level.iter_mut().enumerate() {
        let b = flat.brick_of(i);
        *l = if b[0] < 2 { 0 } else { 1 + u32::from(b[1] >= 2) };
    }
    let reference = Reference::with_levels(&helix, reference_cut(&mixed, [16; 3]));
    let total = |c: &[u32]| c.iter().map(|&n| u64::from(n)).sum::<u64>();
    let mut failures = Vec::new();
    for (name, stride, alpha) in [("faint", 4, 0.02), ("strong", 1, 0.4)] {
        let mut s = RenderSettings::for_volume(64, 64, &helix);
        (s.sampling.step_length, s.sampling.max_stride, s.colour.step_alpha) = (0.5, stride, alpha);
        // Every sample counted, as the reference counts them (skipping would leave out the empty bricks').
        s.sampling.skip_empty = false;
        headless.renderer.show_cut(&gpu, &helix, &flat).expect("level 0");
        let level0 = gpu_sample_counts(&gpu, &mut headless, &s);
        headless.renderer.show_cut(&gpu, &helix, &mixed).expect("mixed cut");
        let counts = gpu_sample_counts(&gpu, &mut headless, &s);
        let expected = reference.render_full(&s).samples;
        let off = common::gpu::counts_off(&counts, &expected);
        if off.len() > 12 {
            failures.push(format!(
                "{name}: {} pixels visit other samples than rule 2's (pixel, GPU, reference): {:?}",
                off.len(),
                &off[..8]
            ));
        }
        let (mixed_total, level0_total) = (total(&counts), total(&level0));
        eprintln!("{name}: {mixed_total} samples in the mixed cut, {level0_total} at level 0");
        if mixed_total * 10 > level0_total * 8 {
            failures.push(format!(
                "{name}: the coarse bricks took their samples at level 0's pace"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
    finish(gpu, headless, Judge::default());
}
