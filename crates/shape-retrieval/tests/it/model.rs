//! The retrieval model (settings → vocabulary → index → queries) on small generated shapes:
//! exact scale invariance end to end, a snapshot of a small retrieval run, the options against
//! independent references, and every validation error.

use crate::common;
use shape_retrieval::hks::TimeSampling;

use common::{sig, small_collection, small_settings};
use faer::Mat;
use mesh_fem::generate::{grid, icosphere};
use mesh_fem::TriMesh;
use shape_retrieval::bof::{Assignment, Vocabulary};
use shape_retrieval::descriptor::Descriptor;
use shape_retrieval::distance::BagDistance;
use shape_retrieval::model::{
    Denoising, DescriptorSettings, GlobalSignature, IndexEntry, RetrievalIndex, ShapeFeatures, ShapeSignature,
    Smoothing, TrainingParams, VertexWeights, VocabularyModel,
};
use shape_retrieval::RetrievalError;

fn small_index() -> RetrievalIndex {
    RetrievalIndex::build(&small_collection(), &small_settings(), None).unwrap()
}

#[test]
fn a_rescaled_copy_retrieves_its_original_at_distance_zero() {
    // SI-HKS in area units is exactly scale invariant, so the bag of a copy scaled by 7.3 equals
    // the original's to rounding, whatever the z-scoring, words and soft assignment.
    let index = small_index();
    let copy = small_collection()[0].1.scaled(7.3).unwrap();
    let features = index.features("copy", &copy).unwrap();
    let ranked = index.rank(&index.signature(&features).unwrap()).unwrap();
    assert_eq!(index.entries()[ranked[0].entry].name, "bumpy");
    assert!(ranked[0].distance < 1e-9, "{ranked:?}");
    assert!(ranked[1].distance > 1e3 * ranked[0].distance.max(1e-12), "{ranked:?}");
    // Every indexed shape is its own nearest neighbour.
    for (i, e) in index.entries().iter().enumerate() {
        let r = index.rank(&e.signature).unwrap();
        assert_eq!((r[0].entry, r[0].distance), (i, 0.0));
    }
}

#[test]
fn snapshot_of_a_small_retrieval_run() {
    // Rounded distances and the first bag: a change of any default shows up in review.
    let index = small_index();
    let mut out = format!(
        "settings: {}\nwords: {}, sigma {}\n",
        serde_json::to_string(index.vocabulary().descriptor()).unwrap(),
        index.vocabulary().vocabulary().size(),
        sig(index.vocabulary().vocabulary().sigma(), 4)
    );
    for e in index.entries() {
        let ranked = index.rank(&e.signature).unwrap();
        let cells: Vec<String> = ranked
            .iter()
            .map(|r| format!("{} {}", index.entries()[r.entry].name, sig(r.distance, 3)))
            .collect();
        out += &format!("{}: {}\n", e.name, cells.join(", "));
    }
    let bag: Vec<String> = index.entries()[0]
        .signature
        .bag
        .iter()
        .map(|x| format!("{x:.4}"))
        .collect();
    out += &format!("bag(bumpy): {}\n", bag.join(" "));
    insta::assert_snapshot!("small_retrieval_run", out);
}

#[test]
fn snapshot_of_default_descriptor_values() {
    let settings = small_settings();
    let f = ShapeFeatures::compute("bumpy", &small_collection()[0].1, &settings.descriptor, &settings.bags).unwrap();
    let mut out = format!("{} × {}\n", f.descriptors.nrows(), f.descriptors.ncols());
    for i in (0..f.descriptors.nrows()).step_by(20) {
        let row: Vec<String> = (0..f.descriptors.ncols())
            .map(|j| sig(f.descriptors[(i, j)], 4))
            .collect();
        out += &format!("v{i:03}: {}\n", row.join(" "));
    }
    insta::assert_snapshot!("default_descriptor_bumpy2_k30", out);
}

