//! `volcast stats`: per label of a label map, its voxels, its volume in mm³ and the mean, minimum and maximum of the
//! volume and every overlay under it (`volume::label_stats`), as a table or JSON.

use super::args::VolumeArgs;
use super::layers::read_labels;
use crate::formats::{open, OpenOptions};
use crate::volume::label_stats::{label_stats, LabelRow};
use crate::volume::Volume;
use anyhow::Result;
use std::path::PathBuf;

#[derive(clap::Args, Clone)]
pub struct StatsArgs {
    #[command(flatten)]
    pub volume: VolumeArgs,
    /// The label map whose labels are measured (an atlas, a segmentation)
    #[arg(long, value_name = "FILE", help_heading = "Layers")]
    pub labels: PathBuf,
    /// Its table of names (FreeSurfer/Slicer, ITK-SNAP, mricron .txt); default: the one beside it
    #[arg(long, value_name = "FILE", help_heading = "Layers")]
    pub label_table: Option<PathBuf>,
    /// A further volume measured under the labels (repeatable), on its own grid
    #[arg(long, value_name = "FILE", help_heading = "Layers")]
    pub overlay: Vec<PathBuf>,
    /// Print a JSON array of rows instead of a table
    #[arg(long, help_heading = "Options")]
    pub json: bool,
}

pub fn stats(args: &StatsArgs) -> Result<()> {
    let base = args.volume.load()?;
    let label_layers = read_labels(&args.labels, args.label_table.as_deref())?;
    let overlays: Vec<Volume> = args
        .overlay
        .iter()
        .map(|p| open(p, &OpenOptions::default()))
        .collect::<Result<_, _>>()?;
    let others: Vec<(&str, &Volume)> = std::iter::once(&base)
        .chain(&overlays)
        .map(|v| (v.name.as_str(), v))
        .collect();
    // A segmentation's layers one after another: every segment a row.
    let rows: Vec<LabelRow> = label_layers
        .iter()
        .flat_map(|(labels, map, table)| label_stats(labels, map, table, &others))
        .collect();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        print!("{}", text(&rows, &others));
    }
    Ok(())
}

/// The rows as a table: id, name, voxels, mm³, then mean, min and max of each volume.
fn text(rows: &[LabelRow], others: &[(&str, &Volume)]) -> String {
    let width = rows.iter().map(|r| r.name.chars().count()).max().unwrap_or(4).max(4);
    let mut out = format!("{:>8}  {:<width$}  {:>10}  {:>12}", "id", "name", "voxels", "mm³");
    for (name, _) in others {
        for stat in ["mean", "min", "max"] {
            let short: String = name.chars().take(11 - stat.len()).collect();
            out += &format!("  {:>12}", format!("{short}.{stat}"));
        }
    }
    out.push('\n');
    let num = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.4}"));
    for r in rows {
        out += &format!(
            "{:>8}  {:<width$}  {:>10}  {:>12.1}",
            r.id, r.name, r.voxels, r.volume_mm3
        );
        for u in &r.under {
            out += &format!("  {:>12}  {:>12}  {:>12}", num(u.mean), num(u.min), num(u.max));
        }
        out.push('\n');
    }
    out
}
