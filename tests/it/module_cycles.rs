//! Guard (issue #26): no crate has a cycle between its top-level modules. A module that uses
//! another one (`crate::other::…`, `use crate::{other, …}`, `super::other` from a top-level
//! file, or a root re-export `crate::Name` whose `use` in `lib.rs`/`main.rs` comes from
//! `other`) depends on it, and dependencies point one way only, as between crates: a module
//! can be read, tested and moved with only the modules below it.
//!
//! Scanned: `src/` of every crate under `crates/`, of the facade and of `xtask`, library code
//! only (comments, string literals and test code are skipped as in [`super::no_unwrap`]).

use super::no_unwrap::{code_lines, module_files, rust_files};
use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::path::{Path, PathBuf};

/// Module graph of one crate: top-level module → the top-level modules it uses.
type Graph = BTreeMap<String, BTreeSet<String>>;

/// The module path of a source file relative to its `src/`: `foo.rs` and `foo/mod.rs` are
/// `[foo]`, `foo/bar.rs` is `[foo, bar]`, the crate roots (`lib.rs`, `main.rs`) are `[]`.
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap_or(file).with_extension("");
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    if parts.last().is_some_and(|l| l == "mod") || (parts.len() == 1 && matches!(parts[0].as_str(), "lib" | "main")) {
        parts.pop();
    }
    parts
}

fn is_ident_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The leading identifier of `s` (after whitespace).
pub(crate) fn leading_ident(s: &str) -> &str {
    let s = s.trim_start();
    let end = s.find(|c: char| !is_ident_char(c)).unwrap_or(s.len());
    &s[..end]
}

/// The first segment of every path of a `{…}` group starting at `s` (which begins after the
/// `{`), e.g. `a, b::c, d::{e, f}}` gives `[a, b, d]`.
pub(crate) fn group_heads(s: &str) -> Vec<&str> {
    let mut heads = Vec::new();
    let mut depth = 0usize;
    let mut start = 0;
    for (i, c) in s.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => {
                heads.push(leading_ident(&s[start..i]));
                break;
            }
            '}' => depth -= 1,
            ',' if depth == 0 => {
                heads.push(leading_ident(&s[start..i]));
                start = i + 1;
            }
            _ => {}
        }
    }
    heads.retain(|h| !h.is_empty());
    heads
}

/// The names `code` refers to through `crate::` (and `super::` chains that climb to the crate
/// root from a file whose module path is `path`): the first segment after the root.
fn root_references(code: &str, path: &[String]) -> Vec<String> {
    let mut names = Vec::new();
    let mut heads = |rest: &str| {
        if let Some(group) = rest.strip_prefix('{') {
            names.extend(group_heads(group).into_iter().map(String::from));
        } else {
            let head = leading_ident(rest);
            if !head.is_empty() {
                names.push(head.to_string());
            }
        }
    };
    for (i, _) in code.match_indices("crate::") {
        if code[..i]
            .chars()
            .next_back()
            .is_some_and(|c| is_ident_char(c) || c == '$')
        {
            continue;
        }
        heads(&code[i + "crate::".len()..]);
    }
    for (i, _) in code.match_indices("super::") {
        if code[..i]
            .chars()
            .next_back()
            .is_some_and(|c| is_ident_char(c) || c == ':')
        {
            continue; // `a::super::` or the second `super::` of a chain
        }
        let mut rest = &code[i..];
        let mut climbs = 0;
        while let Some(r) = rest.strip_prefix("super::") {
            rest = r;
            climbs += 1;
        }
        if climbs == path.len() {
            heads(rest);
        }
    }
    names
}

