//! `wfem heat`: K_t e_i or K_t f for one or several diffusion times.

use super::choice::choice;
use super::output::{short_labels, Column, RenderArgs, Writing};
use super::{limits, progress, read_usable, CliError, MassArgs, MeshArgs, Output};
use clap::Args;
use mesh_fem::FemOperators;
use serde_json::json;
use std::io::Write;
use std::path::PathBuf;
use wfem_base::Choice;
use wfem_heat::method::{Method, MethodOptions};
use wfem_heat::{HeatKernel, HeatParams};

/// `--method` with its options (`--degree`, `--backend`, `--eigenpairs`): the heat method of the
/// library's registry ([`Method`]) with the options that apply to it.
#[derive(Args, Clone, Debug)]
pub struct MethodArgs {
    /// How K_t f is evaluated. Approximate methods are checked against the exact fast path:
    /// an error above 0.1 % of max|K_t f| is refused unless --allow-inaccurate.
    /// [default: fast; rational when --degree or --backend is given]
    #[arg(long = "method", value_parser = choice::<Method>())]
    pub method: Option<Method>,
    /// Degree of the rational approximation, --method rational only (error ≈ 9.3^-degree;
    /// default 16).
    #[arg(long)]
    pub degree: Option<usize>,
    /// Solver of the shifted systems, --method rational only [default: ldlt].
    #[arg(long, value_parser = choice::<shifted_solve::backend::Backend>())]
    pub backend: Option<shifted_solve::backend::Backend>,
    /// Number of eigenpairs, --method spectral only (default min(200, n); at most n/10 on
    /// meshes above 1000 vertices, where more cost more than --method dense or fast).
    #[arg(long = "eigenpairs", alias = "eigs")]
    pub eigs: Option<usize>,
}

impl MethodArgs {
    fn options(&self, eigenpairs: Option<usize>) -> MethodOptions {
        MethodOptions {
            degree: self.degree,
            backend: self.backend,
            eigenpairs,
        }
    }

    /// The method as named: as given, else rational when a rational-only option (--degree,
    /// --backend) is, else the default (the fast exact path), with the registry's options.
    pub fn named(&self) -> Method {
        match &self.method {
            Some(m) => m.clone(),
            None if self.options(None).names_rational() => Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
            None => Method::default(),
        }
    }

    /// Options that do not apply to the method are refused rather than silently ignored.
    pub fn check(&self) -> Result<(), CliError> {
        check_degree(self.degree)?;
        self.named()
            .with_options(&self.options(self.eigs))
            .map(|_| ())
            .map_err(option_error)
    }

    /// The method with the flags' options; `eigs` is the (checked) number of eigenpairs of the
    /// spectral method.
    pub fn resolve(&self, eigs: usize) -> Result<Method, CliError> {
        let method = self.named();
        let eigenpairs = matches!(method, Method::Spectral { .. }).then_some(eigs);
        method.with_options(&self.options(eigenpairs)).map_err(option_error)
    }
}

/// A method option that does not apply, named by its flag.
fn option_error(e: wfem_heat::HeatError) -> CliError {
    match e {
        wfem_heat::HeatError::MisplacedOption { option, method, owner } => CliError::Usage(format!(
            "--{option} applies to --method {owner} only, not to --method {method}"
        )),
        other => CliError::Heat(other),
    }
}

/// `--degree`: one of the shipped rational approximations.
pub(crate) fn check_degree(degree: Option<usize>) -> Result<(), CliError> {
    match degree {
        Some(d) if !shifted_solve::poles::SHIPPED_DEGREES.contains(&d) => Err(CliError::OutOfRange {
            flag: "--degree",
            value: d.to_string(),
            allowed: format!("one of {:?}", shifted_solve::poles::SHIPPED_DEGREES),
            why: "the degrees of the shipped rational approximations of e^-x (error ≈ 9.3^-degree)".into(),
        }),
        _ => Ok(()),
    }
}