#[test]
fn a_vocabulary_trained_elsewhere_is_reused_with_its_settings() {
    let shapes = small_collection();
    let mut settings = small_settings();
    settings.training.words = 4;
    let training: Vec<ShapeFeatures> =
        ShapeFeatures::compute_many(&shapes[2..], &settings.descriptor, &settings.bags).unwrap();
    let vocabulary = VocabularyModel::train(&settings.descriptor, &settings.training, &training).unwrap();
    assert_eq!(vocabulary.info().shapes, vec!["torus", "ellipsoid"]);
    // The index takes the vocabulary's descriptor settings, whatever `settings` says.
    let mut other = settings.clone();
    other.descriptor.descriptor = Descriptor::dhk3_default();
    let index = RetrievalIndex::build(&shapes[..2], &other, Some(vocabulary)).unwrap();
    assert_eq!(index.vocabulary().descriptor(), &settings.descriptor);
    assert_eq!(index.entries().len(), 2);
    assert_eq!(index.vocabulary().vocabulary().size(), 4);
}

#[test]
fn z_scoring_statistics_are_those_of_the_pooled_training_descriptors() {
    let shapes = small_collection();
    let settings = small_settings();
    let f = ShapeFeatures::compute_many(&shapes, &settings.descriptor, &settings.bags).unwrap();
    let v = VocabularyModel::train(&settings.descriptor, &settings.training, &f).unwrap();
    let z = v.standardizer().unwrap();
    let d = settings.descriptor.descriptor.dimension();
    let n: usize = f.iter().map(|x| x.descriptors.nrows()).sum();
    for j in 0..d {
        let all: Vec<f64> = f
            .iter()
            .flat_map(|x| x.descriptors.col(j).iter().copied().collect::<Vec<_>>())
            .collect();
        let m = all.iter().sum::<f64>() / n as f64;
        let s = (all.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n as f64).sqrt();
        assert!((z.mean()[j] - m).abs() <= 1e-12 * m.abs().max(1.0));
        assert!((z.std()[j] - s).abs() <= 1e-12 * s);
    }
    let plain = VocabularyModel::train(
        &settings.descriptor,
        &TrainingParams {
            standardize: false,
            ..settings.training
        },
        &f,
    )
    .unwrap();
    assert!(plain.standardizer().is_none());
}

#[test]
fn capped_and_boundary_weights_match_their_definitions() {
    // The definitions on the meshes as given (a refined mesh has other areas).
    let settings = DescriptorSettings {
        eigenpairs: 10,
        refinement: None,
        ..Default::default()
    };
    // Capped: min(a_i, c·median(a)) computed independently.
    let mesh = mesh_fem::generate::irregular_sphere(2, 0.4);
    let shape = settings.shape(&mesh).unwrap();
    let a = shape.vertex_areas();
    let mut sorted = a.clone();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    let median = if n % 2 == 1 {
        sorted[n / 2]
    } else {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    };
    let w = VertexWeights::CappedArea { factor: 1.1 }.compute(&shape).unwrap();
    for (wi, ai) in w.iter().zip(&a) {
        assert_eq!(*wi, ai.min(1.1 * median));
    }
    assert!(w.iter().zip(&a).any(|(wi, ai)| wi < ai), "the cap binds somewhere");
    // Boundary damping on an open grid: 0 on the boundary, full area ≥ H hops inside.
    let plane = grid(9, 9);
    let shape = settings.shape(&plane).unwrap();
    let a = shape.vertex_areas();
    let w = VertexWeights::BoundaryDamped { hops: 2 }.compute(&shape).unwrap();
    for (i, p) in plane.positions().iter().enumerate() {
        let (ix, iy) = ((p[0] * 8.0).round() as i64, (p[1] * 8.0).round() as i64);
        let hops = ix.min(iy).min(8 - ix).min(8 - iy);
        let x = (hops as f64 / 2.0).min(1.0);
        let want = a[i] * x * x * (3.0 - 2.0 * x);
        assert!((w[i] - want).abs() <= 1e-15 * a[i], "vertex {i} at {hops} hops");
    }
    // A closed mesh keeps its areas.
    let sphere = settings.shape(&icosphere(1)).unwrap();
    assert_eq!(
        VertexWeights::BoundaryDamped { hops: 3 }.compute(&sphere).unwrap(),
        sphere.vertex_areas()
    );
}

