//! The measurements of a report: scaling, the paper's Figures 2 and 3, accuracy.

#[allow(unused_imports)]
use super::*;

pub(crate) fn sphere(level: u32) -> Result<(mesh_fem::TriMesh, FemOperators), BenchError> {
    let mesh = generate::icosphere(level).with_area(4.0 * std::f64::consts::PI)?;
    let ops = assemble(&mesh, &AssemblyParams::default())?;
    Ok((mesh, ops))
}

pub(crate) fn unit_vector(n: usize, i: usize) -> Vec<f64> {
    let mut e = vec![0.0; n];
    e[i] = 1.0;
    e
}

/// The methods of K_t f compared in the timings and the accuracy table (the spectral method is
/// added per k).
pub(crate) fn methods() -> Vec<(String, Method)> {
    vec![
        (BACKWARD_EULER.into(), Method::BackwardEuler),
        ("Taylor (1 step)".into(), Method::Taylor),
        (FAST.into(), Method::Fast(KrylovParams::default())),
        (RATIONAL_LDLT.into(), Method::rational(16)),
        (
            "rational r=16, LU".into(),
            Method::Rational {
                degree: 16,
                backend: Backend::DirectLu,
            },
        ),
        (
            "rational r=16, MINRES".into(),
            Method::Rational {
                degree: 16,
                backend: Backend::Minres(MinresParams::default()),
            },
        ),
        (
            MULTI_SHIFT.into(),
            Method::Rational {
                degree: 16,
                backend: Backend::MultiShift(KrylovParams::default()),
            },
        ),
        ("rational r=7, LDLᵀ (paper's degree)".into(), Method::rational(7)),
    ]
}

pub(crate) fn kernel(ops: &FemOperators, method: Method) -> Result<HeatKernel, wfem_heat::HeatError> {
    HeatKernel::new(
        ops,
        HeatParams {
            method,
            ..Default::default()
        },
    )
}

pub(crate) fn rel_linf(a: &[f64], reference: &[f64]) -> f64 {
    let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a.iter().zip(reference).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    diff / scale
}

pub(crate) fn progress(text: &str) {
    eprintln!("[bench {:>7.1}s] {text}", START.with(|s| s.elapsed().as_secs_f64()));
}

thread_local! {
    static START: Instant = Instant::now();
}

/// Peak memory predicted at `n` from the earlier measurements `(sizes[i], values[i])` of a
/// series: the last measured peak times (n / n_last)^q, with q the fitted memory exponent of
/// the earlier points (at least 1; 1 with a single point). `None` without earlier points.
pub fn predict_peak(sizes: &[usize], values: &[Option<Measurement>], n: usize) -> Option<f64> {
    let points: Vec<(f64, f64)> = sizes
        .iter()
        .zip(values)
        .filter_map(|(&m, v)| v.map(|v| (m as f64, v.peak_bytes as f64)))
        .collect();
    let &(last_n, last_peak) = points.last()?;
    let q = fit_exponent(&points).unwrap_or(1.0).max(1.0);
    Some(last_peak * (n as f64 / last_n).powf(q))
}

pub(crate) struct Scaling {
    sizes: Vec<usize>,
    series: Vec<Series>,
    skipped: Vec<String>,
}

