//! `mesh_fem::gradient`: the per-element gradients reproduce linear functions exactly, and
//! `Gᵀ diag|T| G` is the stiffness L of the same triangles (cotangent and intrinsic).

use mesh_fem::generate::{bumpy, grid, icosphere};
use mesh_fem::gradient::{triangle_gradients, ElementGradients};
use mesh_fem::intrinsic::{robust_triangulation, ROBUST_WEIGHT};
use mesh_fem::{assemble, AssemblyParams, MeshError, RobustParams};

/// `Gᵀ diag|T| G` as a dense matrix.
fn gram(g: &ElementGradients) -> Vec<Vec<f64>> {
    let n = g.n_vertices();
    let mut m = vec![vec![0.0; n]; n];
    for e in 0..g.n_elements() {
        let (c, b, w) = (g.corners(e), g.basis(e), g.measure(e));
        for a in 0..c.len() {
            for d in 0..c.len() {
                let dot: f64 = (0..3).map(|k| b[a][k] * b[d][k]).sum();
                m[c[a] as usize][c[d] as usize] += w * dot;
            }
        }
    }
    m
}

fn max_difference(dense: &[Vec<f64>], sparse: &faer::sparse::SparseColMat<usize, f64>) -> f64 {
    let mut worst = 0.0f64;
    let mut scale = 0.0f64;
    let n = dense.len();
    let mut from_sparse = vec![vec![0.0; n]; n];
    let r = sparse.as_ref();
    for j in 0..n {
        for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            from_sparse[i][j] += v;
        }
    }
    for i in 0..n {
        for j in 0..n {
            worst = worst.max((dense[i][j] - from_sparse[i][j]).abs());
            scale = scale.max(from_sparse[i][j].abs());
        }
    }
    worst / scale
}

#[test]
fn gram_of_the_gradients_is_the_cotangent_stiffness() {
    for mesh in [icosphere(2), bumpy(2), grid(9, 7)] {
        let g = ElementGradients::of_mesh(&mesh);
        let ops = assemble(&mesh, &AssemblyParams::default()).unwrap();
        let e = max_difference(&gram(&g), &ops.stiffness);
        assert!(e < 1e-12, "relative difference {e}");
    }
}

#[test]
fn gram_of_the_intrinsic_gradients_is_the_robust_stiffness() {
    let mesh = bumpy(2);
    let (tri, _) = robust_triangulation(&mesh, &RobustParams::default()).unwrap();
    let g = ElementGradients::of_intrinsic(&tri, ROBUST_WEIGHT).unwrap();
    let ops = tri.operators(ROBUST_WEIGHT, &AssemblyParams::default()).unwrap();
    let e = max_difference(&gram(&g), &ops.stiffness);
    assert!(e < 1e-12, "relative difference {e}");
}

#[test]
fn linear_functions_have_their_exact_gradient_length_and_divergence_sums_to_zero() {
    let mesh = grid(8, 6);
    let g = ElementGradients::of_mesh(&mesh);
    // f = 3x − 4y has |∇f| = 5 on every triangle, whatever its frame.
    let f: Vec<f64> = mesh.positions().iter().map(|p| 3.0 * p[0] - 4.0 * p[1]).collect();
    for e in 0..g.n_elements() {
        let v = g.gradient_on(e, |i| f[i as usize]);
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        assert!((len - 5.0).abs() < 1e-12, "{len}");
    }
    let field: Vec<[f64; 3]> = (0..g.n_elements())
        .map(|e| [0.3, -0.7, 0.0].map(|x| x + e as f64 * 1e-3))
        .collect();
    let b = g.divergence(&field).unwrap();
    assert!(b.iter().sum::<f64>().abs() < 1e-12);
    assert!(matches!(
        g.divergence(&field[1..]),
        Err(MeshError::ElementFieldLength { found, expected }) if found + 1 == expected
    ));
}

#[test]
fn a_triangle_of_zero_area_has_no_gradients() {
    assert!(triangle_gradients([1.0, 1.0, 2.0]).is_none());
    let (g, area) = triangle_gradients([1.0, 2f64.sqrt(), 1.0]).unwrap();
    assert!((area - 0.5).abs() < 1e-15);
    // The gradients of the three hat functions sum to zero.
    for k in 0..3 {
        assert!((g[0][k] + g[1][k] + g[2][k]).abs() < 1e-15);
    }
    assert!(ElementGradients::from_triangles(3, &[[0, 1, 2]], |_| [1.0; 3], 0.0).is_err());
}
