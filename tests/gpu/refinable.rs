//! Only what can be seen is refined (src/render/refinable.rs, docs/large-volumes.md): against the reference's own
//! rule (tests/common/levels.rs `may_refine`, from level 0's values and its own classification). Two balls in an
//! empty 128³ volume, in memory and from a raw file held at level 1 (level 0's ranges made by the pass that read the
//! held level).

use crate::common;

use super::finer::{reference_for, view};
use common::bounds::REFERENCE;
use common::compare::diff;
use common::gpu::{finish, validated_gpu, Judge};
use common::levels::{may_refine, pyramid, screen_cut, screen_cut_where, Cut as RefCut};
use common::reference::Reference;
use common::segments::Segments;
use common::strides::visible_emission;
use volcast::formats::OpenOptions;
use volcast::pyramid::budget::Budgets;
use volcast::render::headless::Headless;
use volcast::render::levels::{Cut, LevelChoice};
use volcast::scene::settings::RenderSettings;
use volcast::volume::Volume;

const BRICK: [usize; 3] = [16; 3];

/// Samples the march takes over the whole frame `s` (the GPU's own count).
fn samples(gpu: &volcast::gpu::Gpu, headless: &mut Headless, s: &RenderSettings) -> u64 {
    let counts = common::gpu::gpu_sample_counts(gpu, headless, s);
    counts.iter().map(|&n| u64::from(n)).sum()
}

fn reference_cut(cut: &Cut, held: u32) -> RefCut {
    RefCut {
        brick: BRICK,
        grid: cut.grid.map(|g| g as usize),
        level: cut.level.clone(),
        held,
    }
}

/// The reference's screen rule for `s` over `v` (128³, top level 3), refining only where [`may_refine`] says
/// so with cells of `cell` voxels.
fn reference_rule(v: &Volume, s: &RenderSettings, cell: usize) -> RefCut {
    let reference = Reference::new(v);
    let level0 = pyramid(v, 0).remove(0);
    let segments = Segments::new(reference.classifier(s), s.colour.window.map(f64::from), None);
    let visible = visible_emission(s, &segments);
    let refine = |l, b| may_refine(&level0, (BRICK, cell), l, b, &visible);
    screen_cut_where([128; 3], BRICK, 3, (&reference.placement(s), s, 1.0), &refine)
}

/// A close view whose background (0) lies outside the window.
fn close_view(v: &Volume) -> RenderSettings {
    let mut s = view(v, 30.0);
    s.colour.window = [0.25, 1.0];
    s
}

/// Two balls (255 at the centre, falling to 0 at the radius) in an empty 128³ uint8 volume, written as a raw file in
/// scratch folder `folder`: the whole volume, and the same file opened within a host budget one byte short of it
/// (level 1 held, level 0 read from the file).
fn balls(folder: &str) -> (Volume, Volume) {
    let dir = common::scratch::scratch(folder);
    let path = dir.join("balls_128x128x128_uint8.raw");
    common::scratch::write_raw(&path, [128; 3], |p, _, out| {
        let ball = |c: [f64; 3], r: f64| {
            let d = (0..3).map(|a| (p[a] as f64 - c[a]).powi(2)).sum::<f64>().sqrt();
            (255.0 * (1.0 - d / r)).max(0.0)
        };
        out.push(
            ball([40.0, 44.0, 52.0], 12.0)
                .max(ball([92.0, 84.0, 76.0], 9.0))
                .round() as u8,
        )
    });
    let whole = volcast::formats::open(&path, &OpenOptions::default()).expect("whole");
    let budgets = Budgets {
        host: 128 * 128 * 128 - 1,
        gpu: None,
    };
    let held = volcast::scale::open(&path, &OpenOptions::default(), budgets, None, &mut |_| {}).expect("open");
    assert_eq!(held.dims, [64; 3], "level 1 is held");
    (whole, held)
}

