//! Guard (issue #8): no `.unwrap()` / `.expect(` in library code, i.e. in `crates/*/src/**`
//! and `src/**` outside test code, except on lines that state why it cannot fail with an
//! `// invariant: <reason>` comment on the same line or the line above. Bad input must give a
//! typed error, never a panic. (The crates also carry
//! `#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]`.)
//!
//! Test code is skipped: items after `#[cfg(test)]` (an inline `mod tests { … }`, a function,
//! an impl) up to their matching brace, files declared as `#[cfg(test)] mod name;`, comments
//! and doc comments (doc tests may unwrap).

use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// One offending line: file, 1-based line number, text.
#[derive(Debug, PartialEq)]
struct Hit {
    file: String,
    line: usize,
    text: String,
}

/// Removes a trailing `// …` comment (outside string literals) and reports whether the line
/// carries an `invariant:` comment.
fn split_comment(line: &str) -> (&str, bool) {
    let bytes = line.as_bytes();
    let mut in_str = false;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' if in_str => i += 1,
            b'"' => in_str = !in_str,
            b'/' if !in_str && bytes.get(i + 1) == Some(&b'/') => {
                let comment = &line[i..];
                return (&line[..i], comment.contains("invariant:"));
            }
            _ => {}
        }
        i += 1;
    }
    (line, false)
}

/// The code with the contents of string literals blanked out.
fn strip_strings(code: &str) -> String {
    let mut out = String::with_capacity(code.len());
    let mut in_str = false;
    let mut chars = code.chars();
    while let Some(c) = chars.next() {
        match c {
            '\\' if in_str => {
                chars.next();
            }
            '"' => {
                in_str = !in_str;
                out.push('"');
            }
            _ if in_str => {}
            _ => out.push(c),
        }
    }
    out
}

/// Net `{` minus `}` on a code line (string and char literals ignored).
fn brace_delta(code: &str) -> i64 {
    let mut depth = 0;
    let mut in_str = false;
    let mut chars = code.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if in_str => {
                chars.next();
            }
            '"' => in_str = !in_str,
            '\'' if !in_str => {
                // A char literal like '{' (not a lifetime): skip it.
                let rest: String = chars.clone().take(3).collect();
                if rest.len() >= 2 && rest.chars().nth(1) == Some('\'') {
                    chars.next();
                    chars.next();
                }
            }
            '{' if !in_str => depth += 1,
            '}' if !in_str => depth -= 1,
            _ => {}
        }
    }
    depth
}

/// One line of library code: neither a comment nor part of test code.
pub(crate) struct CodeLine {
    /// 1-based line number.
    pub(crate) number: usize,
    /// The code without its trailing comment, string literals blanked.
    pub(crate) code: String,
    /// The line's own comment, or the line before it, carries `invariant:`.
    pub(crate) justified: bool,
}

/// The library code of one source text, line by line, and the names of modules declared as
/// `#[cfg(test)] mod name;` (whose files are test code). Skipped: comment lines (including
/// doc comments and doc-test code) and items after `#[cfg(test)]` up to `;` or their
/// matching `}`.
pub(crate) fn code_lines(source: &str) -> (Vec<CodeLine>, Vec<String>) {
    let lines: Vec<&str> = source.lines().collect();
    let mut code_lines = Vec::new();
    let mut test_modules = Vec::new();
    let mut i = 0;
    let mut previous_invariant = false;
    while i < lines.len() {
        let trimmed = lines[i].trim_start();
        if trimmed.starts_with("//") {
            // Comment line (including doc comments and doc-test code).
            previous_invariant = trimmed.contains("invariant:");
            i += 1;
            continue;
        }
        if trimmed.starts_with("#[cfg(test)]") {
            // Skip the attributed item: further attributes, then up to `;` or the matching `}`.
            let mut j = i + 1;
            while j < lines.len() && lines[j].trim_start().starts_with("#[") {
                j += 1;
            }
            let mut depth = 0i64;
            let mut opened = false;
            while j < lines.len() {
                let (code, _) = split_comment(lines[j]);
                let code_trim = code.trim();
                if !opened && depth == 0 && code_trim.ends_with(';') && !code_trim.contains('{') {
                    if let Some(name) = code_trim
                        .strip_prefix("mod ")
                        .or_else(|| code_trim.strip_prefix("pub mod "))
                        .or_else(|| code_trim.strip_prefix("pub(crate) mod "))
                    {
                        test_modules.push(name.trim_end_matches(';').trim().to_string());
                    }
                    break;
                }
                let d = brace_delta(code);
                if d != 0 || code.contains('{') {
                    opened = true;
                }
                depth += d;
                if opened && depth <= 0 {
                    break;
                }
                j += 1;
            }
            i = j + 1;
            previous_invariant = false;
            continue;
        }
        let (code, invariant_here) = split_comment(lines[i]);
        code_lines.push(CodeLine {
            number: i + 1,
            code: strip_strings(code),
            justified: invariant_here || previous_invariant,
        });
        previous_invariant = invariant_here;
        i += 1;
    }
    (code_lines, test_modules)
}

