//! `mesh_repair::filter::despike` against planted spikes and clean meshes.

use mesh_repair::filter::despike;

/// The retrieval policy's threshold (shape-retrieval's `DEFAULT_SPIKE_THRESHOLD`).
const DEFAULT_SPIKE_THRESHOLD: f64 = 3.0;
use mesh_fem::generate::{bumpy, grid, icosphere, irregular_sphere};
use mesh_fem::vec3::{norm, sub};
use mesh_fem::{MeshError, TriMesh};

fn mean_edge(mesh: &TriMesh) -> f64 {
    let p = mesh.positions();
    let mut total = 0.0;
    for f in mesh.faces() {
        for k in 0..3 {
            total += norm(sub(p[f[k] as usize], p[f[(k + 1) % 3] as usize]));
        }
    }
    total / (3 * mesh.n_faces()) as f64
}

/// Pulls the given vertices of a sphere centred at the origin out along the radius by `by`.
fn spiked(mesh: &TriMesh, vertices: &[usize], by: f64) -> TriMesh {
    let mut p = mesh.positions().to_vec();
    for &i in vertices {
        let r = norm(p[i]);
        p[i] = p[i].map(|c| c * (1.0 + by / r));
    }
    TriMesh::new(p, mesh.faces().to_vec()).unwrap()
}

#[test]
fn clean_meshes_come_back_unchanged() {
    for (name, mesh) in [
        ("icosphere(4)", icosphere(4)),
        ("irregular_sphere(4, 4)", irregular_sphere(4, 4.0)),
        ("bumpy(4)", bumpy(4)),
        ("grid(12, 9)", grid(12, 9)),
    ] {
        let d = despike(&mesh, DEFAULT_SPIKE_THRESHOLD).unwrap();
        assert!(d.moved.is_empty(), "{name}: moved {:?}", d.moved);
        assert_eq!(d.mesh, mesh, "{name}");
    }
}

/// The real scans of the corpus (all TOSCA poses: fingers, ears, tails, hooves) lose at most
/// their three sharpest single-vertex tips.
#[test]
fn tosca_shapes_have_almost_no_spikes() {
    let dir = wfem_corpus::meshes_dir()
        .unwrap()
        .join("tosca-bcicp-5k/TOSCA_Isometric");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "off"))
        .collect();
    files.sort();
    assert!(files.len() >= 70, "{} TOSCA shapes", files.len());
    let mut total = 0;
    for path in &files {
        let (mesh, _) = mesh_fem::io::load(path, &Default::default()).unwrap();
        let d = despike(&mesh, DEFAULT_SPIKE_THRESHOLD).unwrap();
        assert!(
            d.moved.len() <= 3,
            "{}: moved {} vertices",
            path.display(),
            d.moved.len()
        );
        total += d.moved.len();
    }
    assert!(
        total <= files.len() / 4,
        "{total} vertices moved over {} shapes",
        files.len()
    );
}

#[test]
fn planted_spikes_are_found_and_put_back() {
    let mesh = icosphere(4);
    let h = mean_edge(&mesh);
    // Isolated spikes and one pair of adjacent ones (vertex 0 and a neighbour of it).
    let neighbour = mesh
        .faces()
        .iter()
        .find(|f| f.contains(&0))
        .map(|f| f[if f[0] == 0 { 1 } else { 0 }])
        .unwrap();
    let mut planted: Vec<usize> = (17..mesh.n_vertices()).step_by(211).collect();
    planted.extend([0, neighbour as usize]);
    planted.sort_unstable();
    for by in [5.0 * h, -5.0 * h] {
        let noisy = spiked(&mesh, &planted, by);
        let d = despike(&noisy, DEFAULT_SPIKE_THRESHOLD).unwrap();
        assert_eq!(d.moved, planted, "by {by:e}");
        for i in 0..mesh.n_vertices() {
            let error = norm(sub(d.mesh.positions()[i], mesh.positions()[i]));
            if planted.contains(&i) {
                // The harmonic fill sits slightly inside the sphere (≈ κh²/2 per ring; a
                // little more for the adjacent pair).
                assert!(error < 0.2 * h, "vertex {i}: {:.3} edge lengths off", error / h);
            } else {
                assert_eq!(d.mesh.positions()[i], noisy.positions()[i], "vertex {i} moved");
            }
        }
        assert_eq!(d.mesh.faces(), mesh.faces());
    }
}

#[test]
fn invalid_thresholds_are_typed_errors() {
    let mesh = icosphere(1);
    for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(despike(&mesh, t), Err(MeshError::Invalid { .. })), "{t}");
    }
}

