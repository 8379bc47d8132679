//! The other subcommands' bodies: `view`, `compare`, `bench`, `info` and `devices`.

use super::args::{BenchArgs, CacheArgs, CompareArgs, InfoArgs, ViewArgs};
use super::with_gpu;
use crate::gpu::GpuError;
use crate::measure::compare;
use crate::render::headless::Headless;
use crate::scene::quality::Quality;
use crate::scene::view_state::ViewState;
use crate::transfer::function::TransferFunction;
use crate::viewer::{self, ViewerOptions, VolumeSource};
use crate::volume::Volume;
use anyhow::{bail, Context, Result};
use std::path::PathBuf;

pub fn view(args: &ViewArgs) -> Result<()> {
    view_source(args, None, Vec::new())
}

/// The layers `args` name, else those of the session restored (with its looks), read before the window opens
/// (`--channels` reads the volume's file here to list them).
fn view_layers(
    args: &ViewArgs,
    restore: Option<&ViewState>,
    held: Vec<(Volume, bool)>,
) -> Result<crate::scene::layer_set::Layers> {
    let (layer_args, saved) = match restore {
        Some(state) => args.layers.or_from(&state.layer_files),
        None => (args.layers.clone(), false),
    };
    let channels = if layer_args.channels.is_empty() {
        Vec::new()
    } else {
        let base = args.volume.load_without_notes()?;
        layer_args.channels_of(&base, |k| args.volume.channel(k))?
    };
    let mut layers = layer_args.load_all(channels, held)?;
    if let Some(state) = restore.filter(|_| saved && !args.layers.styled()) {
        layers.styles = layers.looks(&state.settings.layers);
    }
    Ok(layers)
}

/// The viewer on `source` where one is given (the Python module's volumes), else on what `args` name.
/// `held`: layers the caller holds (the Python module's arrays), each an overlay or (true) a label map.
pub fn view_source(args: &ViewArgs, source: Option<VolumeSource>, held: Vec<(Volume, bool)>) -> Result<()> {
    let restore = match &args.state {
        Some(path) => Some(viewer::session::read(path).map_err(anyhow::Error::msg)?),
        None => None,
    };
    let from_session = restore.as_ref().and_then(|s| viewer::session::source_of(&s.volume));
    let source = match (&args.volume.builtin, &args.volume.file, from_session) {
        _ if source.is_some() => source.expect("matched"),
        (Some(name), _, _) => VolumeSource::Builtin(name.clone(), args.volume.builtin_size),
        (None, Some(path), _) => VolumeSource::File(path.clone(), args.volume.raw_options()?),
        (None, None, Some(source)) => source,
        (None, None, None) => VolumeSource::Builtin("helix".into(), None),
    };
    let script = match &args.script {
        Some(s) => viewer::parse_script(s).map_err(anyhow::Error::msg)?,
        None => Vec::new(),
    };
    let transfer_function = match (&args.preset, &args.tf) {
        (Some(name), _) if name == "auto" => None,
        (Some(name), _) => Some(TransferFunction::preset(name)?),
        (None, Some(path)) => Some(TransferFunction::load(path)?),
        (None, None) => None,
    };
    let layers = view_layers(args, restore.as_ref(), held)?;
    let opts = ViewerOptions {
        source,
        series: args.volume.series.clone(),
        channel: args.volume.channel,
        gpu: args.gpu.options(),
        size: args.size,
        script,
        time: args.volume.time.or(restore.as_ref().map(|s| s.volume.time)),
        host_budget: args.volume.budgets.host_budget,
        gpu_budget: args.volume.budgets.gpu_budget,
        max_dim: args.volume.max_dim,
        cache_dir: args.volume.cache_dir.clone(),
        no_cache: args.volume.no_cache,
        quality: args.quality,
        slices: args.slices,
        restore,
        transfer_function,
        layers,
        layer_looks: args.layers.looks(),
    };
    let log = viewer::run(opts)?;
    if args.gpu.options().validation {
        let (errors, warnings) = (log.error_count(), log.warning_count());
        eprintln!("validation: {errors} errors, {warnings} warnings");
        if errors + warnings > 0 {
            bail!("the validation layer reported {errors} error(s) and {warnings} warning(s)");
        }
    }
    Ok(())
}

