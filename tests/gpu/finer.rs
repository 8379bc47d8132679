//! Full resolution from the file (src/scale/finer.rs, render/brick_upload.rs): a 128³ helix written as a raw file
//! and opened within a host budget that holds only level 1. The pool's level 0 is the file's: its bricks are read
//! from the file as the view wants them. Every step's image matches the reference made from the whole level-0
//! volume for the cut shown (marched at the step of the finest level shown, as the GPU does); with room for every
//! brick the stream reaches the image of the whole volume uploaded at full resolution, bit for bit.

use crate::common;

use common::bounds::REFERENCE;
use common::gpu::{finish, validated_gpu, Judge};
use common::levels::Cut as RefCut;
use common::reference::{Reference, Rendered};
use volcast::formats;
use volcast::formats::OpenOptions;
use volcast::pyramid::budget::Budgets;
use volcast::render::headless::Headless;
use volcast::render::levels::Cut;
use volcast::scene::camera::Camera;
use volcast::scene::settings::{RenderSettings, Shading};
use volcast::volume::{self, Volume};

/// The helix and the same voxels opened from a raw file within a host budget one byte short of level 0.
pub(crate) fn helix_held_at_level_1(folder: &str) -> (Volume, Volume) {
    let helix = volume::builtin("helix", Some(128)).expect("helix");
    let dir = common::scratch::scratch(folder);
    let path = dir.write("helix_128x128x128_uint8.raw", helix.gpu_bytes());
    let budgets = Budgets {
        host: 128 * 128 * 128 - 1,
        gpu: None,
    };
    let held = volcast::scale::open(&path, &OpenOptions::default(), budgets, None, &mut |_| {}).expect("open");
    assert_eq!(held.dims, [64; 3], "level 1 is held");
    assert!(held.finer.is_some(), "level 0 stays in the file");
    assert_eq!(held.range, helix.range, "the held level normalises by level 0's range");
    (helix, held)
}

/// A close shaded view from `azimuth`.
pub(crate) fn view(v: &Volume, azimuth: f32) -> RenderSettings {
    let mut s = RenderSettings::for_volume(96, 96, v);
    s.camera = Camera::orbit(azimuth, 20.0, 1.2, glam::Vec3::ZERO);
    s.lighting.shading = Some(Shading::default());
    s
}

/// The reference's frame for `cut` (it steps by the finest level shown, as the GPU does).
pub(crate) fn reference_for(helix: &Volume, cut: &Cut, s: &RenderSettings) -> Rendered {
    let rc = RefCut {
        brick: [16; 3],
        grid: cut.grid.map(|g| g as usize),
        level: cut.level.clone(),
        held: 1,
    };
    Reference::with_levels(helix, rc).render_full(s)
}

/// A pool of 120 slots streams the held level's top and level-0 bricks from the file: each step's image matches the
/// reference for its cut, and the close view reaches level 0 where it wants it.
#[test]
fn finer_levels_stream_from_the_file() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let (helix, held) = helix_held_at_level_1("gpu-finer-stream");
    headless.renderer.brick_side = Some(16);
    headless.set_volume(&gpu, &held).expect("upload");
    headless.renderer.start_stream(&gpu, &held, 120).expect("stream");
    assert_eq!(
        headless.renderer.pool().unwrap().grid,
        [8, 8, 8],
        "the file's level-0 grid"
    );
    let s = view(&helix, 30.0);
    let mut level0 = false;
    for n in 0..40 {
        let step = headless.renderer.stream_step(&gpu, &held, &s, 1.0, 6).expect("step");
        level0 |= step.shown.level.contains(&0);
        let actual = headless.render(&gpu, &s).expect("render").image;
        let expected = reference_for(&helix, &step.shown, &s);
        judge.against(
            "reference",
            format!("finer-step-{n}"),
            &actual,
            &expected,
            &s,
            REFERENCE,
        );
        if step.missing == 0 {
            assert!(level0, "the close view shows level-0 bricks read from the file");
            return finish(gpu, headless, judge);
        }
    }
    panic!("the stream did not reach its cut in 40 steps");
}

/// With room for every brick and a tiny factor, the stream reaches level 0 everywhere: the image equals the one of
/// the whole volume streamed from memory to level 0, bit for bit (skipping and strides off: the skip grids differ,
/// a brick read from the file taking one range where the volume in memory has one per 8³).
#[test]
fn finer_levels_refine_to_the_whole_image() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let (helix, held) = helix_held_at_level_1("gpu-finer-whole");
    headless.renderer.brick_side = Some(16);
    let mut s = view(&helix, 30.0);
    s.sampling.skip_empty = false;
    s.sampling.max_stride = 1;
    let mut level0 = |v: &Volume| {
        headless.set_volume(&gpu, v).expect("upload");
        headless.renderer.start_stream(&gpu, v, 600).expect("stream");
        for _ in 0..10 {
            let step = headless.renderer.stream_step(&gpu, v, &s, 1e-6, 128).expect("step");
            if step.missing == 0 {
                assert!(step.shown.level.iter().all(|&l| l == 0));
                return headless.render(&gpu, &s).unwrap().image;
            }
        }
        panic!("512 bricks and the top in uploads of 128");
    };
    let from_memory = level0(&helix);
    let from_file = level0(&held);
    assert!(from_file == from_memory, "refined to level 0 from the file");
    finish(gpu, headless, Judge::default());
}