/// The mesh with every coordinate moved by deterministic pseudo-random noise of standard
/// deviation σ (uniform on [−√3σ, √3σ], from a multiplicative hash of the index).
fn noisy(mesh: &TriMesh, sigma: f64) -> TriMesh {
    let u = |k: usize| ((k as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11) as f64 / (1u64 << 53) as f64;
    let p = mesh
        .positions()
        .iter()
        .enumerate()
        .map(|(i, p)| [0, 1, 2].map(|k| p[k] + sigma * 3f64.sqrt() * (2.0 * u(3 * i + k) - 1.0)))
        .collect();
    TriMesh::new(p, mesh.faces().to_vec()).unwrap()
}

#[test]
fn roughness_ignores_curvature_and_resolution_and_grows_with_noise() {
    use mesh_repair::filter::roughness;
    // Curvature and resolution do not count: spheres from 162 to 10K vertices, an irregular
    // sampling and a bumpy surface are all smooth.
    for (name, mesh) in [
        ("icosphere(2)", icosphere(2)),
        ("icosphere(5)", icosphere(5)),
        ("irregular_sphere(4, 4)", irregular_sphere(4, 4.0)),
        ("bumpy(4)", bumpy(4)),
    ] {
        let r = roughness(&mesh);
        assert!(r < 0.05, "{name}: {r}");
    }
    let mesh = icosphere(4);
    let h = mean_edge(&mesh);
    let mut last = roughness(&mesh);
    for sigma in [0.1, 0.2, 0.3, 0.5] {
        let r = roughness(&noisy(&mesh, sigma * h));
        assert!(r > last && (0.5 * sigma..1.5 * sigma).contains(&r), "σ = {sigma}: {r}");
        last = r;
    }
    // Scale invariant, and 0 for a mesh with no interior vertex.
    let rough = noisy(&mesh, 0.3 * h);
    let (r, scaled) = (roughness(&rough), roughness(&rough.scaled(1e5).unwrap()));
    assert!((scaled - r).abs() <= 1e-12 * r, "{scaled} vs {r}");
    let triangle = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]]).unwrap();
    assert_eq!(roughness(&triangle), 0.0);
}

#[test]
fn coherence_tells_noise_from_a_coarse_clean_mesh() {
    use mesh_fem::generate::torus;
    use mesh_repair::filter::surface_noise;
    // Coarse clean meshes: the heights follow the curvature from vertex to vertex.
    for (name, mesh) in [
        ("bumpy(1)", bumpy(1)),
        ("torus 10×5", torus(1.0, 0.3, 10, 5)),
        ("bumpy(4)", bumpy(4)),
    ] {
        let n = surface_noise(&mesh);
        assert!(n.coherence > 0.3, "{name}: {n:?}");
    }
    // Noise of 0.2–0.5 mean edge lengths on fine meshes (2562 vertices): rough and incoherent
    // (measured −0.65 … 0.05).
    for mesh in [icosphere(4), bumpy(4)] {
        let h = mean_edge(&mesh);
        for sigma in [0.2, 0.3, 0.5] {
            let n = surface_noise(&noisy(&mesh, sigma * h));
            assert!(n.roughness > 0.1 && n.coherence < 0.1, "σ = {sigma}: {n:?}");
        }
    }
    // On a 162-vertex bumpy sphere the bumps span a few edges, so noise of 0.2 edge lengths
    // reads incoherent (0.02) but 0.3 and 0.5 still 0.12: the gate errs on the side of leaving
    // a coarse shape as it is. Still far below the clean meshes above.
    let coarse = bumpy(2);
    let h = mean_edge(&coarse);
    assert!(surface_noise(&noisy(&coarse, 0.2 * h)).coherence < 0.1);
    for sigma in [0.3, 0.5] {
        let n = surface_noise(&noisy(&coarse, sigma * h));
        assert!(n.roughness > 0.1 && n.coherence < 0.2, "σ = {sigma}: {n:?}");
    }
    // A correlation coefficient: in [−1, 1], scale invariant, 0 when undefined.
    let rough = noisy(&bumpy(3), 0.3 * mean_edge(&bumpy(3)));
    let (a, b) = (surface_noise(&rough), surface_noise(&rough.scaled(1e-4).unwrap()));
    assert!((-1.0..=1.0).contains(&a.coherence));
    assert!((a.coherence - b.coherence).abs() < 1e-9, "{a:?} vs {b:?}");
    assert_eq!(a.roughness, mesh_repair::filter::roughness(&rough));
    let triangle = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]]).unwrap();
    assert_eq!(surface_noise(&triangle).coherence, 0.0);
    // A round sphere: every height the same, so the correlation is undefined (0).
    assert!(surface_noise(&icosphere(3)).coherence.abs() < 1.0);
}
