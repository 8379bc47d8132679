//! Helpers shared by the integration tests: the CPU reference renderer, image comparison and shared test data.

#![allow(dead_code)]

pub mod compare;
pub mod reference;

use std::path::PathBuf;

/// `../shared/data/<rel>` beside the repository, where the large test volumes live (not in git).
///
/// Missing data skips the test locally (returns `None` after saying so) but fails it in CI, where a silent skip
/// would hide that nothing was tested.
pub fn shared_data(rel: &str) -> Option<PathBuf> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("shared")
        .join("data")
        .join(rel);
    if path.exists() {
        return Some(path);
    }
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!(
            "../shared/data/{rel} not found ({}): ../shared is required in CI",
            path.display()
        );
    }
    eprintln!("skipped: ../shared/data/{rel} not found");
    None
}
