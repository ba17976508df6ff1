//! Loads a mesh and prints its counts and the load report.
//!
//! ```text
//! cargo run -p mesh-fem --example load -- path/to/mesh.obj [--triangulate]
//! cargo run -p mesh-fem --example load            # writes a generated icosphere, loads it back
//! cargo run -p mesh-fem --example load -- --corpus  # loads every file of the mesh corpus
//! ```

use mesh_fem::io::{load, write_mesh, LoadOptions};
use mesh_fem::{generate, MeshError};
use std::path::{Path, PathBuf};

fn show(path: &Path, opts: &LoadOptions) -> Result<(), MeshError> {
    let (mesh, report) = load(path, opts)?;
    println!(
        "{}: {:?}, {} vertices, {} faces, area {:.6}, welded {}, triangulated {}{}",
        path.display(),
        report.format,
        mesh.n_vertices(),
        mesh.n_faces(),
        mesh.area(),
        report.welded_vertices,
        report.triangulated_polygons,
        if report.notes.is_empty() {
            String::new()
        } else {
            format!(" ({})", report.notes.join("; "))
        }
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let opts = LoadOptions::with_triangulation(args.iter().any(|a| a == "--triangulate"));
    let paths: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    if args.iter().any(|a| a == "--corpus") {
        for path in wfem_corpus::all_mesh_files()? {
            if let Err(e) = show(&path, &opts) {
                println!("{}: error: {e}", path.display());
            }
        }
        return Ok(());
    }
    if paths.is_empty() {
        let dir = std::env::temp_dir().join(format!("wfem-load-example-{}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        let path: PathBuf = dir.join("icosphere3.off");
        let mesh = generate::icosphere(3);
        write_mesh(&path, &mesh)?;
        println!(
            "generated icosphere(3): {} vertices, {} faces; written to {}",
            mesh.n_vertices(),
            mesh.n_faces(),
            path.display()
        );
        show(&path, &opts)?;
        std::fs::remove_dir_all(&dir)?;
        return Ok(());
    }
    for p in paths {
        show(Path::new(p), &opts)?;
    }
    Ok(())
}
