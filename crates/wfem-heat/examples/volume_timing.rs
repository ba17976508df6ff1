//! One-shot wall-clock timing of K_t e_i on a tetrahedral mesh (the setting of docs/BENCHMARKS.md,
//! "Volumes", issue #39): the fast path's preparation (the Cholesky analysis, whose ordering is
//! AMD or nested dissection) and its K_t e_i, and one backward-Euler step for reference, at
//! t = 1e-3·V^(2/3), i = n/3.
//!
//! Run: `cargo run --release -p wfem-heat --example volume_timing -- FILE [refinements]`
//! (e.g. `../shared/data/volumes/flip-free-parametrization/armadillo.mesh 1`: 121,309 vertices).

use mesh_fem::AssemblyParams;
use shifted_solve::function::KrylovParams;
use std::time::Instant;
use wfem_heat::method::Method;
use wfem_heat::{HeatKernel, HeatParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args.first().ok_or("usage: volume_timing FILE [refinements]")?;
    let refinements: usize = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(0);
    let mut mesh = mesh_fem::io::volume::read_volume(std::path::Path::new(path))?.mesh;
    for _ in 0..refinements {
        mesh = mesh.refined();
    }
    let ops = mesh_fem::volume::assemble_volume(&mesh, &AssemblyParams::default())?;
    let n = ops.n();
    let volume: f64 = ops.mass.val().iter().sum();
    let t = 1e-3 * volume.powf(2.0 / 3.0);
    let mut e = vec![0.0; n];
    e[n / 3] = 1.0;
    let params = |method| HeatParams {
        method,
        ..Default::default()
    };

    let start = Instant::now();
    let fast = HeatKernel::new(&ops, params(Method::Fast(KrylovParams::default())))?;
    let t_prepare = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let (g, iterations, _) = fast.apply_fast_report(&e, t)?;
    let t_apply = start.elapsed().as_secs_f64();
    drop(fast);

    let start = Instant::now();
    let be = HeatKernel::new(&ops, params(Method::BackwardEuler))?;
    be.apply(&e, t)?;
    let t_be = start.elapsed().as_secs_f64();
    let sum: f64 = g.iter().sum();
    println!(
        "n = {n}, t = {t:.3e}: fast path {:.3} s (prepare {t_prepare:.3} s, K_t e_i {t_apply:.3} s, {iterations} its, Σg = {sum:.6e}); backward Euler {t_be:.3} s",
        t_prepare + t_apply
    );
    Ok(())
}
