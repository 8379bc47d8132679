//! `mpirun -n N volcast render …`: every rank reads its part, agrees the whole volume's range and (for the automatic
//! transfer function) histogram with the others, renders its share of every ray on its own device, and IceT
//! composites the shares onto rank 0, which writes the image. A rank that fails says why and aborts every rank
//! (`MPI_Abort`), so none waits forever on a rank that is gone.

use super::decompose::{held_box, Box3, Decomposition, Viewer};
use super::finish::{depth_of, Finisher, Merge};
use super::icet::{Blend, Compositor};
use super::part::{header, histogram, Part, Source};
use crate::cli::args::RenderArgs;
use crate::cli::UsageError;
use crate::gpu::Gpu;
use crate::render::headless::{Headless, SHARE_FORMAT};
use crate::render::{FrameUniforms, PartInfo, PoolInfo, VolumeInfo};
use crate::scene::settings::{RaySetup, RenderSettings};
use crate::volume::Volume;
use anyhow::{bail, Context, Result};
use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use std::time::Instant;

/// What a rank measured, gathered on rank 0 for `--timings` and `--memory`.
const REPORT_FIELDS: usize = 6;

/// Runs `render` as one rank of an MPI job. Returns only on success; a failing rank aborts the job.
pub fn render(args: &RenderArgs) -> Result<()> {
    let universe = mpi::initialize().context("MPI could not be initialised (was volcast started by mpirun?)")?;
    let world = universe.world();
    let (rank, size) = (world.rank(), world.size());
    abort_on_panic(rank, size);
    match rank_render(&world, args) {
        Ok(()) => Ok(()),
        Err(e) => {
            say(format!(
                "volcast: rank {rank} of {size} failed: {}; stopping every rank",
                crate::cli::error_text(&e)
            ));
            world.abort(if crate::cli::is_usage(&e) { 64 } else { 1 })
        }
    }
}

/// A panic on any rank ends the job (its message first), rather than leaving the others waiting in a collective.
fn abort_on_panic(rank: i32, size: i32) {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        default(info);
        say(format!("volcast: rank {rank} of {size} panicked; stopping every rank"));
        // SAFETY: MPI is initialised (the hook is set after `mpi::initialize`) and MPI_Abort does not return.
        unsafe {
            mpi::ffi::MPI_Abort(mpi::ffi::RSMPI_COMM_WORLD, 101);
        }
    }));
}

/// Writes `line` and a newline to stderr in one write. mpirun forwards each write as it comes, and `eprintln!` writes
/// its pieces one by one, so MPI_Abort's banner from mpirun once landed inside the line (CI, 29 Nov).
fn say(line: String) {
    use std::io::Write;
    let _ = std::io::stderr().lock().write_all(format!("{line}\n").as_bytes());
}

fn rank_render(world: &SimpleCommunicator, args: &RenderArgs) -> Result<()> {
    refuse_unsupported(args)?;
    // An output name rank 0 could not write is refused before any rank reads or renders.
    crate::render::save::check_name(&args.output).map_err(anyhow::Error::msg)?;
    let (rank, size) = (world.rank() as usize, world.size() as usize);
    let t_read = Instant::now();
    let (source, dims, geometry) = Source::open(&args.volume)?;
    let tree = Decomposition::new(dims, size).map_err(|e| UsageError(format!("{e}: use fewer ranks")))?;
    let owned = tree.boxes[rank];
    let held = held_box(owned, dims);
    source.check_budget(held, args.volume.budgets().host)?;
    let mut part = source.read(held, dims, geometry)?;
    drop(source);
    let read_ms = t_read.elapsed().as_secs_f64() * 1e3;
    globalise_range(world, &mut part.volume);
    let whole = header(&part.volume, dims, geometry);
    let own_local = Box3 {
        lo: [0, 1, 2].map(|a| owned.lo[a] - held.lo[a]),
        hi: [0, 1, 2].map(|a| owned.hi[a] - held.lo[a]),
    };
    let args = with_global_transfer_function(world, args, &part.volume, &whole, own_local)?;
    let mut s = crate::cli::render::view_settings(&args, &whole)?;
    // The fragment march: the compute pass writes 8-bit pixels, and its rays are the analytic setup's.
    s.pipeline.compute = false;
    refuse_unsupported_settings(&s)?;
    let info = PartInfo {
        origin: held.lo,
        lo: owned.lo,
        hi: owned.hi,
    };
    crate::cli::with_gpu(&args.gpu, |gpu| {
        let mut headless = Headless::with_format(gpu, SHARE_FORMAT)?;
        let result = share_and_composite(
            world,
            gpu,
            &mut headless,
            &args,
            (&part, info, &tree),
            (&whole, &s),
            read_ms,
        );
        headless.destroy(gpu);
        result
    })
}

