//! Point clouds in retrieval (issue #27): a collection may mix meshes and clouds, a cloud is
//! described with the robust Laplacian of its neighbourhoods, the mesh repairs are skipped for
//! it, and the Laplacian of the meshes is recorded in the settings and followed by every
//! shape described with them.

use crate::common::small_settings;
use mesh_fem::cloud::PointCloud;
use mesh_fem::generate::{bumpy, icosphere, torus};
use mesh_fem::{assemble, AssemblyParams, Laplacian, Lumping, RobustParams, TriMesh};
use shape_retrieval::model::{
    DescriptorSettings, RetrievalIndex, RetrievalSettings, ShapeFeatures, ShapeRef, Smoothing,
};
use shape_retrieval::RetrievalError;
use wfem_base::rng::SplitMix64;

/// n points uniform on the mesh's surface, seeded (the workspace's one generator).
fn cloud_of(mesh: &TriMesh, n: usize, seed: u64) -> PointCloud {
    let mut rng = SplitMix64::new(seed);
    mesh_fem::cloud::sample_surface(mesh, n, &mut || rng.next_f64()).unwrap()
}

/// Four distinct closed shapes, fine enough to be sampled by 1,500 points: a sphere, an
/// ellipsoid (2.2 × 1 × 0.6), a peanut (a waist of 0.45 at the middle of a 4-long body) and a
/// torus.
fn shapes() -> Vec<(String, TriMesh)> {
    let sphere = icosphere(3);
    let mapped = |f: &dyn Fn([f64; 3]) -> [f64; 3]| {
        TriMesh::new(
            sphere.positions().iter().map(|&p| f(p)).collect(),
            sphere.faces().to_vec(),
        )
        .unwrap()
    };
    let ellipsoid = mapped(&|p| [2.2 * p[0], p[1], 0.6 * p[2]]);
    let peanut = mapped(&|p| {
        let s = 0.45 + 0.55 * p[0] * p[0];
        [2.0 * p[0], s * p[1], s * p[2]]
    });
    vec![
        ("sphere".into(), sphere.clone()),
        ("ellipsoid".into(), ellipsoid),
        ("peanut".into(), peanut),
        ("torus".into(), torus(1.0, 0.4, 48, 24)),
    ]
}

const POINTS: usize = 1500;