/// The names a crate root imports, with the top-level module each comes from
/// (`pub use io::{read, Mesh as M};` gives `read → io`, `M → io`).
fn root_imports(code: &str, modules: &BTreeSet<String>) -> BTreeMap<String, String> {
    let mut imports = BTreeMap::new();
    for statement in code.split(';') {
        // Without the attributes before the statement.
        let lines: Vec<&str> = statement
            .lines()
            .map(str::trim)
            .skip_while(|l| l.is_empty() || l.starts_with('#'))
            .collect();
        let s = lines.join(" ");
        let Some(path) = ["pub use ", "pub(crate) use ", "use "]
            .iter()
            .find_map(|p| s.strip_prefix(p))
        else {
            continue;
        };
        let path = path.trim().trim_start_matches("self::").trim_start_matches("crate::");
        let module = leading_ident(path);
        if !modules.contains(module) {
            continue;
        }
        let rest = &path[module.len()..];
        let last_names = |item: &str| -> Option<String> {
            let item = item.trim();
            let name = match item.rsplit_once(" as ") {
                Some((_, alias)) => alias.trim(),
                None => item.rsplit("::").next().unwrap_or(item).trim(),
            };
            (!name.is_empty() && name != "*" && name != "self").then(|| name.to_string())
        };
        if let Some(open) = rest.find('{') {
            let inner = rest[open + 1..].trim_end().trim_end_matches('}');
            for item in inner.split(',') {
                if let Some(name) = last_names(item) {
                    imports.insert(name, module.to_string());
                }
            }
        } else if let Some(name) = last_names(path) {
            imports.insert(name, module.to_string());
        }
    }
    imports
}

/// The module graph of the crate whose sources are under `src`.
fn crate_graph(src: &Path) -> Graph {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut code: Vec<(PathBuf, String)> = Vec::new();
    let mut test_files: HashSet<PathBuf> = HashSet::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let (lines, test_modules) = code_lines(&text);
        for m in test_modules {
            test_files.extend(module_files(f, &m));
        }
        let joined: Vec<String> = lines.into_iter().map(|l| l.code).collect();
        code.push((f.clone(), joined.join("\n")));
    }
    code.retain(|(f, _)| !test_files.contains(f));
    // Binaries under src/bin are crates of their own.
    code.retain(|(f, _)| !f.strip_prefix(src).is_ok_and(|r| r.starts_with("bin")));

    let modules: BTreeSet<String> = code
        .iter()
        .filter_map(|(f, _)| module_path(src, f).first().cloned())
        .collect();
    let mut imports = BTreeMap::new();
    for (f, text) in &code {
        if module_path(src, f).is_empty() {
            imports.extend(root_imports(text, &modules));
        }
    }
    let mut graph: Graph = modules.iter().map(|m| (m.clone(), BTreeSet::new())).collect();
    for (f, text) in &code {
        let path = module_path(src, f);
        let Some(top) = path.first() else { continue };
        for name in root_references(text, &path) {
            let target = if modules.contains(&name) {
                Some(name)
            } else {
                imports.get(&name).cloned()
            };
            if let Some(t) = target.filter(|t| t != top) {
                graph.entry(top.clone()).or_default().insert(t);
            }
        }
    }
    graph
}

