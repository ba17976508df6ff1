//! One-shot wall-clock timing of K_t f on an icosphere of area 4π at t = 0.01 (the setting of
//! the performance targets): one backward-Euler step (one real sparse Cholesky of
//! B + tL plus one solve), the fast path (f = x and f = e_i) and the rational method
//! (degree 16, direct LU), with the relative difference fast vs rational.
//!
//! Run: `cargo run --release -p wfem-heat --example heat_timing -- LEVEL [--no-rational]`
//! (level 5: 10,242 vertices; 6: 40,962; 7: 163,842; 8: 655,362).

use mesh_fem::{assemble, generate, AssemblyParams};
use shifted_solve::function::KrylovParams;
use std::time::Instant;
use wfem_heat::method::Method;
use wfem_heat::{HeatKernel, HeatParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let level: u32 = args.next().as_deref().unwrap_or("5").parse()?;
    let rational = !std::env::args().any(|a| a == "--no-rational");
    let t = 0.01;
    let mesh = generate::icosphere(level).with_area(4.0 * std::f64::consts::PI)?;
    let ops = assemble(&mesh, &AssemblyParams::default())?;
    let n = ops.n();
    let x: Vec<f64> = mesh.positions().iter().map(|p| p[0]).collect();
    let mut e = vec![0.0; n];
    e[n / 3] = 1.0;
    let kernel = |method| {
        HeatKernel::new(
            &ops,
            HeatParams {
                method,
                ..Default::default()
            },
        )
    };

    let be = kernel(Method::BackwardEuler)?;
    let start = Instant::now();
    be.apply(&x, t)?;
    let t_be = start.elapsed().as_secs_f64();

    let mut results = Vec::new();
    for (name, f) in [("x", &x), ("e_i", &e)] {
        let fast = kernel(Method::Fast(KrylovParams::default()))?;
        let start = Instant::now();
        let (g, iterations, _) = fast.apply_fast_report(f, t)?;
        let t_fast = start.elapsed().as_secs_f64();
        let (t_rat, diff) = if rational {
            let start = Instant::now();
            let r = kernel(Method::rational(16))?.apply(f, t)?;
            let t_rat = start.elapsed().as_secs_f64();
            let scale = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let d = g.iter().zip(&r).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            (Some(t_rat), Some(d / scale))
        } else {
            (None, None)
        };
        results.push((name, iterations, t_fast, t_rat, diff));
    }
    println!("n = {n}, t = {t}: backward Euler {t_be:.3} s");
    for (name, iterations, t_fast, t_rat, diff) in results {
        print!(
            "  f = {name}: fast {t_fast:.3} s ({iterations} its, {:.1}x BE)",
            t_fast / t_be
        );
        if let (Some(tr), Some(d)) = (t_rat, diff) {
            print!(", rational {tr:.3} s (incl. symbolic), max|fast - rational|/max|rational| = {d:.1e}");
        }
        println!();
    }
    Ok(())
}