/// A sheet one voxel thick that the held level averages to half its value: where level-0 bricks read from the file
/// show it, the skip grid takes those bricks' own ranges (not the held level's, which never reaches the window), so
/// the sheet is drawn as the reference draws it. In bricks of 16 voxels a brick is one skip cell (16 level-0 voxels
/// at level 1 held); in bricks of 32 the sheet lies in the second of a brick's cells, which takes its own range.
#[test]
fn bricks_read_from_the_file_are_skipped_by_their_own_range() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let dir = common::scratch::scratch("gpu-finer-sheet");
    let path = dir.join("sheet_64x64x64_uint8.raw");
    common::scratch::write_raw(&path, [64, 64, 64], |[x, _, _], _, out| {
        out.push(if x == 21 { 250 } else { 10 })
    });
    let full = formats::open(&path, &OpenOptions::default()).expect("whole");
    let budgets = Budgets {
        host: 64 * 64 * 64 - 1,
        gpu: None,
    };
    let held = volcast::scale::open(&path, &OpenOptions::default(), budgets, None, &mut |_| {}).expect("open");
    assert!(held.finer.is_some());
    let mut s = view(&full, 60.0);
    // Visible only above 180: the held level's sheet (130) is not.
    s.colour.window = [0.7, 1.0];
    for brick in [16, 32] {
        headless.renderer.brick_side = Some(brick);
        headless.set_volume(&gpu, &held).expect("upload");
        headless.renderer.start_stream(&gpu, &held, 80).expect("stream");
        let shown = (0..20)
            .map(|_| headless.renderer.stream_step(&gpu, &held, &s, 1.0, 16).expect("step"))
            .find(|step| step.missing == 0)
            .expect("the stream reaches its cut in 20 steps")
            .shown;
        assert!(shown.level.contains(&0), "the close view shows level-0 bricks");
        let actual = headless.render(&gpu, &s).expect("render").image;
        let rc = RefCut {
            brick: [brick as usize; 3],
            grid: shown.grid.map(|g| g as usize),
            level: shown.level.clone(),
            held: 1,
        };
        let expected = Reference::with_levels(&full, rc).render_full(&s);
        assert!(expected.object.iter().any(|&o| o), "the reference shows the sheet");
        judge.against(
            "reference",
            format!("finer-sheet-{brick}"),
            &actual,
            &expected,
            &s,
            REFERENCE,
        );
    }
    finish(gpu, headless, judge)
}

/// A cut whose finest level is coarser than the held one is marched at that level's step without strides (a skip
/// brick holds at most 4 of its samples): faint strided settings take every sample there, as the reference does,
/// while at level 0 the same settings take fewer (Marschner–Lobb, whose faint bricks stride).
#[test]
fn coarse_cuts_take_no_strides() {
    use common::gpu::gpu_sample_counts;
    use volcast::render::levels::LevelChoice;
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let ml = volume::builtin("marschner-lobb", None).expect("marschner-lobb");
    headless.renderer.brick_side = Some(8);
    headless.set_volume(&gpu, &ml).expect("upload");
    let mut s = RenderSettings::for_volume(96, 96, &ml);
    (s.sampling.step_length, s.sampling.max_stride, s.colour.step_alpha) = (0.4, 4, 0.03);
    let total = |c: Vec<u32>| c.iter().map(|&n| u64::from(n)).sum::<u64>();
    let mut samples = Vec::new();
    for level in [0, 1] {
        let r = &mut headless.renderer;
        r.show_levels(&gpu, &ml, &s, LevelChoice::Forced(level)).expect("cut");
        let strided = total(gpu_sample_counts(&gpu, &mut headless, &s));
        let every = total(gpu_sample_counts(
            &gpu,
            &mut headless,
            &RenderSettings {
                sampling: volcast::scene::settings::Sampling {
                    max_stride: 1,
                    ..s.sampling.clone()
                },
                ..s.clone()
            },
        ));
        samples.push((strided, every));
    }
    assert!(samples[0].0 < samples[0].1, "level 0 takes strides: {samples:?}");
    assert_eq!(samples[1].0, samples[1].1, "level 1 everywhere takes none: {samples:?}");
    finish(gpu, headless, Judge::default());
}
