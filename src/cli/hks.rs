//! `wfem hks`: the heat kernel signature of a mesh (paper, Sect. 5; Eqs. (6)–(8)).

use super::{check_output, load_usable, write_fields, CliError, MeshArgs, Output};
use clap::{Args, ValueEnum};
use mesh_fem::{assemble, AssemblyParams, LumpedMassKind};
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

/// Arguments of `wfem hks`.
#[derive(Args, Clone, Debug)]
pub struct HksArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Diffusion times t > 0 (in the mesh's units); one output column each.
    #[arg(long, num_args = 1.., allow_negative_numbers = true, conflicts_with = "scales")]
    pub times: Vec<f64>,
    /// Number T of automatic times, log-spaced in [4 ln10/λ_k, 4 ln10/λ_2] (default 16).
    #[arg(long)]
    pub scales: Option<usize>,
    /// Which heat kernel.
    #[arg(long, value_enum, default_value = "wfem")]
    pub kernel: HksKernel,
    /// Number k of eigenpairs of the truncated spectral sum (Eq. (8)).
    #[arg(long, default_value_t = shape_retrieval::DEFAULT_EIGENPAIRS)]
    pub eigs: usize,
    /// Output: .npy (n × T array), .csv, .ply (fields `hks_t<t>`) or .png.
    #[arg(short = 'o', long = "output", visible_alias = "out", value_parser = Output::parse)]
    pub output: Output,
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
    check_output(&args.input.mesh, &args.output.path)?;
    if let Some(&t) = args.times.iter().find(|t| !(t.is_finite() && **t > 0.0)) {
        return Err(CliError::Usage(format!(
            "--times: {t} is not a positive diffusion time"
        )));
    }
    if args.scales == Some(0) {
        return Err(CliError::Usage("--scales must be at least 1".into()));
    }
    if args.eigs == 0 {
        return Err(CliError::Usage("--eigs must be at least 1".into()));
    }
    let mesh = load_usable(&args.input)?;
    let times = if args.times.is_empty() {
        TimeSampling::Auto {
            num_times: args.scales.unwrap_or(16),
        }
    } else {
        TimeSampling::Explicit(args.times.clone())
    };
    let params = DescriptorParams {
        eigenpairs: args.eigs,
        times: times.clone(),
        ..Default::default()
    };
    let ops = assemble(
        &mesh,
        &AssemblyParams {
            lumped: LumpedMassKind::Voronoi,
        },
    )?;
    let mut shape = ShapeDescriptors::from_operators(&mesh, ops, &params).map_err(retrieval)?;
    let descriptor = match args.kernel {
        HksKernel::Wfem => Descriptor::Dhk2,
        HksKernel::Lumped => Descriptor::Dhk1,
    };
    let values = shape.dense(descriptor).map_err(retrieval)?;
    // The times actually used (automatic ones come from the same spectrum).
    let used: Vec<f64> = match times {
        TimeSampling::Explicit(t) => t,
        TimeSampling::Auto { num_times } => {
            let basis = shape.eigenbasis(descriptor == Descriptor::Dhk1).map_err(retrieval)?;
            shape_retrieval::hks::auto_times(&basis.values, num_times).map_err(retrieval)?
        }
    };
    let fields: Vec<(String, Vec<f64>)> = used
        .iter()
        .enumerate()
        .map(|(j, t)| (format!("hks_t{t:e}"), values.col(j).iter().copied().collect()))
        .collect();
    for path in write_fields(&args.output, &mesh, &fields, &[])? {
        writeln!(out, "wrote {}", path.display())?;
    }
    writeln!(
        out,
        "HKS ({:?} kernel, k = {}) at {} times from {:e} to {:e} on {} vertices",
        args.kernel,
        args.eigs.min(mesh.n_vertices()),
        used.len(),
        used.first().copied().unwrap_or(0.0),
        used.last().copied().unwrap_or(0.0),
        mesh.n_vertices()
    )?;
    Ok(())
}
