//! Rule 12's spaced rays (`draft`'s one ray per 2×2 pixels) against the reference, which marches the same smaller
//! image and stretches it by the rule's bilinear filter (tests/common/stretch.rs): at odd, non-square sizes whose
//! marched image does not divide them, where a wrong aspect, pixel centre or rounding shows; with every ray setup.

use crate::common;

use common::bounds::SPACED;
use common::cases::{mirrored, standard_cases, with};
use common::gpu::{finish, validated_gpu, Judge};
use volcast::render::headless::Headless;
use volcast::scene::quality::Quality;
use volcast::scene::settings::RaySetup;
use volcast::transfer::Colormap;
use volcast::volume;

const SETUPS: &[(RaySetup, bool)] = &[
    (RaySetup::Faces, false),
    (RaySetup::Analytic, false),
    (RaySetup::Analytic, true),
];

#[test]
fn spaced_rays_match_the_reference_stretched() {
    let gpu = validated_gpu();
    let mut headless = Headless::new(&gpu).expect("renderer");
    let mut judge = Judge::default();
    let helix = volume::builtin("helix", Some(64)).expect("helix");
    for v in [helix.clone(), mirrored(&helix)] {
        let mut cases: Vec<_> = standard_cases(&v, 77).into_iter().take(4).collect();
        cases.push(with(&v, 77, "draft-viridis", |s| {
            s.colour.colormap = Colormap::Viridis;
            Quality::Draft.apply(s, v.range);
        }));
        for case in &mut cases {
            // Odd and not square: 77×53 marches 39×27 (k = 2) or 20×14 (k = 4), neither dividing the output.
            case.settings.height = 53;
            case.settings.sampling.ray_spacing = case.settings.sampling.ray_spacing.max(2);
        }
        let mut wider: Vec<_> = cases.iter().take(2).cloned().collect();
        for case in &mut wider {
            case.name = format!("{}-k4", case.name);
            case.settings.sampling.ray_spacing = 4;
        }
        cases.extend(wider);
        headless.set_volume(&gpu, &v).expect("upload volume");
        judge.run_cases(("spaced", SPACED), &gpu, &mut headless, &v, cases, SETUPS);
    }
    finish(gpu, headless, judge);
}
