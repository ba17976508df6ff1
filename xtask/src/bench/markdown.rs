//! The report as Markdown: number formats, tables and the generated section.

#[allow(unused_imports)]
use super::*;

/// Seconds with three significant digits and a unit (`412 µs`, `3.21 ms`, `12.3 s`).
pub fn format_seconds(s: f64) -> String {
    let (v, unit) = if s < 1e-3 {
        (s * 1e6, "µs")
    } else if s < 1.0 {
        (s * 1e3, "ms")
    } else {
        (s, "s")
    };
    format!("{} {unit}", sig3(v))
}

/// Bytes in MB (10⁶) with three significant digits.
pub fn format_bytes(b: usize) -> String {
    let mb = b as f64 / 1e6;
    if mb < 0.01 {
        format!("{:.0} kB", b as f64 / 1e3)
    } else {
        format!("{} MB", sig3(mb))
    }
}

pub(crate) fn sig3(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// Vertex count with thousands separators (`163,842`).
pub fn format_count(n: usize) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

pub(crate) fn sci(v: f64) -> String {
    format!("{v:.1e}")
}

/// A markdown table.
pub fn table(header: &[String], rows: &[Vec<String>]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "| {} |", header.join(" | "));
    let _ = writeln!(
        s,
        "|{}",
        header
            .iter()
            .enumerate()
            .map(|(i, _)| if i == 0 { "---|" } else { "---:|" })
            .collect::<String>()
    );
    for r in rows {
        let _ = writeln!(s, "| {} |", r.join(" | "));
    }
    s
}

pub(crate) fn setting_command(options: &BenchOptions) -> String {
    let large = options.levels.contains(&8);
    match options.setting {
        Setting::Smoke => "cargo xtask bench --smoke".into(),
        Setting::Quick => "cargo xtask bench --quick".into(),
        Setting::Full if large => "cargo xtask bench --large".into(),
        Setting::Full => "cargo xtask bench".into(),
    }
}

pub(crate) fn find<'a>(report: &'a Report, name: &str) -> Option<&'a Series> {
    report.series.iter().find(|s| s.name == name)
}

/// The generated section of `BENCHMARKS.md` (without the markers).
pub fn markdown(report: &Report) -> String {
    let mut s = String::new();
    let m = &report.machine;
    let o = &report.options;
    let load = |l: Option<f64>| l.map_or("?".into(), |l| format!("{l:.2}"));
    let _ = writeln!(s, "## Generated report\n");
    let _ = writeln!(
        s,
        "**Machine:** {} · {} cores · {} · {} · commit `{}` · {} · load average {} → {} · \
         setting `{}` ({} s in total).\n",
        m.cpu,
        m.cores,
        m.memory_bytes.map_or("memory unknown".into(), |b| format!(
            "{:.1} GiB RAM",
            b as f64 / (1u64 << 30) as f64
        )),
        m.rustc,
        m.commit,
        m.date,
        load(m.load.0),
        load(m.load.1),
        setting_command(o),
        report.total_seconds.round(),
    );
    let _ = writeln!(
        s,
        "Meshes: icospheres scaled to area 4π (unit sphere), L = cotangent stiffness, B = \
         consistent mass. Times are wall-clock medians of up to {} repetitions of one *cold* \
         call (kernel construction and every factorization included); memory is the peak of \
         live heap bytes above the level before the call (counting global allocator). K_t f \
         is computed for f = e_i (a heat-kernel column, i = n/3) at t = {}. A load average \
         above the core count means other processes shared the machine: read ratios, not \
         absolute times.\n",
        o.repetitions, o.t
    );

    s.push_str(&table2(report));
    s.push_str(&figure3(report));
    s.push_str(&figure2(report));
    s.push_str(&scaling(report));
    s.push_str(&targets(report));
    s.push_str(&accuracy(report));
    s
}

