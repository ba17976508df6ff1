//! Evaluation of labelled collections: the measures against hand-computed rankings, the label
//! rules and files, every error, and a snapshot of a small generated labelled run.

use crate::common::small_settings;
use faer::Mat;
use mesh_fem::{generate, TriMesh};
use shape_retrieval::eval::{
    evaluate_collection, evaluate_distances, evaluate_index, evaluate_rankings, parse_labels, ClassRule, Measures,
};
use shape_retrieval::model::{RetrievalIndex, ShapeFeatures, VocabularyModel};
use shape_retrieval::RetrievalError;
use std::path::Path;
use wfem_base::Choice;

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

/// Five shapes, classes a a a b b, and rankings chosen by hand (see the expected values).
fn hand_rankings(q: usize) -> Result<Vec<usize>, RetrievalError> {
    Ok(match q {
        0 => vec![3, 1, 4, 2],
        1 => vec![0, 2, 3, 4],
        2 => vec![0, 1, 3, 4],
        3 => vec![4, 0, 1, 2],
        _ => vec![0, 1, 2, 3],
    })
}

fn close(a: f64, b: f64) {
    assert!((a - b).abs() < 1e-12, "{a} vs {b}");
}

#[test]
fn measures_of_one_ranking_by_hand() {
    // relevant at ranks 2 and 4 of 4 (R = 2).
    let m = Measures::of_ranking(&[false, true, false, true]).unwrap();
    close(m.map, 0.5 * (1.0 / 2.0 + 2.0 / 4.0));
    close(m.nn, 0.0);
    close(m.first_tier, 0.5);
    close(m.second_tier, 1.0);
    // P = 2/4, recall = 1 over the 4 (< 32) results.
    close(m.e_measure, 2.0 * 0.5 * 1.0 / 1.5);
    // (1/log2 2 + 1/log2 4) / (1 + 1/log2 2)
    close(m.dcg, 1.5 / 2.0);
    assert_eq!(Measures::of_ranking(&[false, false]), None);
}

#[test]
fn e_measure_looks_at_the_first_32_results() {
    // 40 results, relevant at ranks 1 and 40: within the first 32, P = 1/32 and recall 1/2.
    let mut rel = vec![false; 40];
    rel[0] = true;
    rel[39] = true;
    let m = Measures::of_ranking(&rel).unwrap();
    let (p, r) = (1.0 / 32.0, 0.5);
    close(m.e_measure, 2.0 * p * r / (p + r));
    close(m.second_tier, 0.5);
}

#[test]
fn collection_measures_by_hand() {
    let names = strings(&["a0", "a1", "a2", "b0", "b1"]);
    let classes = strings(&["a", "a", "a", "b", "b"]);
    let r = evaluate_rankings(&names, &classes, "test", hand_rankings).unwrap();
    assert_eq!((r.shapes, r.classes, r.queries), (5, 2, 5));
    // Per query (AP, NN, FT, ST, E, DCG), computed by hand:
    // q0 .5 0 .5 1 2/3 .75 | q1, q2: 1 1 1 1 2/3 1 | q3: 1 1 1 1 .4 1 | q4: .25 0 0 0 .4 .5
    close(r.overall.map, (0.5 + 1.0 + 1.0 + 1.0 + 0.25) / 5.0);
    close(r.overall.nn, 3.0 / 5.0);
    close(r.overall.first_tier, 3.5 / 5.0);
    close(r.overall.second_tier, 4.0 / 5.0);
    close(r.overall.e_measure, (3.0 * 2.0 / 3.0 + 2.0 * 0.4) / 5.0);
    close(r.overall.dcg, (0.75 + 3.0 + 0.5) / 5.0);
    assert_eq!(r.per_class.len(), 2);
    close(r.per_class[0].measures.map, 2.5 / 3.0);
    close(r.per_class[1].measures.map, 1.25 / 2.0);
    assert_eq!(r.worst_classes()[0].class, "b");
    // b's two queries have one first-tier place each and b1 gave its one to a0; a's three
    // queries have six places and a0 gave one to b0.
    assert_eq!(r.confusions.len(), 2);
    assert_eq!(
        (r.confusions[0].query.as_str(), r.confusions[0].retrieved.as_str()),
        ("b", "a")
    );
    close(r.confusions[0].share, 0.5);
    close(r.confusions[1].share, 1.0 / 6.0);
    assert_eq!(r.per_query[4].nearest.as_deref(), Some("a0"));
}

#[test]
fn distances_rank_like_the_hand_rankings() {
    // Distances that produce exactly the hand rankings (rank k+1 at distance k+1).
    let mut d = Mat::<f64>::zeros(5, 5);
    for q in 0..5 {
        for (k, j) in hand_rankings(q).unwrap().into_iter().enumerate() {
            d[(q, j)] = (k + 1) as f64;
        }
    }
    let names = strings(&["a0", "a1", "a2", "b0", "b1"]);
    let classes = strings(&["a", "a", "a", "b", "b"]);
    let by_matrix = evaluate_distances(&names, &classes, d.as_ref(), "test").unwrap();
    let by_hand = evaluate_rankings(&names, &classes, "test", hand_rankings).unwrap();
    assert_eq!(by_matrix, by_hand);
}