pub fn compare(args: &CompareArgs) -> Result<()> {
    let volume = args.volume.load()?;
    let mut base = args.frame.settings(&volume)?;
    // Rule 13's layers in every view, for both ray setups.
    super::layers::check(args.layers.any(), &base)?;
    let channels = args.layers.channels_of(&volume, |k| args.volume.channel(k))?;
    let layers = args.layers.load_all(channels, Vec::new())?;
    base.layers = layers.styles.clone();
    let mut views = compare::builtin_views(&base, volume.extent());
    if args.frame.camera.eye.is_some() {
        views.push(compare::View {
            name: "eye".into(),
            settings: base.clone(),
        });
    }
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    with_gpu(&args.gpu, |gpu| {
        let volume = args.volume.fit_device(gpu, volume)?;
        let mut headless = Headless::new(gpu)?;
        let result = (|| -> Result<Vec<compare::Row>> {
            headless.set_volume(gpu, &volume)?;
            super::layers::upload(&layers, gpu, &mut headless, &volume)?;
            let mut rows = Vec::new();
            for view in &views {
                let c = compare::compare_view(gpu, &mut headless, view, args.frames)?;
                let diff = crate::measure::image_diff::amplified_diff(&c.faces.image, &c.analytic.image, 10);
                let save = |suffix: &str, img: &image::RgbaImage| -> Result<()> {
                    let path = args.out.join(format!("{}-{suffix}.png", view.name));
                    crate::render::save::save(img, &path).map_err(anyhow::Error::msg)
                };
                save("faces", &c.faces.image)?;
                save("analytic", &c.analytic.image)?;
                save("diff", &diff)?;
                save(
                    "side-by-side",
                    &crate::measure::image_diff::side_by_side(&[&c.faces.image, &c.analytic.image, &diff]),
                )?;
                println!("{:>15}: {}", view.name, c.verdict());
                rows.push(compare::Row::from(&c));
            }
            Ok(rows)
        })();
        headless.destroy(gpu);
        let rows = result?;
        let table = compare::markdown_table(&rows);
        println!(
            "\n{} ({}x{}x{} {}) at {}x{} on {}; images are faces | analytic | difference x10\n\n{table}",
            volume.name,
            volume.dims[0],
            volume.dims[1],
            volume.dims[2],
            volume.source_type,
            base.width,
            base.height,
            gpu.device_name
        );
        std::fs::write(args.out.join("compare.md"), &table)?;
        std::fs::write(args.out.join("compare.json"), serde_json::to_string_pretty(&rows)?)?;
        println!(
            "wrote {}/compare.md, compare.json and 4 images per view",
            args.out.display()
        );
        let differing = rows.iter().filter(|r| !r.agree).count();
        if differing > 0 {
            println!("{differing} view(s) differ beyond the bound");
        }
        Ok(())
    })
}

