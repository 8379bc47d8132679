//! The subcommands of the `volcast` binary: their arguments, value parsers and bodies, one concern per file.

pub(crate) mod args;
pub(crate) mod commands;
pub(crate) mod convert;
pub(crate) mod frame;
pub(crate) mod parse;
pub(crate) mod render;
pub(crate) mod settings;

use anyhow::{bail, Result};

/// A command line whose values do not make a valid frame on their own (an empty window, a light of no direction):
/// it exits 64 like a value that does not parse, and says what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct UsageError(pub(crate) String);
use args::GpuArgs;
use volcast::gpu::Gpu;

/// Runs `body` with a GPU and reports validation messages at the end; any validation error or warning fails the
/// command.
pub(crate) fn with_gpu<T>(args: &GpuArgs, body: impl FnOnce(&Gpu) -> Result<T>) -> Result<T> {
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
