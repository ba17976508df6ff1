//! Generates an icosphere, prints its statistics and validation report, assembles L, B, D,
//! checks two identities and writes the three operators as Matrix Market files.
//!
//! Run with `cargo run -p mesh-fem --example operators [level]` (default level 4).

use mesh_fem::generate::icosphere;
use mesh_fem::mtx::write_operators;
use mesh_fem::stats::stats;
use mesh_fem::validate::validate;
use mesh_fem::{assemble, AssemblyParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let level: u32 = std::env::args().nth(1).map(|s| s.parse()).transpose()?.unwrap_or(4);
    let mesh = icosphere(level);

    let s = stats(&mesh);
    println!("icosphere level {level}");
    println!(
        "  {} vertices, {} edges, {} faces; χ = {}, genus {:?}, closed {}, manifold {}",
        s.n_vertices, s.n_edges, s.n_faces, s.euler_characteristic, s.genus, s.is_closed, s.is_manifold
    );
    println!(
        "  area {:.6} (4π = {:.6}), mean edge {:.4e}, angles {:.2}°..{:.2}°",
        s.area,
        4.0 * std::f64::consts::PI,
        s.mean_edge_length,
        s.min_angle_deg,
        s.max_angle_deg
    );
    println!("{}", validate(&mesh).into_result()?.summary());

    let ops = assemble(&mesh, &AssemblyParams::default())?;
    // L·1 = 0 (constants are harmonic) and 1ᵀB1 = area (B integrates exactly).
    let l = ops.stiffness.as_ref();
    let mut l_one = vec![0.0; ops.n()];
    for j in 0..ops.n() {
        for (&i, &v) in l.row_idx_of_col_raw(j).iter().zip(l.val_of_col(j)) {
            l_one[i] += v;
        }
    }
    let max_l_one = l_one.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    println!("  max |L·1| = {max_l_one:.2e}   (should be ~1e-13 or less)");
    println!(
        "  (1ᵀB1 − area)/area = {:.2e}   (round-off only, ~1e-14)",
        (ops.area() - s.area) / s.area
    );

    let dir = std::env::temp_dir().join(format!("mesh-fem-operators-{}", std::process::id()));
    write_operators(&dir, &ops)?;
    for name in ["stiffness.mtx", "mass.mtx", "lumped_mass.mtx"] {
        let bytes = std::fs::metadata(dir.join(name))?.len();
        println!("  wrote {} ({bytes} bytes)", dir.join(name).display());
    }
    Ok(())
}
