//! The module graph of `src/` is one-way: no import cycle, and the core
//! (what a ground station needs to run the detector on a log) reaches none
//! of the lab modules (simulators, comparison, training, tightly coupled).
//!
//! The graph is read from the source: every `crate::a::b` and `super::`
//! path outside comments, string literals and `#[cfg(test)]` modules is an
//! edge from the file's module to the longest known module prefix of the
//! path. `crate::X` where `X` is a re-export in `lib.rs` resolves to the
//! re-exported module. `mod` declarations are not edges.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Modules the core builds on; none may reach a lab module. (The log
/// readers and the row type are the crate `navguard-logs`, which cannot
/// import navguard at all: cargo refuses the cycle.)
const CORE: [&str; 20] = [
    "anfis", "audit", "codec", "config", "detector", "dragend", "drift", "flatline", "filter", "frames", "indicators", "methods", "metrics", "model",
    "ramp", "rng", "snapshot", "thresholds", "track", "window",
];
/// Lab modules: simulators, the method comparison, training, tightly coupled.
const LAB: [&str; 5] = ["battery", "calibrate", "compare", "sim", "tight"];

/// Source with comments, string and char literals blanked and
/// `#[cfg(...test...)] mod x { ... }` blocks removed.
fn strip(src: &str) -> String {
    let b = src.as_bytes();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if c == b'/' && b.get(i + 1) == Some(&b'*') {
            i += 2;
            while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                i += 1;
            }
            i += 2;
        } else if c == b'r' && (b.get(i + 1) == Some(&b'"') || b.get(i + 1) == Some(&b'#')) && !prev_ident(b, i) {
            // Raw string r"..." or r#"..."#.
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&b'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&b'"') {
                out.push(c as char);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= b.len() {
                    break;
                }
                if b[j] == b'"' && (0..hashes).all(|k| b.get(j + 1 + k) == Some(&b'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            out.push_str("\"\"");
            i = j;
        } else if c == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if c == b'\'' {
            // A char literal ('x', '\n', '{') or a lifetime ('a).
            let close = if b.get(i + 1) == Some(&b'\\') {
                (i + 2..b.len().min(i + 12)).find(|&k| b[k] == b'\'')
            } else {
                let w = src[i + 1..].chars().next().map_or(1, char::len_utf8);
                (b.get(i + 1 + w) == Some(&b'\'')).then_some(i + 1 + w)
            };
            match close {
                Some(k) => {
                    out.push_str("' '");
                    i = k + 1;
                }
                None => {
                    out.push('\'');
                    i += 1;
                }
            }
        } else {
            let w = src[i..].chars().next().map_or(1, char::len_utf8);
            out.push_str(&src[i..i + w]);
            i += w;
        }
    }
    drop_test_modules(&out)
}

fn prev_ident(b: &[u8], i: usize) -> bool {
    i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_')
}

/// Remove `#[cfg(<anything with test>)]` followed by a `mod name {...}`.
fn drop_test_modules(src: &str) -> String {
    let mut out = String::new();
    let mut rest = src;
    while let Some(at) = rest.find("#[cfg(") {
        let attr_end = rest[at..].find(")]").map_or(rest.len(), |e| at + e + 2);
        let attr = &rest[at..attr_end];
        let after = rest[attr_end..].trim_start();
        let is_test_mod = attr.contains("test") && (after.starts_with("mod ") || after.starts_with("pub mod ") || after.starts_with("pub(crate) mod "));
        if !is_test_mod {
            out.push_str(&rest[..attr_end]);
            rest = &rest[attr_end..];
            continue;
        }
        out.push_str(&rest[..at]);
        let body = &rest[attr_end..];
        let Some(open) = body.find(['{', ';']) else { break };
        if body.as_bytes()[open] == b';' {
            rest = &body[open + 1..];
            continue;
        }
        let mut depth = 0usize;
        let mut end = body.len();
        for (k, ch) in body[open..].char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = open + k + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        rest = &body[end..];
    }
    out.push_str(rest);
    out
}

/// `src/a/b.rs` -> `a::b`, `src/a/mod.rs` -> `a`, `src/lib.rs` -> `` (root).
fn module_of(rel: &Path) -> String {
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    let last = parts.pop().unwrap_or_default();
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" && stem != "lib" {
        parts.push(stem.to_string());
    }
    parts.join("::")
}

fn walk(dir: &Path, root: &Path, files: &mut Vec<(String, String)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        let rel = p.strip_prefix(root).unwrap().to_path_buf();
        if p.is_dir() {
            // Binaries are crates of their own.
            if rel != Path::new("bin") {
                walk(&p, root, files);
            }
        } else if p.extension().is_some_and(|e| e == "rs") {
            files.push((module_of(&rel), std::fs::read_to_string(&p).unwrap()));
        }
    }
}

