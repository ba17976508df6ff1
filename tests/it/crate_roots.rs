//! Guard (issue #26): every item of a library crate has one public path. A crate root
//! (`src/lib.rs`) re-exports a short curated list — its error and its few central types —
//! from modules declared without `pub` (`mod x; pub use x::{…};`); every other module is
//! `pub mod` and its items are reached only through it. A root never re-exports another crate
//! or another crate's items: a crate that needs them depends on that crate (ARCHITECTURE.md,
//! "Crate roots").
//!
//! Scanned: `src/lib.rs` of every crate under `crates/` (comments, string literals and test
//! code skipped as in [`super::no_unwrap`]). The facade's `crates/wfem/src/lib.rs` is exempt: its one
//! purpose is to re-export the workspace crates under `wfem::`.

use super::module_cycles::{group_heads, leading_ident};
use super::no_unwrap::code_lines;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The most names a crate root may re-export (the curated list stays short).
const MAX_ROOT_NAMES: usize = 12;

/// How a crate root declares a module.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Visibility {
    /// `mod x;` or `pub(crate) mod x;`: reached only through the root's re-exports.
    Private,
    /// `pub mod x;`: its items are reached through it.
    Public,
}

/// The statements of `code` (split at `;`), each without its leading attributes, on one line.
fn statements(code: &str) -> Vec<String> {
    code.split(';')
        .map(|statement| {
            let lines: Vec<&str> = statement
                .lines()
                .map(str::trim)
                .skip_while(|l| l.is_empty() || l.starts_with('#'))
                .collect();
            lines.join(" ")
        })
        .filter(|s| !s.is_empty())
        .collect()
}

/// The modules a crate root declares, with their visibility.
fn modules(code: &str) -> BTreeMap<String, Visibility> {
    let mut modules = BTreeMap::new();
    for s in statements(code) {
        let (visibility, rest) = if let Some(rest) = s.strip_prefix("pub mod ") {
            (Visibility::Public, rest)
        } else if let Some(rest) = s.strip_prefix("mod ").or_else(|| s.strip_prefix("pub(crate) mod ")) {
            (Visibility::Private, rest)
        } else {
            continue;
        };
        let name = leading_ident(rest);
        if !name.is_empty() && rest.trim() == name {
            modules.insert(name.to_string(), visibility);
        }
    }
    modules
}

/// The re-exports of a crate root that break the rule, one line each, and the number of
/// names it re-exports.
fn root_violations(code: &str) -> (Vec<String>, usize) {
    let modules = modules(code);
    let mut violations = Vec::new();
    let mut names = 0;
    for s in statements(code) {
        let Some(path) = s.strip_prefix("pub use ") else {
            continue;
        };
        let path = path.trim().trim_start_matches("self::").trim_start_matches("crate::");
        // `pub use {a::X, b::Y}` names several modules; `pub use a::{X, Y}` one.
        let heads: Vec<&str> = match path.strip_prefix('{') {
            Some(group) => group_heads(group),
            None => vec![leading_ident(path)],
        };
        names += path
            .split(',')
            .filter(|item| !item.trim().trim_matches(|c| c == '{' || c == '}').trim().is_empty())
            .count();
        for head in heads {
            match modules.get(head) {
                Some(Visibility::Private) => {}
                Some(Visibility::Public) => violations.push(format!(
                    "`pub use {path}`: `{head}` is a public module, so these items already have \
                     a path (drop the re-export, or make `{head}` private if it holds only them)"
                )),
                None => violations.push(format!(
                    "`pub use {path}`: `{head}` is not a module of this crate (a root does not \
                     re-export another crate or its items; depend on that crate instead)"
                )),
            }
        }
    }
    (violations, names)
}

/// The library crates: `crates/*/src/lib.rs`, but the facade `crates/wfem`, whose purpose is to
/// re-export the workspace crates.
fn library_roots(root: &Path) -> Vec<PathBuf> {
    let mut roots: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().is_some_and(|n| n != "wfem"))
        .map(|p| p.join("src").join("lib.rs"))
        .filter(|p| p.is_file())
        .collect();
    roots.sort();
    roots
}

#[test]
fn every_item_has_one_public_path() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let roots = library_roots(root);
    assert!(roots.len() >= 8, "workspace layout changed: {roots:?}");
    let mut problems = Vec::new();
    for lib in &roots {
        let text = std::fs::read_to_string(lib).unwrap();
        let (lines, _) = code_lines(&text);
        let code: Vec<String> = lines.into_iter().map(|l| l.code).collect();
        let (violations, names) = root_violations(&code.join("\n"));
        let name = lib.strip_prefix(root).unwrap_or(lib).display().to_string();
        problems.extend(violations.into_iter().map(|v| format!("  {name}: {v}")));
        if names > MAX_ROOT_NAMES {
            problems.push(format!(
                "  {name}: the root re-exports {names} names (at most {MAX_ROOT_NAMES}: keep the curated \
                 list short, reach the rest through public modules)"
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "crate roots that give an item a second public path (ARCHITECTURE.md, \"Crate roots\"):\n{}",
        problems.join("\n")
    );
}

#[test]
fn scanner_sees_public_modules_and_other_crates() {
    let code =
        "mod error;\nmod mesh;\npub(crate) mod topology;\npub mod io;\n#[doc(hidden)]\npub use error::MeshError;\n\
                pub use mesh::{TriMesh, Face};\npub use topology::Topology;\npub use io::read;\n\
                pub use self::io::{write, AtomicSet};\npub use faer::c64;\npub use mesh_fem;\nuse io::helper;";
    let vis = modules(code);
    assert_eq!(vis.get("mesh"), Some(&Visibility::Private));
    assert_eq!(vis.get("topology"), Some(&Visibility::Private));
    assert_eq!(vis.get("io"), Some(&Visibility::Public));
    let (violations, names) = root_violations(code);
    assert_eq!(names, 9, "{violations:?}");
    assert_eq!(violations.len(), 4, "{violations:?}");
    assert!(violations[0].contains("`io` is a public module"), "{violations:?}");
    assert!(violations[1].contains("`io` is a public module"), "{violations:?}");
    assert!(violations[2].contains("`faer` is not a module"), "{violations:?}");
    assert!(violations[3].contains("`mesh_fem` is not a module"), "{violations:?}");
    let (ok, _) = root_violations("mod a;\npub use a::{X, Y};\npub use {a::Z};");
    assert!(ok.is_empty(), "{ok:?}");
}
