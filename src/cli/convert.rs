//! `volcast convert`: a volume to an OME-Zarr store. Files whose voxels lie uncompressed on disk are read slab by
//! slab in place; everything else is loaded once and streamed from memory.

use super::args::ConvertArgs;
use crate::convert::layout::OmeVersion;
use crate::convert::source::Source;
use crate::convert::{self, Compression, ConvertError, ConvertOptions};
use crate::formats;
use crate::pyramid::reduce::Reduce;
use anyhow::{Context, Result};
use std::time::Instant;

pub fn convert(args: &ConvertArgs) -> Result<()> {
    let started = Instant::now();
    let out = args.out();
    let opts = ConvertOptions {
        version: if args.ome_zarr_version == "0.4" {
            OmeVersion::V04
        } else {
            OmeVersion::V05
        },
        chunk: args.chunk,
        shard: args.shard,
        compression: match args.compression.as_str() {
            "blosc" => Compression::Blosc,
            "none" => Compression::None,
            _ => Compression::Zstd,
        },
        reduce: match args.labels.as_deref() {
            Some("nearest") => Reduce::Nearest,
            Some(_) => Reduce::Mode,
            None => Reduce::Mean,
        },
        step: args.volume.time,
        stored: false,
    };
    // Options and an existing output are refused before the input is loaded; the store's folder is made only once
    // the input has opened.
    check_options(&opts)?;
    if out.symlink_metadata().is_ok() && !args.overwrite {
        return Err(super::UsageError(format!("{} exists; pass --overwrite to replace it", out.display())).into());
    }
    let source = open_source(args)?;
    convert::prepare_output(out, args.overwrite).map_err(usage)?;
    let bar = indicatif::ProgressBar::new(1000);
    if let Ok(style) = indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(format!("writing {}", out.display()));
    let written = convert::convert(&source, out, &opts, &mut |f| bar.set_position((f * 1000.0) as u64));
    bar.finish_and_clear();
    let report = written.map_err(usage).with_context(|| {
        format!(
            "the store {} is incomplete (delete it, or rerun with --overwrite)",
            out.display()
        )
    })?;
    for note in &report.notes {
        eprintln!("note: {note}");
    }
    println!("data type: {}", report.type_reason);
    let shapes: Vec<String> = report.levels.iter().map(|[x, y, z]| format!("{x}x{y}x{z}")).collect();
    let steps = if report.steps > 1 {
        format!(" x {} time steps", report.steps)
    } else {
        String::new()
    };
    println!(
        "wrote {} ({} level{}: {}{steps}) in {:.2} s",
        out.display(),
        report.levels.len(),
        if report.levels.len() == 1 { "" } else { "s" },
        shapes.join(", "),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

fn check_options(opts: &ConvertOptions) -> Result<()> {
    if opts.shard.is_some() && opts.version == OmeVersion::V04 {
        return Err(super::UsageError("--shard needs --ome-zarr-version 0.5 (Zarr v3); 0.4 is Zarr v2".into()).into());
    }
    if opts.chunk == 0 || opts.shard.is_some_and(|s| s == 0 || s % opts.chunk != 0) {
        return Err(
            super::UsageError("--shard must be a positive multiple of --chunk (and --chunk positive)".into()).into(),
        );
    }
    Ok(())
}

/// A usage problem (an existing output, a step past the series) exits 64; other errors keep their type.
fn usage(e: ConvertError) -> anyhow::Error {
    match e {
        ConvertError::Usage(text) => super::UsageError(text).into(),
        e => e.into(),
    }
}

/// The file in place where its voxels allow, else the volume loaded once.
fn open_source(args: &ConvertArgs) -> Result<Source> {
    if let Some(path) = &args.volume.file {
        let opts = args.volume.open_options()?;
        if let Some(v) = formats::in_place::in_place(path, &opts)? {
            for note in &v.notes {
                eprintln!("note: {note}");
            }
            println!("reading {} in place (slab by slab)", v.data_file.display());
            return Ok(Source::in_place(v)?);
        }
    }
    // Converted at full resolution: no host budget (a volume held whole is still within volcast's voxel limit).
    let mut full = args.volume.clone();
    full.budgets.host_budget = Some(u64::MAX);
    Ok(Source::Loaded(Box::new(full.load()?)))
}