/// The paper's Table 2: time to build (L, B) and to compute K_t f, beside the paper's numbers.
fn table2(report: &Report) -> String {
    let mut s = String::new();
    // Table 2.
    let _ = writeln!(
        s,
        "### Table 2 of the paper: time to build (L, B) and to compute K_t f\n"
    );
    let _ = writeln!(
        s,
        "Paper: 1.83 GHz Intel Core Duo, 1 GB RAM; generalized Chebyshev method with r = 7 \
         and MINRES; its n are 1K–500K, so the paper columns are log-log interpolated between \
         its two nearest rows (— outside its range). Ours: (L, B) includes the lumped D; K_t f \
         per method as in the scaling section.\n"
    );
    let kt_methods = [
        "rational r=7, LDLᵀ (paper's degree)",
        RATIONAL_LDLT,
        "rational r=16, LU",
        "rational r=16, MINRES",
        MULTI_SHIFT,
        FAST,
    ];
    let mut header = vec![
        "n".to_string(),
        "(L, B) ours".into(),
        "(L, B) paper".into(),
        "K_t f paper (r=7, MINRES)".into(),
    ];
    header.extend(kt_methods.iter().map(|k| format!("K_t f ours: {k}")));
    header.push("paper / ours: (L, B), K_t f r=7".into());
    let table2: Vec<(f64, f64)> = PAPER_TABLE2.iter().map(|r| (r.0, r.1)).collect();
    let table2k: Vec<(f64, f64)> = PAPER_TABLE2.iter().map(|r| (r.0, r.2)).collect();
    let rows: Vec<Vec<String>> = report
        .sizes
        .iter()
        .enumerate()
        .map(|(i, &n)| {
            let ours = |name: &str| find(report, name).and_then(|s| s.values[i]).map(|m| m.seconds);
            let cell = |name: &str| ours(name).map_or("—".into(), format_seconds);
            let paper = |t: &[(f64, f64)]| interpolate_loglog(t, n as f64);
            let show = |v: Option<f64>| v.map_or("—".into(), format_seconds);
            let mut r = vec![
                format_count(n),
                cell(ASSEMBLY),
                show(paper(&table2)),
                show(paper(&table2k)),
            ];
            r.extend(kt_methods.iter().map(|k| cell(k)));
            let ratio = |p: Option<f64>, o: Option<f64>| match (p, o) {
                (Some(p), Some(o)) if o > 0.0 => format!("{:.0}×", p / o),
                _ => "—".into(),
            };
            r.push(format!(
                "{}, {}",
                ratio(paper(&table2), ours(ASSEMBLY)),
                ratio(paper(&table2k), ours(kt_methods[0]))
            ));
            r
        })
        .collect();
    s.push_str(&table(&header, &rows));
    let _ = writeln!(s, "\nThe paper's rows: {}.\n", {
        PAPER_TABLE2
            .iter()
            .map(|(n, lb, k)| format!("{}K: {lb} s / {k} s", n / 1e3))
            .collect::<Vec<_>>()
            .join("; ")
    });

    s
}

/// The paper's Figure 3: the spectral truncation error.
fn figure3(report: &Report) -> String {
    let mut s = String::new();
    // Figure 3.
    let f3 = &report.figure3;
    let _ = writeln!(s, "### Figure 3 of the paper: spectral truncation error\n");
    let _ = writeln!(
        s,
        "Relative L∞ error ‖F_k − K_t e_i‖∞ / ‖K_t e_i‖∞ of the spectral representation (Eq. (8)) \
         with the k smallest eigenpairs against the rational result (r = 16, Eq. (13)), n = {}, \
         anchor i = {}. The paper plots the absolute L∞ error for its own mesh: the same \
         shape of curves is expected (large for small t; decaying to the rational floor as k \
         grows for large t). Plot: [`bench/figure3_spectral_error.svg`](bench/figure3_spectral_error.svg).\n",
        format_count(f3.n),
        f3.anchor
    );
    let mut header = vec!["t \\ k".to_string()];
    header.extend(f3.ks.iter().map(|k| k.to_string()));
    let rows: Vec<Vec<String>> = f3
        .times
        .iter()
        .zip(&f3.errors)
        .map(|(t, errs)| {
            let mut r = vec![t.to_string()];
            r.extend(errs.iter().map(|&e| sci(e)));
            r
        })
        .collect();
    s.push_str(&table(&header, &rows));
    s.push('\n');

    s
}

