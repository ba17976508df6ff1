//! `refine::split_faces`: the same surface with four times the triangles, and FEM eigenvalues
//! that approach the analytic spectrum as it is applied.

use crate::operators::{dense, generalized_eigenvalues};
use mesh_fem::generate::{grid, icosphere, torus};
use mesh_fem::refine::{split_faces, split_faces_at};
use mesh_fem::{assemble, stats, AssemblyParams};

fn area(mesh: &mesh_fem::TriMesh) -> f64 {
    let p = mesh.positions();
    mesh.faces()
        .iter()
        .map(|f| {
            let (a, b, c) = (p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]);
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
        })
        .sum()
}

#[test]
fn split_keeps_vertices_first_and_the_surface() {
    for mesh in [torus(1.0, 0.3, 12, 8), grid(4, 3)] {
        let s = stats::stats(&mesh);
        let fine = split_faces(&mesh);
        // One new vertex per edge, four faces per face.
        assert_eq!(fine.n_vertices(), mesh.n_vertices() + s.n_edges);
        assert_eq!(fine.faces().len(), 4 * mesh.faces().len());
        assert_eq!(&fine.positions()[..mesh.n_vertices()], mesh.positions());
        assert!((area(&fine) - area(&mesh)).abs() < 1e-12 * area(&mesh));
        let t = stats::stats(&fine);
        assert_eq!(t.euler_characteristic, s.euler_characteristic);
        assert_eq!(
            (t.n_boundary_loops, t.n_boundary_edges),
            (s.n_boundary_loops, 2 * s.n_boundary_edges)
        );
    }
}

#[test]
fn split_at_edge_points_keeps_the_surface_but_not_the_triangulation() {
    let mesh = torus(1.0, 0.3, 12, 8);
    // Midpoints: the mesh of split_faces (the same faces; the positions to rounding, as
    // a + (b − a)/2 is not always (a + b)/2 in floating point).
    let half = split_faces_at(&mesh, |_, _| 0.5).unwrap();
    assert_eq!(half.faces(), split_faces(&mesh).faces());
    for (p, q) in half.positions().iter().zip(split_faces(&mesh).positions()) {
        assert!((0..3).all(|k| (p[k] - q[k]).abs() <= 1e-15), "{p:?} against {q:?}");
    }
    // Points elsewhere on the edges: the same vertices first, the same faces and area, other
    // positions for the edge points.
    let skewed = split_faces_at(&mesh, |a, b| if (a + b) % 2 == 0 { 0.3 } else { 0.8 }).unwrap();
    let fine = split_faces(&mesh);
    assert_eq!(skewed.faces(), fine.faces());
    assert_eq!(&skewed.positions()[..mesh.n_vertices()], mesh.positions());
    assert_ne!(skewed.positions(), fine.positions());
    assert!((area(&skewed) - area(&mesh)).abs() < 1e-12 * area(&mesh));
    // A fraction that folds the triangles over is refused by name.
    for bad in [0.0, 1.0, -0.2, f64::NAN] {
        let err = split_faces_at(&mesh, |_, _| bad).unwrap_err();
        assert!(err.to_string().contains("edge fraction"), "{err}");
    }
}

#[test]
fn split_of_an_icosphere_level_is_the_next_level_before_projection() {
    // The icosphere projects its midpoints on the sphere; the split keeps them on the chords,
    // so the two meshes share faces and the first vertices exactly.
    let (coarse, next) = (icosphere(1), icosphere(2));
    let fine = split_faces(&coarse);
    assert_eq!(fine.faces(), next.faces());
    assert_eq!(
        &fine.positions()[..coarse.n_vertices()],
        &next.positions()[..coarse.n_vertices()]
    );
}

#[test]
fn splitting_a_coarse_square_brings_its_eigenvalues_to_the_analytic_ones() {
    // Neumann spectrum of the unit square: π²(k² + m²): 0, π², π², 2π², 4π², 4π², 5π², 5π².
    let pi2 = std::f64::consts::PI.powi(2);
    let expected = [1.0, 1.0, 2.0, 4.0, 4.0, 5.0, 5.0].map(|c| c * pi2);
    let mut mesh = grid(4, 4);
    let mut errors = Vec::new();
    for _ in 0..3 {
        let ops = assemble(&mesh, &AssemblyParams::default()).unwrap();
        let eig = generalized_eigenvalues(&dense(&ops.stiffness), &dense(&ops.mass));
        assert!(eig[0].abs() < 1e-9);
        let err = eig[1..8]
            .iter()
            .zip(expected)
            .map(|(l, e)| (l - e).abs() / e)
            .fold(0.0, f64::max);
        errors.push(err);
        mesh = split_faces(&mesh);
    }
    // 16 → 49 → 169 vertices: the error falls about fourfold per split (O(h²)); measured
    // 1.19, 0.20, 0.047.
    assert!(errors[0] > 1.0, "{errors:?}");
    assert!(errors[1] < errors[0] / 4.0 && errors[2] < errors[1] / 3.5, "{errors:?}");
    assert!(errors[2] < 0.05, "{errors:?}");
}