#[test]
fn kernel_assignment_matches_its_definition() {
    let words = Mat::from_fn(3, 2, |i, j| (i * 2 + j) as f64);
    let v = Vocabulary::new(words.clone(), 0.7).unwrap();
    let x = Mat::from_fn(4, 2, |i, j| 0.3 * i as f64 - 0.2 * j as f64 + 0.1);
    let k = v.kernel_assignment(x.as_ref()).unwrap();
    let d2 = |i: usize, w: usize| (0..2).map(|j| (x[(i, j)] - words[(w, j)]).powi(2)).sum::<f64>();
    let m = (0..4)
        .flat_map(|i| (0..3).map(move |w| (i, w)))
        .map(|(i, w)| d2(i, w))
        .fold(f64::INFINITY, f64::min);
    for i in 0..4 {
        for w in 0..3 {
            let want = (-(d2(i, w) - m) / (2.0 * 0.49)).exp();
            assert!((k[(i, w)] - want).abs() < 1e-15, "{i} {w}");
        }
    }
    // The normalised assignment sums to 1 per row; the kernel one does not, and a bag of either is
    // the weighted column sum.
    let weights = [1.0, 2.0, 0.5, 1.5];
    let bag = v.bag_with(x.as_ref(), &weights, Assignment::Kernel).unwrap();
    for w in 0..3 {
        let want: f64 = (0..4).map(|i| weights[i] * k[(i, w)]).sum();
        assert!((bag[w] - want).abs() < 1e-14);
    }
}

#[test]
fn shape_dna_is_scale_invariant_and_its_distance_is_the_mean_log_gap() {
    let g = GlobalSignature {
        kind: Default::default(),
        eigenvalues: 8,
        weight: 1.0,
    };
    let settings = DescriptorSettings {
        eigenpairs: 20,
        ..Default::default()
    };
    let mesh = mesh_fem::generate::bumpy(2);
    let a = g.compute(&mut settings.shape(&mesh).unwrap()).unwrap();
    let b = g
        .compute(&mut settings.shape(&mesh.scaled(0.01).unwrap()).unwrap())
        .unwrap();
    assert_eq!(a.len(), 8);
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-9, "{x} vs {y}");
    }
    // On the unit sphere (area 4π) λ₁ = λ₂ = λ₃ ≈ 2: ln(λA) ≈ ln 8π.
    let s = g.compute(&mut settings.shape(&icosphere(3)).unwrap()).unwrap();
    assert!((s[0] - (8.0 * std::f64::consts::PI).ln()).abs() < 5e-3, "{}", s[0]);
}

#[test]
fn fused_distance_adds_the_weighted_shape_dna_gap() {
    let shapes = small_collection();
    let mut settings = small_settings();
    settings.bags.global = Some(GlobalSignature {
        kind: Default::default(),
        eigenvalues: 10,
        weight: 0.5,
    });
    settings.bags.distance = BagDistance::L1;
    let index = RetrievalIndex::build(&shapes, &settings, None).unwrap();
    let (a, b) = (&index.entries()[0].signature, &index.entries()[2].signature);
    let bag: f64 = a.bag.iter().zip(&b.bag).map(|(x, y)| (x - y).abs()).sum();
    let dna: f64 = a.global.iter().zip(&b.global).map(|(x, y)| (x - y).abs()).sum::<f64>() / 10.0;
    assert!((index.distance(a, b).unwrap() - (bag + 0.5 * dna)).abs() < 1e-14);
    assert_eq!(a.global.len(), 10);
}