pub fn bench(args: &BenchArgs) -> Result<()> {
    let opts = crate::measure::bench::BenchOptions {
        frames: if args.quick { args.frames.min(2) } else { args.frames },
        warmup: if args.quick { args.warmup.min(1) } else { args.warmup },
        data_dir: args.data.clone(),
        vtk_raw: args.vtk_raw.clone(),
        quick: args.quick,
        scenes: args.scenes.clone(),
        sizes: args.sizes.clone(),
        shadings: args.shadings.clone(),
        methods: args.methods.clone(),
        sample_only: args.sample_only,
        qualities: if args.qualities.is_empty() {
            vec![Quality::Normal]
        } else {
            args.qualities.clone()
        },
        gradients: args.gradients,
        step_length: args.step_length,
    };
    if args.scale {
        return scale_bench(args);
    }
    // The other benchmarks show their scenes whole: a budget they would ignore is refused, as clap refused it
    // before the budgets were one group of flags.
    if args.budgets.given() {
        bail!(super::UsageError(
            "--host-budget and --gpu-budget apply to bench --scale only".into()
        ));
    }
    if args.playback {
        let play = if args.quick {
            crate::measure::playback::PlaybackOptions::QUICK
        } else {
            crate::measure::playback::PlaybackOptions::FULL
        };
        return with_gpu(&args.gpu, |gpu| {
            let report = crate::measure::playback::run(gpu, &play, &mut |line| eprintln!("{line}"))?;
            if args.json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", report.text());
            }
            Ok(())
        });
    }
    with_gpu(&args.gpu, |gpu| {
        let report = crate::measure::bench::run(gpu, &opts, &mut |line| eprintln!("{line}"))?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&report)?);
        } else {
            print!("{}", report.text());
        }
        Ok(())
    })
}

/// `bench --scale`.
fn scale_bench(args: &BenchArgs) -> Result<()> {
    use crate::measure::scale_bench::{self, ScaleScene};
    let scenes: Vec<ScaleScene> = if args.scale_edges.is_empty() {
        ScaleScene::DEFAULT.to_vec()
    } else {
        let t = if args.scale_type == "uint16" {
            crate::volume::VoxelType::U16
        } else {
            crate::volume::VoxelType::U8
        };
        args.scale_edges
            .iter()
            .map(|&e| ScaleScene::new(e.clamp(16, 16384), t))
            .collect()
    };
    let dir = match &args.cache {
        Some(d) => d.clone(),
        None => std::env::var_os("XDG_CACHE_HOME")
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
            .unwrap_or_else(std::env::temp_dir)
            .join("volcast/bench"),
    };
    let size = args.sizes.first().copied().unwrap_or(512);
    with_gpu(&args.gpu, |gpu| {
        let budgets = args.budgets.on(gpu);
        let rows = scale_bench::run(gpu, &scenes, &dir, budgets, (size, args.frames), &mut |l| {
            eprintln!("{l}")
        })
        .map_err(|e| anyhow::anyhow!("{e}"))?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&rows)?);
        } else {
            print!("{}", scale_bench::table(&rows, &gpu.device_name, size, budgets));
        }
        Ok(())
    })
}

/// `volcast cache`: where the pyramid cache is, what it holds, and `--clear`.
pub fn cache(args: &CacheArgs) -> Result<()> {
    let cache = crate::scale::cache::PyramidCache::new(args.cache_dir.clone());
    let (entries, bytes) = cache.usage();
    println!(
        "pyramid cache: {} ({entries} entr{}, {} MiB)",
        cache.root.join("pyramids").display(),
        if entries == 1 { "y" } else { "ies" },
        bytes >> 20
    );
    if args.clear {
        let freed = cache
            .clear()
            .with_context(|| format!("emptying {}", cache.root.join("pyramids").display()))?;
        println!("emptied: {} MiB freed", freed >> 20);
    }
    Ok(())
}

pub fn info(args: &InfoArgs) -> Result<()> {
    let v = args.volume.load_without_notes()?;
    let info = crate::render::info::Info::of(&v);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&info)?);
    } else {
        print!("{}", info.text(&v));
    }
    Ok(())
}

pub fn devices() -> Result<()> {
    let list = crate::gpu::list_devices()?;
    if list.is_empty() {
        return Err(GpuError::NoDevice("the Vulkan loader found no physical device".into()).into());
    }
    let chosen = crate::gpu::default_device(&list);
    for d in &list {
        let mark = if chosen == Some(d.index) {
            "  <- volcast's choice (--device picks another)"
        } else {
            ""
        };
        println!("{d}{mark}");
    }
    Ok(())
}
