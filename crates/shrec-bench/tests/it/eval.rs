//! End-to-end run of `cargo xtask shrec-eval --subset small` on real TOSCA shapes (generated
//! into a temporary folder), with its rounded tables snapshotted.

use shrec_bench::eval::{markdown, run, verdicts, EvalOptions, Subset};

#[test]
fn small_subset_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let opts = EvalOptions {
        data_dir: dir.path().to_path_buf(),
        meshes_dir: Some(mesh_fem::corpus::meshes_dir().unwrap()),
        subset: Subset::Small,
        seed: 2010,
    };
    let report = run(&opts).unwrap();
    assert_eq!(report.n_null, 2);
    assert_eq!(report.n_transformed, 2 * 4 * 2);
    // Sanity of the metrics: repeatabilities and mAPs in [0, 1], distances ≥ 0, and on the
    // scale class the scale-invariant DHK3 is (near) exact while DHK2 is not.
    for row in report.repeatability.iter().chain(&report.retrieval) {
        assert!(row.values.iter().flatten().all(|v| (0.0..=1.0).contains(v)), "{row:?}");
    }
    let scale5 = report
        .robustness
        .iter()
        .find(|r| r.class == "scale" && r.strength == 5)
        .unwrap();
    let (dhk2, dhk3) = (scale5.values[1].unwrap(), scale5.values[2].unwrap());
    assert!(dhk3 < 1e-6 && dhk2 > 0.1, "{scale5:?}");
    assert!(!verdicts(&report).is_empty());
    // A second run reuses the generated data (manifest covers the subset) and is identical.
    let again = run(&opts).unwrap();
    assert_eq!(markdown(&again), markdown(&report));
    insta::assert_snapshot!("shrec_eval_small", markdown(&report));
}