#[test]
fn a_cloud_query_ranks_its_own_mesh_first_in_a_mixed_index() {
    // The index holds every mesh and a cloud of every shape; a new cloud of each shape (another
    // seed) must find its own shape first, and of the meshes its own mesh first.
    let meshes = shapes();
    let clouds: Vec<PointCloud> = meshes
        .iter()
        .enumerate()
        .map(|(i, (_, mesh))| cloud_of(mesh, POINTS, 1 + i as u64))
        .collect();
    let mut collection: Vec<(String, ShapeRef<'_>)> = Vec::new();
    for ((name, mesh), cloud) in meshes.iter().zip(&clouds) {
        collection.push((name.clone(), mesh.into()));
        collection.push((format!("{name}-cloud"), cloud.into()));
    }
    let index = RetrievalIndex::build(&collection, &small_settings(), None).unwrap();
    for (i, (name, mesh)) in meshes.iter().enumerate() {
        let query = cloud_of(mesh, POINTS, 100 + i as u64);
        let entry = index.describe("query", &query).unwrap();
        let ranked = index.rank(&entry.signature).unwrap();
        let names: Vec<&str> = ranked.iter().map(|r| index.entries()[r.entry].name.as_str()).collect();
        assert!(
            names[0] == name.as_str() || names[0] == format!("{name}-cloud"),
            "{name}: {names:?}"
        );
        let first_mesh = names
            .iter()
            .find(|n| !n.ends_with("-cloud"))
            .copied()
            .unwrap_or_default();
        assert_eq!(first_mesh, name.as_str(), "{names:?}");
    }
}

#[test]
fn a_cloud_is_described_by_its_robust_operators_and_skips_the_mesh_repairs() {
    // Every cleaning step on, and a fixed smoothing: a cloud gets its own operators (the
    // robust L of its neighbourhoods, independently assembled here), all its points described.
    let mesh = &shapes()[2].1;
    let cloud = cloud_of(mesh, POINTS, 7);
    let settings = DescriptorSettings {
        eigenpairs: 30,
        ..Default::default()
    };
    assert!(settings.denoising.is_some() && settings.hole_filling.is_some() && settings.topology_repair.is_some());
    let shape = settings.shape(&cloud).unwrap();
    assert_eq!(shape.described_vertices(), POINTS);
    assert_eq!(shape.mesh().positions(), cloud.positions());
    let reference = mesh_fem::cloud::assemble_cloud(
        &cloud,
        &Default::default(),
        &AssemblyParams {
            lumping: Lumping::Voronoi,
            laplacian: Laplacian::Robust(RobustParams::default()),
        },
    )
    .unwrap();
    // A clean cloud has no spike (despiking is on and would have moved the point).
    assert!(mesh_repair::filter::despike(&reference.neighbourhood, 3.0)
        .unwrap()
        .moved
        .is_empty());
    assert_eq!(
        shape.operators().stiffness.to_dense(),
        reference.operators.stiffness.to_dense()
    );
    assert_eq!(shape.operators().mass.to_dense(), reference.operators.mass.to_dense());
    assert_eq!(shape.mesh().faces(), reference.neighbourhood.faces());
    // The cloud's area approximates the surface's (the local triangulations cover it).
    let ratio = shape.area() / mesh.area();
    assert!((0.8..1.05).contains(&ratio), "{ratio}");
    // A fixed smoothing moves the points (K_t x with the cloud's own operators) and is
    // assembled again; the points stay as many.
    let smoothed = DescriptorSettings {
        smoothing: Some(Smoothing { time: 1e-3 }),
        ..settings.clone()
    }
    .shape(&cloud)
    .unwrap();
    assert_eq!(smoothed.described_vertices(), POINTS);
    assert_ne!(smoothed.mesh().positions(), cloud.positions());
    // The whole feature computation runs: one row per point.
    let features = ShapeFeatures::compute("cloud", &cloud, &settings, &Default::default()).unwrap();
    assert_eq!(features.descriptors.nrows(), POINTS);
    assert_eq!(features.weights.len(), POINTS);
}

#[test]
fn a_cloud_with_duplicate_points_is_a_typed_error_naming_them() {
    let mut points = cloud_of(&icosphere(2), 400, 3).positions().to_vec();
    points[17] = points[4];
    let cloud = PointCloud::new(points, None).unwrap();
    let err = ShapeFeatures::compute("dup", &cloud, &DescriptorSettings::default(), &Default::default()).unwrap_err();
    assert!(
        matches!(
            err,
            RetrievalError::Mesh(mesh_fem::MeshError::DuplicatePoint {
                point: 17,
                duplicate_of: 4
            })
        ),
        "{err}"
    );
}

#[test]
fn the_laplacian_of_the_settings_assembles_the_meshes() {
    // Independent reference: mesh-fem's own assembly of each Laplacian on the same mesh.
    let mesh = bumpy(2);
    for laplacian in [Laplacian::Cotan, Laplacian::Robust(RobustParams::default())] {
        let settings = DescriptorSettings {
            eigenpairs: 20,
            laplacian,
            despiking: None,
            denoising: None,
            hole_filling: None,
            topology_repair: None,
            refinement: None,
            ..Default::default()
        };
        let shape = settings.shape(&mesh).unwrap();
        let reference = assemble(
            &mesh,
            &AssemblyParams {
                lumping: Lumping::Voronoi,
                laplacian,
            },
        )
        .unwrap();
        assert_eq!(
            shape.operators().stiffness.to_dense(),
            reference.stiffness.to_dense(),
            "{laplacian:?}"
        );
        assert_eq!(shape.operators().lumped_diagonal, reference.lumped_diagonal);
    }
}

#[test]
fn the_laplacian_is_recorded_by_name_and_older_files_read_as_cotan() {
    let json = serde_json::to_value(RetrievalSettings::default()).unwrap();
    assert_eq!(json["descriptor"]["laplacian"], "cotan");
    // A file written before the choice existed has no field: the cotangent L.
    let old: DescriptorSettings = serde_json::from_str(r#"{"eigenpairs": 50}"#).unwrap();
    assert_eq!(old.laplacian, Laplacian::Cotan);
    // Names and aliases of the registry are read; another name is refused with the list.
    for name in ["robust", "intrinsic-delaunay", "Tufted"] {
        let s: DescriptorSettings = serde_json::from_str(&format!(r#"{{"laplacian": "{name}"}}"#)).unwrap();
        assert_eq!(s.laplacian, Laplacian::Robust(RobustParams::default()));
        assert_eq!(serde_json::to_value(&s).unwrap()["laplacian"], "robust");
    }
    let err = serde_json::from_str::<DescriptorSettings>(r#"{"laplacian": "belkin"}"#).unwrap_err();
    assert!(
        err.to_string().contains("cotan") && err.to_string().contains("robust"),
        "{err}"
    );
}

#[test]
fn a_vocabulary_brings_its_laplacian_to_the_index_and_its_queries() {
    // A vocabulary trained with the robust Laplacian, used to build an index whose settings
    // say cotan: the index is the vocabulary's (robust), and a mesh is described with it, so
    // its entry equals the one of the index built with robust settings throughout.
    let meshes = shapes();
    let mut robust = small_settings();
    robust.descriptor.laplacian = Laplacian::Robust(RobustParams::default());
    robust.descriptor.eigenpairs = 20;
    let features = ShapeFeatures::compute_many(&meshes, &robust.descriptor, &robust.bags).unwrap();
    let vocabulary =
        shape_retrieval::model::VocabularyModel::train(&robust.descriptor, &robust.training, &features).unwrap();
    let cotan = RetrievalSettings {
        bags: robust.bags.clone(),
        ..small_settings()
    };
    let index = RetrievalIndex::build(&meshes, &cotan, Some(vocabulary.clone())).unwrap();
    assert_eq!(index.vocabulary().descriptor().laplacian, robust.descriptor.laplacian);
    let direct = RetrievalIndex::build(&meshes, &robust, Some(vocabulary)).unwrap();
    let (name, mesh) = &meshes[0];
    let entry = index.describe(name, mesh).unwrap();
    assert_eq!(entry.signature, direct.entries()[0].signature);
    assert_eq!(entry.signature, index.entries()[0].signature);
}
