//! A failing rank ends every rank with its message, and no rank hangs.

use super::{ct_head, mpirun, scratch, text};

#[test]
fn a_file_no_rank_can_read_ends_every_rank_with_its_name() {
    let dir = scratch("missing");
    let o = mpirun(
        4,
        &["/nonexistent/head_64x64x64_uint8.raw".to_string()],
        &dir.join("x.png"),
    );
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("/nonexistent/head_64x64x64_uint8.raw") && t.contains("stopping every rank"),
        "{t}"
    );
    assert!(!dir.join("x.png").exists());
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn shadows_are_refused_with_the_reason() {
    let dir = scratch("shadows");
    let mut args = ct_head();
    args.extend(["--shading", "--shadows"].map(String::from));
    let o = mpirun(2, &args, &dir.join("x.png"));
    let t = text(&o);
    assert!(!o.status.success() && t.contains("do not cross rank borders"), "{t}");
    std::fs::remove_dir_all(dir).ok();
}

/// Layers are refused before anything is read, naming the options: no rank renders half of them.
#[test]
fn layers_are_refused_with_the_reason() {
    let dir = scratch("layers");
    let mut args = ct_head();
    args.extend(["--overlay".to_string(), args[0].clone()]);
    let o = mpirun(2, &args, &dir.join("x.png"));
    let t = text(&o);
    assert!(
        !o.status.success() && t.contains("--overlay, --labels") && t.contains("one process"),
        "{t}"
    );
    assert!(!dir.join("x.png").exists());
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn more_ranks_than_bricks_are_refused() {
    let dir = scratch("tiny");
    // One brick on every side: it cannot be split in two.
    let args = ["--builtin", "box", "--builtin-size", "8"].map(String::from).to_vec();
    let o = mpirun(2, &args, &dir.join("x.png"));
    let t = text(&o);
    assert!(!o.status.success() && t.contains("use fewer ranks"), "{t}");
    std::fs::remove_dir_all(dir).ok();
}

/// The processes whose command line names `needle`.
fn processes_naming(needle: &str) -> usize {
    let out = std::process::Command::new("pgrep")
        .args(["-f", needle])
        .output()
        .unwrap();
    String::from_utf8_lossy(&out.stdout).lines().count()
}

/// A scheduler's time limit sends SIGTERM to mpirun: every rank ends within seconds, the command fails, and no
/// image (nor a part of one) is left.
#[test]
fn sigterm_to_mpirun_ends_every_rank_and_leaves_no_image() {
    let dir = scratch("sigterm");
    let out = dir.join("stopped.png");
    let mut args = ct_head();
    // Large enough to be drawing when the signal comes (tens of seconds on 2 cores).
    args.extend(["--size", "3000x3000", "--shading", "-o"].map(String::from));
    args.push(out.display().to_string());
    let mut mpirun = std::process::Command::new("mpirun")
        .args(["--oversubscribe", "--allow-run-as-root", "-n", "4"])
        .arg(env!("CARGO_BIN_EXE_volcast"))
        .arg("render")
        .args(&args)
        .env("LP_NUM_THREADS", "1")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let needle = out.display().to_string();
    let start = std::time::Instant::now();
    while processes_naming(&needle) < 4 && start.elapsed() < std::time::Duration::from_secs(60) {
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    std::thread::sleep(std::time::Duration::from_millis(1500));
    assert!(
        mpirun.try_wait().unwrap().is_none(),
        "the render ended before the signal: make it larger"
    );
    std::process::Command::new("kill")
        .args(["-TERM", &mpirun.id().to_string()])
        .status()
        .unwrap();
    let sent = std::time::Instant::now();
    let status = loop {
        if let Some(s) = mpirun.try_wait().unwrap() {
            break s;
        }
        assert!(sent.elapsed().as_secs() < 30, "mpirun still runs 30 s after SIGTERM");
        std::thread::sleep(std::time::Duration::from_millis(100));
    };
    assert!(!status.success());
    std::thread::sleep(std::time::Duration::from_millis(500));
    assert_eq!(processes_naming(&needle), 0, "a rank outlived mpirun");
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert!(left.is_empty(), "files left: {left:?}");
    std::fs::remove_dir_all(dir).ok();
}

/// A rank without a Vulkan device (its loader pointed at no driver) fails after the others have gone on to render
/// and wait in the compositor: its message names the rank and the problem, and every rank ends.
#[test]
fn a_rank_without_a_vulkan_device_stops_every_rank() {
    let dir = scratch("nodevice");
    let out = dir.join("x.png");
    let mut args = ct_head();
    args.extend(["--size", "96x96", "-o"].map(String::from));
    args.push(out.display().to_string());
    let exe = env!("CARGO_BIN_EXE_volcast");
    let mut cmd = std::process::Command::new("mpirun");
    cmd.args(["--oversubscribe", "--allow-run-as-root", "-n", "1", "env"])
        .args([
            "VK_ICD_FILENAMES=/nonexistent/icd.json",
            "VK_DRIVER_FILES=/nonexistent/icd.json",
            exe,
            "render",
        ])
        .args(&args)
        .args([":", "-n", "2", exe, "render"])
        .args(&args);
    let o = super::run_with_limit(cmd, std::time::Duration::from_secs(120));
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("rank 0 of 3 failed") && t.to_lowercase().contains("vulkan"),
        "{t}"
    );
    assert!(!out.exists());
    std::fs::remove_dir_all(dir).ok();
}

/// A part over the host budget is refused before it is read, with its size and the remedy.
#[test]
fn a_part_over_the_host_budget_asks_for_more_ranks() {
    let dir = scratch("budget");
    let mut args = ct_head();
    args.extend(["--host-budget", "1M"].map(String::from));
    let o = mpirun(2, &args, &dir.join("x.png"));
    let t = text(&o);
    assert!(
        !o.status.success() && t.contains("over the host budget of 1 MiB") && t.contains("use more ranks"),
        "{t}"
    );
    std::fs::remove_dir_all(dir).ok();
}
