//! `wfem geodesic`: geodesic distances from source vertices (fast marching by default, or the
//! heat method), as a field, one field per source, or the whole n × n matrix streamed to `.npy`.

use super::choice::choice;
use super::output::{write_fields, Column, RenderArgs, Writing};
use super::{progress, read_usable, CliError, MeshArgs, Output};
use clap::Args;
use mesh_fem::cloud::CloudParams;
use mesh_fem::{Laplacian, RobustParams};
use serde_json::json;
use std::io::Write;
use wfem_base::Choice;
use wfem_heat::geodesic::{
    GeodesicMethod, GeodesicParams, GeodesicReport, GeodesicSolver, Source, DEFAULT_T_COEF, MAX_REFINE,
};

/// Arguments of `wfem geodesic`.
#[derive(Args, Clone, Debug)]
pub struct GeodesicArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Source vertices (numbered as in the file): the distance to the nearest one (with
    /// --each: one field per source). Not with --all-pairs.
    #[arg(long, num_args = 1.., value_parser = super::input::vertex_index, allow_negative_numbers = true, required_unless_present = "all_pairs")]
    pub from: Vec<u32>,
    /// One field per source vertex instead of the distance to the nearest.
    #[arg(long)]
    pub each: bool,
    /// The n × n matrix of distances between all vertices, row i from vertex i, streamed to
    /// the -o .npy in blocks of rows (memory: the solver and 64 MB of rows, whatever n);
    /// an interrupted run leaves a partial file beside it that the same command resumes.
    #[arg(long, conflicts_with_all = ["from", "each"])]
    pub all_pairs: bool,
    /// How: fast-marching (the default on surfaces and point clouds: most accurate and
    /// fastest) or heat (Crane et al.'s heat method, potpourri3d's numbers; the only one, and
    /// so the default, on a tetrahedral mesh).
    #[arg(long, value_parser = choice::<GeodesicMethod>())]
    pub method: Option<GeodesicMethod>,
    /// The heat method's time t = C·h² in units of the squared mean edge length h.
    #[arg(long, default_value_t = DEFAULT_T_COEF, allow_negative_numbers = true)]
    pub t_coef: f64,
    /// Split every triangle into four this many times first (same surface, finer: more
    /// accurate, about 4× the work per level; distances at the mesh's own vertices).
    #[arg(long, default_value_t = wfem_heat::geodesic::DEFAULT_REFINE)]
    pub refine: u32,
    /// Output file: .ply, .npy (+ .json sidecar), .csv, .vtu (ParaView; a volume's tetrahedra) or .png (iso-lines, sources marked);
    /// .npy with --all-pairs.
    #[arg(short = 'o', long = "output", value_parser = Output::parse)]
    pub output: Output,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub render: RenderArgs,
}

