//! The house rules that the code's shape must keep (ARCHITECTURE.md), read from the source:
//! - no cycle: no two files, and no two folders, of one folder name each other (`graph`), with every path followed
//!   in full (`scan`);
//! - no arrow up: a room names only rooms below it in [`ORDER`];
//! - no pure room (no Vulkan) names one that drives the GPU;
//! - no source file over 650 lines, no function over 120 (`functions`).

mod functions;
mod graph;
mod links;
mod scan;

use scan::{imports, modules, rust_files, Module};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The rooms of src/, bottom first: each may name only rooms before it (ARCHITECTURE.md draws the same order).
const ORDER: &[&str] = &[
    "volume",
    "pyramid",
    "formats",
    "transfer",
    "scene",
    "convert",
    "scale",
    "gpu",
    "render",
    "measure",
    "movie",
    "distributed",
    "viewer",
];
const PURE: &[&str] = &["volume", "pyramid", "formats", "transfer", "scene", "convert", "scale"];
const GPU: &[&str] = &["gpu", "render", "measure", "movie", "viewer"];

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn edges() -> BTreeMap<Module, BTreeSet<Module>> {
    let edges = imports(&modules(&src()));
    assert!(
        edges.values().map(BTreeSet::len).sum::<usize>() > 300,
        "the import scan found too little"
    );
    edges
}

#[test]
fn no_cycle_between_files_or_folders() {
    let found = graph::cycles(&edges());
    assert!(found.is_empty(), "import cycles:\n{}", found.join("\n"));
}

#[test]
fn no_room_names_a_room_above_it() {
    let found = graph::arrows_up(&edges(), ORDER);
    assert!(found.is_empty(), "arrows up:\n{}", found.join("\n"));
}

#[test]
fn pure_rooms_import_no_gpu_room() {
    let bad: Vec<String> = edges()
        .iter()
        .filter(|(m, _)| PURE.contains(&m[0].as_str()))
        .flat_map(|(m, ts)| ts.iter().filter(|t| GPU.contains(&t[0].as_str())).map(move |t| (m, t)))
        .map(|(m, t)| format!("{} imports {}", m.join("::"), t.join("::")))
        .collect();
    assert!(bad.is_empty(), "pure code importing GPU code:\n{}", bad.join("\n"));
}

#[test]
fn source_files_stay_readable_in_one_sitting() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let n = std::fs::read_to_string(f).unwrap().lines().count();
            (n > 650).then(|| format!("{} has {n} lines", f.display()))
        })
        .collect();
    assert!(long.is_empty(), "split these by concern:\n{}", long.join("\n"));
}

/// A made-up crate of `(file, code)` pairs, as `modules` would read it.
fn planted(files: &[(&str, &str)]) -> BTreeMap<Module, BTreeSet<Module>> {
    let mods = files
        .iter()
        .map(|(f, code)| (f.split('/').map(String::from).collect(), code.to_string()))
        .collect();
    imports(&mods)
}

#[test]
fn the_scan_sees_a_planted_file_cycle_through_a_full_path() {
    // The in_place <-> dicom::slices cycle the old scan missed: `super::dicom::slices` was cut to `dicom`.
    let edges = planted(&[
        ("volume", ""),
        ("volume/dicom", "mod slices;"),
        ("volume/dicom/slices", "use crate::volume::in_place::InPlace;"),
        (
            "volume/in_place",
            "pub slices: Option<Arc<super::dicom::slices::SeriesReader>>,",
        ),
    ]);
    let found = graph::cycles(&edges);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].starts_with("in volume: dicom <-> in_place"), "{found:?}");
}

#[test]
fn the_scan_sees_a_planted_folder_cycle() {
    // No two files name each other, but the folders do: a::x names b::y, and b::z names a::w.
    let edges = planted(&[
        ("a", ""),
        ("b", ""),
        ("a/x", "use crate::b::{y::Y, self};"),
        ("a/w", ""),
        ("b/y", ""),
        ("b/z", "fn f() { super::super::a::w::go() }"),
    ]);
    let found = graph::cycles(&edges);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].starts_with("in src: a <-> b"), "{found:?}");
}

#[test]
fn the_scan_sees_a_planted_arrow_up() {
    let edges = planted(&[
        ("volume", ""),
        ("volume/zarr", "use crate::scale::read::level_geometry;"),
        ("scale", ""),
        ("scale/read", "use crate::volume::Volume;"),
    ]);
    let found = graph::arrows_up(&edges, &["volume", "scale"]);
    assert_eq!(found, ["volume::zarr names scale::read, a room above it"]);
    assert!(graph::arrows_up(&edges, &["volume"])
        .iter()
        .any(|f| f.contains("room scale has no place")));
}
