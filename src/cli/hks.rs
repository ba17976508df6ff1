//! `wfem hks`: the heat kernel signature of a mesh (paper, Sect. 5; Eqs. (6)–(8)).

use super::choice::choice;
use super::output::{short_labels, write_fields, Column, OutputFormat, RenderArgs, Writing};
use super::{limits, progress, read_usable, CliError, MassArgs, MeshArgs, Output};
use clap::Args;
use serde_json::json;
use shape_retrieval::exact::{HksMethod, HksSource};
use shape_retrieval::hks::{TimeSampling, DEFAULT_NUM_TIMES};
use shape_retrieval::mesh_hks::{operators_hks, HksStep, MeshHksParams};
use shape_retrieval::RetrievalError;
use std::io::Write;
use wfem_base::Choice;
use wfem_heat::diagonal::DiagonalMethod;

/// Arguments of `wfem hks`.
#[derive(Args, Clone, Debug)]
pub struct HksArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Diffusion times t > 0 (in the mesh's units); one output column each (at most 1000).
    #[arg(long, num_args = 1.., allow_negative_numbers = true, conflicts_with = "num_times")]
    pub times: Vec<f64>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub time_unit: super::times::TimeUnitArgs,
    #[arg(long, alias = "scales", help = format!(
        "Number T of automatic times, log-spaced in [4 ln10/λ_k, 4 ln10/λ_2] (default {DEFAULT_NUM_TIMES}, at most {})",
        limits::MAX_TIMES
    ))]
    pub num_times: Option<usize>,
    /// The heat kernel, by its mass: consistent is the wFEM kernel (the paper's DHK2),
    /// voronoi the Voronoi-cot kernel (its DHK1).
    #[command(flatten)]
    #[allow(missing_docs)]
    pub mass: MassArgs,
    /// How the signature is evaluated.
    #[arg(long, value_parser = choice::<HksMethod>(), default_value = HksMethod::default_name())]
    pub method: HksMethod,
    /// Number k of eigenpairs of the truncated spectral sum (Eq. (8)); default min(100, n),
    /// at most n/10 above 5000 vertices. Not used by --method exact with --times.
    #[arg(long = "eigenpairs", alias = "eigs")]
    pub eigs: Option<usize>,
    /// Output: .npy (n × T array, + .json sidecar with the times), .csv, .ply (fields
    /// `hks_t<t>`) or .png (one figure per time, at most 64).
    #[arg(short = 'o', long = "output", visible_alias = "out", value_parser = Output::parse)]
    pub output: Output,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub render: RenderArgs,
}

/// A retrieval error as the CLI says it (mesh and heat errors keep their flags).
pub(super) fn retrieval(e: RetrievalError) -> CliError {
    match e {
        RetrievalError::Heat(h) => CliError::Heat(h),
        RetrievalError::Mesh(m) => CliError::Mesh(m),
        other => CliError::Usage(other.to_string()),
    }
}

/// A spinner per step of [`operators_hks`].
struct Steps {
    current: Option<progress::Step>,
}

impl Steps {
    fn start(&mut self, step: HksStep) {
        if let Some(s) = self.current.take() {
            s.done();
        }
        let label = match step {
            HksStep::Assembly => "assembling L, B, D".to_string(),
            HksStep::Eigenpairs { k } => format!("{k} eigenpairs"),
            HksStep::SpectralSum => "signature".to_string(),
            HksStep::Analysis => "symbolic analysis".to_string(),
            HksStep::ExactDiagonal => {
                "exact diagonal (selected inversion) where the spectral sum is not accurate".to_string()
            }
        };
        self.current = Some(progress::step(label));
    }

    fn finish(&mut self) {
        if let Some(s) = self.current.take() {
            s.done();
        }
    }
}

/// What `wfem hks` checked before reading the mesh.
struct Checked {
    /// Output columns T.
    count: usize,
    /// Figure-name suffixes of given times (`None` for automatic ones).
    suffixes: Option<Vec<String>>,
    mass: mesh_fem::Mass,
}

/// What `wfem hks` computed.
struct Computed {
    input: super::input::Input,
    times: super::times::Times,
    hks: shape_retrieval::mesh_hks::MeshHks,
    /// Eigenpairs k of the spectral sum.
    k: usize,
}