/// `wfem geodesic` (validate → compute → write).
pub fn geodesic(args: &GeodesicArgs, out: &mut dyn Write) -> Result<(), CliError> {
    // Validate.
    if !(args.t_coef.is_finite() && args.t_coef > 0.0) {
        return Err(CliError::OutOfRange {
            flag: "--t-coef",
            value: args.t_coef.to_string(),
            allowed: "> 0, finite".into(),
            why: "the heat method's time in units of h²".into(),
        });
    }
    if args.refine > MAX_REFINE {
        return Err(CliError::OutOfRange {
            flag: "--refine",
            value: args.refine.to_string(),
            allowed: format!("0..={MAX_REFINE}"),
            why: "each level multiplies the vertices by about 4".into(),
        });
    }
    let suffixes: Vec<String> = if args.each {
        args.from.iter().map(|v| format!("from{v}")).collect()
    } else {
        vec!["geodesic".into()]
    };
    if args.all_pairs {
        args.output.require_matrix()?;
    }
    args.output
        .check(Some(&suffixes), suffixes.len(), &[&args.input.mesh])?;
    let mut mesh_args = args.input.clone();
    // The robust (intrinsic Delaunay) triangulation unless --laplacian says otherwise.
    let volume = super::volume::is_volume(&args.input);
    if !volume {
        mesh_args.laplacian = Some(
            args.input
                .laplacian
                .unwrap_or(Laplacian::Robust(RobustParams::default())),
        );
    }
    let method = args.method.unwrap_or(if volume {
        GeodesicMethod::Heat
    } else {
        GeodesicMethod::default()
    });
    let input = read_usable(&mesh_args)?;
    let sources: Vec<u32> = args
        .from
        .iter()
        .map(|&v| input.vertex("--from", v))
        .collect::<Result<_, _>>()?;
    let params = GeodesicParams {
        method,
        t_coef: args.t_coef,
        laplacian: input.laplacian,
        refine: args.refine,
    };
    // Compute.
    let solver = progress::run(format!("preparing {} geodesics", method.name()), || {
        match (&input.cloud, &input.volume) {
            (Some(cloud), _) => GeodesicSolver::from_cloud(cloud, &params, &CloudParams::default()),
            (None, Some(v)) => GeodesicSolver::from_volume(&v.mesh, &params),
            (None, None) => GeodesicSolver::new(&input.mesh, &params),
        }
    })?;
    let mut meta = serde_json::Map::new();
    meta.insert("command".into(), json!("geodesic"));
    meta.insert("input".into(), input.meta(&args.input.mesh));
    meta.insert("method".into(), json!(method.name()));
    meta.insert("laplacian".into(), json!(input.laplacian.name()));
    meta.insert("refine".into(), json!(args.refine));
    meta.insert("mean_edge_length".into(), json!(solver.mean_edge_length()));
    if let Some(t) = solver.t() {
        meta.insert("t_coef".into(), json!(args.t_coef));
        meta.insert("t".into(), json!(t));
    }
    if args.all_pairs {
        // What the rows are: a resume continues only the same computation.
        let key = format!("{}|{:?}", input.meta(&args.input.mesh), solver.params());
        let rows = |range: std::ops::Range<usize>, block: &mut [f64]| {
            let sources: Vec<u32> = (range.start as u32..range.end as u32).collect();
            solver.distance_each_into(&sources, block)
        };
        return super::output::write_all_pairs(&args.output, solver.n_vertices(), &key, rows, meta, out);
    }
    let (columns, report) = if args.each {
        let rows = progress::run(format!("distances from {} sources", sources.len()), || {
            solver.distance_each(&sources)
        })?;
        let columns = rows
            .into_iter()
            .zip(&args.from)
            .map(|(values, v)| column(&input.name, method, format!("from{v}"), format!("vertex {v}"), values))
            .collect();
        (columns, None)
    } else {
        let list: Vec<Source> = sources.iter().map(|&v| Source::Vertex(v)).collect();
        let (values, report) = progress::run("distances", || solver.distance_from(&list))?;
        let from = match &args.from[..] {
            [v] => format!("vertex {v}"),
            many => format!("{} sources", many.len()),
        };
        (
            vec![column(&input.name, method, "geodesic".into(), from, values)],
            Some(report),
        )
    };
    warn_about(
        report.as_ref(),
        columns
            .iter()
            .map(|c| c.values.iter().filter(|x| x.is_infinite()).count())
            .max()
            .unwrap_or(0),
    );
    meta.insert("from_vertices".into(), json!(args.from));
    // Write.
    let how = Writing {
        render: args.render,
        splats: input.splats.as_ref(),
        highlight: &sources,
        meta,
        allow_infinity: true,
        volume: input.volume.as_ref().map(|v| &v.mesh),
    };
    for path in write_fields(&args.output, &input.mesh, &columns, how)? {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}

fn column(name: &str, method: GeodesicMethod, suffix: String, from: String, values: Vec<f64>) -> Column {
    Column {
        name: if suffix == "geodesic" {
            "geodesic_distance".into()
        } else {
            format!("geodesic_distance_{suffix}")
        },
        suffix,
        title: format!("{name}: geodesic distance from {from} ({})", method.name()),
        t: None,
        values,
    }
}

fn warn_about(report: Option<&GeodesicReport>, unreachable: usize) {
    if unreachable > 0 {
        progress::warn(&format!(
            "{unreachable} vertices lie in connected components without a source: their distance is inf \
             (written as inf; figures draw them at the largest distance)"
        ));
    }
    if let Some(r) = report.filter(|r| r.heat_underflow > 0) {
        progress::warn(&format!(
            "the heat method's heat underflowed at {} vertices far from the sources: their distances are \
             unreliable there; --method fast-marching has no such limit",
            r.heat_underflow
        ));
    }
}
