//! Streaming bricks through a pool of fixed size (src/render/stream.rs, resident.rs): a 128³ helix in 16³ bricks
//! (512 at level 0) through a pool of 40 slots, a few uploads per step. Every step's image matches the reference
//! for the cut it shows (each brick the finest resident one at or above the rule's level: never a hole), a new view
//! evicts, the wanted cut is reached, and with room for every brick refinement reaches the full-resolution image.

use crate::common;

use common::bounds::REFERENCE;
use common::gpu::{finish, validated_gpu, Judge};
use common::levels::Cut as RefCut;
use common::reference::Reference;
use std::collections::HashSet;
use volcast::gpu::Gpu;
use volcast::render::headless::Headless;
use volcast::render::levels::Cut;
use volcast::render::TexelPolicy;
use volcast::scene::camera::Camera;
use volcast::scene::settings::{RenderSettings, Shading};
use volcast::volume::{self, Volume};

fn reference_cut(cut: &Cut) -> RefCut {
    RefCut {
        brick: [16; 3],
        grid: cut.grid.map(|g| g as usize),
        level: cut.level.clone(),
        held: 0,
    }
}

/// A close shaded view from `azimuth`, `distance` times the default distance.
fn view(v: &Volume, azimuth: f32, distance: f32) -> RenderSettings {
    let mut s = RenderSettings::for_volume(48, 48, v);
    s.camera = Camera::orbit(azimuth, 20.0, 2.5 * distance, glam::Vec3::ZERO);
    s.lighting.shading = Some(Shading::default());
    s
}

/// Checks the step's cut against the pool: each level-0 brick shows the finest resident brick at or above its
/// wanted level, and its page-table entry names the slot holding it. Returns whether any brick fell back.
fn check_shown(headless: &Headless, step: &volcast::render::stream::Step) -> bool {
    let pool = headless.renderer.pool().unwrap();
    let resident: HashSet<(u32, [u32; 3])> = pool.resident.iter().flatten().map(|r| (r.level, r.brick)).collect();
    let top = pool.levels.len() as u32 - 1;
    let mut fell_back = false;
    for (i, (&shown, &wanted)) in step.shown.level.iter().zip(&step.wanted.level).enumerate() {
        let b = step.shown.brick_of(i);
        let finest = (wanted..=top).find(|&l| resident.contains(&(l, b.map(|v| v >> l))));
        assert_eq!(Some(shown), finest, "level-0 brick {b:?} (wanted level {wanted})");
        let r = pool.resident[pool.directory[i] as usize].expect("the page table names a filled slot");
        assert_eq!(
            (r.level, r.brick),
            (shown, b.map(|v| v >> shown)),
            "page table of {b:?}"
        );
        fell_back |= shown > wanted;
    }
    fell_back
}

/// Steps the stream for the view `s` until the wanted cut is shown, judging every step's image.
fn stream_view(
    judge: &mut Judge,
    gpu: &Gpu,
    headless: &mut Headless,
    v: &Volume,
    s: &RenderSettings,
    label: &str,
) -> bool {
    let mut fell_back = false;
    for n in 0..40 {
        let step = headless.renderer.stream_step(gpu, v, s, 1.0, 6).expect("stream step");
        assert!(step.uploads.len() <= 6);
        fell_back |= check_shown(headless, &step);
        let actual = headless.render(gpu, s).expect("render").image;
        let expected = Reference::with_levels(v, reference_cut(&step.shown)).render_full(s);
        judge.against(
            "reference",
            format!("{label}-step-{n}"),
            &actual,
            &expected,
            s,
            REFERENCE,
        );
        if step.missing == 0 {
            assert_eq!(step.shown, step.wanted, "{label}: everything wanted is shown");
            return fell_back;
        }
    }
    panic!("{label}: the stream did not reach its cut in 40 steps");
}

/// A pool of 40 slots: two views (the second closer, from the other side) through the 8-bit corner texture and
/// the float texture (R8 filtering on lavapipe has 8-bit weights; the reference matches exact filtering).
#[test]
fn a_small_pool_streams_without_holes() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let helix = volume::builtin("helix", Some(128)).expect("helix");
    for policy in [TexelPolicy::Corners, TexelPolicy::Float] {
        headless.renderer.texel_policy = policy;
        headless.renderer.brick_side = Some(16);
        headless.set_volume(&gpu, &helix).expect("upload");
        headless.renderer.start_stream(&gpu, &helix, 40).expect("stream");
        assert_eq!(headless.renderer.pool().unwrap().grid, [8, 8, 8]);
        let label = format!("helix-128-pool-40-{policy:?}").to_lowercase();
        let first = stream_view(
            &mut judge,
            &gpu,
            &mut headless,
            &helix,
            &view(&helix, 30.0, 0.6),
            &label,
        );
        assert!(first, "some bricks showed a coarser fallback while they streamed in");
        let stream = headless.renderer.stream().unwrap();
        assert_eq!(stream.evicted, 0, "the first view fits the pool");
        stream_view(
            &mut judge,
            &gpu,
            &mut headless,
            &helix,
            &view(&helix, 210.0, 0.45),
            &format!("{label}-turned"),
        );
        let stream = headless.renderer.stream().unwrap();
        assert!(stream.evicted > 0, "the second view evicts bricks of the first");
        eprintln!("{label}: {} uploads, {} evictions", stream.uploaded, stream.evicted);
    }
    finish(gpu, headless, judge);
}

/// With room for every brick and a tiny factor, the stream reaches level 0 everywhere: the image equals the one of
/// the volume uploaded whole, bit for bit.
#[test]
fn streaming_refines_to_full_resolution() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let helix = volume::builtin("helix", Some(128)).expect("helix");
    headless.renderer.brick_side = Some(16);
    headless.set_volume(&gpu, &helix).expect("upload");
    let s = view(&helix, 30.0, 0.6);
    let whole = headless.render(&gpu, &s).unwrap().image;
    headless.renderer.start_stream(&gpu, &helix, 600).expect("stream");
    let mut steps = 0;
    loop {
        let step = headless
            .renderer
            .stream_step(&gpu, &helix, &s, 1e-6, 128)
            .expect("step");
        steps += 1;
        if step.missing == 0 {
            assert!(step.shown.level.iter().all(|&l| l == 0));
            break;
        }
        assert!(steps < 10, "512 bricks and the top in uploads of 128");
    }
    assert_eq!(headless.render(&gpu, &s).unwrap().image, whole, "refined to level 0");
    finish(gpu, headless, Judge::default());
}
