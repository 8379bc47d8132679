//! The subcommands of the `volcast` binary: their arguments, value parsers and bodies, one concern per file.

pub mod args;
pub mod budgets;
pub mod commands;
pub mod convert;
pub mod frame;
pub mod layers;
pub mod parse;
pub mod render;
pub mod settings;
pub mod stats;

use anyhow::{bail, Result};

/// A command line whose values do not make a valid frame on their own (an empty window, a light of no direction):
/// it exits 64 like a value that does not parse, and says what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);
use crate::gpu::Gpu;
use args::GpuArgs;

/// Runs `body` with a GPU and reports validation messages at the end; any validation error or warning fails the
/// command.
pub fn with_gpu<T>(args: &GpuArgs, body: impl FnOnce(&Gpu) -> Result<T>) -> Result<T> {
    let gpu = Gpu::new(&args.options())?;
    let validating = gpu.validation_enabled();
    let log = gpu.log.clone();
    let result = body(&gpu);
    drop(gpu);
    if validating {
        let (errors, warnings) = (log.error_count(), log.warning_count());
        eprintln!("validation: {errors} errors, {warnings} warnings");
        if errors + warnings > 0 && result.is_ok() {
            bail!("the validation layer reported {errors} error(s) and {warnings} warning(s)");
        }
    }
    result
}

/// `e` and its causes, each cause added only where the text so far does not already say it (errors that embed
/// their source in their own message would otherwise print it twice: "…(os error 2): …(os error 2)").
pub fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let part = cause.to_string();
        if text.is_empty() {
            text = part;
        } else if !text.contains(&part) {
            text = format!("{text}: {part}");
        }
    }
    text
}

/// Whether `e` says there is no usable Vulkan device or no display (exit status 2; the Python module's
/// `RuntimeError` that says what to install).
pub fn is_unavailable(e: &anyhow::Error) -> bool {
    use crate::viewer::ViewerError;
    e.downcast_ref::<crate::gpu::GpuError>()
        .is_some_and(|g| g.is_unavailable())
        || e.downcast_ref::<ViewerError>().is_some_and(|v| match v {
            ViewerError::NoDisplay(_) => true,
            ViewerError::Gpu(g) => g.is_unavailable(),
            ViewerError::Other(_) => false,
        })
}

/// Whether `e` is a usage error: a value or combination of options that cannot work (exit status 64; the Python
/// module's `ValueError`).
pub fn is_usage(e: &anyhow::Error) -> bool {
    e.downcast_ref::<crate::movie::MovieError>()
        .is_some_and(|m| matches!(m, crate::movie::MovieError::Usage(_)))
        || e.downcast_ref::<UsageError>().is_some()
}
