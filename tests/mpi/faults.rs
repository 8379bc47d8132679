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
