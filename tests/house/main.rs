//! The house rules that the code's shape must keep (ARCHITECTURE.md), read from the source: no import cycle
//! between files (a `mod.rs` that re-exports a child counts as importing it), and no pure room (`volume`,
//! `formats`, `convert`, `scale`, `transfer`, `scene`) importing one that drives the GPU. Also the size rule: no source
//! file over 650 lines.

mod functions;
mod links;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Module = Vec<String>;

const PURE: &[&str] = &["volume", "formats", "convert", "scale", "transfer", "scene"];
const GPU: &[&str] = &["gpu", "render", "measure", "movie", "viewer"];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("src/ readable") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The library's modules by path (`cli/` and `main.rs` belong to the binary), each with its source.
fn modules(src: &Path) -> BTreeMap<Module, String> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut out = BTreeMap::new();
    for file in files {
        let rel = file.strip_prefix(src).unwrap().with_extension("");
        let mut parts: Module = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
        if parts.last().is_some_and(|p| p == "mod") {
            parts.pop();
        }
        if parts == ["lib"] || parts == ["main"] || parts.first().is_some_and(|p| p == "cli") {
            continue;
        }
        out.insert(parts, code_of(&std::fs::read_to_string(&file).unwrap()));
    }
    out
}

/// The source without comments and without its `#[cfg(test)] mod tests { … }` (tests may import anything).
fn code_of(text: &str) -> String {
    let end = text.find("#[cfg(test)]\nmod tests {").unwrap_or(text.len());
    text[..end]
        .lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The deepest module that `path` names, if any.
fn resolve(path: &[String], mods: &BTreeMap<Module, String>) -> Option<Module> {
    (1..=path.len())
        .rev()
        .map(|n| path[..n].to_vec())
        .find(|m| mods.contains_key(m))
}

fn words_after<'a>(code: &'a str, prefix: &'a str) -> impl Iterator<Item = (usize, &'a str)> + 'a {
    code.match_indices(prefix).filter_map(move |(i, _)| {
        let before_ok = code[..i]
            .chars()
            .last()
            .is_none_or(|c| !c.is_alphanumeric() && c != '_');
        before_ok.then(|| (i, &code[i + prefix.len()..]))
    })
}

fn path_at(rest: &str) -> Vec<String> {
    let end = rest
        .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
        .unwrap_or(rest.len());
    rest[..end]
        .split("::")
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect()
}

/// Which modules each module imports (not counting its own ancestors).
fn imports(mods: &BTreeMap<Module, String>) -> BTreeMap<Module, BTreeSet<Module>> {
    let mut edges: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
    for (m, code) in mods {
        let mut add = |target: Option<Module>| {
            if let Some(t) = target.filter(|t| t != m && !m.starts_with(t)) {
                edges.entry(m.clone()).or_default().insert(t);
            }
        };
        for (_, rest) in words_after(code, "crate::") {
            let mut path = path_at(rest);
            // `crate::a::{b, c}`: each of b and c.
            let after = &rest[path.join("::").len()..];
            if let Some(group) = after.strip_prefix("::{") {
                for item in group.split('}').next().unwrap_or("").split(',') {
                    let mut p = path.clone();
                    p.extend(path_at(item.trim()).into_iter().take(1));
                    add(resolve(&p, mods));
                }
                continue;
            }
            path.truncate(path.len().max(1));
            add(resolve(&path, mods));
        }
        for (_, rest) in words_after(code, "super::") {
            let mut p = m[..m.len().saturating_sub(1)].to_vec();
            p.extend(path_at(rest).into_iter().take(1));
            add(resolve(&p, mods));
        }
        // A parent's `use child::…` / `pub use child::…` (re-exports) makes the parent depend on the child.
        for (_, rest) in words_after(code, "use ") {
            let first = path_at(rest.trim_start_matches("self::")).into_iter().next();
            if let Some(child) = first
                .map(|c| [m.clone(), vec![c]].concat())
                .filter(|c| mods.contains_key(c))
            {
                edges.entry(m.clone()).or_default().insert(child);
            }
        }
    }
    edges
}

/// Strongly connected components with more than one module (Tarjan).
fn cycles(edges: &BTreeMap<Module, BTreeSet<Module>>, nodes: &[Module]) -> Vec<Vec<Module>> {
    struct T<'a> {
        edges: &'a BTreeMap<Module, BTreeSet<Module>>,
        index: BTreeMap<Module, usize>,
        low: BTreeMap<Module, usize>,
        stack: Vec<Module>,
        on: BTreeSet<Module>,
        out: Vec<Vec<Module>>,
    }
    fn visit(t: &mut T, v: &Module) {
        let i = t.index.len();
        t.index.insert(v.clone(), i);
        t.low.insert(v.clone(), i);
        t.stack.push(v.clone());
        t.on.insert(v.clone());
        for w in t.edges.get(v).into_iter().flatten() {
            if !t.index.contains_key(w) {
                visit(t, w);
                let lw = t.low[w];
                t.low.entry(v.clone()).and_modify(|l| *l = (*l).min(lw));
            } else if t.on.contains(w) {
                let iw = t.index[w];
                t.low.entry(v.clone()).and_modify(|l| *l = (*l).min(iw));
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(&w);
                let done = &w == v;
                comp.push(w);
                if done {
                    break;
                }
            }
            if comp.len() > 1 {
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in nodes {
        if !t.index.contains_key(v) {
            visit(&mut t, v);
        }
    }
    t.out
}

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

#[test]
fn no_import_cycle_between_source_files() {
    let mods = modules(&src());
    let edges = imports(&mods);
    let nodes: Vec<Module> = mods.keys().cloned().collect();
    assert!(
        edges.values().map(BTreeSet::len).sum::<usize>() > 100,
        "the import scan found too little"
    );
    let found: Vec<String> = cycles(&edges, &nodes)
        .iter()
        .map(|c| c.iter().map(|m| m.join("::")).collect::<Vec<_>>().join(" <-> "))
        .collect();
    assert!(found.is_empty(), "import cycles:\n{}", found.join("\n"));
}

#[test]
fn pure_rooms_import_no_gpu_room() {
    let mods = modules(&src());
    let bad: Vec<String> = imports(&mods)
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

#[test]
fn the_scan_sees_a_planted_cycle() {
    let mut mods = BTreeMap::new();
    mods.insert(vec!["a".to_string()], "use crate::b::X;".to_string());
    mods.insert(vec!["b".to_string()], "use crate::a::{Y, Z};".to_string());
    mods.insert(vec!["c".to_string()], "pub use crate::a::Y;".to_string());
    let edges = imports(&mods);
    let nodes: Vec<Module> = mods.keys().cloned().collect();
    assert_eq!(cycles(&edges, &nodes).len(), 1);
}
