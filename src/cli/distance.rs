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
    /// The vertices i (numbered as in the file) whose distances d_t(i, ·) to every vertex are
    /// computed: one field per vertex.
    #[arg(long, num_args = 1.., value_parser = super::input::vertex_index, allow_negative_numbers = true, required_unless_present = "all_pairs")]
    pub from: Vec<u32>,
    /// The n × n matrix of distances between all vertices, row i from vertex i, streamed to
    /// the -o .npy in blocks of rows (memory: the kernel and 64 MB of rows, whatever n); an
    /// interrupted run leaves a partial file beside it that the same command resumes.
    #[arg(long, conflicts_with = "from")]
    pub all_pairs: bool,
    /// Which distance.
    #[arg(long, value_parser = choice::<DistanceKind>(), default_value = DistanceKind::default_name())]
    pub kind: DistanceKind,
    /// Use the paper's rational method of this degree (error ≈ 9.3^-degree) instead of the
    /// default fast exact path.
    #[arg(long)]
    pub degree: Option<usize>,
    /// Output file: .ply, .npy (+ .json sidecar), .csv, .vtu (ParaView; a volume's tetrahedra) or .png.
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
    let suffixes: Vec<String> = match &args.from[..] {
        [_] | [] => vec![suffix.clone()],
        many => many.iter().map(|v| format!("{suffix}-from{v}")).collect(),
    };
    if args.all_pairs {
        args.output.require_matrix()?;
    }
    args.output
        .check(Some(&suffixes), suffixes.len(), &[&args.input.mesh])?;
    let input = read_usable(&args.input)?;
    let sources: Vec<u32> = args
        .from
        .iter()
        .map(|&v| input.vertex("--from", v))
        .collect::<Result<_, _>>()?;
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
    let mut meta = serde_json::Map::new();
    meta.insert("command".into(), json!("distance"));
    meta.insert("input".into(), input.meta(&args.input.mesh));
    meta.insert("kind".into(), json!(kind.name()));
    meta.insert("method".into(), serde_json::json!(method));
    meta.insert("time_unit".into(), times.meta());
    if args.all_pairs {
        let key = format!(
            "{}|{}|{t:e}|{:?}",
            input.meta(&args.input.mesh),
            kind.name(),
            args.degree
        );
        let rows =
            |range: std::ops::Range<usize>, block: &mut [f64]| dd.rows_into(&range.collect::<Vec<usize>>(), block);
        return super::output::write_all_pairs(&args.output, dd.n(), &key, rows, meta, out);
    }
    let list: Vec<usize> = sources.iter().map(|&v| v as usize).collect();
    let rows = progress::run(format!("distances from {} vertices", list.len()), || dd.rows(&list))?;
    let how_computed = match &method {
        Method::Rational { degree, .. } => format!("{}, degree {degree}", method.name()),
        m => m.name().to_string(),
    };
    let columns: Vec<Column> = rows
        .into_iter()
        .zip(&args.from)
        .zip(&suffixes)
        .map(|((values, v), suffix)| Column {
            name: if args.from.len() == 1 {
                format!("{name}_distance_t={label}")
            } else {
                format!("{name}_distance_t={label}_from{v}")
            },
            suffix: suffix.clone(),
            title: format!(
                "{}: {} distance from vertex {v}, t = {label}{} ({how_computed})",
                input.name,
                kind.name(),
                times.suffix(),
            ),
            t: Some(t),
            values,
        })
        .collect();
    if let [v] = &args.from[..] {
        meta.insert("from_vertex".into(), json!(v));
    } else {
        meta.insert("from_vertices".into(), json!(args.from));
    }
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
    let how = Writing {
        render: args.render,
        splats: input.splats.as_ref(),
        highlight: &sources,
        meta,
        allow_infinity: false,
        volume: input.volume.as_ref().map(|v| &v.mesh),
    };
    for path in write_fields(&args.output, &input.mesh, &columns, how)? {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}