/// Scans one source text. Returns the hits and the names of modules declared as
/// `#[cfg(test)] mod name;` (whose files are test code).
fn scan(file: &str, source: &str) -> (Vec<Hit>, Vec<String>) {
    let lines: Vec<&str> = source.lines().collect();
    let (code, test_modules) = code_lines(source);
    let hits = code
        .into_iter()
        .filter(|l| (l.code.contains(".unwrap()") || l.code.contains(".expect(")) && !l.justified)
        .map(|l| Hit {
            file: file.to_string(),
            line: l.number,
            text: lines[l.number - 1].trim().to_string(),
        })
        .collect();
    (hits, test_modules)
}

pub(crate) fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The files of a module declared `#[cfg(test)] mod name;` in `declaring`.
pub(crate) fn module_files(declaring: &Path, name: &str) -> Vec<PathBuf> {
    let dir = declaring.parent().unwrap_or(Path::new("."));
    let stem = declaring.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    let base = if matches!(stem, "lib" | "main" | "mod") {
        dir.to_path_buf()
    } else {
        dir.join(stem)
    };
    vec![base.join(format!("{name}.rs")), base.join(name).join("mod.rs")]
}

fn scan_tree(roots: &[PathBuf]) -> Vec<Hit> {
    let mut files = Vec::new();
    for r in roots {
        rust_files(r, &mut files);
    }
    let mut results = Vec::new();
    let mut test_files: HashSet<PathBuf> = HashSet::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let (hits, modules) = scan(&f.display().to_string(), &text);
        for m in modules {
            test_files.extend(module_files(f, &m));
        }
        results.push((f.clone(), hits));
    }
    results
        .into_iter()
        .filter(|(f, _)| !test_files.contains(f))
        .flat_map(|(_, h)| h)
        .collect()
}

#[test]
fn library_code_has_no_unjustified_unwrap_or_expect() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut roots = vec![root.join("src")];
    for e in std::fs::read_dir(root.join("crates")).unwrap() {
        let src = e.unwrap().path().join("src");
        if src.is_dir() {
            roots.push(src);
        }
    }
    assert!(roots.len() >= 5, "workspace layout changed: {roots:?}");
    let hits = scan_tree(&roots);
    assert!(
        hits.is_empty(),
        "unwrap()/expect( in library code without an `// invariant: <reason>` comment \
         (return a typed error instead, or justify it):\n{}",
        hits.iter()
            .map(|h| format!("  {}:{}: {}", h.file, h.line, h.text))
            .collect::<Vec<_>>()
            .join("\n")
    );
}

#[test]
fn scanner_finds_hits_and_skips_test_code_comments_and_invariants() {
    let snippet = r#"
//! Docs: `let x = f().unwrap();` in a doc test is fine.
fn a(x: Option<u32>) -> u32 {
    x.unwrap()
}
fn b(x: Result<u32, ()>) -> u32 {
    x.expect("user data")
}
fn c(x: Option<u32>) -> u32 {
    // invariant: x is Some because the caller checked it.
    x.unwrap()
}
fn d(x: Option<u32>) -> u32 {
    x.unwrap() // invariant: never None here
}
fn e(x: Option<u32>) -> u32 {
    let s = "a string with .unwrap() inside"; // a comment .unwrap()
    x.unwrap_or(0) + s.len() as u32
}
#[cfg(test)]
mod tests {
    fn t() {
        let c = '{';
        Some(1).unwrap();
        if true { Some(2).expect("fine in tests"); }
    }
}
fn after_tests(x: Option<u32>) -> u32 {
    x.unwrap()
}
#[cfg(test)]
mod cf;
#[cfg(test)]
#[allow(dead_code)]
fn helper() { Some(3).unwrap(); }
fn last(x: Option<u32>) -> u32 { x.expect("boom") }
"#;
    let (hits, modules) = scan("snippet.rs", snippet);
    let lines: Vec<usize> = hits.iter().map(|h| h.line).collect();
    // a (line 4), b (line 7), after_tests (line 29), last (line 36); not the string literal
    // or the comment of line 17, not the invariants, not the test code.
    assert_eq!(lines, vec![4, 7, 29, 36], "{hits:#?}");
    assert_eq!(modules, vec!["cf".to_string()]);
    assert_eq!(
        module_files(Path::new("/x/src/lib.rs"), "cf"),
        vec![PathBuf::from("/x/src/cf.rs"), PathBuf::from("/x/src/cf/mod.rs")]
    );
    assert_eq!(
        module_files(Path::new("/x/src/io/field.rs"), "t"),
        vec![
            PathBuf::from("/x/src/io/field/t.rs"),
            PathBuf::from("/x/src/io/field/t/mod.rs")
        ]
    );
}
