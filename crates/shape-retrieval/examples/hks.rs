//! Heat kernel signatures of a generated bumpy sphere, from a dense spectrum.
//!
//! Run with `cargo run -p shape-retrieval --example hks`. It assembles L and B on `bumpy(2)`
//! (162 vertices), solves the generalized eigenproblem densely (fine for small meshes only),
//! and prints the HKS in both conventions at a few vertices and times, the heat trace, and the
//! first SI-HKS frequencies. Checks a person can make: the operator-diagonal values of one time
//! sum to the heat trace; protruding vertices have larger HKS at small t than flat ones.

#[path = "../tests/it/common/mod.rs"]
mod common;

use shape_retrieval::hks::{heat_kernel_signature, heat_trace, HksParams, Spectrum};
use shape_retrieval::sihks::{scale_invariant_hks, SihksParams};
use shape_retrieval::RetrievalError;
use wfem_heat::KernelDiagonal;

fn main() -> Result<(), RetrievalError> {
    let mesh = mesh_fem::generate::bumpy(2);
    let s = common::dense_spectrum(&mesh);
    let k = 100;
    println!(
        "bumpy(2): {} vertices, area {:.4}, using {k} of {} eigenpairs",
        mesh.n_vertices(),
        s.ops.area(),
        s.eigenvalues.len()
    );
    println!(
        "λ_1 = {:.4}, λ_2 = {:.4}, λ_{k} = {:.2}",
        s.eigenvalues[1],
        s.eigenvalues[2],
        s.eigenvalues[k - 1]
    );
    let spectrum = Spectrum::new(&s.eigenvalues[..k], s.eigenvectors.subcols(0, k))?.with_mass(s.ops.mass.as_ref())?;

    let kv = heat_kernel_signature(&spectrum, &HksParams::default())?;
    let md = heat_kernel_signature(
        &spectrum,
        &HksParams {
            convention: KernelDiagonal::OperatorDiagonal,
            ..Default::default()
        },
    )?;
    let cols = [0, 33, 66, 99];
    println!("\nHKS, kernel value Σ e^(−λt) φ(i)²  (rows: vertices, columns: t)");
    print!("{:>8}", "t =");
    for &j in &cols {
        print!("{:>12.4e}", kv.times[j]);
    }
    println!();
    for i in [0usize, 40, 80, 120, 160] {
        print!("{i:>8}");
        for &j in &cols {
            print!("{:>12.5}", kv.values[(i, j)]);
        }
        println!();
    }
    println!("\nHKS, operator diagonal (Φ D_t Φᵀ B)_ii");
    for i in [0usize, 40, 80, 120, 160] {
        print!("{i:>8}");
        for &j in &cols {
            print!("{:>12.5e}", md.values[(i, j)]);
        }
        println!();
    }
    let z = heat_trace(&s.eigenvalues[..k], &md.times);
    println!("\ncolumn sums of the operator diagonal vs heat trace Z(t):");
    for &j in &cols {
        let sum: f64 = md.values.col(j).iter().sum();
        println!("  t = {:.4e}: Σ_i = {sum:.12}, Z = {:.12}", md.times[j], z[j]);
    }

    // SI-HKS on the full spectrum of the shape scaled by 1000 (TOSCA-like units for the default window).
    let big: Vec<f64> = s.eigenvalues.iter().map(|l| l * 1e-6).collect();
    let big_x = &s.eigenvectors * faer::Scale(1e-3);
    let si = scale_invariant_hks(&Spectrum::new(&big, big_x.as_ref())?, &SihksParams::default())?;
    println!("\nSI-HKS |DFT| frequencies 0..5 (shape ×1000, α = 2, τ ∈ [1, 25] step 1/16):");
    for i in [0usize, 40, 80] {
        let row: Vec<String> = (0..si.ncols()).map(|w| format!("{:.4}", si[(i, w)])).collect();
        println!("{i:>8}  {}", row.join("  "));
    }
    Ok(())
}