#[test]
fn smoothing_is_the_heat_kernel_applied_to_the_coordinates() {
    // Reference: the dense wFEM kernel X e^{−tΛ} XᵀB (Eq. (6)) applied to x, y, z, t = c·A.
    let sphere = icosphere(2);
    let c = 1e-3;
    let smoothed = Smoothing { time: c }.apply(&sphere).unwrap();
    let ops = mesh_fem::assemble(&sphere, &Default::default()).unwrap();
    let area: f64 = shape_retrieval::bof::vertex_areas(ops.mass.as_ref()).iter().sum();
    let dense = wfem_heat::HeatKernel::new(
        &ops,
        wfem_heat::HeatParams {
            mass: mesh_fem::Mass::Consistent,
            method: wfem_heat::method::Method::Dense,
        },
    )
    .unwrap();
    for k in 0..3 {
        let f: Vec<f64> = sphere.positions().iter().map(|p| p[k]).collect();
        let want = dense.apply(&f, c * area).unwrap();
        for (q, w) in smoothed.positions().iter().zip(&want) {
            assert!((q[k] - w).abs() < 1e-9, "{} vs {w}", q[k]);
        }
    }
    // The coordinates of the unit sphere are nearly eigenfunctions with λ ≈ 2 (area ≈ 4π), so the
    // sphere shrinks by ≈ e^{−2t} (to the discretisation error of λ₁, ≈ 1 % at this level).
    let want = (-2.0 * c * area).exp();
    for (p, q) in sphere.positions().iter().zip(smoothed.positions()) {
        let r = |v: &[f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        assert!((r(q) / r(p) - want).abs() < 5e-3, "{} vs {want}", r(q) / r(p));
    }
    assert!(matches!(
        Smoothing { time: 0.0 }.apply(&sphere),
        Err(RetrievalError::InvalidParameter { .. })
    ));
}

/// The mesh with every vertex moved by N(0, σ²I₃) (deterministic).
fn noisy(mesh: &TriMesh, sigma: f64) -> TriMesh {
    let mut rng = wfem_base::rng::SplitMix64::new(11);
    let p = mesh
        .positions()
        .iter()
        .map(|p| p.map(|c| c + sigma * rng.next_normal()))
        .collect();
    TriMesh::new(p, mesh.faces().to_vec()).unwrap()
}

#[test]
fn denoising_leaves_smooth_shapes_alone_and_smooths_noisy_ones_back() {
    use mesh_repair::filter::roughness;
    let sphere = icosphere(4);
    let target = Denoising::default();
    // A smooth shape (roughness ≈ 0: a sphere's heights are the same at every vertex) is
    // returned as it is.
    assert!(roughness(&sphere) < target.roughness);
    assert_eq!(target.apply(&sphere).unwrap(), sphere);
    // Noise of 0.4 mean edge lengths: smoothed to the target (not beyond), and closer to the
    // clean sphere than the noisy copy (K_t shrinks the unit sphere only by e^{−2t}, t ≪ 1).
    let h = 4.0 * std::f64::consts::PI.sqrt() / (sphere.n_faces() as f64).sqrt(); // ≈ mean edge
    let rough = noisy(&sphere, 0.4 * h);
    assert!(roughness(&rough) > 2.0 * target.roughness);
    let smoothed = target.apply(&rough).unwrap();
    assert!(roughness(&smoothed) <= target.roughness, "{}", roughness(&smoothed));
    let error = |m: &TriMesh| -> f64 {
        m.positions()
            .iter()
            .zip(sphere.positions())
            .map(|(p, q)| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt())
            .sum::<f64>()
            / m.n_vertices() as f64
    };
    assert!(
        error(&smoothed) < 0.75 * error(&rough),
        "{} vs {}",
        error(&smoothed),
        error(&rough)
    );
    // Scale invariant: the same relative result on a copy ×1000.
    let big = target.apply(&rough.scaled(1e3).unwrap()).unwrap();
    for (p, q) in big.positions().iter().zip(smoothed.positions()) {
        for k in 0..3 {
            assert!((p[k] / 1e3 - q[k]).abs() < 1e-9, "{} vs {}", p[k] / 1e3, q[k]);
        }
    }
    assert!(matches!(
        Denoising {
            roughness: 0.0,
            ..Default::default()
        }
        .apply(&sphere),
        Err(RetrievalError::InvalidParameter { .. })
    ));
}

#[test]
fn invalid_settings_and_inputs_are_typed_errors() {
    let shapes = small_collection();
    let mut settings = small_settings();
    settings.descriptor.eigenpairs = 1;
    assert!(matches!(
        ShapeFeatures::compute("x", &shapes[0].1, &settings.descriptor, &settings.bags),
        Err(RetrievalError::InvalidParameter { name: "eigenpairs", .. })
    ));
    let mut settings = small_settings();
    settings.bags.global = Some(GlobalSignature {
        kind: Default::default(),
        eigenvalues: 30,
        weight: 1.0,
    });
    assert!(matches!(
        RetrievalIndex::build(&shapes, &settings, None),
        Err(RetrievalError::InvalidParameter {
            name: "global eigenvalues",
            ..
        })
    ));
    settings.bags.global = Some(GlobalSignature {
        kind: Default::default(),
        eigenvalues: 3,
        weight: f64::NAN,
    });
    assert!(matches!(
        RetrievalIndex::build(&shapes, &settings, None),
        Err(RetrievalError::InvalidParameter {
            name: "global weight",
            ..
        })
    ));
    let mut settings = small_settings();
    settings.bags.weights = VertexWeights::CappedArea { factor: -1.0 };
    assert!(matches!(
        RetrievalIndex::build(&shapes, &settings, None),
        Err(RetrievalError::InvalidParameter { .. })
    ));
    settings.bags.weights = VertexWeights::BoundaryDamped { hops: 0 };
    assert!(matches!(
        RetrievalIndex::build(&shapes, &settings, None),
        Err(RetrievalError::InvalidParameter { .. })
    ));
    let mut settings = small_settings();
    settings.descriptor.descriptor = Descriptor::SiHks {
        alpha: 2.0,
        tau_min: 0.0,
        tau_max: 1.0,
        tau_step: 0.5,
        frequencies: 5,
        time_unit: shape_retrieval::sihks::TimeUnit::Area(1.0),
        convention: wfem_heat::KernelDiagonal::KernelValue,
    };
    assert!(matches!(
        settings.descriptor.validate(),
        Err(RetrievalError::InvalidParameter {
            name: "frequencies",
            ..
        })
    ));
    settings.descriptor.descriptor = Descriptor::Dhk2 {
        times: TimeSampling::Explicit(vec![]),
    };
    assert!(matches!(
        settings.descriptor.validate(),
        Err(RetrievalError::Empty { .. })
    ));
    settings.descriptor.descriptor = Descriptor::Dhk2 {
        times: TimeSampling::Explicit(vec![1.0, -1.0]),
    };
    assert!(matches!(
        settings.descriptor.validate(),
        Err(RetrievalError::InvalidParameter { .. })
    ));
    // No training shapes.
    let settings = small_settings();
    assert!(matches!(
        VocabularyModel::train(&settings.descriptor, &settings.training, &[]),
        Err(RetrievalError::Empty { .. })
    ));
    // A shape whose spectrum has two zero eigenvalues (two components) has no Shape-DNA; the
    // failure names the shape.
    let one = icosphere(1);
    let n = one.n_vertices() as u32;
    let mut positions = one.positions().to_vec();
    positions.extend(one.positions().iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
    let mut faces = one.faces().to_vec();
    faces.extend(one.faces().iter().map(|f| f.map(|v| v + n)));
    let two = TriMesh::new(positions, faces).unwrap();
    let mut settings = small_settings();
    settings.bags.global = Some(GlobalSignature {
        kind: Default::default(),
        eigenvalues: 3,
        weight: 1.0,
    });
    let err =
        ShapeFeatures::compute_many(&[("twins".to_string(), two)], &settings.descriptor, &settings.bags).unwrap_err();
    assert!(
        matches!(&err, RetrievalError::Shape { name, .. } if name == "twins"),
        "{err}"
    );
    assert!(err.to_string().starts_with("twins: "), "{err}");
}

#[test]
fn stored_parts_are_validated() {
    let index = small_index();
    let vocabulary = index.vocabulary().clone();
    let entry = |bag: Vec<f64>, global: Vec<f64>| IndexEntry {
        name: "bad.off".into(),
        signature: ShapeSignature { bag, global },
    };
    let v = index.bags().bag_len(vocabulary.vocabulary().size());
    let mut huge = vec![0.0; v];
    huge[2] = 1e308;
    for (bad, what) in [
        (entry(huge, vec![]), "1e308"),
        (entry(vec![1.0 / v as f64; v + 1], vec![]), "bins"),
        (entry(vec![0.5 / v as f64; v], vec![]), "sums to"),
        (entry(vec![1.0 / v as f64; v], vec![1.0]), "global signature"),
    ] {
        let err = RetrievalIndex::from_parts(vocabulary.clone(), index.bags().clone(), vec![bad]).unwrap_err();
        let text = err.to_string();
        assert!(
            matches!(err, RetrievalError::InvalidModel { what: "index", .. }),
            "{text}"
        );
        assert!(
            text.contains(what) && text.contains("bad.off") && !text.contains("inf"),
            "{text}"
        );
    }
    // Words of another dimension than the descriptor's.
    let words = Vocabulary::new(Mat::from_fn(6, 3, |i, j| (i + j) as f64), 1.0).unwrap();
    let err = VocabularyModel::from_parts(
        vocabulary.descriptor().clone(),
        *vocabulary.training(),
        vocabulary.standardizer().cloned(),
        words,
        vocabulary.info().clone(),
    )
    .unwrap_err();
    assert!(
        matches!(err, RetrievalError::InvalidModel { what: "vocabulary", .. }),
        "{err}"
    );
    // A query of the wrong length is refused by rank.
    let q = ShapeSignature {
        bag: vec![1.0],
        global: vec![],
    };
    assert!(matches!(index.rank(&q), Err(RetrievalError::DimensionMismatch { .. })));
}

/// `mesh` without the faces touching `seeds` (nor the then unreferenced vertices), and for each
/// remaining vertex its index in `mesh`.
fn punched(mesh: &TriMesh, seeds: &[u32]) -> (TriMesh, Vec<usize>) {
    let faces = mesh
        .faces()
        .iter()
        .copied()
        .filter(|f| !f.iter().any(|v| seeds.contains(v)))
        .collect();
    let opts = mesh_fem::validate::RepairOptions {
        drop_unreferenced_vertices: true,
        ..Default::default()
    };
    let (holed, report) =
        mesh_fem::validate::repair(&TriMesh::new(mesh.positions().to_vec(), faces).unwrap(), &opts).unwrap();
    let mut kept = vec![0; holed.n_vertices()];
    for (old, new) in report.vertex_map.iter().enumerate() {
        if let Some(new) = new {
            kept[*new as usize] = old;
        }
    }
    (holed, kept)
}

#[test]
fn hole_filling_brings_a_holed_shape_back_to_the_intact_one() {
    let intact = mesh_fem::generate::bumpy(3);
    let (holed, kept) = punched(&intact, &[5, 120, 300, 444, 600]);
    let filled = DescriptorSettings {
        eigenpairs: 30,
        ..Default::default()
    };
    assert!(filled.hole_filling.is_some(), "on by default");
    let open = DescriptorSettings {
        hole_filling: None,
        ..filled.clone()
    };
    let bags = shape_retrieval::model::BagSettings::default();
    let reference = ShapeFeatures::compute("intact", &intact, &filled, &bags).unwrap();
    // A closed shape is described alike with and without hole filling.
    let reference_open = ShapeFeatures::compute("intact", &intact, &open, &bags).unwrap();
    assert_eq!(reference.descriptors, reference_open.descriptors);
    // Only the shape's own vertices are described, with the filling or without.
    let with = ShapeFeatures::compute("filled", &holed, &filled, &bags).unwrap();
    let without = ShapeFeatures::compute("open", &holed, &open, &bags).unwrap();
    for f in [&with, &without] {
        assert_eq!(f.descriptors.nrows(), holed.n_vertices());
        assert_eq!(f.weights.len(), holed.n_vertices());
    }
    // Relative descriptor error at corresponding vertices, against the intact shape.
    let error = |f: &ShapeFeatures| -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for (i, &v) in kept.iter().enumerate() {
            for j in 0..f.descriptors.ncols() {
                num += (f.descriptors[(i, j)] - reference.descriptors[(v, j)]).powi(2);
                den += reference.descriptors[(v, j)].powi(2);
            }
        }
        (num / den).sqrt()
    };
    let (e_with, e_without) = (error(&with), error(&without));
    assert!(e_with < 0.5 * e_without, "filled {e_with} vs open {e_without}");
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let settings = DescriptorSettings {
            hole_filling: Some(shape_retrieval::model::HoleFilling { max_perimeter: bad }),
            ..filled.clone()
        };
        assert!(matches!(
            ShapeFeatures::compute("x", &holed, &settings, &bags),
            Err(RetrievalError::InvalidParameter {
                name: "largest hole perimeter",
                ..
            })
        ));
    }
}

