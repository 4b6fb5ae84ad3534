//! The crate's modules import each other without a loop: read from the source, every top-level
//! module of `preint/src` (a file or a directory: `scheme/`, `fast/`, `propagation/`,
//! `preintegrator/`, the data types `measurement`, `params`, `navstate`, …) with an edge to each
//! module its non-test code names (`use crate::…`, `crate::…` paths, the root's re-exports
//! resolved to the module that defines them) forms a directed acyclic graph. A loop is printed
//! as the chain of modules that closes it, with the whole graph.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// `text` without comments, string and character literals, and `#[cfg(test)]` items.
fn code_of(text: &str) -> String {
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            '/' if b.get(i + 1) == Some(&'/') => {
                while i < b.len() && b[i] != '\n' {
                    i += 1;
                }
            }
            '/' if b.get(i + 1) == Some(&'*') => {
                i += 2;
                while i + 1 < b.len() && !(b[i] == '*' && b[i + 1] == '/') {
                    i += 1;
                }
                i += 2;
            }
            '"' => {
                i += 1;
                while i < b.len() && b[i] != '"' {
                    i += if b[i] == '\\' { 2 } else { 1 };
                }
                i += 1;
                out.push_str("\"\"");
            }
            // A character literal ('x', '\n'); a lifetime ('a) is kept.
            '\'' if b.get(i + 2) == Some(&'\'') || b.get(i + 1) == Some(&'\\') => {
                i += 1;
                while i < b.len() && b[i] != '\'' {
                    i += if b[i] == '\\' { 2 } else { 1 };
                }
                i += 1;
            }
            c => {
                out.push(c);
                i += 1;
            }
        }
    }
    drop_test_items(&out)
}

/// `code` without the item that follows each `#[cfg(test)]` (a braced block or a `;` item).
fn drop_test_items(code: &str) -> String {
    let mut out = String::new();
    let mut rest = code;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let after = &rest[at..];
        let (brace, semi) = (after.find('{'), after.find(';'));
        let end = match (brace, semi) {
            (Some(o), s) if s.is_none_or(|s| o < s) => {
                let mut depth = 0;
                let mut end = after.len();
                for (k, c) in after[o..].char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = o + k + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                end
            }
            (_, Some(s)) => s + 1,
            _ => after.len(),
        };
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// The paths after each `crate::` in `code`, brace groups expanded one level
/// (`crate::{a::X, b}` gives `a::X` and `b`).
fn crate_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (at, _) in code.match_indices("crate::") {
        // `$crate::` and `foo_crate::` are other paths.
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$') {
            continue;
        }
        let rest = &code[at + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 1;
            let mut item = String::new();
            for c in group.chars() {
                match c {
                    '{' => depth += 1,
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            break;
                        }
                    }
                    ',' if depth == 1 => {
                        out.push(std::mem::take(&mut item));
                        continue;
                    }
                    _ => {}
                }
                if depth == 1 {
                    item.push(c);
                }
            }
            out.push(item);
        } else {
            let end = rest
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .unwrap_or(rest.len());
            out.push(rest[..end].to_string());
        }
    }
    out.into_iter()
        .map(|p| p.trim().to_string())
        .filter(|p| !p.is_empty())
        .collect()
}

/// Every `.rs` file under `dir`.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(files(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    out.sort();
    out
}

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The crate root's re-exports: name → the top-level module that defines it
/// (`pub use measurement::{PreintegratedImu, …}` maps `PreintegratedImu` to `measurement`).
fn root_reexports() -> BTreeMap<String, String> {
    let lib = code_of(&std::fs::read_to_string(src().join("lib.rs")).unwrap());
    let mut out = BTreeMap::new();
    for stmt in lib.split(';') {
        let Some(at) = stmt.find("pub use ") else {
            continue;
        };
        let path = stmt[at + "pub use ".len()..].trim();
        let path = path.strip_prefix("crate::").unwrap_or(path);
        let (head, tail) = path.split_once("::").unwrap_or((path, ""));
        let names: Vec<&str> = tail
            .split(|c: char| !(c.is_alphanumeric() || c == '_'))
            .filter(|n| !n.is_empty() && *n != "self")
            .collect();
        for n in names {
            out.insert(n.to_string(), head.to_string());
        }
    }
    out
}