/// The path segments after `crate::` or a run of `super::` at every
/// occurrence, resolved to absolute segments.
fn paths(module: &str, src: &str) -> Vec<Vec<String>> {
    let here: Vec<&str> = if module.is_empty() { vec![] } else { module.split("::").collect() };
    let ident = |s: &str| -> Vec<String> {
        let mut segs = vec![];
        let mut rest = s;
        loop {
            let n = rest.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(rest.len());
            if n == 0 {
                break;
            }
            segs.push(rest[..n].to_string());
            match rest[n..].strip_prefix("::") {
                Some(r) => rest = r,
                None => {
                    // `crate::a::{b, c::d}`: one path per group member.
                    break;
                }
            }
        }
        segs
    };
    let mut out = vec![];
    let b = src.as_bytes();
    for (at, _) in src.match_indices("crate::") {
        if at > 0 && (b[at - 1].is_ascii_alphanumeric() || b[at - 1] == b'_' || b[at - 1] == b'$') {
            continue;
        }
        out.extend(expand(vec![], &src[at + 7..], &ident));
    }
    for (at, _) in src.match_indices("super::") {
        if at > 0 && (b[at - 1].is_ascii_alphanumeric() || b[at - 1] == b'_' || b[at - 1] == b':') {
            continue;
        }
        let mut up = 1;
        let mut rest = &src[at + 7..];
        while let Some(r) = rest.strip_prefix("super::") {
            up += 1;
            rest = r;
        }
        let base: Vec<String> = here[..here.len().saturating_sub(up)].iter().map(|s| s.to_string()).collect();
        out.extend(expand(base, rest, &ident));
    }
    out
}

/// `a::b::{c, d::e}` -> [a::b::c, a::b::d::e] (one level of braces).
fn expand(base: Vec<String>, rest: &str, ident: &dyn Fn(&str) -> Vec<String>) -> Vec<Vec<String>> {
    let head = ident(rest);
    let mut prefix = base;
    prefix.extend(head.iter().cloned());
    let consumed: usize = head.iter().map(|s| s.len() + 2).sum();
    let tail = rest.get(consumed..).unwrap_or("");
    if head.is_empty() || !tail.starts_with('{') {
        if let Some(t) = rest.strip_prefix('{') {
            return group(prefix, t, ident);
        }
        return vec![prefix];
    }
    group(prefix, &tail[1..], ident)
}

fn group(prefix: Vec<String>, t: &str, ident: &dyn Fn(&str) -> Vec<String>) -> Vec<Vec<String>> {
    let end = t.find('}').unwrap_or(t.len());
    t[..end]
        .split(',')
        .map(|m| {
            let mut p = prefix.clone();
            p.extend(ident(m.trim()));
            p
        })
        .collect()
}

struct Graph {
    edges: BTreeMap<String, BTreeSet<String>>,
}

fn graph() -> Graph {
    // The detector crate (`detector/src`, navguard-detector) holds most of
    // the core; `src/lib.rs` re-exports its modules under their own names,
    // so both trees are one module namespace. Its `lib.rs`, like ours, only
    // declares and re-exports.
    let mut files = vec![];
    for dir in ["detector/src", "src"] {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
        walk(&root, &root, &mut files);
    }
    let modules: BTreeSet<String> = files.iter().map(|f| f.0.clone()).collect();
    // lib.rs re-exports: `pub use a::{X, Y};` / `pub use a::X;` -> X => a.
    let lib: String = files.iter().filter(|f| f.0.is_empty()).map(|f| strip(&f.1) + ";").collect();
    let mut alias: BTreeMap<String, String> = BTreeMap::new();
    for stmt in lib.split(';') {
        let Some(u) = stmt.trim().strip_prefix("pub use ") else { continue };
        let (m, items) = match u.split_once("::{") {
            Some((m, items)) => (m.to_string(), items.trim_end_matches('}').split(',').map(|s| s.trim().to_string()).collect::<Vec<_>>()),
            None => match u.rsplit_once("::") {
                Some((m, item)) => (m.to_string(), vec![item.trim().to_string()]),
                None => continue,
            },
        };
        for it in items {
            alias.insert(it, m.clone());
        }
    }
    let resolve = |segs: &[String]| -> Option<String> {
        for n in (1..=segs.len()).rev() {
            let m = segs[..n].join("::");
            if modules.contains(&m) {
                return Some(m);
            }
        }
        segs.first().and_then(|s| alias.get(s)).cloned()
    };
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (m, src) in &files {
        if m.is_empty() {
            continue; // lib.rs only declares and re-exports
        }
        let set = edges.entry(m.clone()).or_default();
        for p in paths(m, &strip(src)) {
            if let Some(to) = resolve(&p) {
                if &to != m && !to.is_empty() {
                    set.insert(to);
                }
            }
        }
    }
    Graph { edges }
}