#[test]
fn a_file_without_hole_filling_reads_as_off_and_a_new_one_records_it() {
    // Files written before hole filling existed hold bags of unfilled shapes: reading them
    // must not turn the filling on for their queries.
    let old = r#"{"eigenpairs": 50, "despiking": {"threshold": 3.0}}"#;
    let settings: DescriptorSettings = serde_json::from_str(old).unwrap();
    assert_eq!(settings.hole_filling, None);
    assert_eq!(settings.despiking, DescriptorSettings::default().despiking);
    let written = serde_json::to_value(DescriptorSettings::default()).unwrap();
    assert_eq!(written["hole_filling"], serde_json::json!({"max_perimeter": 3.0}));
    let back: DescriptorSettings = serde_json::from_value(written).unwrap();
    assert_eq!(back, DescriptorSettings::default());
}

#[test]
fn features_from_parts_keep_the_own_vertices_and_check_sizes() {
    let mesh = mesh_fem::generate::bumpy(2);
    let settings = DescriptorSettings {
        eigenpairs: 10,
        refinement: None,
        ..Default::default()
    };
    let shape = settings.shape(&mesh).unwrap().described_only(5).unwrap();
    let n = mesh.n_vertices();
    let descriptors = Mat::from_fn(n, 2, |i, j| (i * 2 + j) as f64);
    let f = ShapeFeatures::new("x", &shape, descriptors.clone(), vec![1.0; 5], Vec::new()).unwrap();
    assert_eq!(f.descriptors, descriptors.subrows(0, 5).to_owned());
    assert!(matches!(
        ShapeFeatures::new("x", &shape, descriptors.clone(), vec![1.0; n], Vec::new()),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        ShapeFeatures::new(
            "x",
            &shape,
            descriptors.subrows(0, 7).to_owned(),
            vec![1.0; 5],
            Vec::new()
        ),
        Err(RetrievalError::DimensionMismatch { .. })
    ));
    // The weights cover the own vertices only.
    assert_eq!(
        shape_retrieval::model::BagSettings::default()
            .weights
            .compute(&shape)
            .unwrap()
            .len(),
        5
    );
    assert!(settings.shape(&mesh).unwrap().described_only(0).is_err());
    assert!(settings.shape(&mesh).unwrap().described_only(n + 1).is_err());
}

