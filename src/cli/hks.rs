//! `wfem hks`: the heat kernel signature of a mesh (paper, Sect. 5; Eqs. (6)–(8)).

use super::output::{short_labels, write_fields, Column, OutputFormat, RenderArgs, Writing};
use super::{limits, progress, read_usable, CliError, MeshArgs, Output};
use clap::{Args, ValueEnum};
use serde_json::json;
use shape_retrieval::hks::{HksConvention, TimeSampling};
use shape_retrieval::{Descriptor, DescriptorParams, HksMethod, HksSource, RetrievalError, ShapeDescriptors};
use std::io::Write;
use wfem_heat::{DiagonalParams, HeatKernel, HeatParams, KernelKind, Method};

/// Which kernel's signature.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HksKernel {
    /// wFEM kernel, spectrum of (L, B) (Eq. (6)): DHK2.
    #[default]
    Wfem,
    /// Lumped kernel, spectrum of (L, D) (Eq. (7)) with D chosen by --lumped; with
    /// `--lumped voronoi` this is the paper's DHK1 (Voronoi-cot).
    Lumped,
}

impl From<HksKernel> for KernelKind {
    fn from(k: HksKernel) -> Self {
        match k {
            HksKernel::Wfem => KernelKind::Wfem,
            HksKernel::Lumped => KernelKind::Lumped,
        }
    }
}

/// How the signature is evaluated.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HksMethodArg {
    /// Per time: the truncated spectral sum where its estimated truncation error is below
    /// 1e−3 (large t), the exact diagonal of the heat kernel elsewhere (selected inversion:
    /// eight complex factorizations per time, 0.3 s at 28K vertices).
    #[default]
    Auto,
    /// The exact diagonal of K_t at every time, without eigenpairs (selected inversion).
    Exact,
    /// The truncated spectral sum of the --eigs smallest eigenpairs at every time (Eq. (8);
    /// what pyFM and scipy-based code compute; wrong at small t).
    Spectral,
}

impl From<HksMethodArg> for HksMethod {
    fn from(m: HksMethodArg) -> Self {
        match m {
            HksMethodArg::Auto => HksMethod::default(),
            HksMethodArg::Exact => HksMethod::Exact,
            HksMethodArg::Spectral => HksMethod::Spectral,
        }
    }
}

/// Default number of automatic times.
const DEFAULT_SCALES: usize = 16;

/// Arguments of `wfem hks`.
#[derive(Args, Clone, Debug)]
pub struct HksArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Diffusion times t > 0 (in the mesh's units); one output column each (at most 1000).
    #[arg(long, num_args = 1.., allow_negative_numbers = true, conflicts_with = "scales")]
    pub times: Vec<f64>,
    /// Number T of automatic times, log-spaced in [4 ln10/λ_k, 4 ln10/λ_2] (default 16,
    /// at most 1000).
    #[arg(long)]
    pub scales: Option<usize>,
    /// Which heat kernel.
    #[arg(long, value_enum, default_value = "wfem")]
    pub kernel: HksKernel,
    /// Which lumped mass D, --kernel lumped only (default barycentric, Eq. (7); voronoi: the
    /// mixed Voronoi areas of the paper's DHK1).
    #[arg(long, value_enum)]
    pub lumped: Option<super::LumpedArg>,
    /// How the signature is evaluated.
    #[arg(long, value_enum, default_value_t = HksMethodArg::Auto)]
    pub method: HksMethodArg,
    /// Number k of eigenpairs of the truncated spectral sum (Eq. (8)); default min(100, n),
    /// at most n/10 above 5000 vertices. Not used by --method exact with --times.
    #[arg(long)]
    pub eigs: Option<usize>,
    /// Output: .npy (n × T array, + .json sidecar with the times), .csv, .ply (fields
    /// `hks_t<t>`) or .png (one figure per time, at most 64).
    #[arg(short = 'o', long = "output", visible_alias = "out", value_parser = Output::parse)]
    pub output: Output,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub render: RenderArgs,
}

fn retrieval(e: RetrievalError) -> CliError {
    match e {
        RetrievalError::Heat(h) => CliError::Heat(h),
        RetrievalError::Mesh(m) => CliError::Mesh(m),
        other => CliError::Usage(other.to_string()),
    }
}

