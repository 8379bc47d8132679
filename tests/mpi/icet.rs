//! IceT compositing (src/distributed/icet.rs) over four and three MPI ranks (radix-k's power-of-two and
//! remainder cases), checked against the over operator and the z-buffer computed here. The outer test starts
//! `mpirun -n N` on this test binary with VOLCAST_MPI_INNER set; the inner test, a no-op without that variable,
//! is one rank. Needs Open MPI's `mpirun` (libopenmpi-dev).

use std::process::Command;
use std::time::{Duration, Instant};

use mpi::traits::Communicator;
use volcast::distributed::icet::{Blend, Compositor};

const INNER: &str = "VOLCAST_MPI_INNER";
/// The rank counts to run; the images below are drawn for 2 to 4 ranks.
const RANKS: [usize; 2] = [4, 3];
const W: usize = 64;
const H: usize = 48;
const TOLERANCE: f32 = 1e-6;

#[test]
fn icet_composites_under_mpirun() {
    if std::env::var_os(INNER).is_some() {
        return;
    }
    for ranks in RANKS {
        mpirun(ranks);
    }
}

fn mpirun(ranks: usize) {
    let exe = std::env::current_exe().expect("the test binary's path");
    let mut child = Command::new("mpirun")
        .args(["--oversubscribe", "--allow-run-as-root", "-n", &ranks.to_string()])
        .arg(exe)
        .args(["--exact", "icet::icet_rank", "--nocapture", "--test-threads=1"])
        .env(INNER, "1")
        .env("OMPI_MCA_rmaps_base_oversubscribe", "1")
        .spawn()
        .expect("mpirun (Open MPI) must be installed to test the feature `mpi`");
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("waiting for mpirun") {
            break status;
        }
        if start.elapsed() > Duration::from_secs(300) {
            let _ = child.kill();
            panic!("mpirun ran over 300 s: a rank is stuck in a collective call");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(status.success(), "mpirun -n {ranks} exited with {status}");
}

/// Rank `r`'s premultiplied image for Over: a vertical band 32 wide starting at x = 10 r, alpha 0.3 + 0.1 r,
/// colour distinct per rank and shaded by row; alpha 0 and colour 0 elsewhere, except one pixel on the last
/// rank with colour but no alpha (additive light), which IceT drops as background.
fn over_image(r: usize, ranks: usize) -> Vec<f32> {
    let mut img = vec![0.0; W * H * 4];
    let a = 0.3 + 0.1 * r as f32;
    let colour = [(r + 1) as f32 / 5.0, 1.0 - (r + 1) as f32 / 5.0, (r % 2) as f32];
    for y in 0..H {
        for x in 10 * r..(10 * r + 32).min(W) {
            let shade = 0.5 + 0.5 * y as f32 / H as f32;
            let p = &mut img[(y * W + x) * 4..][..4];
            for c in 0..3 {
                p[c] = colour[c] * shade * a;
            }
            p[3] = a;
        }
    }
    if r == ranks - 1 {
        img[(H * W - 1) * 4..][..3].copy_from_slice(&[0.3, 0.3, 0.3]);
    }
    img
}

/// Rank `r`'s colour and depth for ClosestDepth: distinct depths in [0.05, 0.95] (never tied between ranks),
/// and depth 1.0 with a non-zero colour on the first four rows of every rank (nothing there).
fn depth_image(r: usize) -> (Vec<f32>, Vec<f32>) {
    let mut rgba = vec![0.0; W * H * 4];
    let mut depth = vec![0.0; W * H];
    for y in 0..H {
        for x in 0..W {
            let i = y * W + x;
            depth[i] = if y < 4 {
                1.0
            } else {
                0.05 + 0.9 * ((x * 31 + y * 17 + r * 53) % 101) as f32 / 101.0 + r as f32 * 1e-4
            };
            let c = [(r + 1) as f32 / 4.0, x as f32 / W as f32, y as f32 / H as f32, 1.0];
            rgba[i * 4..][..4].copy_from_slice(&c);
        }
    }
    (rgba, depth)
}

/// The over operator front to back, `order[0]` in front; alpha-0 pixels are background (IceT's rule).
fn expected_over(images: &[Vec<f32>], order: &[i32]) -> Vec<f32> {
    let mut out = vec![0.0f32; W * H * 4];
    for &r in order {
        let img = &images[r as usize];
        for (o, p) in out.chunks_exact_mut(4).zip(img.chunks_exact(4)) {
            if p[3] != 0.0 {
                let t = 1.0 - o[3];
                for c in 0..4 {
                    o[c] += t * p[c];
                }
            }
        }
    }
    out
}

/// The z-buffer: the smallest depth below 1.0 wins; nothing there is colour 0 and depth 1.0.
fn expected_closest(images: &[(Vec<f32>, Vec<f32>)]) -> (Vec<f32>, Vec<f32>) {
    let mut rgba = vec![0.0f32; W * H * 4];
    let mut depth = vec![1.0f32; W * H];
    for (colour, z) in images {
        for i in 0..W * H {
            if z[i] < 1.0 && z[i] < depth[i] {
                depth[i] = z[i];
                rgba[i * 4..][..4].copy_from_slice(&colour[i * 4..][..4]);
            }
        }
    }
    (rgba, depth)
}

/// The largest difference, and where, or a message when the lengths differ.
fn worst(what: &str, got: &[f32], want: &[f32], failures: &mut Vec<String>) {
    if got.len() != want.len() {
        failures.push(format!("{what}: {} values, expected {}", got.len(), want.len()));
        return;
    }
    let (i, d) = got
        .iter()
        .zip(want)
        .map(|(g, w)| (g - w).abs())
        .enumerate()
        .fold(
            (0, 0.0f32),
            |best, (i, d)| if d > best.1 || d.is_nan() { (i, d) } else { best },
        );
    if d > TOLERANCE || d.is_nan() {
        failures.push(format!(
            "{what}: value {i} is {} but expected {} (difference {d})",
            got[i], want[i]
        ));
    }
}

#[test]
fn icet_rank() {
    if std::env::var_os(INNER).is_none() {
        return;
    }
    let universe = mpi::initialize().expect("MPI initialises once");
    let world = universe.world();
    let (rank, size) = (world.rank() as usize, world.size() as usize);
    assert!(
        (2..=4).contains(&size),
        "the images are drawn for 2 to 4 ranks, not {size}"
    );
    let mut failures = Vec::new();
    let mut compositor = Compositor::new(&world, W as u32, H as u32);

    // Checks that return before the collective call, the same on every rank.
    let over = over_image(rank, size);
    let ranks: Vec<i32> = (0..size as i32).collect();
    let mut twice = ranks.clone();
    twice[size - 1] = 0;
    assert!(compositor.composite(&over[..10], None, Blend::Over, &ranks).is_err());
    assert!(compositor.composite(&over, None, Blend::Over, &twice).is_err());
    assert!(compositor.composite(&over, None, Blend::Over, &ranks[1..]).is_err());
    assert!(compositor.composite(&over, None, Blend::ClosestDepth, &[]).is_err());
    assert!(compositor
        .composite(&over, Some(&[0.5; W * H]), Blend::Over, &ranks)
        .is_err());

    let overs: Vec<Vec<f32>> = (0..size).map(|r| over_image(r, size)).collect();
    let depths: Vec<(Vec<f32>, Vec<f32>)> = (0..size).map(depth_image).collect();
    // Two shuffles of the ranks (the sort keys are distinct for up to 11 and 7 ranks).
    let shuffled = |key: fn(i32) -> i32| {
        let mut order = ranks.clone();
        order.sort_by_key(|&r| key(r));
        order
    };
    let orders = [
        shuffled(|r| (r * 7 + 2) % 11),
        Vec::new(),
        shuffled(|r| (r * 3 + 5) % 7),
    ];
    // Over, z-buffer (which ignores the order), then Over again in another order: the state switches both ways.
    for (step, order) in orders.iter().enumerate() {
        let (result, what) = if step == 1 {
            let (rgba, depth) = &depths[rank];
            (
                compositor.composite(rgba, Some(depth), Blend::ClosestDepth, order),
                "closest depth".to_owned(),
            )
        } else {
            (
                compositor.composite(&over, None, Blend::Over, order),
                format!("over {order:?}"),
            )
        };
        let stats = compositor.stats();
        if stats.bytes_sent == 0 || stats.composite_seconds.is_nan() || stats.composite_seconds < 0.0 {
            failures.push(format!("rank {rank} {what}: implausible stats {stats:?}"));
        }
        match (rank, result) {
            (0, Ok(Some(got))) if step == 1 => {
                let (rgba, depth) = expected_closest(&depths);
                worst(&format!("{what} rgba"), &got.rgba, &rgba, &mut failures);
                match got.depth {
                    Some(d) => worst(&format!("{what} depth"), &d, &depth, &mut failures),
                    None => failures.push(format!("{what}: no depth")),
                }
            }
            (0, Ok(Some(got))) => {
                worst(&what, &got.rgba, &expected_over(&overs, order), &mut failures);
                // order[0] is the front: the reverse order must give a clearly different image.
                let reversed: Vec<i32> = order.iter().rev().copied().collect();
                let back_to_front = expected_over(&overs, &reversed);
                let apart = got.rgba.iter().zip(&back_to_front).any(|(g, b)| (g - b).abs() > 0.01);
                if !apart {
                    failures.push(format!("{what}: the test cannot tell front from back"));
                }
                let glow = &got.rgba[(H * W - 1) * 4..];
                if glow != [0.0; 4] {
                    failures.push(format!("{what}: an alpha-0 pixel was kept: {glow:?}"));
                }
                if got.depth.is_some() {
                    failures.push(format!("{what}: Over returned a depth"));
                }
            }
            (0, other) => failures.push(format!("rank 0 {what}: expected a composite, got {other:?}")),
            (_, Ok(None)) => {}
            (_, other) => failures.push(format!("rank {rank} {what}: expected Ok(None), got {other:?}")),
        }
    }

    drop(compositor);
    drop(universe);
    if !failures.is_empty() {
        for f in &failures {
            eprintln!("rank {rank}: {f}");
        }
        std::process::exit(1);
    }
    if rank == 0 {
        println!(
            "IceT: Over {:?}, ClosestDepth, Over {:?}: composites match on {size} ranks",
            orders[0], orders[2]
        );
    }
}
