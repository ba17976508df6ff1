//! Samples n points uniformly on the unit sphere, builds the point-cloud operators and writes
//! them to a folder (stiffness.mtx, mass.mtx, lumped_mass.mtx), printing what was done:
//! `cargo run --release -p mesh-fem --example cloud_sphere -- 2000 /tmp/cloud`.

use mesh_fem::cloud::{assemble_cloud, CloudParams, PointCloud};
use mesh_fem::mtx::write_operators;
use mesh_fem::AssemblyParams;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map_or(Ok(2000), |s| s.parse())?;
    let out = args.next();
    // Uniform on the sphere: normalised Gaussian triples (Box–Muller on SplitMix64).
    let mut state = 27u64;
    let mut uniform = || {
        state = state.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        (((z ^ (z >> 31)) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let mut gauss = || (-2.0 * uniform().ln()).sqrt() * (2.0 * std::f64::consts::PI * uniform()).cos();
    let points: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            let p = [gauss(), gauss(), gauss()];
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            p.map(|c| c / r)
        })
        .collect();
    let cloud = PointCloud::new(points, None)?;
    let start = std::time::Instant::now();
    let ops = assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default())?;
    let seconds = start.elapsed().as_secs_f64();
    let area: f64 = ops.operators.lumped_diagonal.iter().sum();
    println!(
        "{n} points: {:.3} s, area {:.6} (4π = {:.6}), {:?}",
        seconds,
        area,
        4.0 * std::f64::consts::PI,
        ops.report
    );
    if let Some(dir) = out {
        write_operators(&dir, &ops.operators)?;
    }
    Ok(())
}
