//! `wfem approx`: the feature-driven approximation f = f_glob + f_loc (paper, Sect. 4.2).

use super::choice::choice;
use super::heat::{far_exponent, prepare_kernel, times_pow2};
use super::input::Input;
use super::output::{short_label, short_labels, write_fields, Column, RenderArgs, Writing};
use super::{limits, progress, read_usable, CliError, MassArgs, MeshArgs, Output, OutputFormat};
use clap::Args;
use mesh_fem::Mass;
use serde_json::json;
use std::io::Write;
use std::path::PathBuf;
use wfem_base::Choice;
use wfem_heat::approx::{
    feature_approximation, ApproxParams, Coefficients, FeatureApproximation, NoiseRule, Persistence, ScaleSampling,
};
use wfem_heat::method::Method;
use wfem_heat::HeatParams;

/// Arguments of `wfem approx`.
#[derive(Args, Clone, Debug)]
pub struct ApproxArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// The per-vertex field f (.npy or .csv, one value per vertex).
    #[arg(long, value_parser = super::input::field_path)]
    pub field: PathBuf,
    /// Persistence threshold of the anchors, as a fraction of max f − min f, or in units of f
    /// with --absolute [default: 0.1, as in the paper's Fig. 13].
    #[arg(long, allow_negative_numbers = true)]
    pub persistence: Option<f64>,
    /// Read --persistence in units of f instead of as a fraction of the range.
    #[arg(long)]
    pub absolute: bool,
    /// Number N of times t₁ < … < t_N of the hierarchy (the paper's "scales"; 1..=100).
    #[arg(long = "num-times", alias = "scales", default_value_t = wfem_heat::approx::ApproxParams::default().scales)]
    pub num_times: usize,
    /// How the N times are sampled.
    #[arg(long, value_parser = choice::<ScaleSampling>(), default_value = ScaleSampling::default_name())]
    pub sampling: ScaleSampling,
    /// Index k of the eigenvalue λ_k setting the coarsest scale 1/λ_k (default min(20, n);
    /// 2..=n, at most n/10 above 1000 vertices).
    #[arg(long)]
    pub k: Option<usize>,
    /// Coefficients of the global component.
    #[arg(long, value_parser = choice::<Coefficients>(), default_value = Coefficients::default_name())]
    pub coefficients: Coefficients,
    /// What to do about noise in f: by default the noise level and a scale t* are estimated
    /// from f (GCV), and when smoothing lowers the estimated error f_glob at t* is the denoised
    /// map (t* is added to the scales and marked in the report).
    #[arg(long, value_parser = choice::<NoiseRule>(), default_value = NoiseRule::default_name())]
    pub noise: NoiseRule,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub mass: MassArgs,
    /// Output file: .ply, .npy (+ .json sidecar with the scales, anchors and coefficients, the
    /// noise estimate and the chosen scale) or .csv (f, then f_glob and f_loc at every scale,
    /// named with their t), or .png (one figure each for f, f_glob and f_loc at the chosen
    /// scale of a denoised f, else at the coarsest scale; anchors highlighted).
    #[arg(short = 'o', long = "output", value_parser = Output::parse)]
    pub output: Output,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub render: RenderArgs,
}

/// What defines every f_glob of a run, for the sidecar: the rule and its formula, the
/// sampling, the anchors with their persistence and values, the noise estimate and the chosen
/// scale and, per scale, t, the anchors with a coefficient and the coefficients.
fn record(a: &FeatureApproximation) -> serde_json::Value {
    let scales: Vec<serde_json::Value> = a
        .scales
        .iter()
        .map(|s| {
            json!({
                "t": s.t,
                "anchors": s.anchors,
                "coefficients": s.coefficients,
                "linf_error": s.linf_error,
                "relative_linf_error": s.relative_linf_error,
                "anchor_error": s.anchor_error,
                "critical_points": s.critical_points,
                "persistent_extrema": s.persistent_extrema,
            })
        })
        .collect();
    let noise = a.noise.as_ref().map(|c| {
        json!({
            "sigma": c.noise,
            "gcv_sigma": c.gcv_noise,
            "t": c.t,
            "smoothing_helps": c.smoothing_helps(),
            "gcv_times": c.scores.len(),
        })
    });
    json!({
        "coefficients": a.coefficients.name(),
        "formula": a.coefficients.formula(),
        "sampling": a.sampling.name(),
        "noise_rule": a.noise_rule.name(),
        "noise": noise,
        "chosen": a.chosen,
        "lambda_k": a.lambda_k,
        "lambda_max": a.lambda_max,
        "range": a.range,
        "threshold": a.threshold,
        "anchors": a.anchors,
        "anchor_values": a.anchor_values,
        "anchor_persistence": a.anchor_persistence,
        "persistent_extrema": a.persistent_extrema,
        "scales": scales,
    })
}