#[test]
fn snapshot_of_default_descriptors_on_a_holed_shape() {
    // The bumpy sphere with four holes, described with the defaults (holes closed, their
    // patches not described): a change of the hole-filling default shows up in review.
    let (holed, _) = punched(&mesh_fem::generate::bumpy(2), &[3, 50, 90, 140]);
    let settings = small_settings();
    let filled = mesh_repair::holes::fill_holes(&holed, shape_retrieval::model::DEFAULT_MAX_HOLE_PERIMETER).unwrap();
    let f = ShapeFeatures::compute("holed", &holed, &settings.descriptor, &settings.bags).unwrap();
    let mut out = format!(
        "{} holes closed, {} patch vertices; {} × {}\n",
        filled.filled,
        filled.mesh.n_vertices() - filled.original_vertices,
        f.descriptors.nrows(),
        f.descriptors.ncols()
    );
    for i in (0..f.descriptors.nrows()).step_by(25) {
        let row: Vec<String> = (0..f.descriptors.ncols())
            .map(|j| sig(f.descriptors[(i, j)], 4))
            .collect();
        out += &format!("v{i:03}: {} | w {}\n", row.join(" "), sig(f.weights[i], 3));
    }
    insta::assert_snapshot!("default_descriptor_holed_bumpy2_k30", out);
}

