//! Sort-last rendering over MPI (issue 34), as a user runs it: `mpirun --oversubscribe -n N volcast render …` against
//! the single-process `volcast render …` of the same options, every process under the validation layer with
//! synchronisation validation. Built only with the feature `mpi` (`cargo test --release --features mpi --test mpi`).
#![cfg(feature = "mpi")]

mod compare;
mod faults;
mod icet;
mod modes;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;

/// The real CT head of ../shared/data (256 x 256 x 108 int16, read by box: raw voxels lie in place).
pub fn ct_head() -> Vec<String> {
    let raw = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/raw/cranium_ct_256x256x108_int16.raw");
    assert!(raw.exists(), "{} is missing (CI has ../shared)", raw.display());
    let mut args = vec![raw.display().to_string()];
    args.extend(["--spacing", "0.957031", "0.957031", "1.5"].map(String::from));
    args
}

/// A scratch folder for one test's images.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("volcast-mpi-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `cmd` to its end, or kills it after `limit` (a hang is a failure, not a stuck CI run).
pub fn run_with_limit(mut cmd: Command, limit: Duration) -> Output {
    let mut child = cmd
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the command starts");
    let start = std::time::Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            child.kill().ok();
            let out = child.wait_with_output().unwrap();
            panic!(
                "no end after {limit:?}: {cmd:?}\n{}\n{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// `volcast render ARGS -o OUT --validate` on one process.
pub fn single(args: &[String], out: &Path) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_volcast"));
    cmd.arg("render").args(args).arg("--validate").arg("-o").arg(out);
    run_with_limit(cmd, Duration::from_secs(300))
}

/// `mpirun --oversubscribe -n N volcast render ARGS -o OUT --validate`.
pub fn mpirun(n: usize, args: &[String], out: &Path) -> Output {
    let mut cmd = Command::new("mpirun");
    cmd.args(["--oversubscribe", "--allow-run-as-root", "-n", &n.to_string()])
        .arg(env!("CARGO_BIN_EXE_volcast"))
        .arg("render")
        .args(args)
        .arg("--validate")
        .arg("-o")
        .arg(out)
        // One lavapipe thread per rank: N ranks share two cores.
        .env("LP_NUM_THREADS", "1");
    run_with_limit(cmd, Duration::from_secs(300))
}

pub fn text(o: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}
