//! Every `volcast render` option in docs/cli.md, through the binary under `--validate`: each must change the
//! output as documented. Options that are rendering rules are checked against the CPU reference rendering the
//! settings the option stands for (so an option that is parsed but ignored, or mapped to the wrong setting,
//! fails); the others by a property (an unchanged image, a line printed, a file written).

use crate::common;

use common::bounds::{POSITIONS_RGBA16F, REFERENCE, REFERENCE_R8, SPACED};
use common::compare::{against_reference, diff, write_failure_images, Bounds};
use common::gpu::Judge;
use common::reference::Reference;
use glam::Vec3;
use image::RgbaImage;
use std::path::PathBuf;
use volcast::scene::camera::Camera;
use volcast::scene::quality::Quality;
use volcast::scene::settings::{CompositeMode, RenderSettings, Shading};
use volcast::transfer::function::TransferFunction;
use volcast::transfer::Colormap;
use volcast::volume::{self, Volume};

const W: u32 = 64;
const H: u32 = 48;

/// Runs `volcast render <volume> --size 64x48 --validate <args>` and returns the image and stdout; panics on a
/// failure or any validation message.
fn render(volume_args: &[&str], args: &[&str], name: &str) -> (RgbaImage, String) {
    let out = common::scratch("cli-options").join(format!("{name}.png"));
    let size = format!("{W}x{H}");
    let size_args: &[&str] = if args.contains(&"--size") {
        &[]
    } else {
        &["--size", &size]
    };
    let validate_out = ["--validate", "-o", out.to_str().unwrap()];
    let o = common::volcast_ok(&[&["render"], volume_args, size_args, &validate_out, args].concat());
    let image = image::open(&out).expect("a PNG").to_rgba8();
    (image, common::stdout(&o))
}

const HELIX: &[&str] = &["--builtin", "helix", "--builtin-size", "48"];

fn helix() -> Volume {
    volume::builtin("helix", Some(48)).expect("helix")
}

/// The settings `volcast render` uses without options, for a volume with box `extent`: the normal quality's
/// 0.4-voxel step, which the helix's default opacity (0.1 per voxel) does not shorten, and its strides of up to
/// 4 steps (which that opacity does not allow: 0.105 extinction × 0.8 > 0.05).
fn defaults(extent: Vec3) -> RenderSettings {
    let mut s = RenderSettings::new(W, H, extent);
    s.sampling.step_length = 0.4;
    s.sampling.max_stride = 4;
    s
}

/// One option: its arguments and the settings it stands for.
struct Rule {
    args: &'static [&'static str],
    settings: fn(&mut RenderSettings, Vec3),
    bounds: Bounds,
}

fn rule(args: &'static [&'static str], settings: fn(&mut RenderSettings, Vec3)) -> Rule {
    Rule {
        args,
        settings,
        bounds: REFERENCE,
    }
}

/// What `render` does last: the step of `--quality` (default normal) for the classification, unless
/// `--step-length` gives one.
fn resolve_quality(s: &mut RenderSettings, args: &[&str], range: [f64; 2]) {
    let value = |flag: &str| args.iter().position(|a| *a == flag).map(|i| args[i + 1]);
    let quality = value("--quality").map_or(Quality::Normal, |q| Quality::parse(q).expect("a quality"));
    quality.apply(s, range);
    if let Some(step) = value("--step-length") {
        s.sampling.step_length = step.parse().expect("a step length");
        s.sampling.max_stride = 1;
    }
    if let Some(stride) = value("--max-stride") {
        s.sampling.max_stride = stride.parse().expect("a stride");
    }
    if let Some(k) = value("--ray-spacing") {
        s.sampling.ray_spacing = k.parse().expect("a ray spacing");
    }
}

