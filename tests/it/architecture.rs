//! Issue #37: ARCHITECTURE.md's list of dependencies between workspace crates is the truth.
//! The block between `<!-- dependencies -->` and `<!-- /dependencies -->` is compared with
//! `cargo metadata`, both ways: every normal dependency on a workspace crate is listed, every
//! listed one exists, and a `?` marks exactly the optional ones.

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

type Graph = BTreeMap<String, BTreeSet<(String, bool)>>;

/// The documented graph: crate → {(dependency, optional)}.
fn documented(text: &str) -> Graph {
    let start = text
        .find("<!-- dependencies -->")
        .expect("ARCHITECTURE.md has a dependencies block");
    let end = text
        .find("<!-- /dependencies -->")
        .expect("the dependencies block is closed");
    let mut graph = Graph::new();
    for line in text[start..end].lines().filter(|l| l.starts_with("- `")) {
        let (name, deps) = line[3..].split_once("`:").expect("a line reads - `crate`: deps");
        let mut set = BTreeSet::new();
        for dep in deps.split(',').map(str::trim).filter(|d| !d.is_empty() && *d != "—") {
            // "retrieval-store? (feature `index`)" → ("retrieval-store", true)
            let word = dep.split_whitespace().next().unwrap_or(dep);
            let optional = word.ends_with('?');
            set.insert((word.trim_end_matches('?').to_string(), optional));
        }
        assert!(graph.insert(name.to_string(), set).is_none(), "{name} is listed twice");
    }
    graph
}

/// The actual graph from `cargo metadata --no-deps`.
fn actual() -> Graph {
    let out = Command::new(env!("CARGO"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "metadata",
            "--no-deps",
            "--format-version",
            "1",
            "--offline",
            "--locked",
        ])
        .output()
        .expect("cargo metadata runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let packages = meta["packages"].as_array().unwrap();
    let names: BTreeSet<&str> = packages.iter().filter_map(|p| p["name"].as_str()).collect();
    let mut graph = Graph::new();
    for p in packages {
        let mut set = BTreeSet::new();
        for d in p["dependencies"].as_array().unwrap() {
            let name = d["name"].as_str().unwrap();
            if names.contains(name) && d["kind"].is_null() {
                set.insert((name.to_string(), d["optional"].as_bool().unwrap_or(false)));
            }
        }
        graph.insert(p["name"].as_str().unwrap().to_string(), set);
    }
    graph
}

#[test]
fn architecture_lists_the_dependencies_cargo_has() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/ARCHITECTURE.md")).unwrap();
    let (doc, cargo) = (documented(&text), actual());
    let mut problems = Vec::new();
    for (name, deps) in &cargo {
        match doc.get(name) {
            None => problems.push(format!("{name} is not listed")),
            Some(listed) if listed != deps => {
                problems.push(format!("{name}: ARCHITECTURE.md says {listed:?}, cargo says {deps:?}"))
            }
            Some(_) => {}
        }
    }
    for name in doc.keys().filter(|n| !cargo.contains_key(*n)) {
        problems.push(format!("{name} is listed but is no workspace package"));
    }
    assert!(
        problems.is_empty(),
        "ARCHITECTURE.md's dependency list is stale:\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_parser_reads_optional_and_empty_lists() {
    let g = documented("<!-- dependencies -->\n- `a`: —\n- `b`: a, c? (feature `x`)\n<!-- /dependencies -->");
    assert!(g["a"].is_empty());
    let b: Vec<_> = g["b"].iter().cloned().collect();
    assert_eq!(b, vec![("a".to_string(), false), ("c".to_string(), true)]);
}