#[test]
fn a_shape_alone_in_its_class_is_not_a_query() {
    let names = strings(&["a0", "a1", "c0"]);
    let classes = strings(&["a", "a", "c"]);
    let r = evaluate_rankings(&names, &classes, "test", |q| Ok((0..3).filter(|&j| j != q).collect())).unwrap();
    assert_eq!((r.shapes, r.classes, r.queries), (3, 2, 2));
    assert!(r.per_query[2].measures.is_none());
    assert_eq!(r.per_class.len(), 1);
    close(r.overall.map, 1.0);
}

#[test]
fn bad_rankings_and_labels_are_errors() {
    let names = strings(&["a0", "a1", "b0"]);
    let classes = strings(&["a", "a", "b"]);
    // A ranking that repeats an item.
    let e = evaluate_rankings(&names, &classes, "t", |_| Ok(vec![1, 1])).unwrap_err();
    assert!(matches!(e, RetrievalError::DimensionMismatch { .. }), "{e}");
    // A ranking that holds the query.
    let e = evaluate_rankings(&names, &classes, "t", |q| Ok(vec![q, (q + 1) % 3])).unwrap_err();
    assert!(matches!(e, RetrievalError::DimensionMismatch { .. }), "{e}");
    // Classes of the wrong length.
    let e = evaluate_rankings(&names, &classes[..2], "t", hand_rankings).unwrap_err();
    assert!(matches!(e, RetrievalError::DimensionMismatch { .. }), "{e}");
    // No class with two shapes.
    let all = strings(&["a", "b", "c"]);
    let e = evaluate_rankings(&names, &all, "t", |q| Ok((0..3).filter(|&j| j != q).collect())).unwrap_err();
    assert!(matches!(e, RetrievalError::NothingToAverage { .. }), "{e}");
    // Empty.
    let e = evaluate_rankings(&[], &[], "t", hand_rankings).unwrap_err();
    assert!(matches!(e, RetrievalError::Empty { .. }), "{e}");
    // A non-finite or non-square distance matrix.
    let mut d = Mat::<f64>::zeros(3, 3);
    d[(0, 1)] = f64::NAN;
    let e = evaluate_distances(&names, &classes, d.as_ref(), "t").unwrap_err();
    assert!(matches!(e, RetrievalError::NonFinite { .. }), "{e}");
    let e = evaluate_distances(&names, &classes, Mat::<f64>::zeros(3, 2).as_ref(), "t").unwrap_err();
    assert!(matches!(e, RetrievalError::DimensionMismatch { .. }), "{e}");
}

#[test]
fn class_rules() {
    let folder = ClassRule::Folder;
    assert_eq!(
        folder.class_of(Path::new("data/chairs/chair_07.off")).unwrap(),
        "chairs"
    );
    let stem = ClassRule::Stem;
    assert_eq!(stem.class_of(Path::new("tosca/cat10.off")).unwrap(), "cat");
    assert_eq!(stem.class_of(Path::new("david_3.obj")).unwrap(), "david");
    assert_eq!(stem.class_of(Path::new("x/dog-12.ply")).unwrap(), "dog");
    // A name of digits has no class by the stem rule; a bare file name none by the folder rule.
    let e = stem.class_of(Path::new("x/0042.off")).unwrap_err();
    assert!(matches!(e, RetrievalError::Labels { .. }), "{e}");
    let e = folder.class_of(Path::new("cat0.off")).unwrap_err();
    assert!(matches!(e, RetrievalError::Labels { .. }), "{e}");
    for name in ClassRule::names() {
        assert_eq!(ClassRule::parse(name).unwrap().name(), name);
    }
    assert_eq!(ClassRule::parse("Parent"), Ok(ClassRule::Folder));
    assert!(ClassRule::parse("grandparent").is_err());
    assert_eq!(ClassRule::default(), ClassRule::Folder);
}

