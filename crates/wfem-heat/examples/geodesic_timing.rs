//! Time per geodesic query on an icosphere: prepare once, then queries from spread sources.
//!
//! Run: `cargo run --release -p wfem-heat --example geodesic_timing -- LEVEL [QUERIES] [--heat]
//! [--repeat R] [--write MESH.off]` (level 6: 40,962 vertices; level 8: 655,362). Prints
//! prepare, the mean query over the queries after a first one (the best of R rounds), and the
//! prepared solver's memory; `--write` saves the icosphere first, so that a peer can be timed
//! on the very same mesh (docs/BENCHMARKS.md, geodesic distances).

use std::time::Instant;
use wfem_heat::geodesic::{GeodesicMethod, GeodesicParams, GeodesicSolver};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut positional = Vec::new();
    let mut params = GeodesicParams::default();
    let (mut repeat, mut write) = (1usize, None);
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--heat" => params.method = GeodesicMethod::Heat,
            "--repeat" => {
                i += 1;
                repeat = args.get(i).ok_or("--repeat needs a count")?.parse()?;
            }
            "--write" => {
                i += 1;
                write = Some(args.get(i).ok_or("--write needs a path")?.clone());
            }
            s => positional.push(s.to_string()),
        }
        i += 1;
    }
    let level: u32 = positional.first().map_or(Ok(6), |s| s.parse())?;
    let queries: usize = positional.get(1).map_or(Ok(10), |s| s.parse())?;
    let mesh = mesh_fem::generate::icosphere(level);
    if let Some(path) = write {
        mesh_fem::io::write_mesh(std::path::Path::new(&path), &mesh)?;
    }
    let n = mesh.n_vertices();
    let start = Instant::now();
    let solver = GeodesicSolver::new(&mesh, &params)?;
    let prepare = start.elapsed().as_secs_f64();
    let first = solver.distance(&[0])?;
    let mut query = f64::INFINITY;
    let mut checksum = 0.0;
    for _ in 0..repeat.max(1) {
        let start = Instant::now();
        checksum = 0.0;
        for q in 0..queries {
            let d = solver.distance(&[((q + 1) * n / (queries + 1)) as u32])?;
            checksum += d.iter().sum::<f64>();
        }
        query = query.min(start.elapsed().as_secs_f64() / queries.max(1) as f64);
    }
    println!(
        "n = {n}, {:?}: prepare {prepare:.3} s, query {:.2} ms, memory {:.1} MB (max distance {:.4}, checksum {checksum:.6e})",
        params.method,
        query * 1e3,
        solver.memory_bytes() as f64 / 1e6,
        first.iter().copied().fold(0.0, f64::max),
    );
    Ok(())
}
