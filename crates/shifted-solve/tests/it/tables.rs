//! The shipped rational approximations against e^{-x} itself (paper Eq. (10), docs/NUMERICS.md §2.2).
#![allow(clippy::excessive_precision)] // published constants are quoted verbatim
use faer::c64;
use shifted_solve::poles::{RationalApprox, DEFAULT_DEGREE, PAPER_DEGREE};
use shifted_solve::*;

fn grid() -> Vec<f64> {
    let mut xs: Vec<f64> = (0..=20_000).map(|k| k as f64 * 0.01).collect();
    xs.extend((0..=700).map(|k| 10f64.powf(2.3 + 7.7 * k as f64 / 700.0)));
    xs
}

#[test]
fn every_table_is_within_its_uniform_error_bound() {
    let xs = grid();
    for approx in RationalApprox::all() {
        let err = xs
            .iter()
            .map(|&x| (approx.eval(x) - (-x).exp()).abs())
            .fold(0.0, f64::max);
        let bound = (1.05 * approx.max_error).max(4e-14);
        assert!(err <= bound, "degree {}: max error {err:e} > {bound:e}", approx.degree);
        // Best approximations equioscillate: the error reaches E_n (down to the f64 floor).
        if approx.max_error > 1e-12 {
            assert!(err >= 0.99 * approx.max_error, "degree {}: {err:e}", approx.degree);
        }
    }
}

#[test]
fn structure_of_the_tables() {
    for approx in RationalApprox::all() {
        let n = approx.degree;
        assert_eq!(approx.poles.len(), n / 2);
        assert_eq!(approx.residues.len(), n / 2);
        assert_eq!(approx.real_pole.is_some(), n % 2 == 1);
        assert_eq!(approx.n_solves(), n.div_ceil(2));
        assert!(approx.poles.iter().all(|z| z.im > 0.0));
        if let Some((z, _)) = approx.real_pole {
            assert!(z < 0.0, "real pole must be negative so that tL − zB is SPD");
        }
        // c0 = r(∞) = ±E_n and r(0) = 1 ∓ E_n (equioscillation includes 0 and ∞).
        assert_eq!(approx.c0.abs(), approx.max_error);
        assert!((approx.eval(1e300) - approx.c0).abs() < 1e-20);
        if approx.max_error > 1e-12 {
            let r0 = approx.eval(0.0) - 1.0;
            assert!((r0.abs() / approx.max_error - 1.0).abs() < 1e-3, "degree {n}");
            // 2n+2 alternation points with 0 and ∞ at the ends: e(0) and e(∞) = c0 differ in sign.
            assert!(r0 * approx.c0 < 0.0, "degree {n}");
        }
        assert!(RationalApprox::cram(n).is_ok());
    }
    assert!(matches!(
        RationalApprox::cram(9),
        Err(SolveError::UnsupportedDegree { degree: 9, .. })
    ));
    assert!(matches!(
        RationalApprox::cram(0),
        Err(SolveError::UnsupportedDegree { .. })
    ));
    assert_eq!(RationalApprox::cram(DEFAULT_DEGREE).unwrap().n_solves(), 8);
    assert_eq!(RationalApprox::cram(PAPER_DEGREE).unwrap().n_solves(), 4);
}

/// Pusa (2011, corrected 2012) CRAM-14 in the nuclear convention: θ, α with
/// exp(z) ≈ α0 + Σ α/(z − θ); the mapping is θ = −conj z, α = −conj c (docs/NUMERICS.md §0.1, §2.3).
#[test]
fn degree_14_matches_pusa_published_values() {
    let a = RationalApprox::cram(14).unwrap();
    let theta = c64::new(5.6231425727459771248, 1.1940690463439669766);
    let alpha = c64::new(-2.7875161940145646468e1, -1.0214733999056451434e2);
    let (t, al) = a.paper_poles()[0];
    assert!((t - theta).norm() / theta.norm() < 1e-15, "{t}");
    assert!((al - alpha).norm() / alpha.norm() < 1e-15, "{al}");
    // Both members of each pair plus the real pole: n poles in the paper's form.
    assert_eq!(RationalApprox::cram(7).unwrap().paper_poles().len(), 7);
}

/// Sums over all n poles in the paper's form reproduce r_n: α0 − Σ α/(−x − θ) with x ↦ z = −x.
#[test]
fn paper_form_evaluates_to_the_same_function() {
    for approx in RationalApprox::all() {
        for x in [0.0, 0.3, 2.0, 11.0, 80.0] {
            let z = c64::new(-x, 0.0);
            let mut s = c64::new(approx.c0, 0.0);
            for (theta, alpha) in approx.paper_poles() {
                s += alpha / (z - theta);
            }
            assert!((s.re - approx.eval(x)).abs() < 1e-13, "degree {}", approx.degree);
            assert!(s.im.abs() < 1e-13);
        }
    }
}