/// Runs the scaling measurements. A measurement whose predicted peak memory
/// ([`predict_peak`]) exceeds `memory_limit` bytes is skipped and listed in the returned notes.
pub(crate) fn scaling(options: &BenchOptions, memory_limit: Option<f64>) -> Result<Scaling, BenchError> {
    let mut skipped = Vec::new();
    let methods = methods();
    let mut names = vec![ASSEMBLY.to_string()];
    names.extend(methods.iter().map(|(name, _)| name.clone()));
    for &k in &options.spectral_ks {
        names.push(format!("spectral k={k} (incl. eigensolve)"));
    }
    for &k in &options.spectral_ks {
        names.push(format!("eigensolve k={k}"));
    }
    let mut series: Vec<Series> = names
        .into_iter()
        .map(|name| Series {
            name,
            values: Vec::new(),
        })
        .collect();
    let mut sizes = Vec::new();
    let (reps, budget) = (options.repetitions, options.budget_seconds);
    for &level in &options.levels {
        let mesh = generate::icosphere(level).with_area(4.0 * std::f64::consts::PI)?;
        let n = mesh.n_vertices();
        sizes.push(n);
        progress(&format!("n = {n}: assembly"));
        let assembly = measure(reps, budget, || Ok(assemble(&mesh, &AssemblyParams::default())?))?;
        let ops = assemble(&mesh, &AssemblyParams::default())?;
        let e = unit_vector(n, n / 3);
        let mut row = vec![Some(assembly)];
        let earlier = &sizes[..sizes.len() - 1];
        let mut too_big = |index: usize| -> bool {
            let predicted = predict_peak(earlier, &series[index].values, n);
            match (predicted, memory_limit) {
                (Some(p), Some(limit)) if p > limit => {
                    skipped.push(format!(
                        "{} at n = {}: predicted peak {} > {} (60% of RAM)",
                        series[index].name,
                        format_count(n),
                        format_bytes(p as usize),
                        format_bytes(limit as usize)
                    ));
                    true
                }
                _ => false,
            }
        };
        for (index, (name, method)) in methods.iter().enumerate() {
            if too_big(1 + index) {
                row.push(None);
                continue;
            }
            progress(&format!("n = {n}: {name}"));
            row.push(Some(measure(reps, budget, || {
                let k = kernel(&ops, method.clone()).map_err(heat_err(name.clone()))?;
                k.apply(&e, options.t).map_err(heat_err(name.clone()))
            })?));
        }
        let mut eig_rows = Vec::new();
        for (index, &k) in options.spectral_ks.iter().enumerate() {
            if level > options.spectral_max_level || k >= n || too_big(1 + methods.len() + index) {
                row.push(None);
                eig_rows.push(None);
                continue;
            }
            progress(&format!("n = {n}: spectral k = {k}"));
            let mut eig_times = Vec::new();
            let what = format!("spectral k={k}");
            let total = measure(reps, budget, || {
                let start = Instant::now();
                let basis = Eigenbasis::partial(&ops.stiffness, &ops.mass, k, &EigenParams::default())
                    .map_err(heat_err(what.clone()))?;
                eig_times.push(start.elapsed().as_secs_f64());
                basis
                    .apply_heat(&ops.mass, &e, options.t)
                    .map_err(heat_err(what.clone()))
            })?;
            row.push(Some(total));
            eig_rows.push(Some(Measurement {
                seconds: median(&eig_times),
                ..total
            }));
        }
        row.extend(eig_rows);
        for (s, m) in series.iter_mut().zip(row) {
            s.values.push(m);
        }
    }
    Ok(Scaling { sizes, series, skipped })
}

pub(crate) fn figure3(options: &BenchOptions) -> Result<Figure3, BenchError> {
    let (_, ops) = sphere(options.figure_level)?;
    let n = ops.n();
    let ks: Vec<usize> = options.figure3_ks.iter().copied().filter(|&k| k < n).collect();
    let kmax = ks.iter().copied().max().unwrap_or(1);
    progress(&format!("figure 3: n = {n}, eigensolve k = {kmax}"));
    let basis = Eigenbasis::partial(&ops.stiffness, &ops.mass, kmax, &EigenParams::default())
        .map_err(heat_err(format!("figure 3 eigensolve k={kmax}")))?;
    let anchor = n / 3;
    // c = Xᵀ B e_i: B is symmetric, so B e_i is column i of B.
    let mut b_col = vec![0.0; n];
    let sym = ops.mass.symbolic();
    for p in sym.col_range(anchor) {
        b_col[sym.row_idx()[p]] += ops.mass.val()[p];
    }
    let x = &basis.vectors;
    let coeff: Vec<f64> = (0..kmax).map(|j| (0..n).map(|r| x[(r, j)] * b_col[r]).sum()).collect();
    let reference = kernel(&ops, Method::rational(16)).map_err(heat_err("figure 3 reference"))?;
    let e = unit_vector(n, anchor);
    let mut errors = Vec::new();
    for &t in &options.times {
        let exact = reference
            .apply(&e, t)
            .map_err(heat_err(format!("figure 3 reference t={t}")))?;
        let mut approx = vec![0.0; n];
        let mut done = 0;
        let mut row = Vec::new();
        for &k in &ks {
            for j in done..k {
                let w = (-t * basis.values[j]).exp() * coeff[j];
                for (r, a) in approx.iter_mut().enumerate() {
                    *a += w * x[(r, j)];
                }
            }
            done = k;
            row.push(rel_linf(&approx, &exact));
        }
        errors.push(row);
    }
    Ok(Figure3 {
        n,
        anchor,
        times: options.times.clone(),
        ks,
        errors,
    })
}