#[test]
fn label_files() {
    let text = "file,class\n# a comment\n\nshrec/T0.obj, snake\nshrec/T1.obj,ants\n";
    let pairs = parse_labels(text, "labels.csv").unwrap();
    assert_eq!(
        pairs,
        vec![
            ("shrec/T0.obj".to_string(), "snake".to_string()),
            ("shrec/T1.obj".to_string(), "ants".to_string())
        ]
    );
    // Without a header.
    assert_eq!(parse_labels("a.off,x\n", "l").unwrap().len(), 1);
    for (bad, line) in [
        ("a.off,x\nb.off\n", "l:2"),
        ("a.off,x\na.off,y\n", "l:2"),
        ("a.off,,\n", "l:1"),
        ("a.off,x,y\n", "l:1"),
    ] {
        match parse_labels(bad, "l").unwrap_err() {
            RetrievalError::Labels { location, .. } => assert_eq!(location, line, "{bad:?}"),
            e => panic!("{e}"),
        }
    }
    let e = parse_labels("file,class\n\n", "l").unwrap_err();
    assert!(matches!(e, RetrievalError::Labels { .. }), "{e}");
    // As spreadsheet programs write them (issue #41): a BOM, CRLF, quoted fields, another header.
    let excel = "\u{feff}File,Label\r\n\"shrec/a, b.obj\",snake\r\n\"say \"\"hi\"\".off\", \"ants\" \r\n";
    assert_eq!(
        parse_labels(excel, "l").unwrap(),
        vec![
            ("shrec/a, b.obj".to_string(), "snake".to_string()),
            ("say \"hi\".off".to_string(), "ants".to_string())
        ]
    );
    match parse_labels("\"a.off,x\n", "l").unwrap_err() {
        RetrievalError::Labels { location, reason } => {
            assert!(location == "l:1" && reason.contains("quoted"), "{reason}")
        }
        e => panic!("{e}"),
    }
}

/// Three classes of three generated shapes each: spheres, tori, ellipsoids, each member a
/// different resolution or proportion.
fn labelled_collection() -> (Vec<(String, TriMesh)>, Vec<String>) {
    let stretch = |m: TriMesh, s: [f64; 3]| {
        TriMesh::new(
            m.positions()
                .iter()
                .map(|p| [s[0] * p[0], s[1] * p[1], s[2] * p[2]])
                .collect(),
            m.faces().to_vec(),
        )
        .unwrap()
    };
    let mut meshes = Vec::new();
    let mut classes = Vec::new();
    for (i, level) in [2u32, 3, 2].into_iter().enumerate() {
        meshes.push((
            format!("sphere{i}"),
            stretch(generate::icosphere(level), [1.0, 1.0, 1.0 + 0.05 * i as f64]),
        ));
        classes.push("sphere".to_string());
    }
    for (i, (minor, nu)) in [(0.4, 24), (0.38, 28), (0.42, 20)].into_iter().enumerate() {
        meshes.push((format!("torus{i}"), generate::torus(1.0, minor, nu, nu / 2)));
        classes.push("torus".to_string());
    }
    for (i, (a, level)) in [(2.2, 2u32), (2.0, 3), (2.4, 2)].into_iter().enumerate() {
        meshes.push((
            format!("ellipsoid{i}"),
            stretch(generate::icosphere(level), [a, 1.0, 0.6]),
        ));
        classes.push("ellipsoid".to_string());
    }
    (meshes, classes)
}

#[test]
fn snapshot_of_a_small_labelled_evaluation() {
    let (meshes, classes) = labelled_collection();
    let settings = small_settings();
    let run = evaluate_collection(&meshes, &classes, &settings, None).unwrap();
    assert_eq!(run.index.entries().len(), 9);
    assert!(run.report.vocabulary.contains("optimistic"));
    // The same from a built index (what the CLI's eval stores and ranks).
    let again = evaluate_index(&run.index, &classes, &run.report.vocabulary).unwrap();
    assert_eq!(again, run.report);
    insta::assert_snapshot!("small_labelled_evaluation", run.report.to_text());
}

#[test]
fn an_outside_vocabulary_is_reported_as_such() {
    let (meshes, classes) = labelled_collection();
    let settings = small_settings();
    let other = vec![
        ("bumpy".to_string(), generate::bumpy(2)),
        ("torus-fat".to_string(), generate::torus(1.0, 0.6, 24, 12)),
    ];
    let features = ShapeFeatures::compute_many(&other, &settings.descriptor, &settings.bags).unwrap();
    let vocabulary = VocabularyModel::train(&settings.descriptor, &settings.training, &features).unwrap();
    let run = evaluate_collection(&meshes, &classes, &settings, Some(vocabulary)).unwrap();
    assert_eq!(run.report.vocabulary, "trained on 2 other shapes");
    // One indexed shape among the training shapes makes the evaluation optimistic.
    let mut mixed = other.clone();
    mixed.push(meshes[0].clone());
    let features = ShapeFeatures::compute_many(&mixed, &settings.descriptor, &settings.bags).unwrap();
    let vocabulary = VocabularyModel::train(&settings.descriptor, &settings.training, &features).unwrap();
    let run_mixed = evaluate_collection(&meshes, &classes, &settings, Some(vocabulary)).unwrap();
    assert_eq!(
        run_mixed.report.vocabulary,
        "trained on 3 shapes, 1 of them indexed (optimistic)"
    );
    let e = evaluate_collection(&meshes, &classes[1..], &settings, None).unwrap_err();
    assert!(matches!(e, RetrievalError::DimensionMismatch { .. }), "{e}");
    let index: &RetrievalIndex = &run.index;
    let e = evaluate_index(index, &classes[1..], "t").unwrap_err();
    assert!(matches!(e, RetrievalError::DimensionMismatch { .. }), "{e}");
}
