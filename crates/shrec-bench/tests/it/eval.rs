//! End-to-end run of `cargo xtask shrec-eval --subset small` on real TOSCA shapes (generated
//! into a temporary folder), with its rounded tables snapshotted: a change of default recipe,
//! protocol or generator shows in review as a changed snapshot.

use shrec_bench::eval::{markdown, run, verdicts, EvalOptions, Subset, VocabularySource};
use shrec_bench::protocol::EigenCache;

#[test]
fn small_subset_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let opts = EvalOptions {
        data_dir: dir.path().to_path_buf(),
        meshes_dir: wfem_corpus::meshes_dir().unwrap(),
        subset: Subset::Small,
        seed: 2010,
        cache: EigenCache::none(),
    };
    let report = run(&opts).unwrap();
    assert_eq!(report.n_null, 2);
    assert_eq!(report.n_transformed, 2 * 4 * 2);
    // Sanity of the metrics: repeatabilities and mAPs in [0, 1], distances ≥ 0, and on the
    // scale class the scale-invariant DHK3 is (near) exact while DHK2 is not.
    for row in &report.repeatability {
        assert!(row.values.iter().flatten().all(|v| (0.0..=1.0).contains(v)), "{row:?}");
    }
    for row in &report.robustness {
        assert!(row.values.iter().flatten().all(|v| *v >= 0.0), "{row:?}");
    }
    let names: Vec<&str> = report.retrieval.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["wFEM SI-HKS (default)", "SG1 (ours)", "SG2 (ours)"]);
    for m in &report.retrieval {
        assert_eq!(m.vocabulary, VocabularySource::NullShapes);
        // 16 queries; the small subset has strengths 1 and 5 only.
        assert_eq!(m.shrec.queries.len(), 16, "{}", m.name);
        let all = |_: &shrec_bench::protocol::QueryResult| true;
        for v in m
            .shrec
            .cumulative(all)
            .into_iter()
            .chain(m.shrec.cumulative_clean(all))
            .chain(m.shrec.cumulative_full(all))
        {
            assert!((0.0..=1.0).contains(&v), "{}: {v}", m.name);
        }
        // Cumulative columns: the strength-1 queries are in every column, so column ≤ 5
        // (database and queries grow) differs from ≤ 1 only through the strength-5 shapes.
        assert!(m
            .shrec
            .queries
            .iter()
            .all(|q| q.ap_cumulative[0].is_some() == (q.strength == 1)));
        assert!(m.shrec.queries.iter().all(|q| q.ap_cumulative[4].is_some()));
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