#[test]
fn refinement_describes_a_coarse_mesh_at_its_own_vertices_on_a_converged_eigenbasis() {
    use shape_retrieval::model::Refinement;
    let coarse = mesh_fem::generate::bumpy(2);
    let n = coarse.n_vertices();
    let refined = DescriptorSettings {
        eigenpairs: 30,
        ..Default::default()
    };
    assert_eq!(refined.refinement, Some(Refinement::default()), "on by default");
    let plain = DescriptorSettings {
        refinement: None,
        ..refined.clone()
    };
    // 162 < 20 · 30 vertices: split once (642 ≥ 600); the own vertices first and described.
    let shape = refined.shape(&coarse).unwrap();
    assert_eq!((shape.mesh().n_vertices(), shape.described_vertices()), (642, n));
    assert_eq!(&shape.mesh().positions()[..n], coarse.positions());
    // A mesh with enough vertices is left as it is.
    let fine = mesh_fem::refine::split_faces(&coarse);
    assert_eq!(refined.shape(&fine).unwrap().mesh().n_vertices(), fine.n_vertices());
    // The reference: the same surface split twice, described without refinement, at the
    // coarse mesh's vertices (the first n).
    let bags = shape_retrieval::model::BagSettings::default();
    let finest = mesh_fem::refine::split_faces(&fine);
    let reference = ShapeFeatures::compute("finest", &finest, &plain, &bags).unwrap();
    let error = |f: &ShapeFeatures| -> f64 {
        assert_eq!(f.descriptors.nrows(), n);
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..n {
            for j in 0..f.descriptors.ncols() {
                num += (f.descriptors[(i, j)] - reference.descriptors[(i, j)]).powi(2);
                den += reference.descriptors[(i, j)].powi(2);
            }
        }
        (num / den).sqrt()
    };
    let with = ShapeFeatures::compute("coarse", &coarse, &refined, &bags).unwrap();
    let without = ShapeFeatures::compute("coarse", &coarse, &plain, &bags).unwrap();
    let (e_with, e_without) = (error(&with), error(&without));
    // Measured: 0.035 refined against 0.131 as it is.
    assert!(e_with < 0.5 * e_without, "refined {e_with} vs as it is {e_without}");
    for bad in [0.0, -1.0, f64::NAN, 101.0] {
        let settings = DescriptorSettings {
            refinement: Some(Refinement {
                vertices_per_eigenpair: bad,
            }),
            ..refined.clone()
        };
        assert!(matches!(
            ShapeFeatures::compute("x", &coarse, &settings, &bags),
            Err(RetrievalError::InvalidParameter {
                name: "vertices per eigenpair",
                ..
            })
        ));
    }
    // Files written before refinement existed read as off; new ones record it.
    let old: DescriptorSettings = serde_json::from_str(r#"{"eigenpairs": 50}"#).unwrap();
    assert_eq!(old.refinement, None);
    let written = serde_json::to_value(DescriptorSettings::default()).unwrap();
    assert_eq!(
        written["refinement"],
        serde_json::json!({"vertices_per_eigenpair": 20.0})
    );
}

#[test]
fn a_combined_descriptor_weighs_its_parts_alike_in_the_vocabulary() {
    // The z-score deviations of si-hks+wks are those of the pooled descriptors divided by the
    // dimension weights 1/√d_p, so that after z-scoring each part has total variance 1.
    let shapes = small_collection();
    let mut settings = small_settings();
    settings.descriptor.descriptor = Descriptor::sihks_wks_default();
    settings.training.words = 4;
    let f = ShapeFeatures::compute_many(&shapes, &settings.descriptor, &settings.bags).unwrap();
    let v = VocabularyModel::train(&settings.descriptor, &settings.training, &f).unwrap();
    let z = v.standardizer().unwrap();
    let w = settings.descriptor.descriptor.dimension_weights().unwrap();
    let n: usize = f.iter().map(|x| x.descriptors.nrows()).sum();
    for (j, wj) in w.iter().enumerate() {
        let all: Vec<f64> = f
            .iter()
            .flat_map(|x| x.descriptors.col(j).iter().copied().collect::<Vec<_>>())
            .collect();
        let m = all.iter().sum::<f64>() / n as f64;
        let s = (all.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n as f64).sqrt();
        assert!((z.std()[j] - s / wj).abs() <= 1e-12 * s / wj, "dimension {j}");
    }
    let index = RetrievalIndex::build(&shapes, &settings, Some(v)).unwrap();
    for (i, e) in index.entries().iter().enumerate() {
        assert_eq!(index.rank(&e.signature).unwrap()[0].entry, i);
    }
}