pub(crate) fn figure2(options: &BenchOptions) -> Result<Vec<Figure2>, BenchError> {
    let (_, ops) = sphere(options.figure_level)?;
    let n = ops.n();
    let solver = ShiftedSolver::new(ops.stiffness.as_ref(), ops.mass.as_ref(), Backend::DirectLu)
        .map_err(solve_err("figure 2 solver"))?;
    let mut out = Vec::new();
    for degree in [shifted_solve::poles::PAPER_DEGREE, shifted_solve::poles::DEFAULT_DEGREE] {
        progress(&format!("figure 2: n = {n}, degree {degree}"));
        let approx = RationalApprox::cram(degree).map_err(solve_err(format!("degree {degree}")))?;
        let mut poles: Vec<c64> = approx.poles.to_vec();
        if let Some((z, _)) = approx.real_pole {
            poles.push(c64::new(z, 0.0));
        }
        let mut matrix = Vec::new();
        let mut preconditioned = Vec::new();
        for &t in &options.times {
            let mut m_row = Vec::new();
            let mut p_row = Vec::new();
            for &z in &poles {
                let report = solver
                    .condition(t, z, None)
                    .map_err(solve_err(format!("condition t={t} z={z:?}")))?;
                m_row.push(report.matrix);
                p_row.push(report.preconditioned);
            }
            matrix.push(m_row);
            preconditioned.push(p_row);
        }
        out.push(Figure2 {
            degree,
            n,
            times: options.times.clone(),
            poles,
            matrix,
            preconditioned,
        });
    }
    Ok(out)
}

pub(crate) fn accuracy(options: &BenchOptions) -> Result<Accuracy, BenchError> {
    let mut columns = Vec::new();
    let mut rows: Vec<(String, Vec<Option<f64>>)> = methods().into_iter().map(|(n, _)| (n, Vec::new())).collect();
    for &k in &options.spectral_ks {
        rows.push((format!("spectral k={k}"), Vec::new()));
    }
    for &level in &options.accuracy_levels {
        let (_, ops) = sphere(level)?;
        let n = ops.n();
        progress(&format!("accuracy: n = {n}, dense reference"));
        let dense = kernel(&ops, Method::Dense).map_err(heat_err("dense reference"))?;
        let e = unit_vector(n, n / 3);
        let mut kernels = Vec::new();
        for (name, method) in methods() {
            kernels.push(Some(kernel(&ops, method).map_err(heat_err(name))?));
        }
        for &k in &options.spectral_ks {
            kernels.push(if k < n {
                Some(kernel(&ops, Method::spectral(k)).map_err(heat_err(format!("spectral k={k}")))?)
            } else {
                None
            });
        }
        for &t in &options.times {
            columns.push((n, t));
            let reference = dense.apply(&e, t).map_err(heat_err("dense reference"))?;
            for ((name, row), k) in rows.iter_mut().zip(&kernels) {
                row.push(match k {
                    Some(k) => Some(rel_linf(
                        &k.apply(&e, t).map_err(heat_err(format!("{name} t={t}")))?,
                        &reference,
                    )),
                    None => None,
                });
            }
        }
    }
    Ok(Accuracy { columns, rows })
}

/// Runs every measurement of the report.
///
/// # Errors
/// The first failing computation, named.
pub fn run(options: &BenchOptions) -> Result<Report, BenchError> {
    let start = Instant::now();
    let mut machine = Machine::probe();
    let accuracy = accuracy(options)?;
    let figure2 = figure2(options)?;
    let figure3 = figure3(options)?;
    let memory_limit = machine.memory_bytes.map(|b| 0.6 * b as f64);
    let Scaling { sizes, series, skipped } = scaling(options, memory_limit)?;
    machine.load.1 = load_average();
    Ok(Report {
        machine,
        options: options.clone(),
        sizes,
        series,
        skipped,
        figure3,
        figure2,
        accuracy,
        total_seconds: start.elapsed().as_secs_f64(),
    })
}

// ---------------------------------------------------------------------------------------------
// Formatting
// ---------------------------------------------------------------------------------------------