/// Relative max error above which an approximate method is refused unless
/// `--allow-inaccurate`: 0.1 % of max|K_t f|.
pub const INACCURATE_ABOVE: f64 = 1e-3;

/// Arguments of `wfem heat`.
#[derive(Args, Clone, Debug)]
pub struct HeatArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Diffusion time(s) t > 0; several values give one output field each.
    #[arg(long = "t", required = true, num_args = 1.., allow_negative_numbers = true)]
    pub t: Vec<f64>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub time_unit: super::times::TimeUnitArgs,
    /// Diffuse the unit impulse e_i at this vertex (numbered as in the file; the canonical
    /// basis function K_t e_i).
    #[arg(long, conflicts_with = "field", value_parser = super::input::vertex_index, allow_negative_numbers = true)]
    pub source: Option<u32>,
    /// Diffuse this per-vertex field (.npy or .csv, one value per vertex).
    #[arg(long, value_parser = super::input::field_path)]
    pub field: Option<PathBuf>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub mass: MassArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub method: MethodArgs,
    /// Write the result of an approximate method even when its estimated error is above
    /// 0.1 % (the estimate is printed and recorded in the .npy sidecar).
    #[arg(long)]
    pub allow_inaccurate: bool,
    /// Output file: .ply, .npy (+ .json sidecar), .csv, .vtu (ParaView; a volume's tetrahedra) or .png (several t: one figure each,
    /// named x-t<t>.png).
    #[arg(short = 'o', long = "output", value_parser = Output::parse)]
    pub output: Output,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub render: RenderArgs,
}

/// Options that do not apply to the method are refused rather than silently ignored.
fn check_method_options(args: &HeatArgs) -> Result<(), CliError> {
    args.method.check()?;
    if args.allow_inaccurate && args.method.named().is_exact() {
        return Err(CliError::Usage(format!(
            "--allow-inaccurate applies to the approximate methods only ({}), not to --method {}",
            approximate_methods(),
            args.method.named().name()
        )));
    }
    Ok(())
}

