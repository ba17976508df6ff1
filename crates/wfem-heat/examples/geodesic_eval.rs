//! Heat-method geodesics of a mesh from given source vertices, one query per source, written as
//! raw little-endian f64 rows (|S| × n) for comparison with exact geodesics (docs/BENCHMARKS.md).
//!
//! Run: `cargo run --release -p wfem-heat --example geodesic_eval -- MESH OUT.f64 [--cotan]
//! [--heat] [--t-coef C] [--refine R] SOURCE...`

use std::io::Write;
use std::time::Instant;
use wfem_heat::geodesic::{GeodesicParams, GeodesicSolver};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mesh_path, out) = (&args[0], &args[1]);
    let mut params = GeodesicParams::default();
    let mut sources = Vec::new();
    let mut i = 2;
    while i < args.len() {
        match args[i].as_str() {
            "--cotan" => params.laplacian = mesh_fem::Laplacian::Cotan,
            "--heat" => params.method = wfem_heat::geodesic::GeodesicMethod::Heat,
            "--t-coef" => {
                i += 1;
                params.t_coef = args[i].parse()?;
            }
            "--refine" => {
                i += 1;
                params.refine = args[i].parse()?;
            }
            s => sources.push(s.parse::<u32>()?),
        }
        i += 1;
    }
    let (mesh, _) = mesh_fem::io::load(std::path::Path::new(mesh_path), &Default::default())?;
    let start = Instant::now();
    let solver = GeodesicSolver::new(&mesh, &params)?;
    let prepare = start.elapsed().as_secs_f64();
    let mut file = std::io::BufWriter::new(std::fs::File::create(out)?);
    let mut query = 0.0;
    for &s in &sources {
        let start = Instant::now();
        let (d, report) = solver.distance_from(&[wfem_heat::geodesic::Source::Vertex(s)])?;
        query += start.elapsed().as_secs_f64();
        eprintln!("source {s}: {report:?}");
        for x in d {
            file.write_all(&x.to_le_bytes())?;
        }
    }
    eprintln!(
        "n = {}, t = {:?}, h = {:.3e}, prepare {prepare:.3} s, query {:.4} s, memory {:.1} MB",
        mesh.n_vertices(),
        solver.t(),
        solver.mean_edge_length(),
        query / sources.len().max(1) as f64,
        solver.memory_bytes() as f64 / 1e6
    );
    Ok(())
}
