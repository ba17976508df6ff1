//! `wfem distance`: diffusion distances from one vertex to every vertex.

use super::choice::choice;
use super::heat::{check_degree, prepare_kernel};
use super::output::{short_label, write_fields, Column, RenderArgs, Writing};
use super::{limits, progress, read_usable, CliError, MeshArgs, Output};
use clap::Args;
use serde_json::json;
use std::io::Write;
use wfem_base::Choice;
use wfem_heat::distance::{DiffusionDistance, DistanceKind, DistanceParams};
use wfem_heat::method::Method;
use wfem_heat::HeatParams;

/// Arguments of `wfem distance`.
#[derive(Args, Clone, Debug)]
pub struct DistanceArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Diffusion time t > 0.
    #[arg(long = "t", allow_negative_numbers = true)]
    pub t: f64,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub time_unit: super::times::TimeUnitArgs,
    /// The vertex i (numbered as in the file) whose distances d_t(i, ·) to every vertex are
    /// computed.
    #[arg(long, value_parser = super::input::vertex_index, allow_negative_numbers = true)]
    pub from: u32,
    /// Which distance.
    #[arg(long, value_parser = choice::<DistanceKind>(), default_value = DistanceKind::default_name())]
    pub kind: DistanceKind,
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
    let kind = args.kind;
    let name = kind.name().replace('-', "_");
    let suffix = format!("{}-distance-t{label}", kind.name());
    args.output
        .check(Some(std::slice::from_ref(&suffix)), 1, &[&args.input.mesh])?;
    let input = read_usable(&args.input)?;
    let i = input.vertex("--from", args.from)?;
    let times = args.time_unit.resolve("--t", &input.mesh, &[args.t])?;
    let t = times.absolute[0];
    let ops = progress::run("assembling L, B, D", || input.assemble(Default::default()))?;
    let method = args.degree.map_or_else(Method::default, Method::rational);
    let kernel = prepare_kernel(
        &ops,
        HeatParams {
            method: method.clone(),
            ..Default::default()
        },
        input.mesh.n_vertices(),
    )?;
    // The diffusion distance is made of kernel values at 2t (its time at infinity is half).
    let doubling = if kind == DistanceKind::Diffusion { 2.0 } else { 1.0 };
    times.warn(kernel.operators(), &input.mesh, doubling)?;
    let dd = progress::run(format!("preparing the {} distance (t = {label})", kind.name()), || {
        DiffusionDistance::new(&kernel, kind, t, &DistanceParams::default())
    })?;
    let row = progress::run(format!("distances from vertex {}", args.from), || dd.row(i as usize))?;
    let column = Column {
        name: format!("{name}_distance_t={label}"),
        suffix,
        title: format!(
            "{}: {} distance from vertex {}, t = {label}{} ({})",
            input.name,
            kind.name(),
            args.from,
            times.suffix(),
            match &method {
                Method::Rational { degree, .. } => format!("{}, degree {degree}", method.name()),
                m => m.name().to_string(),
            }
        ),
        t: Some(t),
        values: row,
    };
    let mut meta = serde_json::Map::new();
    meta.insert("command".into(), json!("distance"));
    meta.insert("input".into(), input.meta(&args.input.mesh));
    meta.insert("kind".into(), json!(kind.name()));
    meta.insert("from_vertex".into(), json!(args.from));
    meta.insert("time_unit".into(), times.meta());
    if let Some(info) = dd.diagonal_info() {
        meta.insert(
            "diagonal".into(),
            match info.hops {
                Some(hops) => json!({ "name": info.method.name(), "probe_columns": info.columns, "hops": hops, "relative_tail": info.relative_tail }),
                None if info.columns == 0 => json!({ "name": info.method.name() }),
                None => json!({ "name": info.method.name(), "probe_columns": info.columns }),
            },
        );
    }
    meta.insert("method".into(), super::heat::method_meta(&method));
    let how = Writing {
        render: args.render,
        splats: input.splats.as_ref(),
        highlight: &[i],
        meta,
    };
    for path in write_fields(&args.output, &input.mesh, &[column], how)? {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}