/// One cycle of `graph` (its modules in order, the first repeated at the end), if any.
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        New,
        Open,
        Done,
    }
    fn visit<'a>(
        v: &'a str,
        graph: &'a Graph,
        marks: &mut BTreeMap<&'a str, Mark>,
        stack: &mut Vec<&'a str>,
    ) -> Option<Vec<String>> {
        marks.insert(v, Mark::Open);
        stack.push(v);
        for w in graph.get(v).into_iter().flatten() {
            match marks.get(w.as_str()).copied().unwrap_or(Mark::New) {
                Mark::Open => {
                    let from = stack.iter().position(|&x| x == w).unwrap_or(0);
                    let mut cycle: Vec<String> = stack[from..].iter().map(|s| s.to_string()).collect();
                    cycle.push(w.clone());
                    return Some(cycle);
                }
                Mark::New if graph.contains_key(w) => {
                    if let Some(c) = visit(w, graph, marks, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        marks.insert(v, Mark::Done);
        None
    }
    let mut marks = BTreeMap::new();
    for v in graph.keys() {
        if marks.get(v.as_str()).copied().unwrap_or(Mark::New) == Mark::New {
            if let Some(c) = visit(v, graph, &mut marks, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

/// Edges that close a cycle still open, each with its crate (its `src` folder relative to the
/// workspace), the two modules and why. They are left out of the graph; the test fails when
/// one of them is no longer there (delete its line then).
const OPEN_EDGES: &[(&str, &str, &str, &str)] = &[];

#[test]
fn no_crate_has_a_module_cycle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut sources = vec![root.join("src"), root.join("xtask").join("src")];
    let mut crates: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path().join("src"))
        .filter(|p| p.is_dir())
        .collect();
    crates.sort();
    sources.extend(crates);
    assert!(sources.len() >= 8, "workspace layout changed: {sources:?}");
    let mut cycles = Vec::new();
    let (mut modules, mut edges) = (0, 0);
    let mut open_edges_seen = 0;
    for src in &sources {
        let mut graph = crate_graph(src);
        for (folder, from, to, why) in OPEN_EDGES {
            if src.ends_with(folder) {
                assert!(
                    graph.get_mut(*from).is_some_and(|e| e.remove(*to)),
                    "{folder}: {from} → {to} is gone ({why}): delete it from OPEN_EDGES"
                );
                open_edges_seen += 1;
            }
        }
        modules += graph.len();
        edges += graph.values().map(BTreeSet::len).sum::<usize>();
        if let Some(cycle) = find_cycle(&graph) {
            cycles.push(format!("  {}: {}", src.display(), cycle.join(" → ")));
        }
    }
    assert_eq!(
        open_edges_seen,
        OPEN_EDGES.len(),
        "a crate of OPEN_EDGES was not scanned"
    );
    // The scan sees the workspace (111 modules and 277 edges when this was written).
    assert!(
        modules >= 80 && edges >= 150,
        "{modules} modules, {edges} edges: the scan lost its way"
    );
    assert!(
        cycles.is_empty(),
        "module cycles (move the code so that the dependency points one way, e.g. into a \
         module above both):\n{}",
        cycles.join("\n")
    );
}

#[test]
fn scanner_sees_every_kind_of_reference_and_finds_cycles() {
    let path = |p: &[&str]| p.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let code = "use crate::{a, b::X, c::{Y, Z}};\nlet x = crate::d::f();\n$crate::e::g();\n\
                use super::h;\nuse super::super::i;\nmy_crate::j();";
    assert_eq!(root_references(code, &path(&["m"])), vec!["a", "b", "c", "d", "h"]);
    assert_eq!(root_references(code, &path(&["m", "n"])), vec!["a", "b", "c", "d", "i"]);
    let modules: BTreeSet<String> = ["io", "mesh"].iter().map(|s| s.to_string()).collect();
    let imports = root_imports(
        "mod io;\npub use io::{read, write as save, atomic::AtomicSet};\npub use mesh::TriMesh;\nuse other_crate::Q",
        &modules,
    );
    let expected: BTreeMap<String, String> = [("read", "io"), ("save", "io"), ("AtomicSet", "io"), ("TriMesh", "mesh")]
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    assert_eq!(imports, expected);
    assert_eq!(module_path(Path::new("/s"), Path::new("/s/io/mod.rs")), path(&["io"]));
    assert_eq!(
        module_path(Path::new("/s"), Path::new("/s/lib.rs")),
        Vec::<String>::new()
    );

    let graph = |edges: &[(&str, &str)]| {
        let mut g = Graph::new();
        for (a, b) in edges {
            g.entry(a.to_string()).or_default().insert(b.to_string());
            g.entry(b.to_string()).or_default();
        }
        g
    };
    assert_eq!(find_cycle(&graph(&[("a", "b"), ("b", "c"), ("a", "c")])), None);
    assert_eq!(
        find_cycle(&graph(&[("a", "b"), ("b", "c"), ("c", "b")])),
        Some(path(&["b", "c", "b"]))
    );
}
