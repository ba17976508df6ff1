//! Prints every shipped rational approximation (degree, solves, E_n, measured max error on
//! [0, 200] ∪ log-spaced points to 1e10), then solves a 2×2 heat problem whose exact answer is
//! known in closed form, with both backends.
//!
//! Run: `cargo run -p shifted-solve --example poles`

use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;
use shifted_solve::backend::Backend;
use shifted_solve::iterative::MinresParams;
use shifted_solve::poles::RationalApprox;
use shifted_solve::ShiftedSolver;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("degree  solves  E_n (documented)  max|r_n(x) − e^-x| (f64)  Σ2|c_j|");
    let mut xs: Vec<f64> = (0..=20_000).map(|k| k as f64 * 0.01).collect();
    xs.extend((0..=500).map(|k| 10f64.powf(2.3 + 7.7 * k as f64 / 500.0)));
    for a in RationalApprox::all() {
        let err = xs.iter().map(|&x| (a.eval(x) - (-x).exp()).abs()).fold(0.0, f64::max);
        println!(
            "{:>6}  {:>6}  {:>16.4e}  {:>24.4e}  {:>7.1}",
            a.degree,
            a.n_solves(),
            a.max_error,
            err,
            a.error_amplification()
        );
    }

    // L = [[1, −1], [−1, 1]] (eigenvalues 0 and 2), B = I: exp(−tL) e₀ = ½(1 + e^{−2t}, 1 − e^{−2t}).
    let l = SparseColMat::try_new_from_triplets(
        2,
        2,
        &[
            Triplet::new(0, 0, 1.0),
            Triplet::new(0, 1, -1.0),
            Triplet::new(1, 0, -1.0),
            Triplet::new(1, 1, 1.0),
        ],
    )?;
    let b = SparseColMat::try_new_from_triplets(2, 2, &[Triplet::new(0, 0, 1.0), Triplet::new(1, 1, 1.0)])?;
    let f = Mat::from_fn(2, 1, |i, _| if i == 0 { 1.0 } else { 0.0 });
    let t: f64 = 0.5;
    let exact = [0.5 * (1.0 + (-2.0 * t).exp()), 0.5 * (1.0 - (-2.0 * t).exp())];
    println!(
        "\n2×2 check, t = {t}: exact K_t e₀ = [{:.15}, {:.15}]",
        exact[0], exact[1]
    );
    for (name, backend) in [
        ("DirectLu", Backend::DirectLu),
        ("Minres", Backend::Minres(MinresParams::default())),
    ] {
        let solver = ShiftedSolver::new(l.as_ref(), b.as_ref(), backend)?;
        for degree in [7, 16] {
            let (g, report) = solver.apply(RationalApprox::cram(degree)?, t, f.as_ref())?;
            let err = (g[(0, 0)] - exact[0]).abs().max((g[(1, 0)] - exact[1]).abs());
            println!(
                "{name:>8}, degree {degree:>2}: [{:.15}, {:.15}]  error {err:.2e}  (iterations {}, residual {:.1e})",
                g[(0, 0)],
                g[(1, 0)],
                report.total_iterations(),
                report.max_relative_residual()
            );
        }
    }
    Ok(())
}
