//! Loads a mesh, prints its statistics and validation report, repairs what is fatal and
//! assembles the FEM operators: the "load → validate → assemble" path of the README.
//!
//! ```text
//! cargo run -p mesh-fem --example validate -- path/to/mesh.obj
//! cargo run -p mesh-fem --example validate   # the corpus's stanford-bunny.obj (unreferenced vertices, holes)
//! ```

use mesh_fem::io::{load, LoadOptions};
use mesh_fem::stats::stats;
use mesh_fem::validate::{repair, validate, RepairOptions};
use mesh_fem::{assemble, AssemblyParams};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = match std::env::args().nth(1) {
        Some(p) => PathBuf::from(p),
        None => wfem_corpus::mesh_path("common-3d-test-models/stanford-bunny.obj")?,
    };
    let (mesh, _) = load(&path, &LoadOptions::with_triangulation(true))?;
    println!("{}", path.display());
    println!("{}", serde_json::to_string_pretty(&stats(&mesh))?);

    let report = validate(&mesh);
    println!("{}", report.summary());
    let mesh = if report.is_usable() {
        mesh
    } else {
        let opts = RepairOptions {
            drop_degenerate_faces: true,
            drop_unreferenced_vertices: true,
            ..Default::default()
        };
        let (fixed, changes) = repair(&mesh, &opts)?;
        println!("{}", changes.summary());
        println!("{}", validate(&fixed).into_result()?.summary());
        fixed
    };
    let ops = assemble(&mesh, &AssemblyParams::default())?;
    println!(
        "assembled L, B, D: n = {}, nnz = {}, area 1ᵀB1 = {:.6}",
        ops.n(),
        ops.stiffness.compute_nnz(),
        ops.area()
    );
    Ok(())
}