/// Options whose meaning does not survive splitting the volume among ranks, refused before anything is read.
fn refuse_unsupported(args: &RenderArgs) -> Result<()> {
    let refuse =
        |what: &str| Err(UsageError(format!("{what} is not available under mpirun (docs/distributed.md)")).into());
    if args.turntable.is_some() || !args.keyframes.is_empty() {
        return refuse("a movie (--turntable, --keyframes)");
    }
    if args.level.is_some() {
        return refuse("--level (every rank renders level 0 of its part)");
    }
    if args.layers.any() {
        return refuse(
            "a layer (--overlay, --labels: each rank would need its part of every layer; render layers on one process)",
        );
    }
    Ok(())
}

fn refuse_unsupported_settings(s: &RenderSettings) -> Result<()> {
    if s.uses_light_volume() {
        bail!(UsageError(
            "shadows and ambient occlusion do not cross rank borders, so they are not available under mpirun; render \
             them on one process (docs/distributed.md)"
                .into()
        ));
    }
    if s.pipeline.count_samples {
        bail!(UsageError("--count-samples is not available under mpirun".into()));
    }
    Ok(())
}

/// Sets `v`'s range and stored range to the whole volume's: the extremes over every rank's part.
fn globalise_range(world: &SimpleCommunicator, v: &mut Volume) {
    let mine = [v.range[0], -v.range[1], v.stored_range[0], -v.stored_range[1]];
    let mut all = [0.0f64; 4];
    world.all_reduce_into(&mine[..], &mut all[..], SystemOperation::min());
    v.range = [all[0], -all[1]];
    v.stored_range = [all[2], -all[3]];
}

/// `args` with the automatic transfer function (where the options ask for it) computed from the whole volume's
/// histogram, the sum of every rank's over its own box, given as a value: every rank classifies alike, and as
/// the single-process render does.
fn with_global_transfer_function(
    world: &SimpleCommunicator,
    args: &RenderArgs,
    part: &Volume,
    whole: &Volume,
    own_local: Box3,
) -> Result<RenderArgs> {
    use crate::transfer::auto::{auto_transfer_function, VolumeFacts, AUTO_BINS};
    let f = &args.frame;
    // Exactly when the settings would compute it from the (here voxel-less) volume (cli/settings.rs).
    let automatic = args.state.is_none() && f.given.from_file && !f.given.any(crate::cli::settings::CLASSIFICATION);
    let named_auto = f.colour.preset.as_deref() == Some("auto");
    if !automatic && !named_auto {
        return Ok(args.clone());
    }
    let mine = histogram(part, own_local, AUTO_BINS);
    let mut sum = vec![0u64; AUTO_BINS];
    world.all_reduce_into(&mine[..], &mut sum[..], SystemOperation::sum());
    let tf = auto_transfer_function(&VolumeFacts::of(whole), &sum);
    let mut out = args.clone();
    out.frame.colour.preset = None;
    out.frame.colour.tf_value = Some(tf);
    out.frame.given.insert("tf");
    Ok(out)
}

/// Where the rays come from, in the whole volume's voxels (the k-d tree's order follows from it).
fn viewer(s: &RenderSettings, whole: &Volume) -> Viewer {
    let info = VolumeInfo {
        dims: whole.dims,
        geometry: whole.geometry,
        scale_bias: (1.0, 0.0),
        range: whole.range,
        pool: PoolInfo::whole(whole.dims),
        held: 0,
        step_level: 0,
        part: None,
        source_voxels: whole.source_voxels as f32,
    };
    let u = FrameUniforms::new(s, &info);
    let d = whole.dims.map(f64::from);
    if s.camera.ortho {
        Viewer::Direction([0, 1, 2].map(|a| f64::from(u.ray_forward[a]) * d[a]))
    } else {
        Viewer::Eye([0, 1, 2].map(|a| f64::from(u.eye_tex[a]) * d[a]))
    }
}

type PartRef<'a> = (&'a Part, PartInfo, &'a Decomposition);

fn share_and_composite(
    world: &SimpleCommunicator,
    gpu: &Gpu,
    headless: &mut Headless,
    args: &RenderArgs,
    (part, info, tree): PartRef,
    (whole, s): (&Volume, &RenderSettings),
    read_ms: f64,
) -> Result<()> {
    let t_upload = Instant::now();
    headless
        .renderer
        .set_volume_part(gpu, &part.volume, info, part.whole_dims, part.geometry)?;
    if s.lighting.gradient_texture {
        headless.renderer.enable_gradient_texture(gpu, &part.volume)?;
    }
    let upload_ms = t_upload.elapsed().as_secs_f64() * 1e3;
    let t_render = Instant::now();
    let share = headless.render_share(gpu, s)?;
    let render_ms = t_render.elapsed().as_secs_f64() * 1e3;
    let t_composite = Instant::now();
    let (merged, bytes_sent) = composite(world, s, share, tree.front_to_back(viewer(s, whole)))?;
    let composite_ms = t_composite.elapsed().as_secs_f64() * 1e3;
    let report = [
        crate::measure::bench::peak_rss_bytes().unwrap_or(0) as f64,
        part.bytes_read as f64,
        bytes_sent as f64,
        read_ms + upload_ms,
        render_ms,
        composite_ms,
    ];
    let reports = gather_reports(world, &report);
    if let Some(merged) = merged {
        write_image(args, s, whole, &merged, (world.size(), part.by_box))?;
        if args.timings || args.memory {
            print_reports(&reports, tree);
        }
        println!("gpu: {}", gpu.device_name);
    }
    Ok(())
}

