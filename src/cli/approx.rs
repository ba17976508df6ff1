//! `wfem approx`: the feature-driven approximation f = f_glob + f_loc (paper, Sect. 4.2).

use super::{check_output, load_usable, write_fields, CliError, KernelArg, MeshArgs, Output, OutputFormat};
use clap::{Args, ValueEnum};
use mesh_fem::io::read_field;
use mesh_fem::{assemble, AssemblyParams};
use std::io::Write;
use std::path::PathBuf;
use wfem_heat::approx::{feature_approximation, ApproxParams, Coefficients, Persistence};
use wfem_heat::{HeatKernel, HeatParams, Method};

/// Coefficients of the global component.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CoefficientsArg {
    /// The best approximation of f in span{K_t e_i : i ∈ A} (M-orthogonal projection).
    #[default]
    LeastSquares,
    /// The feature values averaged with heat-kernel weights: Σ f(p_i) K_t e_i / Σ K_t e_i.
    Normalized,
    /// The paper's literal f_glob = Σ_{i∈A} f(p_i) K_t e_i (small with sparse anchors).
    FeatureValues,
    /// Interpolate f on the anchors: Σ_{i∈A} c_i K_t e_i with f_glob(p_j) = f(p_j), j ∈ A.
    Interpolate,
}

impl From<CoefficientsArg> for Coefficients {
    fn from(c: CoefficientsArg) -> Self {
        match c {
            CoefficientsArg::Normalized => Coefficients::Normalized,
            CoefficientsArg::LeastSquares => Coefficients::LeastSquares,
            CoefficientsArg::FeatureValues => Coefficients::FeatureValues,
            CoefficientsArg::Interpolate => Coefficients::Interpolate,
        }
    }
}

/// Arguments of `wfem approx`.
#[derive(Args, Clone, Debug)]
pub struct ApproxArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// The per-vertex field f (.npy or .csv, one value per vertex).
    #[arg(long)]
    pub field: PathBuf,
    /// Persistence threshold of the anchors, as a fraction of max f − min f (e.g. 0.1), or in
    /// units of f with --absolute.
    #[arg(long)]
    pub persistence: f64,
    /// Read --persistence in units of f instead of as a fraction of the range.
    #[arg(long)]
    pub absolute: bool,
    /// Number of scales t_i = (i/10) / λ_k, i = 1..N.
    #[arg(long, default_value_t = 10)]
    pub scales: usize,
    /// Index k of the eigenvalue λ_k setting the time scale.
    #[arg(long, default_value_t = 20)]
    pub k: usize,
    /// Coefficients of the global component.
    #[arg(long, value_enum, default_value_t = CoefficientsArg::LeastSquares)]
    pub coefficients: CoefficientsArg,
    /// Kernel.
    #[arg(long, value_enum, default_value_t = KernelArg::Wfem)]
    pub kernel: KernelArg,
    /// Output file: .ply, .npy or .csv (f, then f_glob and f_loc at every scale), or .png
    /// (one figure each for f, f_glob and f_loc at the coarsest scale, anchors highlighted).
    #[arg(short = 'o', long = "output", value_parser = Output::parse)]
    pub output: Output,
}

/// `wfem approx`: splits f into its global component on the persistent critical points and
/// its local component at every scale, writes them and prints the per-scale report.
pub fn approx(args: &ApproxArgs, out: &mut dyn Write) -> Result<(), CliError> {
    check_output(&args.input.mesh, &args.output.path)?;
    check_output(&args.field, &args.output.path)?;
    let mesh = load_usable(&args.input)?;
    let n = mesh.n_vertices();
    let f = read_field(&args.field, n)?;
    let ops = assemble(&mesh, &AssemblyParams::default())?;
    let kernel = HeatKernel::new(
        &ops,
        HeatParams {
            kernel: args.kernel.into(),
            method: Method::default(),
        },
    )?;
    let params = ApproxParams {
        k: args.k,
        scales: args.scales,
        persistence: if args.absolute {
            Persistence::Absolute(args.persistence)
        } else {
            Persistence::Relative(args.persistence)
        },
        coefficients: args.coefficients.into(),
        ..ApproxParams::default()
    };
    let approx = feature_approximation(&mesh, &kernel, &f, &params)?;
    writeln!(
        out,
        "{} vertices, {} critical points of f, {} anchors (persistence {}{}), λ_{} = {:.6e}",
        n,
        approx.input_critical_points,
        approx.anchors.len(),
        args.persistence,
        if args.absolute { "" } else { " × range" },
        args.k,
        approx.lambda_k
    )?;
    writeln!(
        out,
        "{:>5} {:>12} {:>12} {:>10} {:>8} {:>12}",
        "scale", "t", "Linf error", "relative", "#crit", "significant"
    )?;
    for (i, s) in approx.scales.iter().enumerate() {
        writeln!(
            out,
            "{:>5} {:>12.6e} {:>12.6e} {:>10.4} {:>8} {:>12}",
            i + 1,
            s.t,
            s.linf_error,
            s.relative_linf_error,
            s.critical_points,
            s.significant_critical_points
        )?;
    }
    let mut fields = vec![("f".to_string(), f.clone())];
    if args.output.format == OutputFormat::Png {
        if let Some(s) = approx.scales.last() {
            fields.push((format!("f_glob t={:.4e}", s.t), s.global.clone()));
            fields.push((format!("f_loc t={:.4e}", s.t), s.local.clone()));
        }
    } else {
        for (i, s) in approx.scales.iter().enumerate() {
            fields.push((format!("glob_{}", i + 1), s.global.clone()));
        }
        for (i, s) in approx.scales.iter().enumerate() {
            fields.push((format!("loc_{}", i + 1), s.local.clone()));
        }
    }
    for path in write_fields(&args.output, &mesh, &fields, &approx.anchors)? {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}