/// The paper's Figure 2(c,d): condition numbers of the shifted matrices.
fn figure2(report: &Report) -> String {
    let mut s = String::new();
    // Figure 2.
    let _ = writeln!(
        s,
        "### Figure 2(c,d) of the paper: condition numbers of the shifted matrices\n"
    );
    let _ = writeln!(
        s,
        "κ₂(tL − z_j B) per distinct pole z_j (upper half plane; each conjugate pole has the \
         same κ; for odd degree the last one is the real pole) and t, and in parentheses κ of \
         the MINRES operator preconditioned by tL + |z_j|B. The paper's Figure 2(c,d) plots \
         κ₂(tL + θ_i B), θ = −conj z, for its degree r = 7 (same matrices up to conjugation) \
         and reports them as well-conditioned; it gives no numbers. n = {}. Plots: {}.\n",
        format_count(report.figure2.first().map_or(0, |f| f.n)),
        report
            .figure2
            .iter()
            .map(|f| format!(
                "[`bench/figure2_condition_r{0}.svg`](bench/figure2_condition_r{0}.svg)",
                f.degree
            ))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for f2 in &report.figure2 {
        let _ = writeln!(s, "Degree r = {}:\n", f2.degree);
        let mut header = vec!["t \\ pole".to_string()];
        header.extend(
            f2.poles
                .iter()
                .enumerate()
                .map(|(j, z)| format!("z{} = {:.2}{:+.2}i", j + 1, z.re, z.im)),
        );
        let rows: Vec<Vec<String>> = f2
            .times
            .iter()
            .enumerate()
            .map(|(a, t)| {
                let mut r = vec![t.to_string()];
                r.extend(
                    f2.matrix[a]
                        .iter()
                        .zip(&f2.preconditioned[a])
                        .map(|(m, p)| format!("{} ({:.2})", sci(*m), p)),
                );
                r
            })
            .collect();
        s.push_str(&table(&header, &rows));
        s.push('\n');
    }

    s
}

/// Time and memory against n, with fitted exponents.
fn scaling(report: &Report) -> String {
    let mut s = String::new();
    let o = &report.options;
    // Scaling.
    let _ = writeln!(s, "### Scaling with n\n");
    let _ = writeln!(
        s,
        "Time and peak heap memory per mesh size, the exponent p of a least-squares fit \
         time ∝ n^p (memory ∝ n^q) on the log-log points, and the ratio of each time to one \
         backward-Euler step on the same mesh. Plots: \
         [`bench/scaling_time.svg`](bench/scaling_time.svg), \
         [`bench/scaling_memory.svg`](bench/scaling_memory.svg).\n"
    );
    let be = find(report, BACKWARD_EULER);
    let mut header = vec!["quantity".to_string()];
    header.extend(report.sizes.iter().map(|&n| format!("n = {}", format_count(n))));
    header.push("time exponent p".into());
    header.push("memory exponent q".into());
    let rows: Vec<Vec<String>> = report
        .series
        .iter()
        .map(|series| {
            let mut r = vec![series.name.clone()];
            for (i, m) in series.values.iter().enumerate() {
                r.push(match m {
                    Some(m) => {
                        let ratio = be
                            .and_then(|b| b.values[i])
                            .map_or(String::new(), |b| format!(", {:.1}× BE", m.seconds / b.seconds));
                        format!("{} ({}{ratio})", format_seconds(m.seconds), format_bytes(m.peak_bytes))
                    }
                    None => "—".into(),
                });
            }
            let exp = |e: Option<f64>| e.map_or("—".into(), |p| format!("{p:.2}"));
            r.push(exp(series.time_exponent(&report.sizes)));
            r.push(exp(series.memory_exponent(&report.sizes)));
            r
        })
        .collect();
    s.push_str(&table(&header, &rows));
    let _ = writeln!(
        s,
        "\nCells: median time (peak heap, time / one backward-Euler step). The spectral rows \
         include the eigensolve (shift-invert block Lanczos without restart, Krylov dimension \
         max(6k, k + 200): memory O(n·k)); it is timed up to {} vertices. The eigensolve rows \
         are the eigensolve alone.\n",
        format_count(generate::icosphere_vertex_count(o.spectral_max_level))
    );
    if !report.skipped.is_empty() {
        let _ = writeln!(s, "Skipped (memory): {}.\n", report.skipped.join("; "));
    }

    s
}

/// Issue #4's targets: against scipy and one backward-Euler step.
fn targets(report: &Report) -> String {
    let mut s = String::new();
    let o = &report.options;
    // Issue #4's performance targets.
    let _ = writeln!(
        s,
        "### Targets of issue #4: against scipy and one backward-Euler step\n"
    );
    let _ = writeln!(
        s,
        "K_t e_i at t = {} (f = e_i, the hardest case for the Krylov methods: ~34 iterations \
         against ~14 for a smooth f), times from the scaling table. scipy: the issue's \
         measurements of the same rational method in scipy on these meshes (only at their \
         sizes). Targets: ≥ 10× faster than scipy; the fast path within 3× of one \
         backward-Euler step.\n",
        o.t
    );
    let header: Vec<String> = [
        "n",
        "backward Euler",
        "fast path",
        "fast / BE (≤ 3×)",
        "scipy rational (issue)",
        "scipy / fast (≥ 10×)",
        "scipy / rational multi-shift",
        "scipy / rational LDLᵀ",
    ]
    .iter()
    .map(|h| h.to_string())
    .collect();
    let rows: Vec<Vec<String>> = report
        .sizes
        .iter()
        .enumerate()
        .map(|(i, &n)| {
            let secs = |name: &str| find(report, name).and_then(|s| s.values[i]).map(|m| m.seconds);
            let scipy = SCIPY_RATIONAL.iter().find(|(m, _)| *m == n).map(|(_, t)| *t);
            let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
                (Some(a), Some(b)) if b > 0.0 => format!("{:.1}×", a / b),
                _ => "—".into(),
            };
            let show = |v: Option<f64>| v.map_or("—".into(), format_seconds);
            vec![
                format_count(n),
                show(secs(BACKWARD_EULER)),
                show(secs(FAST)),
                ratio(secs(FAST), secs(BACKWARD_EULER)),
                show(scipy),
                ratio(scipy, secs(FAST)),
                ratio(scipy, secs(MULTI_SHIFT)),
                ratio(scipy, secs(RATIONAL_LDLT)),
            ]
        })
        .collect();
    s.push_str(&table(&header, &rows));
    s.push('\n');

    s
}

