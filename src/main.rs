//! The `volcast` command line: parses it, picks a subcommand (its arguments and body are in `cli/`), reports errors
//! with their exit status.

use volcast::cli;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use cli::args::{BenchArgs, CacheArgs, CompareArgs, ConvertArgs, GpuArgs, InfoArgs, RenderArgs, ViewArgs, VolumeArgs};
use cli::commands::{bench, compare, devices, info, view};
use cli::render::render;
use std::process::ExitCode;
use volcast::scene::quality::Quality;

#[derive(Parser)]
#[command(
    name = "volcast",
    version,
    about = "Volume ray caster on raw Vulkan",
    propagate_version = true
)]
struct Cli {
    /// Without a subcommand: `volcast view --builtin helix`; `volcast FILE [OPTIONS]` is `volcast view FILE
    /// [OPTIONS]`.
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Open the desktop viewer (the default without a subcommand).
    View(Box<ViewArgs>),
    /// Render a volume to a PNG, JPEG or TIFF file without a window.
    Render(Box<RenderArgs>),
    /// Print a volume's dimensions, type, spacing, value range, placement in space and memory needs.
    Info(Box<InfoArgs>),
    /// Per label of a label map: voxels, volume in mm³, and the mean, min and max of the volume under it.
    Stats(Box<volcast::cli::stats::StatsArgs>),
    /// Render built-in viewpoints with both ray setups and measure how they differ and what each costs.
    Compare(Box<CompareArgs>),
    /// Time a fixed set of scenes and the raw 3D-texture sample rate (docs/performance.md).
    Bench(Box<BenchArgs>),
    /// Write a volume as an OME-Zarr store with a multiscale pyramid (docs/cli.md, convert).
    Convert(Box<ConvertArgs>),
    /// Show or empty the pyramid cache (levels of large files kept for the next open; docs/large-volumes.md).
    Cache(Box<CacheArgs>),
    /// List the Vulkan devices and which one volcast would pick.
    Devices,
}

/// The exit status of a malformed command line.
const USAGE_EXIT: u8 = 64;

/// The options subcommand `name`'s command line gave.
fn given(matches: &clap::ArgMatches, name: &str, volume: &VolumeArgs) -> cli::frame::Given {
    let mut given = matches
        .subcommand_matches(name)
        .map(cli::frame::Given::from_matches)
        .unwrap_or_default();
    given.from_file = volume.builtin.is_none();
    given
}

/// `volcast FILE …` as `volcast view FILE …`: where the first argument names no subcommand and is a file or folder
/// that exists, or reads as a path (a `/` or an extension; a misspelled subcommand has neither, and keeps clap's
/// "did you mean"). A subcommand wins over a file of the same name.
fn view_by_default(mut args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    let command = Cli::command();
    let Some(first) = args.get(1).and_then(|a| a.to_str()) else {
        return args;
    };
    let subcommand = first == "help"
        || command
            .get_subcommands()
            .any(|c| c.get_name() == first || c.get_all_aliases().any(|a| a == first));
    let path = std::path::Path::new(first);
    let a_path = path.exists() || first.contains('/') || path.extension().is_some();
    if !first.starts_with('-') && !subcommand && a_path {
        args.insert(1, "view".into());
    }
    args
}

fn main() -> ExitCode {
    // Usage errors exit 64 (sysexits' EX_USAGE), not clap's 2: 2 says "no usable Vulkan".
    let parsed = Cli::command()
        .try_get_matches_from(view_by_default(std::env::args_os().collect()))
        .and_then(|m| Cli::from_arg_matches(&m).map(|cli| (cli, m)));
    let (mut cli, matches) = match parsed {
        Ok(parsed) => parsed,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { USAGE_EXIT } else { 0 });
        }
    };
    // Which frame options the command line gave: `render --state` applies those over the saved view, and a file
    // given none of the classification options is shown with the automatic transfer function.
    match &mut cli.command {
        Some(Command::Render(a)) => a.frame.given = given(&matches, "render", &a.volume),
        Some(Command::Compare(a)) => a.frame.given = given(&matches, "compare", &a.volume),
        _ => {}
    }
    let result = match &cli.command {
        None => view(&ViewArgs {
            volume: VolumeArgs {
                file: None,
                builtin: Some("helix".into()),
                builtin_size: None,
                dims: None,
                voxel_type: None,
                spacing: None,
                endian: None,
                header_bytes: None,
                max_dim: None,
                budgets: Default::default(),
                cache_dir: None,
                no_cache: false,
                no_downsample: false,
                array: None,
                series: None,
                channel: None,
                time: None,
            },
            layers: Default::default(),
            gpu: GpuArgs {
                validate: false,
                device: None,
                texture: "auto".into(),
                brick_size: None,
            },
            size: (1280, 800),
            quality: Quality::Normal,
            script: None,
            slices: false,
            state: None,
            preset: None,
            tf: None,
        }),
        Some(Command::View(a)) => view(a),
        // Under mpirun: sort-last rendering where built with MPI (one rank included, for measuring), else refused
        // for more than one rank.
        Some(Command::Render(a)) => {
            match volcast::distributed::launched_ranks().filter(|&n| n > 1 || cfg!(feature = "mpi")) {
                Some(ranks) => distributed(a, ranks),
                None => render(a),
            }
        }
        Some(Command::Compare(a)) => compare(a),
        Some(Command::Bench(a)) => bench(a),
        Some(Command::Info(a)) => info(a),
        Some(Command::Stats(a)) => volcast::cli::stats::stats(a),
        Some(Command::Convert(a)) => cli::convert::convert(a),
        Some(Command::Cache(a)) => cli::commands::cache(a),
        Some(Command::Devices) => devices(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", cli::error_text(&e));
            let unavailable = cli::is_unavailable(&e);
            let usage = cli::is_usage(&e);
            ExitCode::from(if unavailable {
                2
            } else if usage {
                USAGE_EXIT
            } else {
                1
            })
        }
    }
}

/// `render` as one of `ranks` processes started by mpirun: sort-last rendering (docs/distributed.md), where the binary
/// was built with the feature `mpi`; else refused, rather than every rank rendering the whole and writing one file.
#[cfg(feature = "mpi")]
fn distributed(args: &RenderArgs, _ranks: u32) -> anyhow::Result<()> {
    volcast::distributed::run::render(args)
}

#[cfg(not(feature = "mpi"))]
fn distributed(_args: &RenderArgs, ranks: u32) -> anyhow::Result<()> {
    anyhow::bail!(cli::UsageError(format!(
        "volcast was started by mpirun as one of {ranks} processes but built without MPI: build it with `cargo build \
         --release --features mpi` (docs/distributed.md), or run it as one process"
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// clap checks ids, conflicts and requirements only in debug builds: this runs its checks in any build, over
    /// the option groups every subcommand flattens.
    #[test]
    fn the_command_line_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
