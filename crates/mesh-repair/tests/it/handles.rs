//! Thin handles: the shortest non-separating cycle of a torus is its minor circle (exact
//! polygon length), cutting it leaves a closed sphere, and genus-0, open or bad-bound inputs.

use mesh_fem::generate::{grid, icosphere, torus};
use mesh_repair::handles::{cut_handles, short_handle_cycle};

/// The retrieval policy's bound (shape-retrieval's `DEFAULT_MAX_HANDLE_LENGTH`).
const DEFAULT_MAX_HANDLE_LENGTH: f64 = 0.35;
use mesh_fem::stats::stats;
use mesh_fem::MeshError;

#[test]
fn the_shortest_cycle_of_a_torus_is_a_minor_circle() {
    let (major, minor, nu, nv) = (1.0, 0.3, 40, 12);
    let mesh = torus(major, minor, nu, nv);
    let (cycle, length) = short_handle_cycle(&mesh).unwrap();
    // The polygon of nv chords of the circle of radius `minor`.
    let exact = nv as f64 * 2.0 * minor * (std::f64::consts::PI / nv as f64).sin();
    assert!((length - exact).abs() < 1e-9, "{length} vs {exact}");
    assert_eq!(cycle.len(), nv);
    // All on one ring u = const: vertex id = i·nv + j.
    let ring = cycle[0] as usize / nv;
    assert!(cycle.iter().all(|&v| v as usize / nv == ring), "{cycle:?}");
}

#[test]
fn cutting_the_handle_of_a_torus_leaves_a_closed_sphere() {
    let mesh = torus(1.0, 0.3, 40, 12);
    let scale = mesh.area().sqrt();
    let (_, length) = short_handle_cycle(&mesh).unwrap();
    // Above the bound: nothing is cut (a real handle); at the default bound neither.
    let kept = cut_handles(&mesh, 0.99 * length / scale).unwrap();
    assert!(kept.cut.is_empty());
    assert_eq!(kept.mesh.positions(), mesh.positions());
    assert!(length / scale > DEFAULT_MAX_HANDLE_LENGTH);
    let cut = cut_handles(&mesh, 1.01 * length / scale).unwrap();
    assert_eq!(cut.cut.len(), 1);
    assert!((cut.cut[0] - length / scale).abs() < 1e-12);
    let s = stats(&cut.mesh);
    assert_eq!((s.n_boundary_loops, s.n_components, s.genus), (0, 1, Some(0)));
    assert_eq!((s.n_non_manifold_edges, s.n_non_manifold_vertices), (0, 0));
    // Old vertices first and unmoved; the 12 copies of the cycle and the two patches after them.
    assert_eq!(cut.original_vertices, mesh.n_vertices());
    assert_eq!(&cut.mesh.positions()[..mesh.n_vertices()], mesh.positions());
    assert!(cut.mesh.n_vertices() > mesh.n_vertices() + 12);
    // The area grows by the two caps only (each about the disk of the tube's cross-section).
    let caps = 2.0 * std::f64::consts::PI * 0.3 * 0.3;
    let grown = cut.mesh.area() - mesh.area();
    assert!(grown > 0.5 * caps && grown < 1.5 * caps, "{grown} vs {caps}");
}

#[test]
fn genus_zero_and_open_meshes_are_left_alone() {
    for mesh in [icosphere(3), grid(6, 6)] {
        assert!(short_handle_cycle(&mesh).is_none());
        let c = cut_handles(&mesh, 10.0).unwrap();
        assert!(c.cut.is_empty());
        assert_eq!(c.mesh.positions(), mesh.positions());
        assert_eq!(c.mesh.faces(), mesh.faces());
    }
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(
            matches!(cut_handles(&icosphere(1), bad), Err(MeshError::Invalid { .. })),
            "{bad}"
        );
    }
}
