//! `wfem distance`: diffusion distances from one vertex to every vertex.

use super::heat::check_degree;
use super::output::{short_label, write_fields, Column, RenderArgs, Writing};
use super::{limits, progress, read_usable, CliError, MeshArgs, Output};
use clap::{Args, ValueEnum};
use mesh_fem::{assemble, AssemblyParams};
use serde_json::json;
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
    /// The vertex i (numbered as in the file) whose distances d_t(i, ·) to every vertex are
    /// computed.
    #[arg(long)]
    pub from: u32,
    /// Which distance.
    #[arg(long, value_enum, default_value_t = DistanceKindArg::Wfem)]
    pub kind: DistanceKindArg,
    /// Degree of the rational approximation (error ≈ 9.3^-degree; default 16).
    #[arg(long)]
    pub degree: Option<usize>,
    /// Output file: .ply, .npy (+ .json sidecar), .csv or .png.
    #[arg(short = 'o', long = "output", value_parser = Output::parse)]
    pub output: Output,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub render: RenderArgs,
}

/// `wfem distance`: the row d_t(i, ·) of diffusion distances by the rational method (one
/// factorization per pole; the diagonal of the Gram matrix costs n right-hand sides).
pub fn distance(args: &DistanceArgs, out: &mut dyn Write) -> Result<(), CliError> {
    limits::time("--t", args.t)?;
    check_degree(args.degree)?;
    let label = short_label(args.t);
    let kind = super::name_of(args.kind);
    let suffix = format!("{kind}-distance-t{label}");
    args.output
        .check(Some(std::slice::from_ref(&suffix)), 1, &[&args.input.mesh])?;
    let input = read_usable(&args.input)?;
    let i = input.vertex("--from", args.from)?;
    let ops = progress::run("assembling L, B, D", || {
        assemble(&input.mesh, &AssemblyParams::default())
    })?;
    let params = DistanceParams {
        degree: args.degree.unwrap_or(shifted_solve::DEFAULT_DEGREE),
        ..Default::default()
    };
    let dd = progress::run(format!("preparing the {kind} distance (t = {label})"), || {
        DiffusionDistance::new(&ops, args.kind.into(), args.t, &params)
    })?;
    let row = progress::run(format!("distances from vertex {}", args.from), || dd.row(i as usize))?;
    let column = Column {
        name: format!("{kind}_distance_t={label}"),
        suffix,
        title: format!(
            "{}: {kind} diffusion distance from vertex {}, t = {label}",
            input.name, args.from
        ),
        t: Some(args.t),
        values: row,
    };
    let mut meta = serde_json::Map::new();
    meta.insert("command".into(), json!("distance"));
    meta.insert("input".into(), input.meta(&args.input.mesh));
    meta.insert("kind".into(), json!(kind));
    meta.insert("from_vertex".into(), json!(args.from));
    meta.insert("degree".into(), json!(params.degree));
    let how = Writing {
        render: args.render,
        highlight: &[i],
        meta,
    };
    for path in write_fields(&args.output, &input.mesh, &[column], how)? {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}
