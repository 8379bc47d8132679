//! Cycles in the import graph, seen in every folder: an edge from `a::x::f` to `a::y::g` is, inside folder `a`,
//! an edge from its child `x` to its child `y`. A cycle among the children of one folder is a folder cycle (two
//! rooms that use each other) or, where the children are files, a file cycle; either way one of them must move.

use crate::scan::Module;
use std::collections::{BTreeMap, BTreeSet};

/// Where the paths of `a` and `b` part: (their common folder, `a`'s child of it, `b`'s child of it); `None` when
/// one is the other's ancestor.
fn parted(a: &Module, b: &Module) -> Option<(Module, String, String)> {
    let k = a.iter().zip(b).take_while(|(x, y)| x == y).count();
    (k < a.len() && k < b.len()).then(|| (a[..k].to_vec(), a[k].clone(), b[k].clone()))
}

/// Per folder, the edges among its children, each with the module edges that make it.
type Projected = BTreeMap<Module, BTreeMap<(String, String), Vec<(Module, Module)>>>;

fn project(edges: &BTreeMap<Module, BTreeSet<Module>>) -> Projected {
    let mut out: Projected = BTreeMap::new();
    for (a, targets) in edges {
        for b in targets {
            if let Some((folder, x, y)) = parted(a, b) {
                let why = out.entry(folder).or_default().entry((x, y)).or_default();
                why.push((a.clone(), b.clone()));
            }
        }
    }
    out
}

/// Every cycle, as one line per folder cycle naming its members and the imports that close it.
pub fn cycles(edges: &BTreeMap<Module, BTreeSet<Module>>) -> Vec<String> {
    let mut found = Vec::new();
    for (folder, inner) in project(edges) {
        let mut next: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (x, y) in inner.keys() {
            next.entry(x.clone()).or_default().insert(y.clone());
        }
        for comp in strongly_connected(&next) {
            let why: Vec<String> = inner
                .iter()
                .filter(|((x, y), _)| comp.contains(x) && comp.contains(y))
                .flat_map(|(_, ms)| ms.iter().map(|(a, b)| format!("{} -> {}", a.join("::"), b.join("::"))))
                .collect();
            let place = if folder.is_empty() {
                "src".to_string()
            } else {
                folder.join("::")
            };
            found.push(format!("in {place}: {} ({})", comp.join(" <-> "), why.join(", ")));
        }
    }
    found
}

/// The strongly connected components of more than one node (Tarjan).
fn strongly_connected(next: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct T<'a> {
        next: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<String, usize>,
        low: BTreeMap<String, usize>,
        stack: Vec<String>,
        on: BTreeSet<String>,
        out: Vec<Vec<String>>,
    }
    fn visit(t: &mut T, v: &str) {
        let i = t.index.len();
        t.index.insert(v.to_string(), i);
        t.low.insert(v.to_string(), i);
        t.stack.push(v.to_string());
        t.on.insert(v.to_string());
        for w in t.next.get(v).into_iter().flatten() {
            if !t.index.contains_key(w) {
                visit(t, w);
                let lw = t.low[w];
                t.low.entry(v.to_string()).and_modify(|l| *l = (*l).min(lw));
            } else if t.on.contains(w) {
                let iw = t.index[w];
                t.low.entry(v.to_string()).and_modify(|l| *l = (*l).min(iw));
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(&w);
                let done = w == v;
                comp.push(w);
                if done {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        next,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in next.keys() {
        if !t.index.contains_key(v) {
            visit(&mut t, v);
        }
    }
    t.out
}

/// Every import from a room to a room that comes later in `order` (bottom first): an arrow up. A room missing
/// from `order` is reported too, so that a new room must be given its place.
pub fn arrows_up(edges: &BTreeMap<Module, BTreeSet<Module>>, order: &[&str]) -> Vec<String> {
    let rank = |m: &Module| order.iter().position(|r| *r == m[0]);
    let mut found = BTreeSet::new();
    for (a, targets) in edges {
        for b in targets.iter().filter(|b| b[0] != a[0]) {
            match (rank(a), rank(b)) {
                (Some(i), Some(j)) if j > i => {
                    found.insert(format!("{} names {}, a room above it", a.join("::"), b.join("::")));
                }
                (None, _) => drop(found.insert(format!("room {} has no place in the order", a[0]))),
                (_, None) => drop(found.insert(format!("room {} has no place in the order", b[0]))),
                _ => {}
            }
        }
    }
    found.into_iter().collect()
}
