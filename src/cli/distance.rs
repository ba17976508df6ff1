//! `wfem distance`: diffusion distances from one vertex to every vertex.

use super::heat::{check_degree, prepare_kernel};
use super::output::{short_label, write_fields, Column, RenderArgs, Writing};
use super::{limits, progress, read_usable, CliError, MeshArgs, Output};
use clap::{Args, ValueEnum};
use serde_json::json;
use std::io::Write;
use wfem_heat::{DiffusionDistance, DistanceKind, DistanceParams, HeatParams, Method};

/// Which diffusion distance.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DistanceKindArg {
    /// The diffusion distance (Σ_k e^{−2λ_k t}(x_k(i) − x_k(j))²)^{1/2}, from H_{2t} = K_{2t}B⁻¹
    /// (the paper's linear FEM diffusion distance): 0 at the source, growing with distance.
    #[default]
    #[value(alias = "linear")]
    Diffusion,
    /// The paper's wFEM distance ‖h_i − h_j‖_B, h_i = K_{t/2} e_i (Eq. (18b)), from S_t = B K_t:
    /// weighted by the vertex areas twice, it follows the mesh's areas on irregular meshes.
    #[value(alias = "wfem")]
    MassWeighted,
}

impl From<DistanceKindArg> for DistanceKind {
    fn from(k: DistanceKindArg) -> Self {
        match k {
            DistanceKindArg::Diffusion => DistanceKind::Diffusion,
            DistanceKindArg::MassWeighted => DistanceKind::MassWeighted,
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
    #[arg(long, value_enum, default_value_t = DistanceKindArg::Diffusion)]
    pub kind: DistanceKindArg,
    /// Use the paper's rational method of this degree (error ≈ 9.3^-degree) instead of the
    /// default fast exact path.
    #[arg(long)]
    pub degree: Option<usize>,
    /// Output file: .ply, .npy (+ .json sidecar), .csv or .png.
    #[arg(short = 'o', long = "output", value_parser = Output::parse)]
    pub output: Output,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub render: RenderArgs,
}

/// `wfem distance`: the row d_t(i, ·) of diffusion distances (one kernel column and the
/// diagonal of the Gram matrix).
pub fn distance(args: &DistanceArgs, out: &mut dyn Write) -> Result<(), CliError> {
    limits::time("--t", args.t)?;
    check_degree(args.degree)?;
    let label = short_label(args.t);
    let kind: DistanceKind = args.kind.into();
    let name = kind.name().replace('-', "_");
    let suffix = format!("{}-distance-t{label}", kind.name());
    args.output
        .check(Some(std::slice::from_ref(&suffix)), 1, &[&args.input.mesh])?;
    let input = read_usable(&args.input)?;
    let i = input.vertex("--from", args.from)?;
    let ops = progress::run("assembling L, B, D", || input.assemble(Default::default()))?;
    let method = args.degree.map_or_else(Method::default, Method::rational);
    let kernel = prepare_kernel(
        &ops,
        HeatParams {
            method,
            ..Default::default()
        },
        input.mesh.n_vertices(),
    )?;
    let dd = progress::run(format!("preparing the {} distance (t = {label})", kind.name()), || {
        DiffusionDistance::new(&kernel, kind, args.t, &DistanceParams::default())
    })?;
    let row = progress::run(format!("distances from vertex {}", args.from), || dd.row(i as usize))?;
    let column = Column {
        name: format!("{name}_distance_t={label}"),
        suffix,
        title: format!(
            "{}: {} distance from vertex {}, t = {label} ({})",
            input.name,
            kind.name(),
            args.from,
            args.degree
                .map_or("fast".to_string(), |d| format!("rational, degree {d}"))
        ),
        t: Some(args.t),
        values: row,
    };
    let mut meta = serde_json::Map::new();
    meta.insert("command".into(), json!("distance"));
    meta.insert("input".into(), input.meta(&args.input.mesh));
    meta.insert("kind".into(), json!(kind.name()));
    meta.insert("from_vertex".into(), json!(args.from));
    if let Some(info) = dd.diagonal_info() {
        meta.insert(
            "diagonal".into(),
            match info.hops {
                Some(hops) => json!({ "name": "probing", "columns": info.columns, "hops": hops, "relative_tail": info.relative_tail }),
                None if info.columns == 0 => json!({ "name": "selected inversion" }),
                None => json!({ "name": "exact columns", "columns": info.columns }),
            },
        );
    }
    meta.insert(
        "method".into(),
        args.degree.map_or(
            json!({ "name": "fast" }),
            |d| json!({ "name": "rational", "degree": d }),
        ),
    );
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