/// `wfem hks`: writes the n × T heat kernel signature `h(i, t) = Σ_k e^{−λ_k t} φ_k(i)²` of
/// the chosen kernel, from its k smallest eigenpairs.
pub fn hks(args: &HksArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let count = if args.times.is_empty() {
        limits::count(
            "--scales",
            args.scales.unwrap_or(DEFAULT_SCALES),
            1,
            limits::MAX_TIMES,
            "number of automatic times (output columns)",
        )?
    } else {
        limits::times("--times", &args.times)?;
        args.times.len()
    };
    let labels = (!args.times.is_empty()).then(|| short_labels(&args.times));
    let suffixes = labels
        .as_ref()
        .map(|l| l.iter().map(|l| format!("t{l}")).collect::<Vec<_>>());
    args.output.check(suffixes.as_deref(), count, &[&args.input.mesh])?;

    if args.lumped.is_some() && args.kernel != HksKernel::Lumped {
        return Err(CliError::Usage(
            "--lumped applies to --kernel lumped only, not to --kernel wfem".into(),
        ));
    }
    // The eigenpairs serve the spectral sum and the automatic times; exact values at given
    // times need none.
    let spectrum_needed = args.method != HksMethodArg::Exact || args.times.is_empty();
    if args.eigs.is_some() && !spectrum_needed {
        return Err(CliError::Usage(
            "--eigs applies to --method auto|spectral or automatic times, not to --method exact with --times".into(),
        ));
    }

    let input = read_usable(&args.input)?;
    let n = input.mesh.n_vertices();
    let k = limits::descriptor_eigenpairs(args.eigs.unwrap_or(shape_retrieval::DEFAULT_EIGENPAIRS.min(n)), n)?;
    limits::columns(if args.times.is_empty() { "--scales" } else { "--times" }, count, n)?;
    let times = if args.times.is_empty() {
        TimeSampling::Auto { num_times: count }
    } else {
        TimeSampling::Explicit(args.times.clone())
    };
    let params = DescriptorParams {
        eigenpairs: k,
        times: times.clone(),
        ..Default::default()
    };
    let lumped_mass = args.lumped.unwrap_or_default().kind();
    let ops = progress::run("assembling L, B, D", || input.assemble(lumped_mass))?;
    let mut shape = ShapeDescriptors::from_operators(&input.mesh, ops, &params).map_err(retrieval)?;
    let descriptor = match args.kernel {
        HksKernel::Wfem => Descriptor::Dhk2,
        HksKernel::Lumped => Descriptor::Dhk1,
    };
    let lumped = descriptor == Descriptor::Dhk1;
    // (values, times used, eigenvalues) of the truncated sum.
    let spectral = if spectrum_needed {
        progress::run(format!("{k} eigenpairs"), || shape.eigenbasis(lumped).map(|_| ())).map_err(retrieval)?;
        let values = progress::run("signature", || shape.dense(descriptor)).map_err(retrieval)?;
        let basis = shape.eigenbasis(lumped).map_err(retrieval)?;
        // The times actually used (automatic ones come from the same spectrum).
        let used: Vec<f64> = match &times {
            TimeSampling::Explicit(t) => t.clone(),
            TimeSampling::Auto { num_times } => {
                shape_retrieval::hks::auto_times(&basis.values, *num_times).map_err(retrieval)?
            }
        };
        Some((values, used, basis.values.clone()))
    } else {
        None
    };
    let method = HksMethod::from(args.method);
    let kernel_of = |shape: &ShapeDescriptors| {
        progress::run("symbolic analysis", || {
            HeatKernel::new(
                shape.operators(),
                HeatParams {
                    kernel: args.kernel.into(),
                    method: Method::default(),
                },
            )
        })
    };
    let diagonal = DiagonalParams::default();
    let (values, used, sources) = match spectral {
        Some((values, used, eigenvalues)) => {
            let kernel = if method == HksMethod::Spectral {
                None
            } else {
                Some(kernel_of(&shape)?)
            };
            let (values, sources) = match &kernel {
                Some(kernel) => progress::run("exact diagonal where the spectral sum is not accurate", || {
                    shape_retrieval::signature_by_method(
                        kernel,
                        &eigenvalues,
                        values,
                        &used,
                        HksConvention::KernelValue,
                        method,
                        &diagonal,
                    )
                })
                .map_err(retrieval)?,
                None => {
                    let sources = used
                        .iter()
                        .map(|&t| HksSource::Spectral {
                            bound: shape_retrieval::truncation_bound(&eigenvalues, n, t),
                            estimate: shape_retrieval::truncation_estimate(&eigenvalues, n, t),
                        })
                        .collect();
                    (values, sources)
                }
            };
            (values, used, sources)
        }
        None => {
            let kernel = kernel_of(&shape)?;
            let series = progress::run("exact diagonal (selected inversion)", || {
                shape_retrieval::exact_signature(&kernel, &args.times, HksConvention::KernelValue, &diagonal)
            })
            .map_err(retrieval)?;
            let sources = vec![
                HksSource::Exact {
                    relative_tail: series.info.relative_tail
                };
                args.times.len()
            ];
            (series.values, args.times.clone(), sources)
        }
    };
    let labels = short_labels(&used);
    let kernel = super::name_of(args.kernel);
    let columns: Vec<Column> = labels
        .iter()
        .enumerate()
        .map(|(j, label)| Column {
            name: format!("hks_t{label}"),
            suffix: format!("t{label}"),
            title: format!(
                "{}: HKS, t = {label} ({kernel} kernel, {})",
                input.name,
                match sources[j] {
                    HksSource::Exact { .. } => "exact".to_string(),
                    HksSource::Spectral { .. } => format!("k = {k}"),
                }
            ),
            t: used.get(j).copied(),
            values: values.col(j).iter().copied().collect(),
        })
        .collect();
    if args.output.format == OutputFormat::Png && suffixes.is_none() {
        // The automatic times are known only now: check their figure names.
        let names: Vec<String> = columns.iter().map(|c| c.suffix.clone()).collect();
        args.output.check(Some(&names), columns.len(), &[&args.input.mesh])?;
    }
    let mut meta = serde_json::Map::new();
    meta.insert("command".into(), json!("hks"));
    meta.insert("input".into(), input.meta(&args.input.mesh));
    meta.insert("kernel".into(), json!(kernel));
    meta.insert("descriptor".into(), json!(descriptor.name()));
    if args.kernel == HksKernel::Lumped {
        meta.insert("lumped".into(), json!(super::name_of(args.lumped.unwrap_or_default())));
    }
    meta.insert("method".into(), json!(super::name_of(args.method)));
    if spectrum_needed {
        meta.insert("eigenpairs".into(), json!(k));
    }
    meta.insert(
        "sources".into(),
        json!(sources
            .iter()
            .zip(&used)
            .map(|(s, t)| match s {
                HksSource::Exact { relative_tail } if *relative_tail > 0.0 =>
                    json!({"t": t, "method": "exact", "probing_relative_tail": relative_tail}),
                HksSource::Exact { .. } => json!({"t": t, "method": "exact", "diagonal": "selected inversion"}),
                HksSource::Spectral { bound, estimate } =>
                    json!({"t": t, "method": "spectral", "truncation_bound": bound, "truncation_estimate": estimate}),
            })
            .collect::<Vec<_>>()),
    );
    let how = Writing {
        render: args.render,
        highlight: &[],
        meta,
    };
    for path in write_fields(&args.output, &input.mesh, &columns, how)? {
        writeln!(out, "wrote {}", path.display())?;
    }
    let exact = sources.iter().filter(|s| matches!(s, HksSource::Exact { .. })).count();
    // The rigorous bound is pessimistic by orders of magnitude; the Weyl-law estimate is close
    // (shape_retrieval::truncation_estimate): warn where a spectral column is ~1 % off.
    let truncated: Vec<f64> = sources
        .iter()
        .zip(&used)
        .filter(|(s, _)| matches!(s, HksSource::Spectral { estimate, .. } if *estimate > 1e-2))
        .map(|(_, &t)| t)
        .collect();
    if let Some(t) = truncated.iter().copied().reduce(f64::max) {
        eprintln!(
            "wfem: warning: at {} of the times (up to t = {t:e}) the truncated sum of {k} eigenpairs misses \
             more than ~1 % of the HKS (Weyl-law estimate); --method auto or exact computes it exactly \
             (selected inversion)",
            truncated.len(),
        );
    }
    let worst_bound = sources.iter().fold(0.0f64, |m, s| match s {
        HksSource::Spectral { estimate, .. } => m.max(*estimate),
        HksSource::Exact { .. } => m,
    });
    writeln!(
        out,
        "HKS ({kernel} kernel) at {} times from {:e} to {:e} on {n} vertices: {exact} exact (selected inversion), {} spectral (k = {k}{})",
        used.len(),
        used.first().copied().unwrap_or(0.0),
        used.last().copied().unwrap_or(0.0),
        used.len() - exact,
        if exact < used.len() { format!(", estimated truncation error ≤ {worst_bound:.1e}") } else { String::new() },
    )?;
    Ok(())
}
