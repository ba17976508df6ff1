//! Issue #37: every file the documentation names exists, and every `cargo xtask` command it
//! names is one. Scanned: README.md, ARCHITECTURE.md, docs/*.md and crates/*/README.md —
//! markdown links (relative to the page) and code spans that start with a folder of the
//! repository (relative to its root).

use std::path::{Path, PathBuf};

/// Folders a code span must start with to be taken as a path of the repository.
const ROOTS: [&str; 9] = [
    "crates/", "src/", "docs/", "tests/", "benches/", "xtask/", "fuzz/", ".ci/", ".github/",
];

/// Folders a run makes and git ignores (the fuzzer's), named by the docs before they exist.
const MADE_BY_RUNS: [&str; 4] = ["fuzz/target", "fuzz/corpus", "fuzz/artifacts", "fuzz/logs"];

fn pages(root: &Path) -> Vec<PathBuf> {
    let mut pages = vec![root.join("README.md"), root.join("ARCHITECTURE.md")];
    for dir in [root.join("docs")] {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "md") {
                pages.push(p);
            }
        }
    }
    for e in std::fs::read_dir(root.join("crates")).unwrap() {
        let p = e.unwrap().path().join("README.md");
        if p.is_file() {
            pages.push(p);
        }
    }
    pages.sort();
    pages
}

/// The link targets `](target)` of a page (external links and anchors left out).
fn links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        let Some(end) = rest.find(')') else { break };
        let target = rest[..end].split('#').next().unwrap_or("").trim().to_string();
        if !target.is_empty() && !target.contains("://") && !target.starts_with("mailto:") && !target.contains(' ') {
            out.push(target);
        }
    }
    out
}

/// Code spans that look like paths of the repository.
fn code_paths(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (i, span) in text.split('`').enumerate() {
        if i % 2 == 0 {
            continue;
        }
        let span = span.trim().trim_end_matches([',', '.', ':', ';']);
        if ROOTS.iter().any(|r| span.starts_with(r))
            && !span.contains(['*', '<', '{', '…', ' ', '$', '|', '(', '['])
            && !span.contains("::")
        {
            out.push(span.to_string());
        }
    }
    out
}

/// The `cargo xtask` subcommands: the kebab-case variants of xtask's `Cmd`.
fn xtask_commands(root: &Path) -> Vec<String> {
    let main = std::fs::read_to_string(root.join("xtask/src/main.rs")).unwrap();
    let start = main.find("enum Cmd {").expect("xtask has an enum Cmd");
    let body = &main[start..];
    let end = body.find("\n}").unwrap_or(body.len());
    body[..end]
        .lines()
        .filter_map(|l| {
            let t = l.trim_start();
            let indent = l.len() - t.len();
            let name: String = t.chars().take_while(|c| c.is_ascii_alphanumeric()).collect();
            (indent == 4 && name.starts_with(|c: char| c.is_ascii_uppercase())).then_some(name)
        })
        .map(|n| {
            let mut kebab = String::new();
            for (i, c) in n.chars().enumerate() {
                if c.is_ascii_uppercase() && i > 0 {
                    kebab.push('-');
                }
                kebab.push(c.to_ascii_lowercase());
            }
            kebab
        })
        .collect()
}

#[test]
fn every_path_and_chore_the_docs_name_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let commands = xtask_commands(root);
    assert!(
        commands.iter().any(|c| c == "real-eval") && commands.iter().any(|c| c == "test-all"),
        "{commands:?}"
    );
    let mut missing = Vec::new();
    for page in pages(root) {
        let text = std::fs::read_to_string(&page).unwrap();
        let name = page.strip_prefix(root).unwrap().display().to_string();
        let dir = page.parent().unwrap();
        for target in links(&text) {
            if !dir.join(&target).exists() {
                missing.push(format!("{name}: link {target}"));
            }
        }
        for path in code_paths(&text) {
            // A crate's README names its files relative to the crate; the others from the root.
            let made = MADE_BY_RUNS.iter().any(|m| path.starts_with(m));
            if !made && !root.join(&path).exists() && !dir.join(&path).exists() {
                missing.push(format!("{name}: `{path}`"));
            }
        }
        for (i, _) in text.match_indices("cargo xtask ") {
            let word: String = text[i + 12..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                .collect();
            if !word.is_empty() && !word.starts_with('-') && !commands.contains(&word) {
                missing.push(format!("{name}: cargo xtask {word}"));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "the docs name what does not exist:\n{}",
        missing.join("\n")
    );
}

#[test]
fn the_scanners_find_links_paths_and_commands() {
    let text = "see [a](docs/A.md#x), [web](https://x.y), `crates/mesh-fem/src/lib.rs`, `crates/*/src`, `x`";
    assert_eq!(links(text), vec!["docs/A.md"]);
    assert_eq!(code_paths(text), vec!["crates/mesh-fem/src/lib.rs"]);
}