/// The names of the approximate methods (whose error is estimated), from the registry.
fn approximate_methods() -> String {
    Method::entries()
        .iter()
        .filter(|e| Method::from_canonical(e.name).is_some_and(|m| !m.is_exact()))
        .map(|e| e.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The power of two e with max|f|·2^−e ∈ [1, 2) when max|f| is far from 1 (beyond 2^±200),
/// else 0. Scaling by 2^−e is exact, and K_t (like the feature approximation) is linear, so
/// a field of 1e308 is computed without overflowing inside the solvers (B f and the shifted
/// right-hand sides overflowed to −∞ before) and a field of 1e−300 keeps its digits.
pub(crate) fn far_exponent(f: &[f64]) -> i32 {
    let max = f.iter().fold(0.0f64, |m, &x| m.max(x.abs()));
    if max == 0.0 || !max.is_finite() {
        return 0;
    }
    let e = max.log2().floor() as i32;
    if e.abs() > 200 {
        e.clamp(-1000, 1000)
    } else {
        0
    }
}

/// x·2^e for every x.
pub(crate) fn times_pow2(f: &[f64], e: i32) -> Vec<f64> {
    let s = 2f64.powi(e);
    f.iter().map(|x| x * s).collect()
}

/// `K_t f`, with f scaled into [1, 2) first when it is far from 1 ([`far_exponent`]).
pub(crate) fn apply_scaled(kernel: &HeatKernel, f: &[f64], t: f64) -> Result<Vec<f64>, CliError> {
    match far_exponent(f) {
        0 => Ok(kernel.apply(f, t)?),
        e => Ok(times_pow2(&kernel.apply(&times_pow2(f, -e), t)?, e)),
    }
}

/// max|a − b| / max|b| (or the absolute difference when b = 0).
pub(crate) fn relative_error(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, &x| m.max(x.abs()));
    let diff = a.iter().zip(b).fold(0.0f64, |m, (&x, &y)| m.max((x - y).abs()));
    if scale > 0.0 {
        diff / scale
    } else {
        diff
    }
}

/// The kernel of a method, built with a spinner that says what is being prepared.
pub(crate) fn prepare_kernel(ops: &FemOperators, params: HeatParams, n: usize) -> Result<HeatKernel, CliError> {
    let label = match &params.method {
        Method::Dense => format!("dense eigendecomposition ({n} × {n})"),
        Method::Spectral { k, .. } => format!("{k} eigenpairs"),
        Method::Taylor => "factorizing the mass matrix".to_string(),
        Method::Rational { degree, .. } => format!("symbolic analysis (rational, degree {degree})"),
        _ => "symbolic analysis".to_string(),
    };
    progress::run(label, || HeatKernel::new(ops, params)).map_err(|e| match e {
        wfem_heat::HeatError::TooLargeForDense { n_vertices, limit } => CliError::Usage(format!(
            "--method {} is limited to {limit} vertices (O(n³) time, 3 dense n × n matrices) and this mesh has \
             {n_vertices}: use --method {} (exact, sparse)",
            Method::Dense.name(),
            Method::fast().name()
        )),
        other => CliError::Heat(other),
    })
}

/// `wfem heat`: K_t e_i or K_t f for one or several t.
pub fn heat(args: &HeatArgs, out: &mut dyn Write) -> Result<(), CliError> {
    limits::times("--t", &args.t)?;
    check_method_options(args)?;
    let labels = short_labels(&args.t);
    let suffixes: Vec<String> = labels.iter().map(|l| format!("t{l}")).collect();
    let mut inputs = vec![args.input.mesh.as_path()];
    inputs.extend(args.field.as_deref());
    args.output.check(Some(&suffixes), args.t.len(), &inputs)?;
    if args.source.is_none() && args.field.is_none() {
        return Err(CliError::Usage("give exactly one of --source I or --field FILE".into()));
    }

    let input = read_usable(&args.input)?;
    let times = args.time_unit.resolve("--t", &input.mesh, &args.t)?;
    let n = input.mesh.n_vertices();
    let (f, what, source) = match (&args.source, &args.field) {
        (Some(i), _) => {
            let v = input.vertex("--source", *i)?;
            let mut e = vec![0.0; n];
            e[v as usize] = 1.0;
            (e, format!("K_t e_{i}"), Some(v))
        }
        (None, Some(path)) => {
            let name = path
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default();
            (input.field(path)?, format!("K_t f, f = {name}"), None)
        }
        (None, None) => return Err(CliError::Usage("give exactly one of --source I or --field FILE".into())),
    };
    let mass = args.mass.mass()?;
    let method = args.method.named();
    let eigs = match &method {
        Method::Spectral { k, .. } => limits::spectral_eigenpairs(args.method.eigs.unwrap_or((*k).min(n)), n)?,
        _ => 0,
    };
    let method = args.method.resolve(eigs)?;
    let ops = progress::run("assembling L, B, D", || input.assemble(mass.lumping()))?;
    let kernel = prepare_kernel(
        &ops,
        HeatParams {
            mass,
            method: method.clone(),
        },
        n,
    )?;
    times.warn(kernel.operators(), &input.mesh, 1.0)?;
    // The exact reference of an approximate method, built on first use.
    let mut reference: Option<HeatKernel> = None;
    let mut errors = Vec::new();
    let mut columns = Vec::with_capacity(args.t.len());
    let bar = progress::bar(args.t.len(), "K_t");
    for ((&t, label), suffix) in times.absolute.iter().zip(&labels).zip(&suffixes) {
        bar.set_detail(&format!("t = {label}"));
        let g = apply_scaled(&kernel, &f, t)?;
        if let Some((vertex, &value)) = g.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(CliError::NonFinite {
                what: format!("K_t (--method {}, t = {label})", method.name()),
                vertex,
                value,
            });
        }
        if !method.is_exact() {
            if reference.is_none() {
                let params = HeatParams {
                    mass,
                    method: Method::fast(),
                };
                reference = Some(prepare_kernel(&ops, params, n)?);
            }
            if let Some(exact) = &reference {
                let error = relative_error(&g, &apply_scaled(exact, &f, t)?);
                check_accuracy(args, &method, t, label, error)?;
                errors.push(error);
            }
        }
        columns.push(Column {
            name: format!("t={label}"),
            suffix: suffix.clone(),
            title: format!(
                "{}: {what}, t = {label}{} ({} mass, {}){}",
                input.name,
                times.suffix(),
                mass.name(),
                method.name(),
                negative_note(&f, &g)
            ),
            t: Some(t),
            values: g,
        });
        bar.inc(&format!("t = {label}"));
    }
    bar.done();

    let mut meta = serde_json::Map::new();
    meta.insert("command".into(), json!("heat"));
    meta.insert("input".into(), input.meta(&args.input.mesh));
    meta.insert("mass".into(), json!(mass.name()));
    meta.insert("method".into(), json!(method));
    meta.insert("time_unit".into(), times.meta());
    match (&args.source, &args.field) {
        (Some(i), _) => meta.insert("source_vertex".into(), json!(i)),
        (_, f) => meta.insert("field".into(), json!(f.as_ref().map(|p| p.display().to_string()))),
    };
    if !errors.is_empty() {
        meta.insert("estimated_relative_error".into(), json!(errors));
    }
    let highlight: Vec<u32> = source.into_iter().collect();
    let how = Writing {
        render: args.render,
        splats: input.splats.as_ref(),
        highlight: &highlight,
        meta,
        allow_infinity: false,
        volume: input.volume.as_ref().map(|v| &v.mesh),
    };
    let written = super::output::write_fields(&args.output, &input.mesh, &columns, how)?;
    for path in written {
        writeln!(out, "wrote {}", path.display())?;
    }
    if input.renumbered() {
        writeln!(out, "(per-vertex values of the repaired mesh: {n} vertices)")?;
    }
    Ok(())
}

