//! Timings of the point-cloud operators and of K_t f on clouds and meshes, one JSON line per
//! run (driven side by side with robust_laplacian by `benches/peers/clouds.py`):
//!
//! ```sh
//! cloud_bench operators cloud.npy           # L, B, D from the cloud (k = 30)
//! cloud_bench heat-cloud cloud.npy 0.01     # operators, then K_t x on the cloud
//! cloud_bench heat-mesh 1000000 0.01        # a torus mesh of about that many vertices
//! cloud_bench heat-cloud-torus 1000000 0.01 # the same torus's vertices as a cloud
//! ```
//! `kernel_seconds` excludes reading the file; `heat_seconds` is `HeatKernel::new` plus one
//! `apply` (the wFEM kernel, fast exact path).

use mesh_fem::cloud::{assemble_cloud, CloudParams};
use mesh_fem::io::load_points;
use mesh_fem::{assemble, generate, AssemblyParams, FemOperators};
use std::time::Instant;
use wfem_heat::{HeatKernel, HeatParams};

fn heat_seconds(ops: &FemOperators, f: &[f64], t: f64) -> Result<f64, Box<dyn std::error::Error>> {
    let start = Instant::now();
    let kernel = HeatKernel::new(ops, HeatParams::default())?;
    let g = kernel.apply(f, t)?;
    let seconds = start.elapsed().as_secs_f64();
    assert!(g.iter().all(|x| x.is_finite()));
    Ok(seconds)
}

/// A torus of nu × nv ≈ n vertices with nu = 2.5 nv (well-shaped triangles).
fn torus_of(n: usize) -> mesh_fem::TriMesh {
    let nv = ((n as f64 / 2.5).sqrt()).round() as usize;
    let nu = n.div_ceil(nv);
    generate::torus(1.0, 0.4, nu, nv)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mode = args.first().map(String::as_str).unwrap_or("");
    let t: f64 = args.get(2).map_or(Ok(0.01), |s| s.parse())?;
    match mode {
        "operators" | "heat-cloud" => {
            let cloud = load_points(std::path::Path::new(&args[1]))?;
            let start = Instant::now();
            let ops = assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default())?;
            let kernel_seconds = start.elapsed().as_secs_f64();
            let heat = if mode == "heat-cloud" {
                let f: Vec<f64> = cloud.positions().iter().map(|p| p[0]).collect();
                heat_seconds(&ops.operators, &f, t)?
            } else {
                0.0
            };
            println!(
                "{{\"n\": {}, \"nnz\": {}, \"kernel_seconds\": {kernel_seconds}, \"heat_seconds\": {heat}, \"flips\": {}, \"triangles\": {}}}",
                cloud.n_points(),
                ops.operators.stiffness.val().len(),
                ops.report.n_flips,
                ops.report.n_triangles
            );
        }
        "heat-cloud-torus" => {
            // The vertices of the torus mesh of `heat-mesh`, as a cloud (no faces): the same
            // points and surface, so the two runs compare the cloud path with the mesh path.
            let n: usize = args.get(1).map_or(Ok(1_000_000), |s| s.parse())?;
            let mesh = torus_of(n);
            let cloud = mesh_fem::cloud::PointCloud::new(mesh.positions().to_vec(), None)?;
            let start = Instant::now();
            let ops = assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default())?;
            let kernel_seconds = start.elapsed().as_secs_f64();
            let f: Vec<f64> = cloud.positions().iter().map(|p| p[0]).collect();
            let heat = heat_seconds(&ops.operators, &f, t)?;
            println!(
                "{{\"n\": {}, \"nnz\": {}, \"kernel_seconds\": {kernel_seconds}, \"heat_seconds\": {heat}}}",
                cloud.n_points(),
                ops.operators.stiffness.val().len()
            );
        }
        "heat-mesh" => {
            let n: usize = args.get(1).map_or(Ok(1_000_000), |s| s.parse())?;
            let mesh = torus_of(n);
            let start = Instant::now();
            let ops = assemble(&mesh, &AssemblyParams::default())?;
            let kernel_seconds = start.elapsed().as_secs_f64();
            let f: Vec<f64> = mesh.positions().iter().map(|p| p[0]).collect();
            let heat = heat_seconds(&ops, &f, t)?;
            println!(
                "{{\"n\": {}, \"nnz\": {}, \"kernel_seconds\": {kernel_seconds}, \"heat_seconds\": {heat}}}",
                mesh.n_vertices(),
                ops.stiffness.val().len()
            );
        }
        _ => {
            return Err(
                "usage: cloud_bench operators|heat-cloud POINTS.npy [t] | heat-mesh N [t] | heat-cloud-torus N [t]"
                    .into(),
            )
        }
    }
    Ok(())
}
