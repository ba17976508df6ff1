//! A collection with a shape that cannot be described (issue #25): left out and reported by
//! default, fatal when strict, every usable shape indexed exactly as the strict build would;
//! progress reported once per shape; an interrupted collection stops (issue #23).

use crate::common::{small_collection, small_settings};
use mesh_fem::TriMesh;
use shape_retrieval::collection::{build_index, describe_collection, Tolerance};
use shape_retrieval::model::RetrievalIndex;
use shape_retrieval::RetrievalError;
use shifted_solve::SolveError;
use std::sync::Mutex;
use wfem_base::interrupt::Interrupt;
use wfem_heat::HeatError;

/// A mesh that reads but cannot be described: one of its two faces has zero area.
fn too_small() -> (String, TriMesh) {
    let mesh = TriMesh::new(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2], [0, 1, 3]],
    )
    .unwrap();
    ("tiny".into(), mesh)
}

#[test]
fn an_unusable_shape_is_left_out_and_named() {
    let good = small_collection();
    let mut shapes = good.clone();
    shapes.insert(1, too_small());
    let seen = Mutex::new(Vec::new());
    let (index, refused) = build_index(&shapes, &small_settings(), None, Tolerance::Skip, &|n| {
        seen.lock().unwrap().push(n.to_string())
    })
    .unwrap();
    assert_eq!(refused.len(), 1);
    assert_eq!(refused[0].name, "tiny");
    assert!(!refused[0].reason.to_string().is_empty());
    // Exactly the index of the usable shapes alone.
    let strict = RetrievalIndex::build(&good, &small_settings(), None).unwrap();
    assert_eq!(index.entries(), strict.entries());
    // One progress step per shape, the refused one included.
    let mut seen = seen.into_inner().unwrap();
    seen.sort();
    let mut names: Vec<String> = shapes.iter().map(|(n, _)| n.clone()).collect();
    names.sort();
    assert_eq!(seen, names);
}

#[test]
fn strict_fails_on_the_first_unusable_shape_by_name() {
    let mut shapes = small_collection();
    shapes.push(too_small());
    let err = build_index(&shapes, &small_settings(), None, Tolerance::Strict, &|_| ()).unwrap_err();
    assert!(
        matches!(&err, RetrievalError::Shape { name, .. } if name == "tiny"),
        "{err}"
    );
    // RetrievalIndex::build is the strict one.
    let err = RetrievalIndex::build(&shapes, &small_settings(), None).unwrap_err();
    assert!(
        matches!(&err, RetrievalError::Shape { name, .. } if name == "tiny"),
        "{err}"
    );
}

#[test]
fn nothing_usable_names_every_shape() {
    let shapes = vec![too_small(), ("tiny2".to_string(), too_small().1)];
    let err = build_index(&shapes, &small_settings(), None, Tolerance::Skip, &|_| ()).unwrap_err();
    match &err {
        RetrievalError::NothingUsable { shapes: 2, reasons } => {
            assert!(reasons.contains("tiny:") && reasons.contains("tiny2:"), "{reasons}")
        }
        other => panic!("{other}"),
    }
    // Describing alone reports them without failing.
    let s = small_settings();
    let d = describe_collection(&shapes, &s.descriptor, &s.bags, Tolerance::Skip, &|_| ()).unwrap();
    assert!(d.features.is_empty() && d.refused.len() == 2);
}

#[test]
fn an_interrupted_collection_stops_with_interrupted() {
    let shapes = small_collection();
    let s = small_settings();
    let interrupt = Interrupt::new();
    interrupt.raise();
    // Skip must not turn the interruption into refusals.
    for tolerance in [Tolerance::Skip, Tolerance::Strict] {
        let err = interrupt
            .install(|| describe_collection(&shapes, &s.descriptor, &s.bags, tolerance, &|_| ()))
            .unwrap_err();
        let interrupted = matches!(&err, RetrievalError::Heat(HeatError::Solve(SolveError::Interrupted(_))))
            || matches!(&err, RetrievalError::Shape { source, .. }
                if matches!(**source, RetrievalError::Heat(HeatError::Solve(SolveError::Interrupted(_)))));
        assert!(interrupted, "{tolerance:?}: {err}");
    }
    // Not raised: the same call succeeds.
    let fresh = Interrupt::new();
    let d = fresh
        .install(|| describe_collection(&shapes, &s.descriptor, &s.bags, Tolerance::Skip, &|_| ()))
        .unwrap();
    assert_eq!(d.features.len(), shapes.len());
}