/// The one-line note of a figure whose values dip below 0 for a non-negative input (beyond
/// round-off: 1e−6 of the largest value): K_t is not positivity-preserving (the consistent
/// mass B has positive off-diagonal entries, so exp(−tB⁻¹L) can have negative ones).
pub(crate) fn negative_note(f: &[f64], g: &[f64]) -> String {
    let max = g.iter().fold(0.0f64, |m, &x| m.max(x.abs()));
    let min = g.iter().fold(0.0f64, |m, &x| m.min(x));
    if f.iter().all(|&x| x >= 0.0) && min < -1e-6 * max {
        format!("; min {min:.1e} < 0: this kernel is not positivity-preserving")
    } else {
        String::new()
    }
}

/// Prints the estimated error of an approximate method and refuses it above
/// [`INACCURATE_ABOVE`] unless `--allow-inaccurate`.
fn check_accuracy(args: &HeatArgs, method: &Method, t: f64, label: &str, error: f64) -> Result<(), CliError> {
    let text = format!(
        "--method {} at t = {label}: estimated relative error {error:.1e} (max|g − g_exact| / max|g_exact| against --method {})",
        method.name(),
        Method::fast().name()
    );
    if error <= INACCURATE_ABOVE {
        progress::note(&text);
        Ok(())
    } else if args.allow_inaccurate {
        progress::warn(&format!("{text}; written anyway (--allow-inaccurate)"));
        Ok(())
    } else {
        Err(CliError::Inaccurate {
            method: method.name().to_string(),
            t,
            error,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::negative_note;

    #[test]
    fn negative_values_of_a_non_negative_input_get_a_note() {
        assert_eq!(
            negative_note(&[1.0, 0.0], &[0.5, -0.01]),
            "; min -1.0e-2 < 0: this kernel is not positivity-preserving"
        );
        // Round-off below zero, or an input that is itself negative: no note.
        assert_eq!(negative_note(&[1.0, 0.0], &[0.5, -1e-9]), "");
        assert_eq!(negative_note(&[1.0, -1.0], &[0.5, -0.4]), "");
    }
}