/// The shares merged on rank 0 (None elsewhere), and the bytes this rank sent.
fn composite(
    world: &SimpleCommunicator,
    s: &RenderSettings,
    share: Vec<f32>,
    order: Vec<usize>,
) -> Result<(Option<Vec<f32>>, u64)> {
    let order: Vec<i32> = order.into_iter().map(|r| r as i32).collect();
    match Merge::of(s.compositing.mode) {
        Merge::Sum => {
            let root = world.process_at_rank(0);
            let bytes = (share.len() * 4) as u64;
            if world.rank() == 0 {
                let mut sum = vec![0f32; share.len()];
                root.reduce_into_root(&share[..], &mut sum[..], SystemOperation::sum());
                Ok((Some(sum), 0))
            } else {
                root.reduce_into(&share[..], SystemOperation::sum());
                Ok((None, bytes))
            }
        }
        merge => {
            let mut icet = Compositor::new(world, s.width, s.height);
            let out = if merge == Merge::Over {
                icet.composite(&share, None, Blend::Over, &order)
            } else {
                let (rgba, depth) = closest_share(s, &share);
                icet.composite(&rgba, Some(&depth), Blend::ClosestDepth, &order)
            }
            .map_err(|e| anyhow::anyhow!("IceT: {e}"))?;
            Ok((out.map(|c| c.rgba), icet.stats().bytes_sent))
        }
    }
}

/// A MIP or MinIP share as IceT's depth test takes it: colour (value, 0, 0, 1) where the rank saw a visible
/// sample, and the depth that orders the values; nothing (depth 1) elsewhere.
fn closest_share(s: &RenderSettings, share: &[f32]) -> (Vec<f32>, Vec<f32>) {
    let mut rgba = vec![0f32; share.len()];
    let mut depth = vec![1f32; share.len() / 4];
    for (i, p) in share.chunks_exact(4).enumerate() {
        if p[1] > 0.0 {
            rgba[4 * i..4 * i + 4].copy_from_slice(&[p[0], 0.0, 0.0, 1.0]);
            depth[i] = depth_of(s.compositing.mode, p[0]);
        }
    }
    (rgba, depth)
}

fn write_image(
    args: &RenderArgs,
    s: &RenderSettings,
    whole: &Volume,
    merged: &[f32],
    (ranks, by_box): (i32, bool),
) -> Result<()> {
    let mut image = Finisher::new(s, whole.range).image(s.width, s.height, merged);
    if args.colorbar {
        image = crate::render::figure::with_colorbar(&image, s, whole);
    }
    crate::render::save::save(&image, &args.output).map_err(anyhow::Error::msg)?;
    println!(
        "rendered {} ({}x{}x{} {}) at {}x{} with {} ray setup on {} ranks ({}) -> {}",
        whole.name,
        whole.dims[0],
        whole.dims[1],
        whole.dims[2],
        whole.source_type,
        s.width,
        s.height,
        if s.pipeline.ray_setup == RaySetup::Faces {
            "entry/exit faces"
        } else {
            "analytic"
        },
        ranks,
        if by_box {
            "each read its part by box"
        } else {
            "each read the file whole"
        },
        args.output.display()
    );
    Ok(())
}

fn gather_reports(world: &SimpleCommunicator, mine: &[f64; REPORT_FIELDS]) -> Vec<f64> {
    let root = world.process_at_rank(0);
    if world.rank() == 0 {
        let mut all = vec![0f64; REPORT_FIELDS * world.size() as usize];
        root.gather_into_root(&mine[..], &mut all[..]);
        all
    } else {
        root.gather_into(&mine[..]);
        Vec::new()
    }
}

/// The table `--timings` / `--memory` print under mpirun: per rank its box, peak memory, bytes read and sent, and
/// times.
fn print_reports(all: &[f64], tree: &Decomposition) {
    println!(
        "rank  box (voxels)                       peak RSS MiB  read MiB  sent MiB  load ms  share ms  composite ms"
    );
    for (r, f) in all.chunks_exact(REPORT_FIELDS).enumerate() {
        let b = tree.boxes[r];
        println!(
            "{r:>4}  {:<33}  {:>12.1}  {:>8.1}  {:>8.2}  {:>7.0}  {:>8.0}  {:>12.1}",
            format!("{:?}..{:?}", b.lo, b.hi),
            f[0] / 1048576.0,
            f[1] / 1048576.0,
            f[2] / 1048576.0,
            f[3],
            f[4],
            f[5]
        );
    }
}
