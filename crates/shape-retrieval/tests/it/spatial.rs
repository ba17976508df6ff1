//! Spatially sensitive bags and global signatures against independent dense references, their
//! invariances, storage round trips and errors.

use crate::common::{dense_spectrum, small_collection, small_settings};
use faer::Mat;
use mesh_fem::generate::{bumpy, icosphere};
use shape_retrieval::global::{GlobalKind, Measure, BIHARMONIC_BINS};
use shape_retrieval::model::{DescriptorSettings, GlobalSignature, RetrievalIndex, ShapeFeatures, VertexWeights};
use shape_retrieval::spatial::{grouped, word_groups, ShapeSpectrum, SpatialBag};
use shape_retrieval::store::{IndexStore, JsonFile};
use shape_retrieval::RetrievalError;
use wfem_base::Choice;

/// A fixed assignment Θ (n × V, rows summing to 1) from a smooth function of the position.
fn assignment(mesh: &mesh_fem::TriMesh, v: usize) -> Mat<f64> {
    let p = mesh.positions();
    Mat::from_fn(p.len(), v, |i, a| {
        let raw: Vec<f64> = (0..v).map(|b| (1.0 + (b as f64 + 1.0) * p[i][b % 3]).exp()).collect();
        raw[a] / raw.iter().sum::<f64>()
    })
}