/// In memory: the cut refines only bricks near the balls, as the reference's rule does; it shows fewer bricks than
/// the rule without it (skipping off), never a finer level, the same finest level, the same samples and the same
/// image.
#[test]
fn bricks_that_show_nothing_are_not_refined() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let (v, _) = balls("gpu-refine-memory");
    headless.renderer.brick_side = Some(16);
    headless.set_volume(&gpu, &v).expect("upload");
    let s = close_view(&v);
    let everything = RenderSettings {
        sampling: volcast::scene::settings::Sampling {
            skip_empty: false,
            ..s.sampling.clone()
        },
        ..s.clone()
    };
    let free = LevelChoice::Screen {
        factor: 1.0,
        bricks: usize::MAX,
    };
    let all = headless.renderer.show_levels(&gpu, &v, &everything, free).expect("cut");
    let reference = Reference::new(&v);
    let unfiltered = screen_cut([128; 3], BRICK, 3, &reference.placement(&s), &s, 1.0);
    assert_eq!(
        reference_cut(&all, 0),
        unfiltered,
        "without skipping every brick may be refined"
    );
    let whole = headless.render(&gpu, &s).expect("render").image;
    let all_samples = samples(&gpu, &mut headless, &s);
    let seen = headless.renderer.show_levels(&gpu, &v, &s, free).expect("cut");
    // Skipping leaps the bricks left coarse as it leapt their children: not one sample more or less.
    assert_eq!(samples(&gpu, &mut headless, &s), all_samples, "samples taken");
    assert_eq!(reference_cut(&seen, 0), reference_rule(&v, &s, 8), "the rule");
    let (n_seen, n_all) = (seen.shown().len(), all.shown().len());
    eprintln!("bricks shown: {n_seen} (only what can be seen refined) of {n_all}");
    assert!(n_seen < n_all, "{n_seen} of {n_all} bricks");
    assert!(seen.level.iter().zip(&all.level).all(|(a, b)| a >= b), "never finer");
    let finest = |c: &Cut| c.level.iter().min().copied();
    assert_eq!(finest(&seen), finest(&all), "the same step");
    let actual = headless.render(&gpu, &s).expect("render").image;
    let d = diff(&actual, &whole);
    assert!(d.max <= 1.0, "the bricks not refined showed something: {d:?}");
    let expected = Reference::with_levels(&v, reference_cut(&seen, 0)).render_full(&s);
    judge.against("reference", "refine-seen".into(), &actual, &expected, &s, REFERENCE);
    finish(gpu, headless, judge);
}

/// From a file held at level 1: the stream wants the reference rule's cut over level 0's values in cells of 16
/// voxels, reads no brick outside it (room for every brick: the uploads are the wanted bricks and the top), and takes
/// the same samples as the cut without the rule.
#[test]
fn a_files_bricks_that_show_nothing_are_never_read() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let (v, held) = balls("gpu-refine-file");
    assert!(
        held.cells.as_ref().is_some_and(|c| c.cell == 16),
        "the read pass made level 0's ranges"
    );
    headless.renderer.brick_side = Some(16);
    headless.set_volume(&gpu, &held).expect("upload");
    headless.renderer.start_stream(&gpu, &held, 600).expect("stream");
    let s = close_view(&v);
    let all = (headless.renderer)
        .stream_wanted(
            &held,
            &RenderSettings {
                sampling: volcast::scene::settings::Sampling {
                    skip_empty: false,
                    ..s.sampling.clone()
                },
                ..s.clone()
            },
            1.0,
        )
        .expect("streamed");
    let wanted = headless.renderer.stream_wanted(&held, &s, 1.0).expect("streamed");
    let rule = RefCut {
        held: 1,
        ..reference_rule(&v, &s, 16)
    };
    assert_eq!(reference_cut(&wanted, 1), rule, "the rule");
    let (n_wanted, n_all) = (wanted.shown().len(), all.shown().len());
    assert!(n_wanted < n_all, "{n_wanted} of {n_all} bricks");
    assert!(wanted.level.contains(&0), "the close view reads level-0 bricks");
    headless.renderer.refine_to(&gpu, &held, &all).expect("refine");
    let all_samples = samples(&gpu, &mut headless, &s);
    headless.renderer.start_stream(&gpu, &held, 600).expect("stream");
    let progress = headless.renderer.refine_to(&gpu, &held, &wanted).expect("refine");
    assert_eq!(samples(&gpu, &mut headless, &s), all_samples, "samples taken");
    assert!(progress.done);
    let uploaded = headless.renderer.stream().expect("streamed").uploaded as usize;
    let top = usize::from(!wanted.level.contains(&3));
    assert_eq!(uploaded, n_wanted + top, "only the wanted bricks and the top were read");
    let actual = headless.render(&gpu, &s).expect("render").image;
    let expected = reference_for(&v, &wanted, &s);
    judge.against("reference", "refine-file".into(), &actual, &expected, &s, REFERENCE);
    finish(gpu, headless, judge);
}
