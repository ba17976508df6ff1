//! End-to-end run of `cargo xtask bench --smoke` (tiny meshes, about a second): every section
//! of the report is present, the numbers it reports are right where an independent check
//! exists, the SVGs are well-formed, hand-written text survives a rewrite, and the structure of
//! the report (headings, table headers and row labels; no timings) is snapshotted.

use xtask::bench::{self, BenchOptions, Setting, BEGIN_MARKER, END_MARKER, NOTES_HEADING};

/// Minimal XML well-formedness check: every start tag is closed in order, the root is `<svg>`.
fn check_xml(text: &str) -> Result<(), String> {
    let mut stack: Vec<String> = Vec::new();
    let mut rest = text;
    let mut root = None;
    while let Some(open) = rest.find('<') {
        rest = &rest[open..];
        if let Some(r) = rest.strip_prefix("<?") {
            rest = &r[r.find("?>").ok_or("unterminated <?")? + 2..];
            continue;
        }
        if let Some(r) = rest.strip_prefix("<!--") {
            rest = &r[r.find("-->").ok_or("unterminated comment")? + 3..];
            continue;
        }
        let close = rest.find('>').ok_or("unterminated tag")?;
        let tag = &rest[1..close];
        rest = &rest[close + 1..];
        if let Some(name) = tag.strip_prefix('/') {
            match stack.pop() {
                Some(open) if open == name.trim() => {}
                other => return Err(format!("</{name}> closes {other:?}")),
            }
        } else {
            let name: String = tag.chars().take_while(|c| !c.is_whitespace() && *c != '/').collect();
            root.get_or_insert_with(|| name.clone());
            if !tag.ends_with('/') {
                stack.push(name);
            }
        }
    }
    if !stack.is_empty() {
        return Err(format!("unclosed {stack:?}"));
    }
    match root.as_deref() {
        Some("svg") => Ok(()),
        other => Err(format!("root element {other:?}")),
    }
}

/// Headings, table headers and the first cell of every table row; all other cells masked.
fn structure(markdown: &str) -> String {
    let mut out = String::new();
    let lines: Vec<&str> = markdown.lines().collect();
    for (i, line) in lines.iter().enumerate() {
        if line.starts_with('#') || line.starts_with("Degree r") {
            out.push_str(line);
            out.push('\n');
        } else if line.starts_with('|') {
            let header = lines.get(i + 1).is_some_and(|next| next.starts_with("|---"));
            if header || line.starts_with("|---") {
                out.push_str(line);
            } else {
                let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
                out.push_str(&format!("| {} |{}", cells[0], " # |".repeat(cells.len() - 1)));
            }
            out.push('\n');
        }
    }
    out
}

fn cell(report: &bench::Report, name: &str, column: usize) -> Option<f64> {
    report.accuracy.rows.iter().find(|(n, _)| n == name).unwrap().1[column]
}

#[test]
fn smoke_report_end_to_end() {
    let options = BenchOptions::for_setting(Setting::Smoke, false);
    let report = bench::run(&options).unwrap();
    assert_eq!(report.sizes, vec![162, 642]);

    // Numbers with an independent check: the rational (r = 16) and fast methods agree with the
    // dense eigendecomposition to ~1e−12, the paper's r = 7 to its bound E_7 ≈ 1e−7 (relative
    // L∞ on an impulse, so a few times larger), one backward-Euler step does not.
    for (j, &(_, t)) in report.accuracy.columns.iter().enumerate() {
        for exact in [
            "rational r=16, LDLᵀ (default)",
            "rational r=16, LU",
            "rational r=16, MINRES",
            bench::MULTI_SHIFT,
            "fast path (rational Krylov)",
        ] {
            let e = cell(&report, exact, j).unwrap();
            assert!(e < 1e-10, "{exact} t={t}: {e}");
        }
        let e7 = cell(&report, "rational r=7, LDLᵀ (paper's degree)", j).unwrap();
        assert!(e7 < 1e-5 && e7 > 1e-10, "r=7 t={t}: {e7}");
        assert!(cell(&report, bench::BACKWARD_EULER, j).unwrap() > 1e-4);
    }
    // Figure 3: the spectral error at t = 1 decreases with k to the rational floor, and at
    // t = 0.001 (impulse, few eigenpairs) it stays of order one.
    let f3 = &report.figure3;
    let last = f3.errors.last().unwrap();
    assert!(last.windows(2).all(|w| w[1] <= w[0]), "{last:?}");
    assert!(*last.last().unwrap() < 1e-8, "{last:?}");
    assert!(f3.errors[0][0] > 0.5, "{:?}", f3.errors[0]);
    // Figure 2: condition numbers are ≥ 1 and the preconditioned ones are small (MINRES
    // operator with P = tL + |z|B has κ ≤ √2·something modest on these meshes).
    for f2 in &report.figure2 {
        for (m, p) in f2.matrix.iter().flatten().zip(f2.preconditioned.iter().flatten()) {
            assert!(*m >= 1.0 - 1e-9 && (1.0 - 1e-9..10.0).contains(p), "{m} {p}");
        }
    }
    // Scaling: every series has a value at both sizes and a fitted exponent; times are > 0.
    for s in &report.series {
        assert!(
            s.values.iter().all(|m| m.is_some_and(|m| m.seconds > 0.0)),
            "{}",
            s.name
        );
        assert!(s.time_exponent(&report.sizes).is_some(), "{}", s.name);
    }

    // Writing: a hand-written file gets the generated block; a rewrite keeps the notes.
    let dir = tempfile::tempdir().unwrap();
    let md = dir.path().join("BENCHMARKS.md");
    std::fs::write(&md, "# Benchmarks\n\n## Hand-written\n\nkeep me\n").unwrap();
    let written = bench::write(&report, dir.path()).unwrap();
    assert_eq!(written.len(), 6, "{written:?}");
    let text = std::fs::read_to_string(&md).unwrap();
    let before_rewrite = text.clone();
    bench::write(&report, dir.path()).unwrap();
    let text = std::fs::read_to_string(&md).unwrap();
    assert_eq!(text, before_rewrite);
    assert!(text.contains(&format!("{NOTES_HEADING}\n\n### Hand-written\n\nkeep me\n")));
    let generated = &text[text.find(BEGIN_MARKER).unwrap()..text.find(END_MARKER).unwrap()];
    for section in [
        "**Machine:**",
        "### Table 2 of the paper",
        "### Figure 3 of the paper",
        "### Figure 2(c,d) of the paper",
        "### Scaling with n",
        "time exponent p",
        "× BE",
        "### Accuracy against the dense reference",
    ] {
        assert!(generated.contains(section), "missing {section}");
    }
    for path in written.iter().filter(|p| p.extension().is_some_and(|e| e == "svg")) {
        let svg = std::fs::read_to_string(path).unwrap();
        assert!(svg.contains("<svg"), "{}", path.display());
        check_xml(&svg).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        // Every referenced plot exists.
        let name = path.file_name().unwrap().to_str().unwrap();
        assert!(generated.contains(&format!("bench/{name}")), "{name} not linked");
    }
    insta::assert_snapshot!("bench_smoke_structure", structure(generated));
}

#[test]
fn xml_checker_rejects_broken_documents() {
    assert!(check_xml("<?xml version=\"1.0\"?><svg a=\"1\"><g><rect/></g></svg>").is_ok());
    assert!(check_xml("<svg><g></svg>").is_err());
    assert!(check_xml("<svg><g>").is_err());
    assert!(check_xml("<html></html>").is_err());
}