impl Graph {
    /// A cycle as a path `a -> b -> ... -> a`, if any.
    fn cycle(&self) -> Option<Vec<String>> {
        #[derive(Clone, Copy, PartialEq)]
        enum Mark {
            New,
            Open,
            Done,
        }
        fn visit(g: &Graph, n: &str, mark: &mut BTreeMap<String, Mark>, stack: &mut Vec<String>) -> Option<Vec<String>> {
            mark.insert(n.to_string(), Mark::Open);
            stack.push(n.to_string());
            for m in g.edges.get(n).into_iter().flatten() {
                match mark.get(m).copied().unwrap_or(Mark::New) {
                    Mark::Open => {
                        let from = stack.iter().position(|s| s == m).unwrap_or(0);
                        let mut c = stack[from..].to_vec();
                        c.push(m.clone());
                        return Some(c);
                    }
                    Mark::New => {
                        if let Some(c) = visit(g, m, mark, stack) {
                            return Some(c);
                        }
                    }
                    Mark::Done => {}
                }
            }
            stack.pop();
            mark.insert(n.to_string(), Mark::Done);
            None
        }
        let mut mark = BTreeMap::new();
        for n in self.edges.keys() {
            if mark.get(n).copied().unwrap_or(Mark::New) == Mark::New {
                if let Some(c) = visit(self, n, &mut mark, &mut vec![]) {
                    return Some(c);
                }
            }
        }
        None
    }

    /// Every module reachable from `from` (itself excluded), with the
    /// module it was first reached through.
    fn reach(&self, from: &str) -> BTreeMap<String, String> {
        let mut seen = BTreeMap::new();
        let mut todo = vec![from.to_string()];
        while let Some(n) = todo.pop() {
            for m in self.edges.get(&n).into_iter().flatten() {
                if m != from && !seen.contains_key(m) {
                    seen.insert(m.clone(), n.clone());
                    todo.push(m.clone());
                }
            }
        }
        seen
    }
}

fn top(m: &str) -> &str {
    m.split("::").next().unwrap_or(m)
}

#[test]
fn module_graph_has_no_cycle() {
    let g = graph();
    assert!(g.edges.len() > 30, "parsed only {} modules", g.edges.len());
    if let Some(c) = g.cycle() {
        panic!("import cycle: {}", c.join(" -> "));
    }
}

#[test]
fn core_reaches_no_lab_module() {
    let g = graph();
    let mut bad = vec![];
    for (m, _) in g.edges.iter().filter(|(m, _)| CORE.contains(&top(m))) {
        for (to, via) in g.reach(m) {
            if LAB.contains(&top(&to)) || top(&to) == "wasm" {
                bad.push(format!("{m} reaches {to} (via {via})"));
            }
        }
    }
    assert!(bad.is_empty(), "core modules reach lab or facade modules:\n{}", bad.join("\n"));
}

/// The checker itself: it sees `use`, inline and grouped paths, `super::`,
/// root re-exports, and ignores comments, strings and test modules.
#[test]
fn checker_finds_planted_edges_and_cycles() {
    let src = "use crate::a::{b, c::D};\n// crate::zz::x\nfn f() { let s = \"crate::yy\"; crate::e::f(); super::g::H; }\n#[cfg(test)]\nmod tests { use crate::tt::x; fn k() { let _ = '{'; } }\nuse crate::after;\n";
    let p: Vec<String> = paths("m::n", &strip(src)).into_iter().map(|p| p.join("::")).collect();
    assert_eq!(p, ["a::b", "a::c::D", "e::f", "after", "m::g::H"]);
    let mut edges = BTreeMap::new();
    edges.insert("x".to_string(), BTreeSet::from(["y".to_string()]));
    edges.insert("y".to_string(), BTreeSet::from(["z".to_string()]));
    edges.insert("z".to_string(), BTreeSet::new());
    assert_eq!(Graph { edges: edges.clone() }.cycle(), None);
    edges.get_mut("z").unwrap().insert("x".to_string());
    assert_eq!(Graph { edges }.cycle().map(|c| c.join(" -> ")), Some("x -> y -> z -> x".to_string()));
}

/// Arrows run from the facade to the core: audit uses the detector, the
/// detector the filter, indicators and ANFIS, never back.
#[test]
fn layers_run_one_way() {
    let g = graph();
    let reach = |a: &str, b: &str| g.reach(a).contains_key(b);
    for (hi, lo) in [("audit", "detector"), ("detector", "filter"), ("detector", "indicators"), ("detector", "anfis"), ("detector", "model"), ("detector", "track"), ("config", "model")] {
        assert!(reach(hi, lo), "{hi} should use {lo}");
        assert!(!reach(lo, hi), "{lo} reaches {hi}");
    }
}
