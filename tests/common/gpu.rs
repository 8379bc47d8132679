//! Running cases on the GPU under validation and judging them against the reference: one GPU per test, every
//! comparison recorded with the bounds it is held to, a summary per family printed for measuring the bounds, and
//! at the end one assertion over all comparisons and one that the validation layer said nothing.

use super::cases::Case;
use super::compare::{against_reference, write_failure_images, Bounds, ImageDiff};
use super::reference::{Reference, Rendered};
use image::RgbaImage;
use std::collections::BTreeMap;
use volcast::gpu::{Gpu, GpuOptions};
use volcast::render::headless::Headless;
use volcast::scene::settings::{decode_sample_count, RaySetup, RenderSettings};
use volcast::volume::Volume;

pub fn validated_gpu() -> Gpu {
    Gpu::new(&GpuOptions {
        validation: true,
        ..Default::default()
    })
    .expect("a Vulkan device with the validation layer (apt-get install mesa-vulkan-drivers vulkan-validationlayers)")
}

/// Tears down and asserts the validation layer said nothing, leaks at device destruction included.
pub fn close(gpu: Gpu, headless: Headless) {
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    let problems = log.problems();
    assert!(
        problems.is_empty(),
        "validation layer reported {} problem(s):\n{problems:#?}",
        problems.len()
    );
}

/// The per-pixel sample counts of a `count_samples` frame.
pub fn sample_counts(image: &RgbaImage) -> Vec<u32> {
    image.pixels().map(|p| decode_sample_count(p.0)).collect()
}

/// Renders `s` on the GPU with `count_samples` on.
pub fn gpu_sample_counts(gpu: &Gpu, headless: &mut Headless, s: &RenderSettings) -> Vec<u32> {
    let mut s = s.clone();
    s.pipeline.count_samples = true;
    sample_counts(&headless.render(gpu, &s).expect("render").image)
}

/// The pixels whose GPU sample count differs from the reference's by more than one: (pixel, GPU, reference).
pub fn counts_off(gpu: &[u32], reference: &[u32]) -> Vec<(usize, u32, u32)> {
    gpu.iter()
        .zip(reference)
        .enumerate()
        .filter(|(_, (g, r))| g.abs_diff(**r) > 1)
        .map(|(i, (g, r))| (i, *g, *r))
        .collect()
}

pub struct Outcome {
    pub family: &'static str,
    pub label: String,
    pub diff: ImageDiff,
    pub bounds: Bounds,
    pub verdict: Result<(), String>,
}

/// Every comparison a test made.
#[derive(Default)]
pub struct Judge {
    pub outcomes: Vec<Outcome>,
}

/// The ray setups every reference case runs with (the compute march has tests of its own).
pub const METHODS: &[(RaySetup, bool)] = &[(RaySetup::Faces, false), (RaySetup::Analytic, false)];

impl Judge {
    /// Records `diff` under `bounds`; on failure writes the images to target/test-failures.
    pub fn record(
        &mut self,
        family: &'static str,
        label: String,
        diff: ImageDiff,
        bounds: Bounds,
        images: (&RgbaImage, &RgbaImage),
    ) {
        let verdict = bounds.check(&diff);
        eprintln!(
            "{label}: {diff}{}",
            verdict
                .as_ref()
                .err()
                .map_or(String::new(), |e| format!("  FAILS: {e}"))
        );
        if verdict.is_err() {
            write_failure_images(&label, images.0, images.1);
        }
        self.outcomes.push(Outcome {
            family,
            label,
            diff,
            bounds,
            verdict,
        });
    }

    /// `actual` against the reference's `expected` over the object pixels.
    pub fn against(
        &mut self,
        family: &'static str,
        label: String,
        actual: &RgbaImage,
        expected: &Rendered,
        s: &RenderSettings,
        bounds: Bounds,
    ) {
        let d = against_reference(actual, expected, s.background);
        self.record(family, label, d, bounds, (actual, &expected.image));
    }

    /// Renders each case with each of `methods` on the GPU (`volume` already set) and compares it with the
    /// reference.
    pub fn run_cases(
        &mut self,
        (family, bounds): (&'static str, Bounds),
        gpu: &Gpu,
        headless: &mut Headless,
        volume: &Volume,
        cases: Vec<Case>,
        methods: &[(RaySetup, bool)],
    ) {
        let reference = Reference::new(volume);
        for case in cases {
            let expected = reference.render_full(&case.settings);
            for &(method, compute) in methods {
                let mut s = case.settings.clone();
                s.pipeline.ray_setup = method;
                s.pipeline.compute = compute;
                let suffix = if compute { "-compute" } else { "" };
                let label = format!("{}-{}-{:?}{suffix}", volume.name, case.name, method).to_lowercase();
                let actual = headless.render(gpu, &s).expect("render").image;
                self.against(family, label, &actual, &expected, &s, bounds);
            }
        }
    }

    /// Prints per family the worst of each statistic (what the bounds are set from) and asserts every outcome.
    pub fn assert_all(&self) {
        let mut families: BTreeMap<&str, Vec<&Outcome>> = BTreeMap::new();
        for o in &self.outcomes {
            families.entry(o.family).or_default().push(o);
        }
        for (family, list) in &families {
            let worst = |f: &dyn Fn(&ImageDiff) -> f64| list.iter().map(|o| f(&o.diff)).fold(0.0, f64::max);
            let above: Vec<String> = [1u8, 2, 3, 4, 6, 8, 12, 16]
                .iter()
                .map(|&e| format!(">{e}: {}", list.iter().map(|o| o.diff.above(e)).max().unwrap_or(0)))
                .collect();
            let outliers = list[0].bounds.outliers;
            eprintln!(
                "family {family}: {} comparisons; worst mean {:.3} (without {outliers} outliers), p99 {}, max {}; \
                 most pixels {}; bounds {}",
                list.len(),
                worst(&|d| d.mean_without(outliers)),
                worst(&|d| d.p99),
                worst(&|d| d.max),
                above.join(", "),
                list[0].bounds
            );
        }
        let failed: Vec<String> = self
            .outcomes
            .iter()
            .filter_map(|o| {
                o.verdict
                    .as_ref()
                    .err()
                    .map(|e| format!("  {}: {} — {e}", o.label, o.diff))
            })
            .collect();
        assert!(
            failed.is_empty(),
            "{} of {} comparisons break their bounds:\n{}",
            failed.len(),
            self.outcomes.len(),
            failed.join("\n")
        );
    }
}

/// Asserts the outcomes and that the validation layer stayed silent.
pub fn finish(gpu: Gpu, headless: Headless, judge: Judge) {
    headless.destroy(&gpu);
    let log = gpu.log.clone();
    drop(gpu);
    judge.assert_all();
    let problems = log.problems();
    assert!(
        problems.is_empty(),
        "validation layer reported {} problem(s):\n{problems:#?}",
        problems.len()
    );
}
