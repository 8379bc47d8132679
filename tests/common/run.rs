//! The `volcast` binary run as a user runs it, and what every validated run must show.

use std::fmt::Debug;
use std::process::{Command, Output};

/// `volcast`, for a test that sets more than arguments (environment, working folder, streams) before it runs.
/// Its config folder is one of the tests' own, so that no test reads or writes the user's (the viewer's recent
/// files); a test may set another.
pub fn volcast_command() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_volcast"));
    command.env("XDG_CONFIG_HOME", concat!(env!("CARGO_TARGET_TMPDIR"), "/xdg-config"));
    // The pyramid cache too: never the user's ~/.cache.
    command.env("XDG_CACHE_HOME", concat!(env!("CARGO_TARGET_TMPDIR"), "/xdg-cache"));
    command
}

/// Runs `volcast ARGS` and returns what it did; asserts nothing.
pub fn volcast(args: &[&str]) -> Output {
    volcast_command().args(args).output().expect("run volcast")
}

/// Runs `volcast ARGS --validate` (`--validate` added unless `args` has it) and asserts
/// [`assert_validation_clean`]; whether it succeeded is the caller's to check (a refusal is a fine outcome).
pub fn volcast_validated(args: &[&str]) -> Output {
    let o = if args.contains(&"--validate") {
        volcast(args)
    } else {
        volcast(&[args, &["--validate"]].concat())
    };
    assert_validation_clean(&args, &o);
    o
}

/// Runs `volcast ARGS --validate` as [`volcast_validated`] does, and asserts that it succeeded and that the layer
/// printed its summary of nothing found.
pub fn volcast_ok(args: &[&str]) -> Output {
    let o = volcast_validated(args);
    let err = stderr(&o);
    assert!(o.status.success(), "{args:?} failed ({}):\n{err}", o.status);
    assert!(
        err.contains("validation: 0 errors, 0 warnings"),
        "{args:?}: no clean validation summary:\n{err}"
    );
    o
}

/// What a run under `--validate` must show: no message of the validation layer, its summary (where it printed
/// one) clean, and no panic.
pub fn assert_validation_clean(what: &dyn Debug, o: &Output) {
    let err = stderr(o);
    assert!(
        !err.contains("[validation"),
        "{what:?}: the validation layer spoke:\n{err}"
    );
    if err.contains("validation:") {
        assert!(err.contains("validation: 0 errors, 0 warnings"), "{what:?}:\n{err}");
    }
    assert!(!err.contains("panicked"), "{what:?} panicked:\n{err}");
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}