/// The top-level module of a file: `scheme` for `src/scheme/euler.rs`, `params` for
/// `src/params.rs`.
fn top_of(file: &Path) -> String {
    let rel = file.strip_prefix(src()).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// A cycle of `graph`, as the chain of nodes that closes it, if there is one.
fn cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(n.to_string(), 1);
        path.push(n.to_string());
        for m in g.get(n).into_iter().flatten() {
            match state.get(m.as_str()).copied().unwrap_or(0) {
                1 => {
                    let from = path.iter().position(|x| x == m).unwrap();
                    let mut c = path[from..].to_vec();
                    c.push(m.clone());
                    return Some(c);
                }
                0 => {
                    if let Some(c) = visit(m, g, state, path) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in graph.keys() {
        if state.get(n.as_str()).copied().unwrap_or(0) == 0 {
            let mut path = Vec::new();
            if let Some(c) = visit(n, graph, &mut state, &mut path) {
                return Some(c);
            }
        }
    }
    None
}

/// The graph of the top-level modules: an edge from each to every other one its code names.
fn top_level_graph() -> BTreeMap<String, BTreeSet<String>> {
    let reexports = root_reexports();
    let tops: BTreeSet<String> = files(&src())
        .iter()
        .map(|f| top_of(f))
        .filter(|t| t != "lib")
        .collect();
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files(&src()) {
        let from = top_of(&f);
        if from == "lib" {
            continue;
        }
        let code = code_of(&std::fs::read_to_string(&f).unwrap());
        let entry = g.entry(from.clone()).or_default();
        for p in crate_paths(&code) {
            let head = p.split("::").next().unwrap().to_string();
            let to = if tops.contains(&head) {
                head
            } else if let Some(m) = reexports.get(&head) {
                m.clone()
            } else {
                continue;
            };
            if to != from {
                entry.insert(to);
            }
        }
    }
    g
}

fn assert_acyclic(what: &str, g: &BTreeMap<String, BTreeSet<String>>) {
    if let Some(c) = cycle(g) {
        let edges: Vec<String> = g
            .iter()
            .map(|(k, v)| {
                format!(
                    "  {k} → {}",
                    v.iter().cloned().collect::<Vec<_>>().join(", ")
                )
            })
            .collect();
        panic!(
            "{what}: import cycle {}\nthe graph:\n{}",
            c.join(" → "),
            edges.join("\n")
        );
    }
}

/// The top-level modules of the crate (the directories `scheme/`, `fast/`, `propagation/`,
/// `preintegrator/` and every file: the data types, the factors, the window path) import each
/// other without a loop.
#[test]
fn top_level_modules_form_no_import_cycle() {
    let g = top_level_graph();
    for dir in [
        "scheme",
        "fast",
        "propagation",
        "preintegrator",
        "sample",
        "noise",
        "params",
        "measurement",
        "navstate",
    ] {
        assert!(g.contains_key(dir), "{dir} not found in {:?}", g.keys());
    }
    assert_acyclic("preint/src", &g);
}

/// The reader finds what it must: paths in code, groups, re-exports; not paths in comments,
/// strings or test modules.
#[test]
fn the_reader_sees_code_paths_only() {
    let text = "use crate::a::X; // crate::b\n/// crate::c\nfn f() { crate::{d::Y, e}; \
                \"crate::g\"; }\n#[cfg(test)]\nmod tests { use crate::h; }\nuse crate::i;";
    let got = crate_paths(&code_of(text));
    assert_eq!(got, ["a::X", "d::Y", "e", "i"]);
    let mut g = BTreeMap::new();
    g.insert("a".to_string(), BTreeSet::from(["b".to_string()]));
    g.insert("b".to_string(), BTreeSet::from(["c".to_string()]));
    g.insert("c".to_string(), BTreeSet::from(["a".to_string()]));
    assert_eq!(cycle(&g).unwrap(), ["a", "b", "c", "a"]);
    g.get_mut("c").unwrap().clear();
    assert!(cycle(&g).is_none());
}
