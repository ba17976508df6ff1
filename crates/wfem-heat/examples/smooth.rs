//! Smooths a noisy function on a generated bumpy sphere (642 vertices, area 4π) with the
//! wFEM heat kernel, by every method, and prints each method's relative difference from the
//! dense reference (paper, Eq. (6)).
//!
//! Run: `cargo run -p wfem-heat --example smooth`.
use mesh_fem::{assemble, generate, AssemblyParams, Mass};
use std::f64::consts::PI;
use std::time::Instant;
use wfem_heat::method::Method;
use wfem_heat::spectral::EigenParams;
use wfem_heat::{HeatError, HeatKernel, HeatParams};

fn main() -> Result<(), HeatError> {
    let mesh = generate::bumpy(3).with_area(4.0 * PI)?;
    let ops = assemble(&mesh, &AssemblyParams::default())?;
    let n = ops.n();
    // A smooth signal plus deterministic "noise".
    let f: Vec<f64> = mesh
        .positions()
        .iter()
        .enumerate()
        .map(|(i, p)| p[2] + 0.3 * ((i as f64) * 12.9898).sin())
        .collect();
    println!("bumpy sphere: {n} vertices, area {:.4}", ops.area());

    let methods = [
        ("dense (Eq. 6)", Method::Dense),
        (
            "spectral k=32 (Eq. 8)",
            Method::Spectral {
                k: 32,
                eigen: EigenParams::default(),
            },
        ),
        (
            "spectral k=128 (Eq. 8)",
            Method::Spectral {
                k: 128,
                eigen: EigenParams::default(),
            },
        ),
        ("Taylor (Eq. 9)", Method::Taylor),
        ("backward Euler", Method::BackwardEuler),
        ("fast (rational Krylov)", Method::default()),
    ];
    let mut kernels = Vec::new();
    for (name, method) in methods {
        let start = Instant::now();
        let k = HeatKernel::new(
            &ops,
            HeatParams {
                mass: Mass::Consistent,
                method,
            },
        )?;
        println!("  built {name:<24} in {:>8.1} ms", start.elapsed().as_secs_f64() * 1e3);
        kernels.push((name, k));
    }
    for t in [1e-3, 1e-2, 1e-1] {
        let reference = kernels[0].1.apply(&f, t)?;
        let rnorm = reference.iter().map(|x| x * x).sum::<f64>().sqrt();
        println!("t = {t:e}");
        for (name, k) in &kernels[1..] {
            let start = Instant::now();
            let g = k.apply(&f, t)?;
            let ms = start.elapsed().as_secs_f64() * 1e3;
            let d = g
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt()
                / rnorm;
            println!("  {name:<24} relative difference {d:9.2e}   ({ms:6.2} ms)");
        }
    }
    Ok(())
}