#[test]
fn spatial_histogram_is_the_heat_flow_between_words() {
    // Reference: F = Θᵀ W (Φ e^{−tΛ} Φᵀ) W Θ with the full dense spectrum of (L, B).
    let mesh = bumpy(1);
    let s = dense_spectrum(&mesh);
    let n = mesh.n_vertices();
    let theta = assignment(&mesh, 4);
    let weights: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * (i % 5) as f64).collect();
    let area: f64 = shape_retrieval::bof::vertex_areas(s.ops.mass.as_ref()).iter().sum();
    let bag = SpatialBag {
        time: 0.01,
        groups: None,
    };
    let t = 0.01 * area;
    let kernel = Mat::from_fn(n, n, |i, j| {
        (0..n)
            .map(|c| s.eigenvectors[(i, c)] * (-s.eigenvalues[c] * t).exp() * s.eigenvectors[(j, c)])
            .sum::<f64>()
    });
    let wt = Mat::from_fn(n, 4, |i, a| weights[i] * theta[(i, a)]);
    let f = wt.transpose() * &kernel * &wt;
    let mut want = Vec::new();
    for a in 0..4 {
        for b in a..4 {
            want.push(if a == b { f[(a, b)] } else { 2.0 * f[(a, b)] });
        }
    }
    let total: f64 = want.iter().sum();
    let spectrum = ShapeSpectrum {
        values: s.eigenvalues.clone(),
        vectors: s.eigenvectors.clone(),
        area,
    };
    let got = bag.histogram(theta.as_ref(), &weights, &spectrum).unwrap();
    assert_eq!(got.len(), SpatialBag::bins(4));
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w / total).abs() < 1e-12, "{g} vs {}", w / total);
    }
    assert!((got.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    // Errors: mismatched sizes, zero weights, a bad time.
    let e = bag.histogram(theta.as_ref(), &weights[1..], &spectrum).unwrap_err();
    assert!(matches!(e, RetrievalError::DimensionMismatch { .. }), "{e}");
    let e = bag.histogram(theta.as_ref(), &vec![0.0; n], &spectrum).unwrap_err();
    assert!(matches!(e, RetrievalError::InvalidModel { .. }), "{e}");
    let e = SpatialBag {
        time: -1.0,
        groups: None,
    }
    .histogram(theta.as_ref(), &weights, &spectrum)
    .unwrap_err();
    assert!(matches!(e, RetrievalError::InvalidParameter { .. }), "{e}");
}

/// The full V × V matrix of a spatial histogram (upper triangle, off-diagonal doubled).
fn flow_matrix(hist: &[f64], v: usize) -> Mat<f64> {
    let mut f = Mat::<f64>::zeros(v, v);
    let mut k = 0;
    for a in 0..v {
        for b in a..v {
            let x = if a == b { hist[k] } else { 0.5 * hist[k] };
            f[(a, b)] = x;
            f[(b, a)] = x;
            k += 1;
        }
    }
    f
}

#[test]
fn grouped_flow_is_the_word_flow_summed_over_groups() {
    // F is bilinear in Θ, so the flow between groups is Gᵀ F G (G the V × G membership matrix):
    // checked against the words' own histogram, not against the grouped code path.
    let mesh = bumpy(1);
    let s = dense_spectrum(&mesh);
    let n = mesh.n_vertices();
    let v = 5;
    let theta = assignment(&mesh, v);
    let weights = vec![1.0; n];
    let spectrum = ShapeSpectrum {
        values: s.eigenvalues.clone(),
        vectors: s.eigenvectors.clone(),
        area: shape_retrieval::bof::vertex_areas(s.ops.mass.as_ref()).iter().sum(),
    };
    let bag = SpatialBag::default();
    let words = flow_matrix(&bag.histogram(theta.as_ref(), &weights, &spectrum).unwrap(), v);
    let group = [1u32, 0, 1, 2, 0];
    let g = grouped(theta.as_ref(), &group, 3).unwrap();
    for i in 0..n {
        assert!((g.row(i).iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert_eq!(g[(i, 2)], theta[(i, 3)]);
    }
    let got = flow_matrix(&bag.histogram(g.as_ref(), &weights, &spectrum).unwrap(), 3);
    let member = Mat::from_fn(v, 3, |a, c| if group[a] as usize == c { 1.0 } else { 0.0 });
    let want = member.transpose() * &words * &member;
    for a in 0..3 {
        for b in 0..3 {
            assert!((got[(a, b)] - want[(a, b)]).abs() < 1e-12, "{a},{b}");
        }
    }
    let e = grouped(theta.as_ref(), &group[1..], 3).unwrap_err();
    assert!(matches!(e, RetrievalError::DimensionMismatch { .. }), "{e}");
}

#[test]
fn word_groups_are_the_clusters_of_the_words() {
    // Two tight clusters of three words each, far apart: two groups split them exactly.
    let centres = [
        [0.0, 0.0],
        [0.1, 0.0],
        [0.0, 0.1],
        [10.0, 10.0],
        [10.1, 10.0],
        [10.0, 9.9],
    ];
    let words = Mat::from_fn(6, 2, |i, j| centres[i][j]);
    let g = word_groups(words.as_ref(), 2).unwrap();
    assert_eq!(g[0], g[1]);
    assert_eq!(g[0], g[2]);
    assert_eq!(g[3], g[4]);
    assert_eq!(g[3], g[5]);
    assert_ne!(g[0], g[3]);
    // As many groups as words or more: each word is its own group.
    assert_eq!(word_groups(words.as_ref(), 6).unwrap(), vec![0, 1, 2, 3, 4, 5]);
    assert_eq!(word_groups(words.as_ref(), 60).unwrap(), vec![0, 1, 2, 3, 4, 5]);
    let e = word_groups(words.as_ref(), 0).unwrap_err();
    assert!(matches!(e, RetrievalError::InvalidParameter { .. }), "{e}");
    let e = SpatialBag {
        groups: Some(0),
        ..SpatialBag::default()
    }
    .validate()
    .unwrap_err();
    assert!(matches!(e, RetrievalError::InvalidParameter { .. }), "{e}");
}

#[test]
fn grouped_spatial_bags_have_g_classes_and_round_trip() {
    let shapes = small_collection();
    let mut settings = spatial_settings();
    settings.bags.spatial = Some(SpatialBag {
        groups: Some(3),
        ..SpatialBag::default()
    });
    let index = RetrievalIndex::build(&shapes, &settings, None).unwrap();
    let v = index.vocabulary().vocabulary().size();
    assert!(v > 3);
    let groups = word_groups(index.vocabulary().vocabulary().words(), 3).unwrap();
    for e in index.entries() {
        let bag = &e.signature.bag;
        assert_eq!(bag.len(), v + SpatialBag::bins(3));
        assert_eq!(bag.len(), index.bags().bag_len(v));
        let (plain, flow) = bag.split_at(v);
        assert!((flow.iter().sum::<f64>() - 0.5).abs() < 1e-12);
        // Half the mass in the plain bag, half in the flow between groups.
        assert!((plain.iter().sum::<f64>() - 0.5).abs() < 1e-12);
    }
    // The word-level spatial bag of the same vocabulary, summed over the groups, is the grouped one.
    let words_level = RetrievalIndex::new(index.vocabulary().clone(), spatial_settings().bags).unwrap();
    let f = words_level.features("bumpy", &shapes[0].1).unwrap();
    let full = words_level.signature(&f).unwrap().bag;
    let member = Mat::from_fn(v, 3, |a, c| if groups[a] as usize == c { 1.0 } else { 0.0 });
    let want = member.transpose() * &flow_matrix(&full[v..], v) * &member;
    let got = flow_matrix(&index.entries()[0].signature.bag[v..], 3);
    for a in 0..3 {
        for b in 0..3 {
            // Not to rounding: with k = 30 eigenpairs a few word-pair flows dip below zero and are
            // clipped before the words' histogram is normalised (exact with the whole spectrum:
            // `grouped_flow_is_the_word_flow_summed_over_groups`).
            let (g, w) = (got[(a, b)], want[(a, b)]);
            assert!((g - w).abs() < 1e-3, "{a},{b}: {g} vs {w} (of a total mass ½)");
        }
    }
    // Stored and read back: the same bags, and a query of a stored shape finds itself.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("index.json");
    JsonFile::new(&path).save_index(&index).unwrap();
    let back = JsonFile::new(&path).load_index().unwrap();
    assert_eq!(back.bags(), index.bags());
    assert_eq!(back.entries(), index.entries());
    let again = back.describe("again", &shapes[1].1).unwrap();
    assert_eq!(again.signature.bag, index.entries()[1].signature.bag);
    // A file without the field reads as spatial bags over the words.
    let old: SpatialBag = serde_json::from_str(r#"{"time": 0.01}"#).unwrap();
    assert_eq!(old.groups, None);
}

fn spatial_settings() -> shape_retrieval::model::RetrievalSettings {
    let mut settings = small_settings();
    settings.bags.spatial = Some(SpatialBag::default());
    settings
}

#[test]
fn spatial_bags_are_half_plain_half_flow_and_scale_invariant() {
    let shapes = small_collection();
    let settings = spatial_settings();
    let index = RetrievalIndex::build(&shapes, &settings, None).unwrap();
    let v = index.vocabulary().vocabulary().size();
    for e in index.entries() {
        let bag = &e.signature.bag;
        assert_eq!(bag.len(), v + SpatialBag::bins(v));
        let (plain, flow) = bag.split_at(v);
        assert!((plain.iter().sum::<f64>() - 0.5).abs() < 1e-12);
        assert!((flow.iter().sum::<f64>() - 0.5).abs() < 1e-12);
    }
    // The plain half is the bag without spatial bags (same vocabulary).
    let mut plain_settings = settings.clone();
    plain_settings.bags.spatial = None;
    let plain = RetrievalIndex::new(index.vocabulary().clone(), plain_settings.bags.clone()).unwrap();
    let f = plain.features("bumpy", &shapes[0].1).unwrap();
    let sig = plain.signature(&f).unwrap();
    for (a, b) in sig.bag.iter().zip(&index.entries()[0].signature.bag) {
        assert!((0.5 * a - b).abs() < 1e-12);
    }
    // Scale invariant: a copy ×50 is at distance ~0 from its original.
    let copy = index.describe("copy", &shapes[0].1.scaled(50.0).unwrap()).unwrap();
    let ranked = index.rank(&copy.signature).unwrap();
    assert_eq!(ranked[0].entry, 0);
    assert!(ranked[0].distance < 1e-9, "{ranked:?}");
}

#[test]
fn spatial_indexes_round_trip_and_plain_files_stay_plain() {
    let shapes = small_collection();
    let index = RetrievalIndex::build(&shapes, &spatial_settings(), None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("index.json");
    JsonFile::new(&path).save_index(&index).unwrap();
    let back = JsonFile::new(&path).load_index().unwrap();
    assert_eq!(back.entries(), index.entries());
    assert_eq!(back.bags(), index.bags());
    // An index written without the field holds plain bags and reads as such.
    let mut plain_settings = small_settings();
    plain_settings.bags.spatial = None;
    let plain = RetrievalIndex::build(&shapes, &plain_settings, None).unwrap();
    JsonFile::new(&path).save_index(&plain).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(!text.contains("spatial"));
    assert_eq!(JsonFile::new(&path).load_index().unwrap().bags().spatial, None);
    // A bag of the wrong length for the settings is refused.
    let mut broken = index.entries().to_vec();
    broken[0].signature.bag.truncate(5);
    let e = RetrievalIndex::from_parts(index.vocabulary().clone(), index.bags().clone(), broken).unwrap_err();
    assert!(matches!(e, RetrievalError::InvalidModel { .. }), "{e}");
    // Features without their eigenpairs cannot make a spatial bag.
    let mut f =
        ShapeFeatures::compute("b", &shapes[0].1, &small_settings().descriptor, &small_settings().bags).unwrap();
    f.spectrum = None;
    let e = index.signature(&f).unwrap_err();
    assert!(matches!(e, RetrievalError::InvalidModel { .. }), "{e}");
}

#[test]
fn weyl_shape_dna_matches_the_dense_spectrum() {
    let mesh = bumpy(2);
    // The spectrum of the mesh as given (refined, it would be another discretisation).
    let settings = DescriptorSettings {
        eigenpairs: 12,
        refinement: None,
        ..Default::default()
    };
    let g = GlobalSignature {
        kind: GlobalKind::WeylShapeDna,
        eigenvalues: 10,
        weight: 1.0,
    };
    let got = g.compute(&mut settings.shape(&mesh).unwrap()).unwrap();
    let s = dense_spectrum(&mesh);
    let area = mesh.area();
    for (i, x) in got.iter().enumerate() {
        let want = s.eigenvalues[i + 1] * area / (4.0 * std::f64::consts::PI * (i + 1) as f64);
        assert!((x - want).abs() < 1e-7 * want, "{i}: {x} vs {want}");
    }
    // Its distance is Euclidean; the logarithmic kind (the default of older files) the mean
    // absolute log gap.
    let (a, b) = ([1.0, 2.0, 2.0], [1.0, 5.0, 6.0]);
    assert_eq!(GlobalKind::WeylShapeDna.distance(&a, &b), 5.0);
    assert_eq!(GlobalKind::LogShapeDna.distance(&a, &b), 7.0 / 3.0);
    let old: GlobalSignature = serde_json::from_str(r#"{"eigenvalues": 20, "weight": 0.5}"#).unwrap();
    assert_eq!(old.kind, GlobalKind::LogShapeDna);
    for name in GlobalKind::names() {
        assert_eq!(GlobalKind::parse(name).unwrap().name(), name);
    }
    assert_eq!(GlobalKind::parse("shape_dna"), Ok(GlobalKind::WeylShapeDna));
}

#[test]
fn biharmonic_distribution_is_a_scale_invariant_histogram() {
    let settings = DescriptorSettings {
        eigenpairs: 30,
        ..Default::default()
    };
    let g = GlobalSignature {
        kind: GlobalKind::Biharmonic,
        eigenvalues: 20,
        weight: 1.0,
    };
    let mesh = bumpy(2);
    let a = g.compute(&mut settings.shape(&mesh).unwrap()).unwrap();
    let b = g
        .compute(&mut settings.shape(&mesh.scaled(30.0).unwrap()).unwrap())
        .unwrap();
    assert_eq!(a.len(), BIHARMONIC_BINS);
    assert!((a.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    assert!(a.iter().all(|&x| x >= 0.0));
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-9, "{x} vs {y}");
    }
    // A sphere and a stretched sphere have different distributions.
    let long = mesh_fem::TriMesh::new(
        icosphere(2)
            .positions()
            .iter()
            .map(|p| [3.0 * p[0], p[1], p[2]])
            .collect(),
        icosphere(2).faces().to_vec(),
    )
    .unwrap();
    let s = g.compute(&mut settings.shape(&icosphere(2)).unwrap()).unwrap();
    let l = g.compute(&mut settings.shape(&long).unwrap()).unwrap();
    assert!(GlobalKind::Biharmonic.distance(&s, &l) > 0.05);
    // Too few eigenpairs for the signature.
    let e = GlobalKind::Biharmonic
        .compute(
            &[0.0, 1.0],
            Mat::<f64>::zeros(3, 2).as_ref(),
            &[1.0; 3],
            Measure::Area(1.0),
            5,
        )
        .unwrap_err();
    assert!(matches!(e, RetrievalError::DimensionMismatch { .. }), "{e}");
}

#[test]
fn repair_damped_weights_fade_next_to_added_vertices() {
    // A punched sphere, filled: the vertices on the patch's rim weigh 0, those 3 hops away or
    // more their capped area.
    let intact = icosphere(3);
    let keep: Vec<bool> = intact.positions().iter().map(|p| p[2] < 0.9).collect();
    let faces: Vec<[u32; 3]> = intact
        .faces()
        .iter()
        .filter(|f| f.iter().all(|&v| keep[v as usize]))
        .copied()
        .collect();
    let holed = mesh_fem::validate::repair(
        &mesh_fem::TriMesh::new(intact.positions().to_vec(), faces).unwrap(),
        &mesh_fem::validate::RepairOptions {
            drop_unreferenced_vertices: true,
            ..Default::default()
        },
    )
    .unwrap()
    .0;
    let settings = DescriptorSettings {
        eigenpairs: 10,
        ..Default::default()
    };
    let shape = settings.shape(&holed).unwrap();
    assert!(shape.mesh().n_vertices() > shape.described_vertices());
    let capped = VertexWeights::CappedArea { factor: 3.0 }.compute(&shape).unwrap();
    let damped = VertexWeights::RepairDamped { factor: 3.0, hops: 3 }
        .compute(&shape)
        .unwrap();
    let rim: Vec<usize> = mesh_repair::holes::boundary_loops(&holed)
        .into_iter()
        .flat_map(|l| l.vertices)
        .map(|v| v as usize)
        .collect();
    assert!(!rim.is_empty());
    for &v in &rim {
        assert!(
            damped[v] < 0.3 * capped[v],
            "rim vertex {v}: {} vs {}",
            damped[v],
            capped[v]
        );
    }
    let far = holed.positions().iter().position(|p| p[2] < -0.9).unwrap();
    assert_eq!(damped[far], capped[far]);
    let e = VertexWeights::RepairDamped { factor: 3.0, hops: 0 }
        .validate()
        .unwrap_err();
    assert!(matches!(e, RetrievalError::InvalidParameter { .. }), "{e}");
}
