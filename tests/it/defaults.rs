//! Issue #37, point 2: every numeric default is one Rust constant (or a library `Default`) that
//! the command line and the Python bindings read. This scans the places where a default could
//! be written out again: clap's `default_value_t = …` under `src/cli` and pyo3's
//! `#[pyo3(signature = (…))]` under `crates/wfem-py/src`; neither may hold a number. (The pure
//! Python layer and its `.pyi` are scanned by `crates/wfem-py/tests/test_defaults.py`.)

use std::path::Path;

/// The numbers written in `text` (a default's expression): tokens that start with a digit, or a
/// `.` followed by one, outside identifiers (`f64`, `e_1`, `MAX_2` are not numbers).
fn numbers(text: &str) -> Vec<String> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let after_ident = i > 0 && (chars[i - 1].is_alphanumeric() || chars[i - 1] == '_');
        if c.is_ascii_digit() && !after_ident {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_' || chars[i] == '.') {
                // `1..=3` is a range: stop before the dots.
                if chars[i] == '.' && chars.get(i + 1) == Some(&'.') {
                    break;
                }
                i += 1;
            }
            out.push(chars[start..i].iter().collect());
            continue;
        }
        i += 1;
    }
    out
}

/// The `(file, line, expression)` of every default under `dir` that `extract` finds.
fn defaults_in(dir: &Path, extract: Extract) -> Vec<(String, usize, String)> {
    let mut out = Vec::new();
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .collect();
    files.sort();
    for file in files {
        let source = std::fs::read_to_string(&file).unwrap();
        // Join attribute lines that continue (a pyo3 signature spans several lines).
        let mut attribute = String::new();
        let mut first = 0;
        for (i, line) in source.lines().enumerate() {
            let trimmed = line.trim();
            if attribute.is_empty() && !trimmed.starts_with("#[") {
                continue;
            }
            if attribute.is_empty() {
                first = i + 1;
            }
            attribute.push_str(trimmed);
            attribute.push(' ');
            if trimmed.ends_with(']') {
                for expr in extract(&attribute) {
                    out.push((file.display().to_string(), first, expr));
                }
                attribute.clear();
            }
        }
    }
    out
}

/// Finds the default expressions in one attribute.
type Extract = fn(&str) -> Vec<String>;

/// The expressions of `default_value_t = …` in a clap attribute.
fn clap_defaults(attribute: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = attribute;
    while let Some(at) = rest.find("default_value_t") {
        let tail = rest[at + "default_value_t".len()..].trim_start();
        let Some(tail) = tail.strip_prefix('=') else {
            rest = &rest[at + 1..];
            continue;
        };
        let end = tail.find([',', ')']).unwrap_or(tail.len());
        out.push(tail[..end].trim().to_string());
        rest = &tail[end..];
    }
    out
}

/// The default expressions `name=expr` of a pyo3 signature.
fn pyo3_defaults(attribute: &str) -> Vec<String> {
    let Some(at) = attribute.find("signature") else {
        return Vec::new();
    };
    let Some(open) = attribute[at..].find('(') else {
        return Vec::new();
    };
    let body = &attribute[at + open + 1..];
    // Split on top-level commas.
    let (mut depth, mut start, mut out) = (0i32, 0, Vec::new());
    for (i, c) in body.char_indices() {
        match c {
            '(' | '[' | '{' => depth += 1,
            ')' | ']' | '}' if depth == 0 => {
                out.push(body[start..i].to_string());
                break;
            }
            ')' | ']' | '}' => depth -= 1,
            ',' if depth == 0 => {
                out.push(body[start..i].to_string());
                start = i + 1;
            }
            _ => {}
        }
    }
    out.into_iter()
        .filter_map(|arg| arg.split_once('=').map(|(_, expr)| expr.trim().to_string()))
        .collect()
}

#[test]
fn the_scanners_find_numbers_and_only_numbers() {
    assert_eq!(numbers("10"), ["10"]);
    assert!(!numbers("-1e-10").is_empty());
    assert_eq!(numbers("0x5eed_2010"), ["0x5eed_2010"]);
    assert_eq!(numbers("Some(1.5)"), ["1.5"]);
    assert!(numbers("EigenParams::default().tol").is_empty());
    assert!(numbers("MAX_2 + f64::EPSILON").is_empty());
    assert_eq!(clap_defaults("#[arg(long, default_value_t = 5)]"), ["5"]);
    assert_eq!(
        clap_defaults("#[arg(long, default_value_t = DEFAULT_T_COEF, allow_negative_numbers = true)]"),
        ["DEFAULT_T_COEF"]
    );
    assert_eq!(
        pyo3_defaults("#[pyo3(signature = (v, f, k=None, tol=1e-10, seed=E::default().seed, x=Some((1, 2))))]"),
        ["None", "1e-10", "E::default().seed", "Some((1, 2))"]
    );
}

#[test]
fn cli_and_bindings_write_no_numeric_default() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Vec::new();
    let scans: [(&str, Extract); 2] = [("src/cli", clap_defaults), ("crates/wfem-py/src", pyo3_defaults)];
    for (dir, extract) in scans {
        let defaults = defaults_in(&root.join(dir), extract);
        assert!(
            !defaults.is_empty(),
            "no default found under {dir}: the scanner is broken"
        );
        for (file, line, expr) in defaults {
            if !numbers(&expr).is_empty() {
                found.push(format!("{file}:{line}: {expr}"));
            }
        }
    }
    assert!(
        found.is_empty(),
        "numeric defaults written out instead of read from a library constant:\n{}",
        found.join("\n")
    );
}