/// Figure names of a PNG output (f, f_glob, f_loc).
const PNG_FIGURES: [&str; 3] = ["f", "glob", "loc"];

/// `wfem approx`: splits f into its global component on the persistent critical points and
/// its local component at every scale, writes them and prints the per-scale report.
pub fn approx(args: &ApproxArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let persistence = validate(args)?;
    let run = compute(args, persistence)?;
    write(args, &run, out)
}

/// The checks that need neither the mesh nor the field: the number of scales, the
/// persistence and the output paths.
fn validate(args: &ApproxArgs) -> Result<Persistence, CliError> {
    limits::count(
        "--num-times",
        args.num_times,
        1,
        limits::MAX_APPROX_SCALES,
        "number of scales t_i = (i/10)/λ_k (paper: 5 to 10)",
    )?;
    let persistence = match (args.persistence, ApproxParams::default().persistence) {
        (Some(x), _) if args.absolute => Persistence::Absolute(x),
        (Some(x), _) => Persistence::Relative(x),
        (None, _) if args.absolute => return Err(CliError::Usage("--absolute needs --persistence".into())),
        (None, default) => default,
    };
    let (Persistence::Relative(threshold) | Persistence::Absolute(threshold)) = persistence;
    if !(threshold.is_finite() && threshold >= 0.0) {
        return Err(CliError::OutOfRange {
            flag: "--persistence",
            value: threshold.to_string(),
            allowed: "a finite number ≥ 0".into(),
            why: if args.absolute {
                "a persistence in units of f".into()
            } else {
                "a fraction of max f − min f, e.g. 0.1".into()
            },
        });
    }
    let inputs = [args.input.mesh.as_path(), args.field.as_path()];
    let png_names: Vec<String> = PNG_FIGURES.iter().map(|s| s.to_string()).collect();
    if args.output.format == OutputFormat::Png {
        args.output.check(Some(&png_names), PNG_FIGURES.len(), &inputs)?;
    } else {
        args.output.check(Some(&[]), 1 + 2 * (args.num_times + 1), &inputs)?;
    }
    Ok(persistence)
}

/// A decomposition with what it was computed from.
struct Run {
    input: Input,
    f: Vec<f64>,
    k: usize,
    mass: Mass,
    approx: FeatureApproximation,
}