/// `wfem hks`: writes the n × T heat kernel signature `h(i, t) = Σ_k e^{−λ_k t} φ_k(i)²` of
/// the chosen kernel (shape_retrieval::mesh_hks).
pub fn hks(args: &HksArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let checked = validate(args)?;
    let computed = compute(args, &checked)?;
    write(args, &checked, &computed, out)
}

/// The arguments, before anything is read.
fn validate(args: &HksArgs) -> Result<Checked, CliError> {
    let count = if args.times.is_empty() {
        limits::count(
            "--num-times",
            args.num_times.unwrap_or(DEFAULT_NUM_TIMES),
            1,
            limits::MAX_TIMES,
            "number of automatic times (output columns)",
        )?
    } else {
        limits::times("--times", &args.times)?;
        args.times.len()
    };
    let suffixes = (!args.times.is_empty()).then(|| {
        short_labels(&args.times)
            .iter()
            .map(|l| format!("t{l}"))
            .collect::<Vec<_>>()
    });
    args.output.check(suffixes.as_deref(), count, &[&args.input.mesh])?;
    let mass = args.mass.mass()?;
    // The eigenpairs serve the spectral sum and the automatic times; exact values at given
    // times need none.
    let spectrum_needed = args.method != HksMethod::Exact || args.times.is_empty();
    if args.eigs.is_some() && !spectrum_needed {
        return Err(CliError::Usage(format!(
            "--eigenpairs does not apply to --method {} with --times (no eigenpairs are computed)",
            args.method.name()
        )));
    }
    Ok(Checked { count, suffixes, mass })
}

/// Reads the mesh and computes the signature.
fn compute(args: &HksArgs, checked: &Checked) -> Result<Computed, CliError> {
    let (count, mass) = (checked.count, checked.mass);
    let input = read_usable(&args.input)?;
    let n = input.mesh.n_vertices();
    let k = limits::descriptor_eigenpairs(
        args.eigs
            .unwrap_or(shape_retrieval::descriptor::DEFAULT_EIGENPAIRS.min(n)),
        n,
    )?;
    let flag = if args.times.is_empty() {
        "--num-times"
    } else {
        "--times"
    };
    limits::columns(flag, count, n)?;
    let times = args.time_unit.resolve("--times", &input.mesh, &args.times)?;
    if !args.times.is_empty() {
        let fem = progress::run("assembling L, B, D", || input.assemble(mass.lumping()))?;
        times.warn(&wfem_heat::Operators::new(&fem, mass)?, &input.mesh, 1.0)?;
    }
    let params = MeshHksParams {
        mass,
        method: args.method,
        times: if args.times.is_empty() {
            TimeSampling::Auto { num_times: count }
        } else {
            TimeSampling::Explicit(times.absolute.clone())
        },
        eigenpairs: k,
        ..Default::default()
    };
    let mut steps = Steps { current: None };
    steps.start(HksStep::Assembly);
    let fem = input.assemble(mass.lumping());
    let result = fem
        .map_err(CliError::from)
        .and_then(|fem| operators_hks(&fem, &params, None, &mut |s| steps.start(s)).map_err(retrieval));
    steps.finish();
    Ok(Computed {
        hks: result?,
        input,
        times,
        k,
    })
}

/// One output column per time, titled with how it was computed.
fn columns(args: &HksArgs, checked: &Checked, c: &Computed) -> Vec<Column> {
    // Given times keep their labels (in their unit); automatic ones are in the mesh's units.
    let (labels, unit) = if args.times.is_empty() {
        (short_labels(&c.hks.times), "")
    } else {
        (short_labels(&c.times.given), c.times.suffix())
    };
    labels
        .iter()
        .enumerate()
        .map(|(j, label)| Column {
            name: format!("hks_t{label}"),
            suffix: format!("t{label}"),
            title: format!(
                "{}: HKS, t = {label}{unit} ({} mass, {})",
                c.input.name,
                checked.mass.name(),
                match c.hks.sources[j] {
                    HksSource::Exact { .. } => HksMethod::Exact.name().to_string(),
                    HksSource::Spectral { .. } => format!("k = {}", c.k),
                }
            ),
            t: c.hks.times.get(j).copied(),
            values: c.hks.values.col(j).iter().copied().collect(),
        })
        .collect()
}

