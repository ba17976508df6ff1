//! Fills the bumpy shape with tetrahedra (or reads a volume file), refines it, prints its
//! validation report, assembles L, B, D of the tetrahedra and checks two identities: L·1 = 0
//! and 1ᵀB1 = the volume. Prints the assembly's wall time (best of `repeat`).
//!
//! Run with `cargo run --release -p mesh-fem --example volume [FILE|level] [refinements] [repeat]`
//! (default: the level-3 icosphere in 8 shells, no refinement, 3 repetitions).

use mesh_fem::io::volume::read_volume;
use mesh_fem::volume::{assemble_volume, validate_volume};
use mesh_fem::AssemblyParams;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let first = args.get(1).map_or("3", String::as_str);
    let mut mesh = match first.parse::<u32>() {
        Ok(level) if level <= 6 => mesh_fem::generate::tet_bumpy(level, 8),
        _ => read_volume(std::path::Path::new(first))?.mesh,
    };
    let refinements: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(0);
    let repeat: usize = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(3).max(1);
    for _ in 0..refinements {
        mesh = mesh.refined();
    }
    let r = validate_volume(&mesh);
    println!(
        "{} vertices, {} tetrahedra, volume {:.6}, boundary: {} triangles, χ = {}, genus {:?}; quality min {:.3e} (tetrahedron {}), median {:.3}",
        r.n_vertices, r.n_tets, r.volume, r.n_boundary_faces, r.boundary_euler, r.boundary_genus, r.quality.0, r.worst_tet, r.quality.1
    );
    for p in &r.problems {
        println!("  {p}");
    }
    let mut best = f64::INFINITY;
    let mut ops = None;
    for _ in 0..repeat {
        let start = Instant::now();
        let o = assemble_volume(&mesh, &AssemblyParams::default())?;
        best = best.min(start.elapsed().as_secs_f64());
        ops = Some(o);
    }
    let Some(ops) = ops else { return Ok(()) };
    let l = ops.stiffness.as_ref();
    let mut l_one = vec![0.0; ops.n()];
    for j in 0..ops.n() {
        for (&i, &v) in l.row_idx_of_col_raw(j).iter().zip(l.val_of_col(j)) {
            l_one[i] += v;
        }
    }
    let worst = l_one.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mass: f64 = ops.mass.val().iter().sum();
    println!(
        "assembly: {:.1} ms (best of {repeat}), {} nonzeros per matrix; max|L·1| = {worst:.1e}, 1ᵀB1 − volume = {:.1e}",
        1e3 * best,
        ops.stiffness.val().len(),
        mass - r.volume
    );
    Ok(())
}