/// Reads the mesh and the field, checks k, assembles and decomposes.
fn compute(args: &ApproxArgs, persistence: Persistence) -> Result<Run, CliError> {
    let input = read_usable(&args.input)?;
    if input.volume.is_some() {
        return Err(CliError::Usage(format!(
            "{}: approx takes its features on a surface; a tetrahedral mesh is not supported yet",
            input.name
        )));
    }
    let n = input.mesh.n_vertices();
    let f = input.field(&args.field)?;
    // λ_1 = 0 on a connected mesh, so the time scale needs k ≥ 2.
    let k = args.k.unwrap_or(20.min(n));
    limits::count("--k", k, 2, n, &format!("the index of λ_k; the mesh has {n} vertices"))?;
    limits::eigenpairs("--k", k, n)?;
    if n > limits::SMALL_MESH && k > n / limits::SPECTRAL_FRACTION {
        return Err(CliError::OutOfRange {
            flag: "--k",
            value: k.to_string(),
            allowed: format!("2..={} on this {n}-vertex mesh", n / limits::SPECTRAL_FRACTION),
            why: "λ_k comes from a partial eigensolve of k pairs, which slows down sharply beyond n/10".into(),
        });
    }
    limits::columns("--num-times", 1 + 2 * (args.num_times + 1), n)?;
    let mass = args.mass.mass()?;
    let ops = progress::run("assembling L, B, D", || input.assemble(mass.lumping()))?;
    let kernel = prepare_kernel(
        &ops,
        HeatParams {
            mass,
            method: Method::default(),
        },
        n,
    )?;
    // A field far from 1 (e.g. 1e308) is decomposed at a scale 2^−e (exact; the decomposition
    // is linear in f, and an absolute persistence scales with it) and scaled back.
    let e = far_exponent(&f);
    let params = ApproxParams {
        k,
        scales: args.num_times,
        persistence: match persistence {
            Persistence::Absolute(x) => Persistence::Absolute(x * 2f64.powi(-e)),
            relative => relative,
        },
        coefficients: args.coefficients,
        sampling: args.sampling,
        noise: args.noise,
        ..ApproxParams::default()
    };
    let mut approx = progress::run(format!("λ_{k}, noise, anchors and {} scales", args.num_times), || {
        feature_approximation(&input.mesh, &kernel, &times_pow2(&f, -e), &params)
    })?;
    if e != 0 {
        scale_back(&mut approx, e);
    }
    if let Some(w) = approx.warning() {
        progress::warn(&w.message(&|p, v| format!("--{p}{}", v.map(|v| format!(" {v}")).unwrap_or_default())));
    }
    Ok(Run {
        input,
        f,
        k,
        mass,
        approx,
    })
}

/// Multiplies every value in units of f by 2^e (the field was decomposed at 2^−e).
fn scale_back(approx: &mut FeatureApproximation, e: i32) {
    let up = 2f64.powi(e);
    for s in &mut approx.scales {
        s.global = times_pow2(&s.global, e);
        s.local = times_pow2(&s.local, e);
        s.coefficients = times_pow2(&s.coefficients, e);
        s.linf_error *= up;
    }
    approx.anchor_values = times_pow2(&approx.anchor_values, e);
    approx.anchor_persistence = times_pow2(&approx.anchor_persistence, e);
    approx.threshold *= up;
    approx.range *= up;
    if let Some(c) = &mut approx.noise {
        c.noise *= up;
        c.gcv_noise *= up;
        c.smoothed = times_pow2(&c.smoothed, e);
        c.residual
            .iter_mut()
            .chain(c.scores.iter_mut())
            .for_each(|x| *x *= up * up);
    }
}

/// The columns to write: f, then f_glob and f_loc at the figure's scale (PNG) or at every
/// scale.
fn columns(args: &ApproxArgs, run: &Run) -> Vec<Column> {
    let (input, approx) = (&run.input, &run.approx);
    let field_name = args
        .field
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    let column = |name: String, suffix: &str, title: String, t: Option<f64>, values: &[f64]| Column {
        name,
        suffix: suffix.to_string(),
        title: format!("{}: {title}", input.name),
        t,
        values: values.to_vec(),
    };
    let mut columns = vec![column(
        "f".into(),
        "f",
        format!("f = {field_name} (anchors: persistent critical points)"),
        None,
        &run.f,
    )];
    if args.output.format == OutputFormat::Png {
        // A denoised f is shown at its chosen scale, where f_glob is the denoised map.
        let figure = approx
            .chosen
            .and_then(|i| approx.scales.get(i))
            .or(approx.scales.last());
        if let Some(s) = figure {
            let label = short_label(s.t);
            let what = if approx.chosen.is_some() { "denoised, " } else { "" };
            columns.push(column(
                format!("f_glob_t{label}"),
                "glob",
                format!(
                    "f_glob of {field_name}, {what}t = {label} ({} anchors, {} mass)",
                    approx.anchors.len(),
                    run.mass.name()
                ),
                Some(s.t),
                &s.global,
            ));
            columns.push(column(
                format!("f_loc_t{label}"),
                "loc",
                format!("f_loc = f - f_glob of {field_name}, t = {label}"),
                Some(s.t),
                &s.local,
            ));
        }
        return columns;
    }
    let times: Vec<f64> = approx.scales.iter().map(|s| s.t).collect();
    let labels = short_labels(&times);
    for (s, label) in approx.scales.iter().zip(&labels) {
        columns.push(column(
            format!("f_glob_t{label}"),
            "",
            String::new(),
            Some(s.t),
            &s.global,
        ));
    }
    for (s, label) in approx.scales.iter().zip(&labels) {
        columns.push(column(
            format!("f_loc_t{label}"),
            "",
            String::new(),
            Some(s.t),
            &s.local,
        ));
    }
    columns
}

