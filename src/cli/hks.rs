//! `wfem hks`: the heat kernel signature of a mesh (paper, Sect. 5; Eqs. (6)–(8)).

use super::output::{short_labels, write_fields, Column, OutputFormat, RenderArgs, Writing};
use super::{limits, progress, read_usable, CliError, MeshArgs, Output};
use clap::{Args, ValueEnum};
use mesh_fem::{assemble, AssemblyParams, LumpedMassKind};
use serde_json::json;
use shape_retrieval::hks::TimeSampling;
use shape_retrieval::{Descriptor, DescriptorParams, RetrievalError, ShapeDescriptors};
use std::io::Write;

/// Which kernel's signature.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HksKernel {
    /// wFEM kernel, spectrum of (L, B) (Eq. (6)): DHK2.
    #[default]
    Wfem,
    /// Lumped Voronoi-cot kernel, spectrum of (L, D) with mixed Voronoi areas (Eq. (7)): DHK1.
    Lumped,
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
    /// Number k of eigenpairs of the truncated spectral sum (Eq. (8)); default min(100, n),
    /// at most n/10 above 5000 vertices.
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
    let ops = progress::run("assembling L, B, D", || {
        assemble(
            &input.mesh,
            &AssemblyParams {
                lumped: LumpedMassKind::Voronoi,
            },
        )
    })?;
    let mut shape = ShapeDescriptors::from_operators(&input.mesh, ops, &params).map_err(retrieval)?;
    let descriptor = match args.kernel {
        HksKernel::Wfem => Descriptor::Dhk2,
        HksKernel::Lumped => Descriptor::Dhk1,
    };
    let lumped = descriptor == Descriptor::Dhk1;
    progress::run(format!("{k} eigenpairs"), || shape.eigenbasis(lumped).map(|_| ())).map_err(retrieval)?;
    let values = progress::run("signature", || shape.dense(descriptor)).map_err(retrieval)?;
    // The times actually used (automatic ones come from the same spectrum).
    let used: Vec<f64> = match times {
        TimeSampling::Explicit(t) => t,
        TimeSampling::Auto { num_times } => {
            let basis = shape.eigenbasis(lumped).map_err(retrieval)?;
            shape_retrieval::hks::auto_times(&basis.values, num_times).map_err(retrieval)?
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
            title: format!("{}: HKS, t = {label} ({kernel} kernel, k = {k})", input.name),
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
    meta.insert("eigenpairs".into(), json!(k));
    let how = Writing {
        render: args.render,
        highlight: &[],
        meta,
    };
    for path in write_fields(&args.output, &input.mesh, &columns, how)? {
        writeln!(out, "wrote {}", path.display())?;
    }
    writeln!(
        out,
        "HKS ({kernel} kernel, k = {k}) at {} times from {:e} to {:e} on {n} vertices",
        used.len(),
        used.first().copied().unwrap_or(0.0),
        used.last().copied().unwrap_or(0.0),
    )?;
    Ok(())
}