/// Renders each rule through the binary and checks it against the reference of its settings, and that it
/// differs from the image without the option.
fn check_rules(rules: Vec<Rule>) {
    let v = helix();
    let reference = Reference::new(&v);
    let (baseline, _) = render(HELIX, &[], "baseline");
    let mut failures = Vec::new();
    for r in rules {
        let name = r.args.join("_").replace(['-', ',', ':', '.', ' ', '/'], "");
        let (actual, _) = render(HELIX, r.args, &name);
        let mut s = defaults(v.extent());
        (r.settings)(&mut s, v.extent());
        // The step each rule states is the one `render` resolves (the quality rule, src/scene/quality.rs).
        let stated = (s.sampling.step_length, s.sampling.max_stride, s.sampling.ray_spacing);
        resolve_quality(&mut s, r.args, v.range);
        if (s.sampling.step_length - stated.0).abs() > 1e-6
            || (s.sampling.max_stride, s.sampling.ray_spacing) != (stated.1, stated.2)
        {
            failures.push(format!(
                "{:?}: the quality rule gives step {} (strides up to {}, ray spacing {}), the test states {stated:?}",
                r.args, s.sampling.step_length, s.sampling.max_stride, s.sampling.ray_spacing
            ));
        }
        let expected = reference.render_full(&s);
        let d = against_reference(&actual, &expected, s.background);
        eprintln!("{:?}: {d}", r.args);
        if let Err(e) = r.bounds.check(&d) {
            write_failure_images(&format!("cli-{name}"), &actual, &expected.image);
            failures.push(format!("{:?} differs from the reference of its settings: {e}", r.args));
        }
        if actual.dimensions() == baseline.dimensions() && diff(&actual, &baseline).max == 0.0 {
            failures.push(format!("{:?} left the image unchanged", r.args));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn camera_options_take_effect() {
    check_rules(vec![
        rule(&["--azimuth", "120"], |s, _| {
            s.camera = Camera::orbit(120.0, 25.0, s.camera.eye.length(), Vec3::ZERO)
        }),
        rule(&["--elevation", "-40"], |s, _| {
            s.camera = Camera::orbit(35.0, -40.0, s.camera.eye.length(), Vec3::ZERO)
        }),
        rule(&["--distance", "1.1"], |s, _| {
            s.camera = Camera::orbit(35.0, 25.0, 1.1, Vec3::ZERO)
        }),
        rule(&["--eye", "0.9,-1.1,0.6"], |s, _| {
            s.camera = Camera::looking_at(Vec3::new(0.9, -1.1, 0.6), Vec3::ZERO)
        }),
        // A look-at point for the eye, the orbit and a view direction.
        rule(&["--eye", "0.9,-1.1,0.6", "--look-at", "0.15,0,-0.1"], |s, _| {
            s.camera = Camera::looking_at(Vec3::new(0.9, -1.1, 0.6), Vec3::new(0.15, 0.0, -0.1))
        }),
        rule(&["--look-at", "0,0.2,0.1"], |s, _| {
            s.camera = Camera::orbit(35.0, 25.0, s.camera.eye.length(), Vec3::new(0.0, 0.2, 0.1))
        }),
        rule(&["--view-dir", "-1,0.5,-0.3", "--distance", "1.6"], |s, _| {
            let dir = Vec3::new(-1.0, 0.5, -0.3).normalize();
            s.camera = Camera::looking_at(-dir * 1.6, Vec3::ZERO)
        }),
        // Through the pole without a jump: the azimuth still turns the image at 90° elevation.
        rule(&["--azimuth", "140", "--elevation", "90"], |s, _| {
            s.camera = Camera::orbit(140.0, 90.0, s.camera.eye.length(), Vec3::ZERO)
        }),
        rule(&["--fov", "50"], |s, e| {
            s.camera = Camera::orbit(35.0, 25.0, Camera::fit_distance(e.length() * 0.5, 50.0), Vec3::ZERO);
            s.camera.fov_y_deg = 50.0;
        }),
        rule(&["--ortho"], |s, _| s.camera.ortho = true),
        rule(&["--size", "80x36"], |s, _| (s.width, s.height) = (80, 36)),
    ]);
}

#[test]
fn classification_options_take_effect() {
    let tf_path = common::scratch("cli-options").join("tf.json");
    let tf = TransferFunction {
        name: "cli".into(),
        units: volcast::transfer::function::TfUnits::Normalized,
        colors: vec![[0.2, 1.0, 0.5, 0.0], [0.8, 0.0, 0.3, 1.0]],
        colormap: Colormap::Plasma,
        opacity: vec![[0.15, 0.0], [0.6, 0.3]],
    };
    std::fs::write(&tf_path, tf.to_json()).unwrap();
    // The rules are plain fns: the file's content is rebuilt inside the one that needs it.
    let mut rules = vec![
        rule(&["--colormap", "viridis"], |s, _| s.colour.colormap = Colormap::Viridis),
        rule(&["--colormap", "plasma"], |s, _| s.colour.colormap = Colormap::Plasma),
        rule(&["--colormap", "rainbow"], |s, _| s.colour.colormap = Colormap::Rainbow),
        rule(&["--colormap", "gnuplot"], |s, _| s.colour.colormap = Colormap::Gnuplot),
        rule(&["--colormap", "grayscale"], |s, _| {
            s.colour.colormap = Colormap::Grayscale
        }),
        rule(&["--window", "30%,80%"], |s, _| s.colour.window = [0.3, 0.8]),
        rule(&["--step-alpha", "0.4"], |s, _| s.colour.step_alpha = 0.4),
        // A forced step takes every sample.
        rule(&["--step-length", "2.5"], |s, _| {
            s.sampling.step_length = 2.5;
            s.sampling.max_stride = 1;
        }),
        // The helix's default opacity (0.1 per voxel) keeps each level's base step.
        rule(&["--quality", "fast"], |s, _| {
            s.sampling.step_length = 1.0;
            s.sampling.max_stride = 2;
        }),
        rule(&["--quality", "converged"], |s, _| {
            s.sampling.step_length = 0.125;
            s.sampling.max_stride = 1;
        }),
        // The helix's default opacity starts sharply at the window's edge: draft takes every pixel there, and
        // spaces its rays (rule 12) for a ramp from 0.
        rule(&["--quality", "draft"], |s, _| {
            s.sampling.step_length = 3.0;
            s.sampling.max_stride = 2;
            s.sampling.stride_tolerance = 4.0;
        }),
        Rule {
            bounds: SPACED,
            ..rule(&["--quality", "draft", "--multiplied-alpha"], |s, _| {
                s.sampling.step_length = 3.0;
                s.sampling.max_stride = 2;
                s.sampling.stride_tolerance = 4.0;
                s.colour.multiplied_alpha = true;
                s.sampling.ray_spacing = 2;
            })
        },
        Rule {
            bounds: SPACED,
            ..rule(&["--ray-spacing", "4"], |s, _| s.sampling.ray_spacing = 4)
        },
        // A faint opacity (extinction 0.0202 per voxel) lets every occupied brick stride 4 steps; --max-stride
        // caps it.
        rule(&["--step-alpha", "0.02"], |s, _| s.colour.step_alpha = 0.02),
        rule(&["--step-alpha", "0.02", "--max-stride", "2"], |s, _| {
            s.colour.step_alpha = 0.02;
            s.sampling.max_stride = 2;
        }),
        // A strong opacity shortens the step below the normal 0.4: to 0.25 / −ln(1 − 0.6) of a voxel.
        rule(&["--step-alpha", "0.6"], |s, _| {
            s.colour.step_alpha = 0.6;
            s.sampling.step_length = (0.25 / -(0.4f64).ln()) as f32;
        }),
        rule(&["--multiplied-alpha"], |s, _| s.colour.multiplied_alpha = true),
        rule(&["--preset", "mr-default"], |s, _| {
            s.colour.transfer_function = Some(TransferFunction::preset("mr-default").unwrap());
            s.colour.window = [0.0, 1.0];
        }),
        rule(&["--preset", "qt-example", "--window", "20%,90%"], |s, _| {
            s.colour.transfer_function = Some(TransferFunction::preset("qt-example").unwrap());
            s.colour.window = [0.2, 0.9];
        }),
        rule(&["--early-termination", "0.6"], |s, _| {
            s.compositing.early_termination = 0.6
        }),
        // Channels off the .5 rounding ties (0.3 × 255 = 76.5 would round either way).
        rule(&["--background", "0.2,0.35,0.45"], |s, _| {
            s.background = Vec3::new(0.2, 0.35, 0.45)
        }),
    ];
    let tf_arg: &'static str = Box::leak(tf_path.to_string_lossy().into_owned().into_boxed_str());
    rules.push(Rule {
        args: Box::leak(vec!["--tf", tf_arg].into_boxed_slice()),
        settings: |s, _| {
            let path = common::scratch("cli-options").join("tf.json");
            s.colour.transfer_function = Some(TransferFunction::load(&path).unwrap());
            s.colour.window = [0.0, 1.0];
        },
        bounds: REFERENCE,
    });
    check_rules(rules);
}

#[test]
fn mode_and_shading_options_take_effect() {
    check_rules(vec![
        rule(&["--mode", "mip"], |s, _| s.compositing.mode = CompositeMode::Mip),
        rule(&["--mode", "minip"], |s, _| s.compositing.mode = CompositeMode::MinIp),
        rule(&["--mode", "average"], |s, _| {
            s.compositing.mode = CompositeMode::Average
        }),
        // Iso-surfaces read gradients: the texture by default.
        rule(&["--mode", "iso"], |s, _| {
            s.compositing.mode = CompositeMode::Isosurface;
            s.lighting.gradient_texture = true;
        }),
        rule(&["--mode", "iso", "--iso", "30%"], |s, _| {
            s.compositing.mode = CompositeMode::Isosurface;
            s.compositing.iso_value = 0.3;
            s.lighting.gradient_texture = true;
        }),
        rule(
            &[
                "--mode",
                "iso",
                "--iso",
                "60%",
                "--iso-color",
                "colormap",
                "--iso-opacity",
                "0.7",
            ],
            |s, _| {
                s.compositing.mode = CompositeMode::Isosurface;
                (
                    s.compositing.iso_value,
                    s.compositing.iso_color,
                    s.compositing.iso_opacity,
                ) = (0.6, None, 0.7);
                s.lighting.gradient_texture = true;
            },
        ),
        rule(
            &[
                "--mode",
                "iso",
                "--iso-color",
                "0.2,0.8,0.4",
                "--surface",
                "30%,1,0,0,0.4",
                "--surface",
                "70%",
            ],
            |s, _| {
                s.compositing.mode = CompositeMode::Isosurface;
                s.compositing.iso_color = Some(glam::Vec3::new(0.2, 0.8, 0.4));
                s.compositing.extra_isosurfaces = vec![
                    volcast::scene::lighting::IsoSurface {
                        value: 0.3,
                        color: Some(glam::Vec3::X),
                        opacity: 0.4,
                    },
                    volcast::scene::lighting::IsoSurface {
                        value: 0.7,
                        ..Default::default()
                    },
                ];
                s.lighting.gradient_texture = true;
            },
        ),
        // Light options turn shading on.
        rule(
            &[
                "--light",
                "1,-2,0.5",
                "--light-color",
                "1,0.5,0.2",
                "--light-intensity",
                "1.5",
            ],
            |s, _| {
                s.lighting.shading = Some(Shading::default());
                s.lighting.light = volcast::scene::lighting::Light {
                    direction: Some(glam::Vec3::new(1.0, -2.0, 0.5)),
                    color: glam::Vec3::new(1.0, 0.5, 0.2),
                    intensity: 1.5,
                };
                s.lighting.gradient_texture = true;
            },
        ),
        rule(&["--mode", "iso", "--light", "head"], |s, _| {
            s.compositing.mode = CompositeMode::Isosurface;
            s.lighting.shading = Some(Shading::default());
            s.lighting.gradient_texture = true;
        }),
        // At one voxel per step and density 1 the density model's opacity a·1·1 equals emission's 1 − (1 − a)¹.
        rule(&["--mode", "density", "--step-length", "2"], |s, _| {
            s.compositing.mode = CompositeMode::Density;
            s.sampling.step_length = 2.0;
            s.sampling.max_stride = 1;
        }),
        rule(&["--mode", "density", "--density", "3"], |s, _| {
            s.compositing.mode = CompositeMode::Density;
            s.compositing.density = 3.0;
        }),
        // Shaded and gradient-opacity frames take the gradient texture by default (`--gradients auto`).
        rule(&["--shading"], |s, _| {
            s.lighting.shading = Some(Shading::default());
            s.lighting.gradient_texture = true;
        }),
        rule(&["--shading", "--gradients", "samples"], |s, _| {
            s.lighting.shading = Some(Shading::default())
        }),
        rule(&["--shading", "--lighting", "0.1,0.5,0.8,40"], |s, _| {
            s.lighting.shading = Some(Shading {
                ambient: 0.1,
                diffuse: 0.5,
                specular: 0.8,
                shininess: 40.0,
            });
            s.lighting.gradient_texture = true;
        }),
        rule(&["--gradient-opacity", "0.05"], |s, _| {
            s.lighting.gradient_opacity = Some(0.05);
            s.lighting.gradient_texture = true;
        }),
        rule(&["--gradient-opacity", "0.05", "--gradients", "samples"], |s, _| {
            s.lighting.gradient_opacity = Some(0.05)
        }),
        rule(&["--shading", "--gradient-texture"], |s, _| {
            s.lighting.shading = Some(Shading::default());
            s.lighting.gradient_texture = true;
        }),
        rule(&["--no-jitter"], |s, _| s.sampling.jitter = None),
        rule(&["--jitter-seed", "9"], |s, _| s.sampling.jitter = Some(9)),
        rule(&["--slice", "x:0.4:0.3"], |s, _| s.cut.set_slab(0, 0.4, 0.3)),
        rule(&["--slice", "x:0.4:0.3", "--slice", "z:0.6:0.5"], |s, _| {
            s.cut.set_slab(0, 0.4, 0.3);
            s.cut.set_slab(2, 0.6, 0.5);
        }),
    ]);
}

/// Options that change how the image is made but not which image: each must match the reference of the
/// default settings (and `--no-skip` the default image exactly).
#[test]
fn method_and_storage_options_keep_the_image() {
    let v = helix();
    let expected = Reference::new(&v).render_full(&defaults(v.extent()));
    let (baseline, _) = render(HELIX, &[], "same-baseline");
    let cases: [(&[&str], &'static str, Bounds); 9] = [
        (&["--method", "faces"], "reference", REFERENCE),
        (&["--method", "analytic"], "reference", REFERENCE),
        (&["--method", "compute"], "reference", REFERENCE),
        (&["--positions", "rgba16f"], "positions-rgba16f", POSITIONS_RGBA16F),
        (&["--texture", "native"], "reference-r8", REFERENCE_R8),
        (&["--texture", "float"], "reference", REFERENCE),
        (&["--texture", "corners"], "reference", REFERENCE),
        (&["--max-stride", "1"], "reference", REFERENCE),
        (&["--no-skip"], "reference", REFERENCE),
    ];
    let mut judge = Judge::default();
    let mut failures = Vec::new();
    for (args, family, bounds) in cases {
        let name = args.join("_").replace('-', "");
        let (actual, stdout) = render(HELIX, args, &name);
        let d = against_reference(&actual, &expected, Vec3::ZERO);
        judge.record(family, format!("cli-{name}"), d, bounds, (&actual, &expected.image));
        if args == ["--method", "compute"] && !stdout.contains("analytic (compute pass)") {
            failures.push(format!(
                "--method compute does not say it marched in a compute pass: {stdout}"
            ));
        }
        if args == ["--no-skip"] && diff(&actual, &baseline).max > 0.0 {
            failures.push("--no-skip changed the image: skipping must not".into());
        }
    }
    judge.assert_all();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The volume options, on the helix written as a raw file: each is checked against the reference of the volume
/// the option should produce.
#[test]
fn volume_options_take_effect() {
    let v = helix();
    let bytes = v.gpu_bytes().to_vec();
    let named = common::scratch("cli-options").join("helix_48x48x48_uint8.raw");
    std::fs::write(&named, &bytes).unwrap();
    let unnamed = common::scratch("cli-options").join("scan.bin");
    std::fs::write(&unnamed, &bytes).unwrap();
    let mut header = vec![0xabu8; 100];
    header.extend_from_slice(&bytes);
    let headed = common::scratch("cli-options").join("headed.bin");
    std::fs::write(&headed, &header).unwrap();
    // The same values as uint16, big-endian (value × 257 keeps the normalised values).
    let big: Vec<u8> = bytes.iter().flat_map(|&b| (u16::from(b) * 257).to_be_bytes()).collect();
    let big_path = common::scratch("cli-options").join("big.bin");
    std::fs::write(&big_path, &big).unwrap();

    let raw = |p: &PathBuf, rest: &[&str]| {
        let mut args = vec![p.to_string_lossy().into_owned()];
        args.extend(rest.iter().map(|s| s.to_string()));
        args
    };
    let spaced = v.clone().with_spacing([1.0, 1.0, 2.0]).unwrap();
    let helix_spaced: Vec<String> = [HELIX, &["--spacing", "1", "1", "2"]]
        .concat()
        .iter()
        .map(|s| s.to_string())
        .collect();
    let cases: Vec<(Vec<String>, Volume)> = vec![
        (raw(&named, &[]), v.clone()),
        (raw(&named, &["--spacing", "1", "1", "2"]), spaced.clone()),
        (helix_spaced, spaced),
        (
            raw(&unnamed, &["--dims", "48", "48", "48", "--type", "uint8"]),
            v.clone(),
        ),
        (
            raw(
                &headed,
                &["--dims", "48", "48", "48", "--type", "uint8", "--header-bytes", "100"],
            ),
            v.clone(),
        ),
        (
            raw(
                &big_path,
                &["--dims", "48", "48", "48", "--type", "uint16", "--endian", "big"],
            ),
            v.clone(),
        ),
        (
            raw(&named, &["--max-dim", "32"]),
            volcast::pyramid::max_dim::downsample_to(v.clone(), 32),
        ),
    ];
    let mut failures = Vec::new();
    for (i, (args, volume)) in cases.iter().enumerate() {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (actual, stdout) = render(&args, &[], &format!("volume-{i}"));
        let mut s = defaults(volume.extent());
        if args[0] != "--builtin" {
            // A file given no classification option is shown with the automatic transfer function (as the viewer
            // shows it), at the normal quality's step for that function.
            s.colour.transfer_function = Some(volcast::transfer::auto::auto_for_volume(volume));
            s.colour.window = [0.0, 1.0];
            volcast::scene::quality::Quality::Normal.apply(&mut s, volume.range);
            if !stdout.contains("transfer function 'auto: ") {
                failures.push(format!(
                    "{args:?}: render does not say it took the automatic function: {stdout}"
                ));
            }
        }
        let expected = Reference::new(volume).render_full(&s);
        let d = against_reference(&actual, &expected, s.background);
        eprintln!("{args:?}: {d}");
        if let Err(e) = REFERENCE.check(&d) {
            write_failure_images(&format!("cli-volume-{i}"), &actual, &expected.image);
            failures.push(format!("{args:?}: {e}"));
        }
        let dims = format!("{}x{}x{}", volume.dims[0], volume.dims[1], volume.dims[2]);
        if !stdout.contains(&dims) {
            failures.push(format!("{args:?}: expected {dims} in: {stdout}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
