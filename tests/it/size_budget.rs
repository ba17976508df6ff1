//! Issue #37: rooms of a readable size. A source file of the workspace's libraries and tools
//! (`crates/*/src`, `src`, `xtask/src`) has at most [`MAX_FILE_LINES`] lines and a function at
//! most [`MAX_FN_LINES`] (from its `fn` line to its closing brace), unless it is on the short
//! allow-list below, each entry with the reason it stays. Test code is not measured.

use super::no_unwrap::{code_lines, rust_files};
use std::path::{Path, PathBuf};

/// Most lines of a source file.
const MAX_FILE_LINES: usize = 800;
/// Most lines of a function.
const MAX_FN_LINES: usize = 150;

/// Files allowed above the budget (path relative to the workspace root) and why.
const FILE_ALLOW: &[(&str, &str)] = &[(
    "crates/mesh-fem/src/validate.rs",
    "one report type and its checks; the repairs are next to split out",
)];

/// Functions allowed above the budget (`path::name`) and why.
const FN_ALLOW: &[(&str, &str)] = &[
    (
        "crates/mesh-fem/src/mtx.rs::read_matrix_market",
        "one pass over a header and its entries",
    ),
    (
        "crates/mesh-fem/src/topology.rs::new",
        "one pass building five connected structures",
    ),
    (
        "crates/shrec-bench/src/eval/methods.rs::methods",
        "the table of methods, one line each",
    ),
];

/// Net `{` minus `}` of a code line whose string literals are already blanked.
fn braces(code: &str) -> i64 {
    code.chars().fold(0, |d, c| match c {
        '{' => d + 1,
        '}' => d - 1,
        _ => d,
    })
}

/// The name of the function a code line declares (`fn name`), if any.
fn declared_fn(code: &str) -> Option<&str> {
    let at = code.find("fn ")?;
    if at > 0
        && code[..at]
            .chars()
            .last()
            .is_some_and(|c| c.is_alphanumeric() || c == '_')
    {
        return None;
    }
    let rest = &code[at + 3..];
    let name: &str = &rest[..rest
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(rest.len())];
    (!name.is_empty()).then_some(name)
}

/// Every function of a source text with its length in lines (declaration to closing brace).
fn functions(source: &str) -> Vec<(String, usize)> {
    let (lines, _) = code_lines(source);
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let Some(name) = declared_fn(&line.code) else { continue };
        // The body opens on this line or a later one (a signature over several lines); a
        // declaration that ends with `;` first has no body.
        let mut depth = 0i64;
        let mut opened = false;
        for next in &lines[i..] {
            if !opened && next.code.trim_end().ends_with(';') && !next.code.contains('{') {
                break;
            }
            depth += braces(&next.code);
            opened |= next.code.contains('{');
            if opened && depth <= 0 {
                out.push((name.to_string(), next.number - line.number + 1));
                break;
            }
        }
    }
    out
}

fn sources(root: &Path) -> Vec<PathBuf> {
    let mut dirs = vec![root.join("src"), root.join("xtask").join("src")];
    for e in std::fs::read_dir(root.join("crates")).unwrap() {
        dirs.push(e.unwrap().path().join("src"));
    }
    let mut files = Vec::new();
    for d in dirs.iter().filter(|d| d.is_dir()) {
        rust_files(d, &mut files);
    }
    files.sort();
    files
}

#[test]
fn files_and_functions_stay_within_the_budget() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut problems = Vec::new();
    let mut used_file_allows = Vec::new();
    let mut used_fn_allows = Vec::new();
    for file in sources(root) {
        let rel = file.strip_prefix(root).unwrap().display().to_string();
        let text = std::fs::read_to_string(&file).unwrap();
        let n = text.lines().count();
        if n > MAX_FILE_LINES {
            if FILE_ALLOW.iter().any(|(p, _)| *p == rel) {
                used_file_allows.push(rel.clone());
            } else {
                problems.push(format!("{rel}: {n} lines (at most {MAX_FILE_LINES})"));
            }
        }
        for (name, lines) in functions(&text) {
            if lines > MAX_FN_LINES {
                let key = format!("{rel}::{name}");
                if FN_ALLOW.iter().any(|(k, _)| *k == key) {
                    used_fn_allows.push(key);
                } else {
                    problems.push(format!("{key}: {lines} lines (at most {MAX_FN_LINES})"));
                }
            }
        }
    }
    // An allowance that is no longer needed is removed, so the list stays short and true.
    for (p, _) in FILE_ALLOW
        .iter()
        .filter(|(p, _)| !used_file_allows.iter().any(|u| u == p))
    {
        problems.push(format!("{p}: on the file allow-list but within the budget; remove it"));
    }
    for (k, _) in FN_ALLOW.iter().filter(|(k, _)| !used_fn_allows.iter().any(|u| u == k)) {
        problems.push(format!(
            "{k}: on the function allow-list but within the budget; remove it"
        ));
    }
    assert!(
        problems.is_empty(),
        "over the size budget (split them):\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_scanner_measures_functions_from_declaration_to_closing_brace() {
    let src = "fn a() {\n    let x = \"}\";\n}\n\n// fn not_code() {\npub(crate) fn b(\n    x: u32,\n) -> u32 {\n    if x > 0 {\n        1\n    } else {\n        2\n    }\n}\ntrait T {\n    fn c(&self);\n}\n";
    let f = functions(src);
    assert_eq!(f, vec![("a".to_string(), 3), ("b".to_string(), 9)]);
    assert_eq!(declared_fn("    async fn go() {"), Some("go"));
    assert_eq!(declared_fn("let of_fn = 3;"), None);
}
