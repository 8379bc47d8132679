//! `volcast render`'s and `volcast view`'s own options, parsed from the argument list the Python side builds of
//! its keyword arguments (`python/volcast/_options.py`): one definition of every option, its values and its
//! defaults, shared with the command line. [`render_options`] lists them for that conversion and for the test that
//! walks them.

use clap::{ArgAction, CommandFactory, Parser};
use pyo3::prelude::*;
use volcast::cli::args::{GpuArgs, RenderArgs, ViewArgs, VolumeArgs};
use volcast::cli::frame::Given;
use volcast::cli::UsageError;
use volcast::transfer::function::TransferFunction;

#[derive(Parser)]
#[command(name = "volcast.render", no_binary_name = true, disable_help_flag = true)]
struct RenderLine {
    #[command(flatten)]
    args: RenderArgs,
}

#[derive(Parser)]
#[command(name = "volcast.view", no_binary_name = true, disable_help_flag = true)]
struct ViewLine {
    #[command(flatten)]
    args: ViewArgs,
}

#[derive(Parser)]
#[command(name = "volcast.open", no_binary_name = true, disable_help_flag = true)]
struct OpenLine {
    #[command(flatten)]
    args: VolumeArgs,
}

#[derive(Parser)]
#[command(name = "volcast", no_binary_name = true, disable_help_flag = true)]
struct GpuLine {
    #[command(flatten)]
    args: GpuArgs,
}

/// The device options' defaults (VOLCAST_VALIDATION still applies).
pub fn default_gpu_args() -> GpuArgs {
    GpuLine::parse_from(Vec::<String>::new()).args
}

/// clap's message as a Python user reads it: its first line, options named as keyword arguments (`azimuth=`
/// for `--azimuth`).
fn clap_message(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let first = text.lines().next().unwrap_or_default().trim_start_matches("error: ");
    let mut out = String::new();
    let mut rest = first;
    while let Some(at) = rest.find("--") {
        out.push_str(&rest[..at]);
        let name: String = rest[at + 2..]
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
            .collect();
        out.push_str(&name.replace('-', "_"));
        out.push('=');
        rest = &rest[at + 2 + name.len()..];
        // "--size <WxH>" reads "size=<WxH>"; "--size=<WxH>" would read "size==<WxH>".
        rest = rest.strip_prefix(' ').filter(|r| r.starts_with('<')).unwrap_or(rest);
        rest = rest.strip_prefix('=').unwrap_or(rest);
    }
    out.push_str(rest);
    out
}

fn parse<P: Parser>(argv: Vec<String>) -> anyhow::Result<(P, clap::ArgMatches)> {
    let matches = P::command()
        .try_get_matches_from(argv)
        .map_err(|e| UsageError(clap_message(&e)))?;
    let line = P::from_arg_matches(&matches).map_err(|e| UsageError(clap_message(&e)))?;
    Ok((line, matches))
}

/// A transfer function from its JSON (the `--tf` file format), checked.
pub fn tf_from_json(json: &str) -> anyhow::Result<TransferFunction> {
    let tf: TransferFunction =
        serde_json::from_str(json).map_err(|e| UsageError(format!("not a transfer function: {e}")))?;
    tf.validate()?;
    Ok(tf)
}

/// `render`'s arguments from `argv` (options only; the volume is the caller's), with a transfer function given
/// as JSON counting as `--tf`.
pub fn parse_render(argv: Vec<String>, tf_json: Option<String>) -> anyhow::Result<RenderArgs> {
    let (line, matches) = parse::<RenderLine>(argv)?;
    let mut args = line.args;
    args.frame.given = Given::from_matches(&matches);
    args.frame.given.from_file = args.volume.builtin.is_none();
    if let Some(json) = tf_json {
        if args.frame.colour.preset.is_some() || args.frame.colour.tf.is_some() {
            return Err(UsageError("tf= takes a TransferFunction or a file; preset= is another".into()).into());
        }
        args.frame.colour.tf_value = Some(tf_from_json(&json)?);
        args.frame.given.insert("tf");
    }
    Ok(args)
}

/// The volume options of `open` (a file's path after `--`).
pub fn parse_open(argv: Vec<String>) -> anyhow::Result<VolumeArgs> {
    Ok(parse::<OpenLine>(argv)?.0.args)
}

/// `view`'s arguments from `argv`.
pub fn parse_view(argv: Vec<String>) -> anyhow::Result<ViewArgs> {
    Ok(parse::<ViewLine>(argv)?.0.args)
}

/// One option as the Python side converts it: (keyword, flag, kind, help, defaults, allowed values). `kind` is
/// "flag" (true or false), "value", "values" (a sequence of a fixed count, as `dims`) or "repeat" (one value or
/// a list of them, as `surface`).
type OptionSpec = (String, String, String, String, Vec<String>, Vec<String>);

fn specs(command: clap::Command) -> Vec<OptionSpec> {
    command
        .get_arguments()
        .filter_map(|a| {
            let long = a.get_long()?;
            let kind = match a.get_action() {
                ArgAction::SetTrue => "flag",
                _ if a.get_num_args().is_some_and(|n| n.max_values() > 1) => "values",
                ArgAction::Append => "repeat",
                _ => "value",
            };
            let help = a.get_help().map(|h| h.to_string()).unwrap_or_default();
            let defaults = a
                .get_default_values()
                .iter()
                .map(|v| v.to_string_lossy().into_owned())
                .collect();
            let allowed = a
                .get_possible_values()
                .iter()
                .map(|v| v.get_name().to_string())
                .collect();
            Some((
                long.replace('-', "_"),
                format!("--{long}"),
                kind.to_string(),
                help,
                defaults,
                allowed,
            ))
        })
        .collect()
}

/// Every option of `volcast render` (the FILE aside, which is the call's first argument).
#[pyfunction]
pub fn render_options() -> Vec<OptionSpec> {
    specs(RenderLine::command())
}

/// Every volume option (how a file is read), as `volcast.open` takes them.
#[pyfunction]
pub fn open_options() -> Vec<OptionSpec> {
    specs(OpenLine::command())
}

/// Every option of `volcast view`.
#[pyfunction]
pub fn view_options() -> Vec<OptionSpec> {
    specs(ViewLine::command())
}

/// The transfer function `json` describes, checked and written back in full (`ValueError` where it is not one).
#[pyfunction]
pub fn check_tf(json: &str) -> PyResult<String> {
    tf_from_json(json)
        .map(|tf| tf.to_json())
        .map_err(|e| crate::errors::to_py(e, crate::errors::While::Converting))
}

/// A preset transfer function's JSON.
#[pyfunction]
pub fn preset_tf(name: &str) -> PyResult<String> {
    TransferFunction::preset(name)
        .map(|tf| tf.to_json())
        .map_err(|e| crate::errors::to_py(e.into(), crate::errors::While::Converting))
}
