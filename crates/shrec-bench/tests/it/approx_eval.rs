//! The feature-driven approximation benchmark (issue #24) on its small cases: the smooth maps
//! meet the paper's 2 % at the finest scale with the defaults, the anchors keep f's values,
//! f_glob has no spurious persistent extrema, and a snapshot of the rounded metrics pins the
//! defaults (a change of rule, sampling or threshold shows in review). Issue #40: on the noisy
//! maps at σ = 5 % the default at its own scale is within the bounds of the oracle, on the
//! clean maps it finds no noise to remove, and a second snapshot pins the rounded errors of the
//! noisy-map column.

use shrec_bench::approx_eval::denoise::{DENOISE_LEVELS, REQUIRED_LEVEL};
use shrec_bench::approx_eval::{
    evaluate_case, falls_with_persistence, load_case, BenchField, CaseResult, ERROR_THRESHOLD, SMALL_CASES,
};
use shrec_bench::BenchError;
use std::fmt::Write as _;

fn rounded(results: &[CaseResult]) -> String {
    let mut s = String::new();
    let pct = |x: f64| format!("{:.1}", 100.0 * x);
    for c in results {
        let _ = writeln!(s, "{} ({} vertices)", c.case.name, c.n_vertices);
        for f in &c.fields {
            let m = &f.smooth;
            let _ = writeln!(
                s,
                "  {}: smooth {} anchors, finest {} %, coarsest {} %, paper t1 {} %, literal {} %, extrema {}/{}/{}",
                f.field.name(),
                m.anchors,
                pct(m.finest_error),
                pct(m.coarsest_error),
                pct(m.paper_scales_error),
                pct(m.literal_error),
                m.persistent_extrema.0,
                m.persistent_extrema.1,
                m.persistent_extrema.2,
            );
            let anchors: Vec<String> = f.noisy.iter().map(|r| r.anchors.to_string()).collect();
            let crit: Vec<String> = f.noisy.iter().map(|r| r.critical_points.to_string()).collect();
            let first = &f.noisy[0];
            let _ = writeln!(
                s,
                "  {}: noisy anchors {}, to clean {} % (corr {:.2}), critical {}, smooth {} % (corr {:.2}), literal {} %",
                f.field.name(),
                anchors.join("/"),
                pct(first.error),
                first.correlation,
                crit.join("/"),
                pct(f.smoother_floor.1),
                f.smoother_floor.2,
                pct(f.literal_error),
            );
        }
    }
    s
}

#[test]
fn small_cases_meet_the_smooth_threshold_and_pin_the_defaults() {
    let meshes = wfem_corpus::meshes_dir().expect("the mesh corpus is required (or set WFEM_MESHES)");
    let results: Vec<CaseResult> = SMALL_CASES.iter().map(|c| evaluate_case(&meshes, c).unwrap()).collect();
    for c in &results {
        assert_eq!(c.fields.len(), BenchField::ALL.len());
        for f in &c.fields {
            let m = &f.smooth;
            let what = format!("{} {}", c.case.name, f.field.name());
            assert!(m.finest_error < ERROR_THRESHOLD, "{what}: {}", m.finest_error);
            assert!(m.anchor_error < 1e-6, "{what}: {}", m.anchor_error);
            assert!(
                m.persistent_extrema.0 <= m.persistent_extrema.2,
                "{what}: {:?}",
                m.persistent_extrema
            );
            // The paper's formula is nowhere near its claim.
            assert!(m.literal_error > 0.3, "{what}: {}", m.literal_error);
            assert!(falls_with_persistence(&f.noisy), "{what}: {:?}", f.noisy);
            // Issue #40: the clean map is left as it is; the noisy one is denoised within the
            // bounds at σ = 5 %.
            assert!(!f.smooth_denoised, "{what}");
            assert_eq!(f.denoising.len(), DENOISE_LEVELS.len());
            for d in &f.denoising {
                if d.sigma == REQUIRED_LEVEL {
                    assert!(d.chosen_t.is_some(), "{what}: {d:?}");
                    assert!(d.meets_the_bounds(), "{what}: {d:?}");
                }
                assert!((d.estimated_sigma / d.sigma - 1.0).abs() < 0.3, "{what}: {d:?}");
            }
        }
    }
    insta::assert_snapshot!("approx_eval_small", rounded(&results));
    insta::assert_snapshot!("approx_eval_small_denoising", rounded_denoising(&results));
}

/// The noisy-map column (issue #40), rounded: per map and level, σ̂/σ, t*·λ₂₀ and the
/// oracle's and the default's L∞ and L2 errors in per cent of the range.
fn rounded_denoising(results: &[CaseResult]) -> String {
    let mut s = String::new();
    for c in results {
        let _ = writeln!(s, "{}", c.case.name);
        for f in &c.fields {
            for d in &f.denoising {
                let _ = writeln!(
                    s,
                    "  {} σ {:.1} %: σ̂/σ {:.2}, t* {}, L∞ {:.2} % (oracle {:.2} %), L2 {:.2} % (oracle {:.2} %), corr {:.2}",
                    f.field.name(),
                    100.0 * d.sigma,
                    d.estimated_sigma / d.sigma,
                    d.chosen_t.map_or("kept".into(), |t| format!("{t:.3}")),
                    100.0 * d.linf,
                    100.0 * d.oracle.linf,
                    100.0 * d.l2,
                    100.0 * d.oracle.l2,
                    d.correlation,
                );
            }
        }
    }
    s
}

/// A heat-kernel failure inside the benchmark is `BenchError::Heat` (here a negative time).
#[test]
fn heat_errors_are_reported_as_such() {
    let meshes = wfem_corpus::meshes_dir().expect("the mesh corpus is required (or set WFEM_MESHES)");
    let (mesh, kernel, _) = load_case(&meshes, &SMALL_CASES[0]).unwrap();
    let err = BenchField::Distance.values(&mesh, &kernel, -1.0).unwrap_err();
    assert!(
        matches!(err, BenchError::Heat(wfem_heat::HeatError::InvalidTime { .. })),
        "{err:?}"
    );
}
