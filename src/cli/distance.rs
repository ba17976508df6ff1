//! `wfem distance`: diffusion distances from one vertex to every vertex.

use super::{check_output, load_usable, write_fields, CliError, MeshArgs, Output};
use clap::{Args, ValueEnum};
use mesh_fem::{assemble, AssemblyParams};
use std::io::Write;
use wfem_heat::{DiffusionDistance, DistanceKind, DistanceParams};

/// Which diffusion distance.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DistanceKindArg {
    /// wFEM: ‖h_i − h_j‖_B with h_i = K_{t/2} e_i (paper, Eq. (18b)), i.e. from S_t = B K_t.
    #[default]
    Wfem,
    /// Linear FEM / standard: (Σ_k e^{−2λ_k t}(x_k(i) − x_k(j))²)^{1/2}, from H̃_{2t} = K_{2t}B⁻¹.
    Linear,
}

impl From<DistanceKindArg> for DistanceKind {
    fn from(k: DistanceKindArg) -> Self {
        match k {
            DistanceKindArg::Wfem => DistanceKind::Wfem,
            DistanceKindArg::Linear => DistanceKind::Linear,
        }
    }
}

/// Arguments of `wfem distance`.
#[derive(Args, Clone, Debug)]
pub struct DistanceArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Diffusion time t > 0.
    #[arg(long = "t", allow_negative_numbers = true)]
    pub t: f64,
    /// The vertex i whose distances d_t(i, ·) to every vertex are computed.
    #[arg(long)]
    pub from: u32,
    /// Which distance.
    #[arg(long, value_enum, default_value_t = DistanceKindArg::Wfem)]
    pub kind: DistanceKindArg,
    /// Degree of the rational approximation (error ≈ 9.3^-degree).
    #[arg(long)]
    pub degree: Option<usize>,
    /// Output file: .ply, .npy, .csv or .png.
    #[arg(short = 'o', long = "output", value_parser = Output::parse)]
    pub output: Output,
}

/// `wfem distance`: the row d_t(i, ·) of diffusion distances by the rational method (one
/// factorization per pole; the diagonal of the Gram matrix costs n right-hand sides).
pub fn distance(args: &DistanceArgs, out: &mut dyn Write) -> Result<(), CliError> {
    check_output(&args.input.mesh, &args.output.path)?;
    let mesh = load_usable(&args.input)?;
    let n = mesh.n_vertices();
    let i = args.from as usize;
    if i >= n {
        return Err(CliError::Usage(format!(
            "--from {i} is not a vertex (the mesh has {n} vertices)"
        )));
    }
    let ops = assemble(&mesh, &AssemblyParams::default())?;
    let params = DistanceParams {
        degree: args.degree.unwrap_or(shifted_solve::DEFAULT_DEGREE),
        ..Default::default()
    };
    let dd = DiffusionDistance::new(&ops, args.kind.into(), args.t, &params)?;
    let row = dd.row(i)?;
    let name = match args.kind {
        DistanceKindArg::Wfem => format!("wfem_distance_t={}", args.t),
        DistanceKindArg::Linear => format!("linear_distance_t={}", args.t),
    };
    for path in write_fields(&args.output, &mesh, &[(name, row)], &[args.from])? {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}