/// The sidecar's record of how every column was computed.
fn meta(args: &HksArgs, checked: &Checked, c: &Computed) -> serde_json::Map<String, serde_json::Value> {
    let mut meta = serde_json::Map::new();
    meta.insert("command".into(), json!("hks"));
    meta.insert("input".into(), c.input.meta(&args.input.mesh));
    meta.insert("mass".into(), json!(checked.mass.name()));
    meta.insert("method".into(), json!(args.method.name()));
    meta.insert("time_unit".into(), c.times.meta());
    if c.hks.eigenvalues.is_some() {
        meta.insert("eigenpairs".into(), json!(c.k));
    }
    meta.insert(
        "sources".into(),
        json!(c
            .hks
            .sources
            .iter()
            .zip(&c.hks.times)
            .map(|(s, t)| match s {
                HksSource::Exact { relative_tail } if *relative_tail > 0.0 =>
                    json!({"t": t, "method": s.method().name(), "probing_relative_tail": relative_tail}),
                HksSource::Exact { .. } =>
                    json!({"t": t, "method": s.method().name(), "diagonal": DiagonalMethod::SelectedInversion.name()}),
                HksSource::Spectral { bound, estimate } =>
                    json!({"t": t, "method": s.method().name(), "truncation_bound": bound, "truncation_estimate": estimate}),
            })
            .collect::<Vec<_>>()),
    );
    meta
}

/// Writes the outputs, warns where the truncated sum is off, and prints the summary.
fn write(args: &HksArgs, checked: &Checked, c: &Computed, out: &mut dyn Write) -> Result<(), CliError> {
    let columns = columns(args, checked, c);
    if args.output.format == OutputFormat::Png && checked.suffixes.is_none() {
        // The automatic times are known only now: check their figure names.
        let names: Vec<String> = columns.iter().map(|c| c.suffix.clone()).collect();
        args.output.check(Some(&names), columns.len(), &[&args.input.mesh])?;
    }
    let how = Writing {
        render: args.render,
        splats: c.input.splats.as_ref(),
        highlight: &[],
        meta: meta(args, checked, c),
        allow_infinity: false,
        volume: c.input.volume.as_ref().map(|v| &v.mesh),
    };
    for path in write_fields(&args.output, &c.input.mesh, &columns, how)? {
        writeln!(out, "wrote {}", path.display())?;
    }
    let (hks, k) = (&c.hks, c.k);
    // The rigorous bound is pessimistic by orders of magnitude; the Weyl-law estimate is close
    // (shape_retrieval::exact::truncation_estimate): warn where a spectral column is ~1 % off.
    let truncated: Vec<f64> = hks
        .sources
        .iter()
        .zip(&hks.times)
        .filter(|(s, _)| matches!(s, HksSource::Spectral { estimate, .. } if *estimate > 1e-2))
        .map(|(_, &t)| t)
        .collect();
    if let Some(t) = truncated.iter().copied().reduce(f64::max) {
        progress::warn(&format!(
            "at {} of the times (up to t = {t:e}) the truncated sum of {k} eigenpairs misses \
             more than ~1 % of the HKS (Weyl-law estimate); --method {} or {} computes it exactly \
             (selected inversion)",
            truncated.len(),
            HksMethod::default_name(),
            HksMethod::Exact.name(),
        ));
    }
    let exact = hks.exact_count();
    let used = &hks.times;
    writeln!(
        out,
        "HKS ({} mass) at {} times from {:e} to {:e} on {} vertices: {exact} exact (selected inversion), {} spectral (k = {k}{})",
        checked.mass.name(),
        used.len(),
        used.first().copied().unwrap_or(0.0),
        used.last().copied().unwrap_or(0.0),
        c.input.mesh.n_vertices(),
        used.len() - exact,
        if exact < used.len() { format!(", estimated truncation error ≤ {:.1e}", hks.worst_estimate()) } else { String::new() },
    )?;
    Ok(())
}
