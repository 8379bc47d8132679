//! Which module of the library names which, read from the source. Every path is followed in full: `crate::a::b::c`,
//! `super::super::x`, `self::y` and use-trees with nested groups (`crate::a::{b::{c, d}, e}`) each resolve to the
//! deepest module they name, so `super::dicom::slices::SeriesReader` counts as naming `dicom::slices`, not `dicom`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module by its path under `src/` (`["volume", "dicom", "slices"]`).
pub type Module = Vec<String>;

pub fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("src/ readable") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The library's modules by path (`cli/` and `main.rs` belong to the binary; a `tests.rs` is a test module, which
/// may import anything), each with its code.
pub fn modules(src: &Path) -> BTreeMap<Module, String> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut out = BTreeMap::new();
    for file in files {
        let rel = file.strip_prefix(src).unwrap().with_extension("");
        let mut parts: Module = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
        if parts.last().is_some_and(|p| p == "mod") {
            parts.pop();
        }
        let binary = parts == ["lib"] || parts == ["main"] || parts.first().is_some_and(|p| p == "cli");
        if binary || parts.last().is_some_and(|p| p == "tests") {
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

/// Where each occurrence of `prefix` that starts a path (not the tail of a longer name) is followed by.
fn after<'a>(code: &'a str, prefix: &'a str) -> impl Iterator<Item = &'a str> + 'a {
    code.match_indices(prefix).filter_map(move |(i, _)| {
        let before = code[..i].chars().last();
        let starts = before.is_none_or(|c| !c.is_alphanumeric() && c != '_' && c != ':');
        starts.then(|| &code[i + prefix.len()..])
    })
}

/// The paths a use-tree at the start of `text` spells, each as its segments: `a::{b::{c, d}, e}` is `a::b::c`,
/// `a::b::d` and `a::e`; `self` in a group stands for the group's prefix. Stops where the path ends.
pub fn use_tree(text: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    tree(text.trim_start(), &[], &mut out);
    out
}

/// Parses one tree at the start of `text` under `prefix` into `out`; returns the text after it.
fn tree<'a>(text: &'a str, prefix: &[String], out: &mut Vec<Vec<String>>) -> &'a str {
    let mut path = prefix.to_vec();
    let mut rest = text;
    loop {
        rest = rest.trim_start();
        if let Some(group) = rest.strip_prefix('{') {
            return group_of(group, &path, out);
        }
        let end = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        let word = &rest[..end];
        rest = &rest[end..];
        if !word.is_empty() && word != "self" {
            path.push(word.to_string());
        }
        match rest.strip_prefix("::") {
            Some(tail) => rest = tail,
            None => {
                out.push(path);
                return skip_rename(rest);
            }
        }
    }
}

/// The items of a group after its `{`, each a tree under `prefix`; returns the text after the closing `}`.
fn group_of<'a>(text: &'a str, prefix: &[String], out: &mut Vec<Vec<String>>) -> &'a str {
    let mut rest = text;
    loop {
        rest = rest.trim_start();
        if let Some(after) = rest.strip_prefix('}') {
            return after;
        }
        rest = tree(rest, prefix, out).trim_start();
        match rest.strip_prefix(',') {
            Some(after) => rest = after,
            None => return rest.strip_prefix('}').unwrap_or(rest),
        }
    }
}

/// The text after an `as name` or a glob `*` that ends a path.
fn skip_rename(text: &str) -> &str {
    let t = text.trim_start();
    if let Some(glob) = t.strip_prefix('*') {
        return glob;
    }
    match t.strip_prefix("as ") {
        Some(name) => name
            .trim_start()
            .trim_start_matches(|c: char| c.is_alphanumeric() || c == '_'),
        None => text,
    }
}

/// `m`'s `n`-th ancestor (`super` once is 1), or `None` above the crate. A module's `super` is the module one
/// up its path, whether its file is `a/b.rs`, `a/b/mod.rs` or `a.rs` beside `a/`.
fn ancestor(m: &Module, n: usize) -> Option<Module> {
    m.len().checked_sub(n).map(|k| m[..k].to_vec())
}

/// Every module `m` (whose code is `code`) names, as resolved full paths.
fn named_by(m: &Module, code: &str, mods: &BTreeMap<Module, String>) -> BTreeSet<Module> {
    let mut found = BTreeSet::new();
    for rest in after(code, "crate::") {
        found.extend(use_tree(rest).iter().filter_map(|p| resolve(p, mods)));
    }
    for rest in after(code, "super::") {
        let mut ups = 1;
        let mut tail = rest;
        while let Some(t) = tail.strip_prefix("super::") {
            ups += 1;
            tail = t;
        }
        let Some(base) = ancestor(m, ups) else { continue };
        for p in use_tree(tail) {
            found.extend(resolve(&[base.clone(), p].concat(), mods));
        }
    }
    // `self::child::…`, and a plain `use child::…` of a child module (2018 paths), name the child.
    for rest in after(code, "self::").chain(after(code, "use ")) {
        for p in use_tree(rest) {
            if p.first()
                .is_some_and(|c| mods.contains_key(&[m.clone(), vec![c.clone()]].concat()))
            {
                found.extend(resolve(&[m.clone(), p].concat(), mods));
            }
        }
    }
    found
}

/// Which modules each module names, not counting itself and its own ancestors (a child may use what its parent
/// holds; a parent that names a child, as a `mod.rs` re-exporting it does, depends on that child).
pub fn imports(mods: &BTreeMap<Module, String>) -> BTreeMap<Module, BTreeSet<Module>> {
    let mut edges: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
    for (m, code) in mods {
        let named = named_by(m, code, mods);
        let kept: BTreeSet<Module> = named.into_iter().filter(|t| t != m && !m.starts_with(t)).collect();
        if !kept.is_empty() {
            edges.insert(m.clone(), kept);
        }
    }
    edges
}

#[test]
fn use_trees_expand_in_full() {
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    assert_eq!(use_tree("a::b::C;"), vec![s(&["a", "b", "C"])]);
    assert_eq!(
        use_tree("a::{b::{c, d}, self, e as f};"),
        vec![s(&["a", "b", "c"]), s(&["a", "b", "d"]), s(&["a"]), s(&["a", "e"])]
    );
    assert_eq!(
        use_tree("a::b::{\n    c,\n    d,\n};"),
        vec![s(&["a", "b", "c"]), s(&["a", "b", "d"])]
    );
    assert_eq!(use_tree("a::f(x)"), vec![s(&["a", "f"])]);
    assert_eq!(
        use_tree("a::{b::*, c as d, e};"),
        vec![s(&["a", "b"]), s(&["a", "c"]), s(&["a", "e"])]
    );
}