/// Accuracy of every method against the dense reference.
fn accuracy(report: &Report) -> String {
    let mut s = String::new();
    // Accuracy.
    let acc = &report.accuracy;
    let _ = writeln!(s, "### Accuracy against the dense reference\n");
    let _ = writeln!(
        s,
        "Relative L∞ error ‖g − g_ref‖∞ / ‖g_ref‖∞ of K_t e_i (i = n/3) against the dense \
         generalized eigendecomposition (Eq. (6), all n eigenpairs). Taylor and backward Euler \
         are one step of a first-order method (error O(t²λ²) per mode, not small for an \
         impulse); the spectral method's error is the discarded tail e^{{−tλ_{{k+1}}}}.\n"
    );
    let mut header = vec!["method".to_string()];
    header.extend(
        acc.columns
            .iter()
            .map(|(n, t)| format!("n = {}, t = {t}", format_count(*n))),
    );
    let rows: Vec<Vec<String>> = acc
        .rows
        .iter()
        .map(|(name, v)| {
            let mut r = vec![name.clone()];
            r.extend(v.iter().map(|e| e.map_or("—".into(), sci)));
            r
        })
        .collect();
    s.push_str(&table(&header, &rows));
    s
}

// ---------------------------------------------------------------------------------------------
// Plots
// ---------------------------------------------------------------------------------------------