/// The sentence on the noise estimate of the report.
fn noise_line(a: &FeatureApproximation) -> String {
    let percent = |x: f64| if a.range > 0.0 { 100.0 * x / a.range } else { 0.0 };
    match (&a.noise, a.chosen) {
        (None, _) => format!(
            "noise: not estimated (--noise {}): f taken as clean",
            a.noise_rule.name()
        ),
        (Some(c), Some(i)) => format!(
            "noise: σ̂ = {:.3e} ({:.2} % of the range of f); GCV scale t* = {:.6e} (scale {}, marked *): f_glob there \
             is the denoised map, its anchors the persistent critical points of K_t* f with the values of K_(φt*) f, \
             φ = {}",
            c.noise,
            percent(c.noise),
            c.t,
            i + 1,
            ApproxParams::default().value_time_fraction
        ),
        (Some(c), None) => format!(
            "noise: σ̂ = {:.3e} ({:.2} % of the range of f); smoothing at the GCV scale t* = {:.6e} would not lower \
             the estimated error: f taken as clean",
            c.noise,
            percent(c.noise),
            c.t
        ),
    }
}

/// Writes the files, then the report (a reader that stops early (`| head`) loses nothing
/// but the report).
fn write(args: &ApproxArgs, run: &Run, out: &mut dyn Write) -> Result<(), CliError> {
    let (input, approx) = (&run.input, &run.approx);
    let mut meta = serde_json::Map::new();
    meta.insert("command".into(), json!("approx"));
    meta.insert("input".into(), input.meta(&args.input.mesh));
    meta.insert("field".into(), json!(args.field.display().to_string()));
    meta.insert("mass".into(), json!(run.mass.name()));
    meta.insert("lambda_k".into(), json!({ "k": run.k, "value": approx.lambda_k }));
    meta.insert("anchors".into(), json!(approx.anchors));
    meta.insert("approximation".into(), record(approx));
    let how = Writing {
        render: args.render,
        splats: input.splats.as_ref(),
        highlight: &approx.anchors,
        meta,
        allow_infinity: false,
        volume: input.volume.as_ref().map(|v| &v.mesh),
    };
    let written = write_fields(&args.output, &input.mesh, &columns(args, run), how)?;
    let (Persistence::Relative(default) | Persistence::Absolute(default)) = ApproxParams::default().persistence;
    let threshold = args.persistence.unwrap_or(default);
    writeln!(
        out,
        "{} vertices, {} critical points of f, {} anchors (persistence {}{}), λ_{} = {:.6e}; {} coefficients, {} scales",
        input.mesh.n_vertices(),
        approx.input_critical_points,
        approx.anchors.len(),
        threshold,
        if args.absolute { "" } else { " × range" },
        run.k,
        approx.lambda_k,
        approx.coefficients.name(),
        approx.sampling.name(),
    )?;
    writeln!(out, "{}", noise_line(approx))?;
    writeln!(
        out,
        "{:>5} {:>12} {:>12} {:>10} {:>8} {:>12}",
        "scale", "t", "Linf error", "relative", "#crit", "significant"
    )?;
    for (i, s) in approx.scales.iter().enumerate() {
        writeln!(
            out,
            "{:>5} {:>12.6e} {:>12.6e} {:>10.4} {:>8} {:>12}{}",
            i + 1,
            s.t,
            s.linf_error,
            s.relative_linf_error,
            s.critical_points,
            s.significant_critical_points,
            if approx.chosen == Some(i) { " *" } else { "" }
        )?;
    }
    for path in written {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}
