//! Tests of the FEM operators L (cotangent stiffness), B (consistent mass) and D (lumped
//! mass) of `mesh_fem::assemble` (paper, Eq. (3) and Eq. (7)).
//!
//! References used, all independent of the assembly code:
//! * closed-form identities (L·1 = 0, 1ᵀB1 = area, D = row sums of B, symmetry, scaling);
//! * a two-triangle mesh whose entries are derived by hand below;
//! * the analytic spectra of the Laplace–Beltrami operator on the unit sphere, l(l+1) with
//!   multiplicity 2l+1, and of the Neumann Laplacian on the unit square, π²(k² + m²),
//!   computed by a dense generalized symmetric eigendecomposition written here;
//! * libigl 2.6.3's `cotmatrix`, `massmatrix(FULL)` and `massmatrix(BARYCENTRIC)` stored in
//!   `../shared/reference/` found by `wfem_corpus::reference_dir` (overridable with `WFEM_REFERENCE`), compared entry by entry.

use faer::{Mat, Par, Side};
use mesh_fem::generate::{bumpy, grid, icosphere, irregular_sphere, torus, uv_sphere};
use mesh_fem::{assemble, AssemblyParams, FemOperators, Lumping, MeshError, TriMesh};
use std::collections::HashMap;
use std::path::PathBuf;

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------

fn ops(mesh: &TriMesh) -> FemOperators {
    assemble(mesh, &AssemblyParams::default()).expect("generated meshes assemble")
}

fn voronoi_ops(mesh: &TriMesh) -> FemOperators {
    let params = AssemblyParams {
        lumping: Lumping::Voronoi,
        ..Default::default()
    };
    assemble(mesh, &params).expect("generated meshes assemble")
}

/// All stored entries `(row, col, value)` of a CSC matrix.
pub(crate) fn entries(a: &faer::sparse::SparseColMat<usize, f64>) -> Vec<(usize, usize, f64)> {
    let sym = a.symbolic();
    let mut out = Vec::with_capacity(a.val().len());
    for j in 0..a.ncols() {
        for p in sym.col_range(j) {
            out.push((sym.row_idx()[p], j, a.val()[p]));
        }
    }
    out
}

/// Entry map `(row, col) → value` of a CSC matrix.
pub(crate) fn entry_map(a: &faer::sparse::SparseColMat<usize, f64>) -> HashMap<(usize, usize), f64> {
    entries(a).into_iter().map(|(i, j, v)| ((i, j), v)).collect()
}

pub(crate) fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// y = A x for a CSC matrix.
pub(crate) fn matvec(a: &faer::sparse::SparseColMat<usize, f64>, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.nrows()];
    for (i, j, v) in entries(a) {
        y[i] += v * x[j];
    }
    y
}

/// Max |A − Aᵀ| over the stored entries (a missing transposed entry counts as zero).
pub(crate) fn asymmetry(a: &faer::sparse::SparseColMat<usize, f64>) -> f64 {
    let m = entry_map(a);
    m.iter()
        .map(|(&(i, j), &v)| (v - m.get(&(j, i)).copied().unwrap_or(0.0)).abs())
        .fold(0.0, f64::max)
}

/// The generated meshes every identity is checked on.
fn test_meshes() -> Vec<(&'static str, TriMesh)> {
    vec![
        ("icosphere(3)", icosphere(3)),
        ("uv_sphere(16, 24)", uv_sphere(16, 24)),
        ("grid(20, 15)", grid(20, 15)),
        ("torus(1, 0.3, 40, 16)", torus(1.0, 0.3, 40, 16)),
        ("irregular_sphere(3, 5.6)", irregular_sphere(3, 5.6)),
        ("bumpy(3)", bumpy(3)),
    ]
}

// ---------------------------------------------------------------------------------------
// Identities on generated meshes
// ---------------------------------------------------------------------------------------

#[test]
fn stiffness_annihilates_constants() {
    for (name, mesh) in test_meshes() {
        let o = ops(&mesh);
        let l1 = matvec(&o.stiffness, &vec![1.0; o.n()]);
        let rel = max_abs(&l1) / max_abs(o.stiffness.val());
        assert!(rel < 1e-13, "{name}: ‖L·1‖∞ / max|L| = {rel:e}");
    }
}

#[test]
fn stiffness_and_mass_are_symmetric() {
    for (name, mesh) in test_meshes() {
        let o = ops(&mesh);
        // Assembly adds the same per-face terms in the same order on both sides of the
        // diagonal, so the symmetry is exact, not just up to rounding.
        assert_eq!(asymmetry(&o.stiffness), 0.0, "{name}: L not symmetric");
        assert_eq!(asymmetry(&o.mass), 0.0, "{name}: B not symmetric");
        assert_eq!(asymmetry(&o.lumped_mass()), 0.0, "{name}: D not symmetric");
    }
}

#[test]
fn stiffness_has_positive_diagonal_and_mass_is_positive() {
    for (name, mesh) in test_meshes() {
        let o = ops(&mesh);
        for (i, j, v) in entries(&o.stiffness) {
            if i == j {
                assert!(v > 0.0, "{name}: L[{i},{i}] = {v}");
            }
        }
        for (i, j, v) in entries(&o.mass) {
            assert!(v > 0.0, "{name}: B[{i},{j}] = {v} (every mass entry is a sum of areas)");
        }
        assert!(o.lumped_diagonal.iter().all(|&d| d > 0.0), "{name}: D not positive");
    }
}

#[test]
fn masses_sum_to_the_area() {
    for (name, mesh) in test_meshes() {
        let area = mesh.area();
        let o = ops(&mesh);
        let b_total: f64 = o.mass.val().iter().sum();
        let d_total: f64 = o.lumped_mass().val().iter().sum();
        let d_diag_total: f64 = o.lumped_diagonal.iter().sum();
        let v_total: f64 = voronoi_ops(&mesh).lumped_diagonal.iter().sum();
        for (what, total) in [
            ("1ᵀB1", b_total),
            ("1ᵀD1", d_total),
            ("Σ lumped_diagonal", d_diag_total),
            ("Σ Voronoi areas", v_total),
            ("FemOperators::area", o.area()),
        ] {
            assert!(
                (total - area).abs() <= 1e-13 * area,
                "{name}: {what} = {total}, area Σ|T| = {area}"
            );
        }
    }
}

#[test]
fn lumped_mass_is_row_sum_of_mass() {
    for (name, mesh) in test_meshes() {
        let o = ops(&mesh);
        let row_sums = matvec(&o.mass, &vec![1.0; o.n()]);
        let scale = max_abs(&o.lumped_diagonal);
        for (i, (&r, &d)) in row_sums.iter().zip(&o.lumped_diagonal).enumerate() {
            assert!(
                (r - d).abs() <= 1e-14 * scale,
                "{name}: row {i}: Σ_j B_ij = {r}, D = {d}"
            );
        }
        // D is diagonal: off-diagonal stored values are explicit zeros.
        for (i, j, v) in entries(&o.lumped_mass()) {
            let expected = if i == j { o.lumped_diagonal[i] } else { 0.0 };
            assert_eq!(v, expected, "{name}: D[{i},{j}]");
        }
    }
}

#[test]
fn operators_share_one_sorted_pattern() {
    for (name, mesh) in test_meshes() {
        for o in [ops(&mesh), voronoi_ops(&mesh)] {
            let s = o.stiffness.symbolic();
            for m in [&o.mass, &o.lumped_mass()] {
                assert_eq!(s.col_ptr(), m.symbolic().col_ptr(), "{name}");
                assert_eq!(s.row_idx(), m.symbolic().row_idx(), "{name}");
            }
            // Pattern = edges (both directions) plus the diagonal, rows sorted, no duplicates.
            let mut edges = std::collections::HashSet::new();
            for f in mesh.faces() {
                for k in 0..3 {
                    let (a, b) = (f[k] as usize, f[(k + 1) % 3] as usize);
                    edges.insert((a, b));
                    edges.insert((b, a));
                }
            }
            assert_eq!(s.row_idx().len(), edges.len() + mesh.n_vertices(), "{name}");
            for j in 0..o.n() {
                let rows = &s.row_idx()[s.col_range(j)];
                assert!(rows.windows(2).all(|w| w[0] < w[1]), "{name}: column {j}");
                assert!(rows.contains(&j), "{name}: no diagonal in column {j}");
                for &i in rows {
                    assert!(i == j || edges.contains(&(i, j)), "{name}: ({i},{j}) not an edge");
                }
            }
            // The identity mass lives on the same pattern.
            let id = o.identity_mass();
            assert_eq!(id.symbolic().row_idx(), s.row_idx(), "{name}");
            for (i, j, v) in entries(&id) {
                assert_eq!(v, if i == j { 1.0 } else { 0.0 }, "{name}");
            }
        }
    }
}

#[test]
fn voronoi_equals_barycentric_on_equilateral_triangles() {
    // The icosahedron has 20 equilateral faces. Each Voronoi corner area of an equilateral
    // triangle is |T|/3, exactly the barycentric share.
    let ico = icosphere(0);
    // A flat patch of equilateral triangles with a boundary: a strip of the triangular lattice.
    let h = 3f64.sqrt() / 2.0;
    let (nx, ny) = (6usize, 4usize);
    let mut positions = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            positions.push([i as f64 + 0.5 * (j % 2) as f64, j as f64 * h, 0.0]);
        }
    }
    let id = |i: usize, j: usize| (j * nx + i) as u32;
    let mut faces = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            if j % 2 == 0 {
                faces.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                faces.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            }
        }
    }
    let lattice = TriMesh::new(positions, faces).unwrap();
    for (name, mesh) in [("icosahedron", ico), ("triangular lattice", lattice)] {
        let bary = ops(&mesh).lumped_diagonal;
        let vor = voronoi_ops(&mesh).lumped_diagonal;
        for (i, (b, v)) in bary.iter().zip(&vor).enumerate() {
            assert!(
                (b - v).abs() <= 1e-14 * b,
                "{name}: vertex {i}: barycentric {b}, Voronoi {v}"
            );
        }
    }
    // On non-equilateral meshes the two differ (so the comparison above can fail).
    let m = irregular_sphere(2, 5.6);
    let (b, v) = (ops(&m).lumped_diagonal, voronoi_ops(&m).lumped_diagonal);
    let diff = b.iter().zip(&v).map(|(x, y)| (x - y).abs() / x).fold(0.0, f64::max);
    assert!(
        diff > 1e-3,
        "Voronoi and barycentric agree on an irregular mesh ({diff:e})"
    );
}

#[test]
fn voronoi_handles_obtuse_triangles() {
    // One obtuse triangle (angle 120° at vertex 0): mixed Voronoi areas give |T|/2 to the
    // obtuse corner and |T|/4 to the other two (Meyer et al. 2003, Fig. 4).
    let h = 3f64.sqrt() / 2.0;
    let mesh = TriMesh::new(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-0.5, h, 0.0]], vec![[0, 1, 2]]).unwrap();
    let area = 0.5 * h; // ½ |e01| |e02| sin 120° = ½ · 1 · 1 · √3/2
    let vor = voronoi_ops(&mesh).lumped_diagonal;
    let expected = [area / 2.0, area / 4.0, area / 4.0];
    for k in 0..3 {
        assert!((vor[k] - expected[k]).abs() < 1e-15, "{vor:?} vs {expected:?}");
    }
}

/// Dense reference assembly from the element matrices of linear hat functions, written
/// without cotangents: with e_a = p_{a+2} − p_{a+1} the edge opposite corner a,
/// ∇φ_a·∇φ_b = e_a·e_b / (4|T|²), so K^T_ab = e_a·e_b / (4|T|), and M^T_ab = |T|(1 + δ_ab)/12.
fn dense_reference(mesh: &TriMesh) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let n = mesh.n_vertices();
    let (mut k, mut m) = (vec![vec![0.0; n]; n], vec![vec![0.0; n]; n]);
    for (f, face) in mesh.faces().iter().enumerate() {
        let p = mesh.corners(f);
        let area = mesh.face_area(f);
        let e = |a: usize| {
            let (u, v) = (p[(a + 2) % 3], p[(a + 1) % 3]);
            [u[0] - v[0], u[1] - v[1], u[2] - v[2]]
        };
        for a in 0..3 {
            for b in 0..3 {
                let (ea, eb) = (e(a), e(b));
                let dot = ea[0] * eb[0] + ea[1] * eb[1] + ea[2] * eb[2];
                let (i, j) = (face[a] as usize, face[b] as usize);
                k[i][j] += dot / (4.0 * area);
                m[i][j] += area * if a == b { 2.0 } else { 1.0 } / 12.0;
            }
        }
    }
    (k, m)
}

#[test]
fn operators_match_dense_element_assembly() {
    // A "book" of three triangles sharing the edge 0–1 (non-manifold), plus a fourth page
    // attached to another edge, exercises merges of more than two faces per edge.
    let book = TriMesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.4, 1.0, 0.0],
            [0.6, -0.3, 0.8],
            [0.5, -0.7, -0.6],
            [1.2, 1.1, 0.4],
        ],
        vec![[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 5, 2]],
    )
    .unwrap();
    for (name, mesh) in [
        ("book", book),
        ("bumpy(1)", bumpy(1)),
        ("grid(7, 5)", grid(7, 5)),
        ("torus(1, 0.4, 9, 7)", torus(1.0, 0.4, 9, 7)),
    ] {
        let o = ops(&mesh);
        let (k, m) = dense_reference(&mesh);
        let scale_k = k.iter().flatten().fold(0.0f64, |a, b| a.max(b.abs()));
        let scale_m = m.iter().flatten().fold(0.0f64, |a, b| a.max(b.abs()));
        let (l, b) = (entry_map(&o.stiffness), entry_map(&o.mass));
        for i in 0..mesh.n_vertices() {
            for j in 0..mesh.n_vertices() {
                let lij = l.get(&(i, j)).copied().unwrap_or(0.0);
                let bij = b.get(&(i, j)).copied().unwrap_or(0.0);
                assert!(
                    (lij - k[i][j]).abs() <= 1e-13 * scale_k,
                    "{name}: L[{i},{j}] = {lij}, reference {}",
                    k[i][j]
                );
                assert!(
                    (bij - m[i][j]).abs() <= 1e-14 * scale_m,
                    "{name}: B[{i},{j}] = {bij}, reference {}",
                    m[i][j]
                );
            }
        }
        assert_eq!(asymmetry(&o.stiffness), 0.0, "{name}");
        assert_eq!(asymmetry(&o.mass), 0.0, "{name}");
        let l1 = matvec(&o.stiffness, &vec![1.0; o.n()]);
        assert!(max_abs(&l1) <= 1e-14 * scale_k, "{name}: L·1 = {l1:?}");
    }
}

/// A deterministic pseudo-random permutation of 0..n (LCG-driven Fisher–Yates).
fn permutation(n: usize, seed: u64) -> Vec<usize> {
    let mut p: Vec<usize> = (0..n).collect();
    let mut state = seed;
    for i in (1..n).rev() {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        p.swap(i, (state >> 33) as usize % (i + 1));
    }
    p
}

#[test]
fn assembly_is_equivariant_under_vertex_and_face_permutations() {
    // Renumbering the vertices by p permutes the operators: L'[p(i), p(j)] = L[i, j]; reordering
    // the faces changes nothing but the summation order. A random numbering also destroys the
    // locality of generated meshes, which exercises the vertex-range scatter.
    let mesh = irregular_sphere(3, 5.6);
    let n = mesh.n_vertices();
    let p = permutation(n, 7);
    let mut positions = vec![[0.0; 3]; n];
    for (i, &pi) in p.iter().enumerate() {
        positions[pi] = mesh.positions()[i];
    }
    let face_order = permutation(mesh.n_faces(), 11);
    let faces: Vec<[u32; 3]> = face_order
        .iter()
        .map(|&f| mesh.faces()[f].map(|v| p[v as usize] as u32))
        .collect();
    let shuffled = TriMesh::new(positions, faces).unwrap();
    for (a, b) in [
        (ops(&mesh), ops(&shuffled)),
        (voronoi_ops(&mesh), voronoi_ops(&shuffled)),
    ] {
        for (what, x, y) in [
            ("L", &a.stiffness, &b.stiffness),
            ("B", &a.mass, &b.mass),
            ("D", &a.lumped_mass(), &b.lumped_mass()),
        ] {
            let y = entry_map(y);
            assert_eq!(x.val().len(), y.len(), "{what}: pattern size");
            let scale = max_abs(x.val());
            for (i, j, v) in entries(x) {
                let w = y[&(p[i], p[j])];
                assert!((v - w).abs() <= 1e-14 * scale, "{what}[{i},{j}] = {v}, permuted {w}");
            }
        }
        for (i, &pi) in p.iter().enumerate() {
            let (u, w) = (a.lumped_diagonal[i], b.lumped_diagonal[pi]);
            assert!((u - w).abs() <= 1e-14 * u, "diag D[{i}]");
        }
    }
}

#[test]
fn assembly_is_bitwise_independent_of_the_thread_count() {
    // Contributions are summed in face order whatever the parallel split, so the result is
    // reproducible bit for bit on any number of threads.
    let mesh = bumpy(3);
    let reference = ops(&mesh);
    for threads in [1, 3, 5] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let o = pool.install(|| ops(&mesh));
        assert_eq!(
            o.stiffness.symbolic().row_idx(),
            reference.stiffness.symbolic().row_idx()
        );
        assert_eq!(o.stiffness.val(), reference.stiffness.val(), "{threads} threads: L");
        assert_eq!(o.mass.val(), reference.mass.val(), "{threads} threads: B");
        assert_eq!(
            o.lumped_mass().val(),
            reference.lumped_mass().val(),
            "{threads} threads: D"
        );
        assert_eq!(o.lumped_diagonal, reference.lumped_diagonal, "{threads} threads");
    }
}

// ---------------------------------------------------------------------------------------
// Scale covariance
// ---------------------------------------------------------------------------------------

#[test]
fn scale_covariance() {
    // In 2D the cotangent weights are scale invariant, and areas scale with α².
    for (name, mesh) in [
        ("irregular_sphere(2, 5.6)", irregular_sphere(2, 5.6)),
        ("grid(9, 7)", grid(9, 7)),
        ("bumpy(2)", bumpy(2)),
    ] {
        let base = ops(&mesh);
        for alpha in [1e-6, 1e6] {
            let scaled = ops(&mesh.scaled(alpha).unwrap());
            let a2 = alpha * alpha;
            let cmp = |what: &str, x: &[f64], y: &[f64], factor: f64| {
                let scale = max_abs(x) * factor;
                let err = x.iter().zip(y).map(|(a, b)| (a * factor - b).abs()).fold(0.0, f64::max);
                assert!(err <= 1e-12 * scale, "{name}, α = {alpha:e}: {what} error {err:e}");
            };
            cmp("L", base.stiffness.val(), scaled.stiffness.val(), 1.0);
            cmp("B", base.mass.val(), scaled.mass.val(), a2);
            cmp("D", base.lumped_mass().val(), scaled.lumped_mass().val(), a2);
            cmp("diag D", &base.lumped_diagonal, &scaled.lumped_diagonal, a2);
        }
    }
}

/// Scaling by an exact power of two 2ᵏ changes nothing but the exponents: L is bitwise the
/// same and B, D are bitwise 4ᵏ times the unscaled ones, for k on both sides of the range where
/// the element code skips its own power-of-two scaling (edges between 1e−60 and 1e60), up to
/// edges of 1e±100 and areas far beyond what an unscaled cross product could hold.
#[test]
fn power_of_two_scaling_is_bitwise_exact() {
    let mesh = irregular_sphere(2, 5.6);
    let base = ops(&mesh);
    for k in [-330, -230, -205, -195, -100, 100, 195, 205, 230, 330] {
        let s = 2f64.powi(k);
        let scaled = ops(&mesh.scaled(s).unwrap());
        assert_eq!(scaled.stiffness.val(), base.stiffness.val(), "k = {k}: L");
        let b: Vec<f64> = base.mass.val().iter().map(|v| v * s * s).collect();
        assert_eq!(scaled.mass.val(), &b[..], "k = {k}: B");
        let d: Vec<f64> = base.lumped_diagonal.iter().map(|v| v * s * s).collect();
        assert_eq!(scaled.lumped_diagonal, d, "k = {k}: D");
    }
}

/// `lumped_mass()` is D on the shared pattern: the lumped diagonal on the diagonal, explicit
/// zeros elsewhere; `identity_mass()` the same with ones.
#[test]
fn lumped_and_identity_mass_sit_on_the_shared_pattern() {
    let o = ops(&irregular_sphere(2, 5.6));
    for (m, diagonal) in [
        (o.lumped_mass(), o.lumped_diagonal.clone()),
        (o.identity_mass(), vec![1.0; o.n()]),
    ] {
        assert_eq!(m.symbolic().col_ptr(), o.stiffness.symbolic().col_ptr());
        assert_eq!(m.symbolic().row_idx(), o.stiffness.symbolic().row_idx());
        for (i, j, v) in entries(&m) {
            assert_eq!(v, if i == j { diagonal[i] } else { 0.0 }, "({i}, {j})");
        }
    }
}

// ---------------------------------------------------------------------------------------
// Hand-computed two-triangle case
// ---------------------------------------------------------------------------------------

#[test]
fn unit_square_two_triangles_by_hand() {
    // 3 ---- 2        T0 = (0, 1, 2): right angle at 1, 45° at 0 and 2.
    // |    / |        T1 = (0, 2, 3): right angle at 3, 45° at 0 and 2.
    // |  /   |        |T0| = |T1| = ½, area 1.
    // 0 ---- 1
    //
    // Stiffness L_ij = −½ Σ cot(angle opposite ij):
    //   edge 01: opposite 2 in T0 (45°, cot 1)            → L01 = −½
    //   edge 12: opposite 0 in T0 (45°, cot 1)            → L12 = −½
    //   edge 23: opposite 0 in T1 (45°, cot 1)            → L23 = −½
    //   edge 30: opposite 2 in T1 (45°, cot 1)            → L03 = −½
    //   edge 02: opposite 1 in T0 and 3 in T1 (90°, cot 0) → L02 = 0 (stored)
    //   vertices 1 and 3 share no edge                      → not stored
    //   L_ii = −Σ_j L_ij = 1 for every vertex.
    // Consistent mass: B_ii = Σ_{T∋i}|T|/6, B_ij = Σ_{T∋ij}|T|/12:
    //   B00 = B22 = 2·½/6 = 1/6,  B11 = B33 = ½/6 = 1/12,
    //   B02 = 2·½/12 = 1/12,      B01 = B12 = B23 = B03 = ½/12 = 1/24.
    // Lumped barycentric D_ii = Σ_{T∋i}|T|/3: D00 = D22 = 1/3, D11 = D33 = 1/6.
    // Mixed Voronoi (right triangles are not obtuse, so the circumcentre is the hypotenuse
    // midpoint): each corner of the unit square gets the quarter square, D_ii = 1/4.
    let mesh = TriMesh::new(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let o = ops(&mesh);
    let (h, q) = (0.5, 1.0 / 24.0);
    #[rustfmt::skip]
    let expected_l = [
        [1.0, -h,  0.0, -h ],
        [-h,  1.0, -h,  f64::NAN],
        [0.0, -h,  1.0, -h ],
        [-h,  f64::NAN, -h, 1.0],
    ];
    #[rustfmt::skip]
    let expected_b = [
        [1.0 / 6.0,  q,          1.0 / 12.0, q         ],
        [q,          1.0 / 12.0, q,          f64::NAN  ],
        [1.0 / 12.0, q,          1.0 / 6.0,  q         ],
        [q,          f64::NAN,   q,          1.0 / 12.0],
    ];
    let expected_d = [1.0 / 3.0, 1.0 / 6.0, 1.0 / 3.0, 1.0 / 6.0];
    let (l, b, d) = (entry_map(&o.stiffness), entry_map(&o.mass), entry_map(&o.lumped_mass()));
    assert_eq!(l.len(), 14, "4 diagonal + 2·5 edge entries");
    for i in 0..4 {
        for j in 0..4 {
            if expected_l[i][j].is_nan() {
                assert!(!l.contains_key(&(i, j)), "({i},{j}) must not be stored");
                continue;
            }
            assert!(
                (l[&(i, j)] - expected_l[i][j]).abs() < 1e-15,
                "L[{i},{j}] = {}",
                l[&(i, j)]
            );
            assert!(
                (b[&(i, j)] - expected_b[i][j]).abs() < 1e-15,
                "B[{i},{j}] = {}",
                b[&(i, j)]
            );
            let dij = if i == j { expected_d[i] } else { 0.0 };
            assert!((d[&(i, j)] - dij).abs() < 1e-15, "D[{i},{j}] = {}", d[&(i, j)]);
        }
        assert!((o.lumped_diagonal[i] - expected_d[i]).abs() < 1e-15);
    }
    let vor = voronoi_ops(&mesh).lumped_diagonal;
    for (i, v) in vor.iter().enumerate() {
        assert!((v - 0.25).abs() < 1e-15, "Voronoi D[{i}] = {v}");
    }
}

// ---------------------------------------------------------------------------------------
// Spectra against analytic eigenvalues
// ---------------------------------------------------------------------------------------

pub(crate) fn dense(a: &faer::sparse::SparseColMat<usize, f64>) -> Mat<f64> {
    let mut m = Mat::zeros(a.nrows(), a.ncols());
    for (i, j, v) in entries(a) {
        m[(i, j)] = v;
    }
    m
}

/// Eigenvalues of the symmetric-definite pencil (L, B), ascending: with B = RRᵀ (Cholesky),
/// L x = λ B x ⇔ C y = λ y for C = R⁻¹ L R⁻ᵀ, y = Rᵀx.
pub(crate) fn generalized_eigenvalues(l: &Mat<f64>, b: &Mat<f64>) -> Vec<f64> {
    let r = b.llt(Side::Lower).expect("B is positive definite");
    let r = r.L();
    // X = R⁻¹ L, then C = R⁻¹ Xᵀ = R⁻¹ L R⁻ᵀ (L symmetric).
    let mut x = l.clone();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(r, x.as_mut(), Par::Seq);
    let mut c = x.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(r, c.as_mut(), Par::Seq);
    // Symmetrize the rounding before the symmetric eigensolver.
    let c = Mat::from_fn(c.nrows(), c.ncols(), |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    c.self_adjoint_eigenvalues(Side::Lower)
        .expect("symmetric eigendecomposition converges")
}

/// Max relative error of eigenvalues 0..expected.len() against `expected` (λ0 = 0 absolute).
fn spectrum_errors(eig: &[f64], expected: &[f64]) -> Vec<f64> {
    eig.iter()
        .zip(expected)
        .map(|(l, e)| if *e == 0.0 { l.abs() } else { (l - e).abs() / e })
        .collect()
}

#[test]
fn sphere_spectrum_approaches_l_times_l_plus_one() {
    // Eigenvalues of the unit sphere: l(l+1) with multiplicity 2l+1: 0; 2 (×3); 6 (×5); 12 (×7).
    let mut expected = vec![0.0];
    for l in 1..=3 {
        expected.extend(std::iter::repeat_n((l * (l + 1)) as f64, 2 * l + 1));
    }
    let mut worst = Vec::new();
    for level in [2, 3] {
        let mesh = icosphere(level);
        let o = ops(&mesh);
        let eig = generalized_eigenvalues(&dense(&o.stiffness), &dense(&o.mass));
        // λ0 = 0 is simple: the sphere is connected.
        assert!(eig[0].abs() < 1e-10, "level {level}: λ0 = {}", eig[0]);
        assert!(eig[1] > 1.0, "level {level}: λ1 = {} (λ0 must be simple)", eig[1]);
        // The cluster l = 3 ends at index 15, and index 16 starts l = 4 (20).
        assert!(eig[16] > 15.0, "level {level}: λ16 = {}", eig[16]);
        let errs = spectrum_errors(&eig, &expected);
        let max_err = errs[1..].iter().cloned().fold(0.0, f64::max);
        eprintln!(
            "icosphere({level}): λ1..15 = {:?}, max rel err {max_err:e}",
            &eig[1..16]
        );
        // Multiplicities 3, 5, 7: each cluster is tight (icosahedral symmetry keeps l = 1, 2
        // exactly degenerate and splits l = 3 into 3 + 4 by less than 1e-3 relative).
        for (lo, hi) in [(1, 4), (4, 9), (9, 16)] {
            let spread = (eig[hi - 1] - eig[lo]) / eig[lo];
            assert!(spread < 2e-3, "level {level}: cluster {lo}..{hi} spread {spread:e}");
        }
        worst.push(max_err);
    }
    // Measured: max relative error 8.4e-2 at level 2 (162 vertices), 2.06e-2 at level 3
    // (642 vertices): the O(h²) rate of linear elements (a factor 4.1 per halving of h).
    assert!(worst[0] < 0.10, "level 2 error {:e}", worst[0]);
    assert!(worst[1] < 0.025, "level 3 error {:e}", worst[1]);
    assert!(worst[1] < worst[0] / 3.5, "error must decrease like h²: {worst:?}");
}

#[test]
fn square_neumann_spectrum_approaches_pi_squared_sums() {
    // Neumann Laplacian on [0,1]²: π²(k² + m²), k, m ≥ 0: 0, π², π², 2π², 4π², 4π², 5π², 5π², 8π².
    let mut expected: Vec<f64> = (0..5)
        .flat_map(|k| (0..5).map(move |m| (k * k + m * m) as f64))
        .collect();
    expected.sort_by(f64::total_cmp);
    let expected: Vec<f64> = expected[..9].iter().map(|s| s * std::f64::consts::PI.powi(2)).collect();
    let mut worst = Vec::new();
    for n in [13, 25] {
        let o = ops(&grid(n, n));
        let eig = generalized_eigenvalues(&dense(&o.stiffness), &dense(&o.mass));
        assert!(eig[0].abs() < 1e-10, "grid {n}: λ0 = {}", eig[0]);
        let errs = spectrum_errors(&eig, &expected);
        let max_err = errs[1..].iter().cloned().fold(0.0, f64::max);
        eprintln!(
            "grid({n},{n}): λ1..8 / π² = {:?}, max rel err {max_err:e}",
            eig[1..9]
                .iter()
                .map(|x| x / std::f64::consts::PI.powi(2))
                .collect::<Vec<_>>()
        );
        worst.push(max_err);
    }
    // Measured: max relative error 6.2e-2 at h = 1/12 and 1.53e-2 at h = 1/24 (the largest
    // is at 8π²): a factor 4.0 per halving of h, the O(h²) rate of linear elements.
    assert!(worst[0] < 0.075, "grid 13×13 error {:e}", worst[0]);
    assert!(worst[1] < 0.019, "grid 25×25 error {:e}", worst[1]);
    assert!(worst[1] < worst[0] / 3.5, "error must decrease like h²: {worst:?}");
}

// ---------------------------------------------------------------------------------------
// Entry-wise agreement with libigl
// ---------------------------------------------------------------------------------------

fn reference_dir() -> Option<PathBuf> {
    let dir = wfem_corpus::reference_dir();
    if dir.is_none() {
        eprintln!("../shared/reference is not present: the libigl cross-check does not run");
    }
    dir
}

/// Minimal OBJ reader: `v x y z` and `f a b c` (1-based; `a/t/n` forms allowed).
pub(crate) fn read_obj(path: &std::path::Path) -> TriMesh {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let (mut positions, mut faces) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).map(|s| s.parse().unwrap()).collect();
                positions.push([c[0], c[1], c[2]]);
            }
            Some("f") => {
                let c: Vec<u32> = it
                    .map(|s| s.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                assert_eq!(c.len(), 3, "{path:?}: non-triangle face");
                faces.push([c[0], c[1], c[2]]);
            }
            _ => {}
        }
    }
    TriMesh::new(positions, faces).unwrap()
}

/// Minimal Matrix Market reader (coordinate real, general or symmetric) into a full entry map.
pub(crate) fn read_mtx(path: &std::path::Path) -> (usize, HashMap<(usize, usize), f64>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_lowercase();
    assert!(header.starts_with("%%matrixmarket matrix coordinate real"), "{header}");
    let symmetric = header.contains("symmetric");
    let mut lines = lines.filter(|l| !l.starts_with('%') && !l.trim().is_empty());
    let size: Vec<usize> = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(|s| s.parse().unwrap())
        .collect();
    let mut map = HashMap::new();
    for line in lines {
        let mut it = line.split_whitespace();
        let i: usize = it.next().unwrap().parse::<usize>().unwrap() - 1;
        let j: usize = it.next().unwrap().parse::<usize>().unwrap() - 1;
        let v: f64 = it.next().unwrap().parse().unwrap();
        *map.entry((i, j)).or_insert(0.0) += v;
        if symmetric && i != j {
            *map.entry((j, i)).or_insert(0.0) += v;
        }
    }
    assert!(map.len() <= size[2] * 2, "{path:?}: more entries than declared");
    (size[0], map)
}

/// Max |ours − reference| over the union of both patterns, and max |reference|.
pub(crate) fn compare(ours: &HashMap<(usize, usize), f64>, reference: &HashMap<(usize, usize), f64>) -> (f64, f64) {
    let mut diff = 0.0f64;
    for (k, v) in ours {
        diff = diff.max((v - reference.get(k).copied().unwrap_or(0.0)).abs());
    }
    for (k, v) in reference {
        diff = diff.max((v - ours.get(k).copied().unwrap_or(0.0)).abs());
    }
    let scale = reference.values().fold(0.0f64, |m, v| m.max(v.abs()));
    (diff, scale)
}

#[test]
fn operators_match_libigl_entry_by_entry() {
    let Some(dir) = reference_dir() else { return };
    for name in ["irregular_sphere_L4", "grid_70x70", "ellipsoid_L4"] {
        let mesh = read_obj(&dir.join(format!("{name}.obj")));
        let o = ops(&mesh);
        for (what, ours, file) in [
            ("stiffness", &o.stiffness, "stiffness"),
            ("mass", &o.mass, "mass"),
            ("lumped mass", &o.lumped_mass(), "lumped_mass"),
        ] {
            let (n, reference) = read_mtx(&dir.join(format!("{name}_{file}.mtx")));
            assert_eq!(n, o.n(), "{name}: size");
            let (diff, scale) = compare(&entry_map(ours), &reference);
            eprintln!("{name} {what}: max |ours − libigl| = {diff:e}, max |entry| = {scale:e}");
            assert!(diff <= 1e-13 * scale, "{name} {what}: {diff:e} vs scale {scale:e}");
        }
        if name == "irregular_sphere_L4" {
            // The obtuse triangles produce positive off-diagonal stiffness entries (negative
            // cotangent weights), which are therefore covered by the comparison above.
            let positive = entries(&o.stiffness)
                .iter()
                .filter(|&&(i, j, v)| i != j && v > 0.0)
                .count();
            assert!(positive > 0, "{name}: expected negative cotangent weights");
        }
    }
}

// ---------------------------------------------------------------------------------------
// Snapshot
// ---------------------------------------------------------------------------------------

/// Rounds to 10 significant digits (and maps −0 and rounding noise below 1e-15 to 0).
fn sig10(x: f64) -> String {
    if x.abs() < 1e-15 {
        "0".to_string()
    } else {
        format!("{x:.9e}")
    }
}

#[test]
fn snapshot_grid_3x3_operators() {
    let o = ops(&grid(3, 3));
    let d = entry_map(&o.lumped_mass());
    let b = entry_map(&o.mass);
    let mut out = String::from("row col L B D\n");
    for (i, j, l) in entries(&o.stiffness) {
        out.push_str(&format!(
            "{i} {j} {} {} {}\n",
            sig10(l),
            sig10(b[&(i, j)]),
            sig10(d[&(i, j)])
        ));
    }
    insta::assert_snapshot!(out);
}

// ---------------------------------------------------------------------------------------
// Typed errors
// ---------------------------------------------------------------------------------------

fn square_positions() -> Vec<[f64; 3]> {
    vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
}

#[test]
fn zero_area_face_is_a_typed_error() {
    // Face 2 joins three collinear points (0,0), (1,0), (½,0).
    let mut positions = square_positions();
    positions.push([0.5, 0.0, 0.0]);
    let mesh = TriMesh::new(positions, vec![[0, 1, 2], [0, 2, 3], [0, 4, 1]]).unwrap();
    match assemble(&mesh, &AssemblyParams::default()) {
        Err(MeshError::DegenerateFace { face, vertices }) => {
            assert_eq!(face, 2);
            assert_eq!(vertices, [0, 4, 1]);
        }
        other => panic!("expected DegenerateFace, got {other:?}"),
    }
    // A face that repeats a vertex has zero area too.
    let mesh = TriMesh::new(square_positions(), vec![[0, 1, 2], [0, 2, 3], [3, 3, 1]]).unwrap();
    let err = assemble(&mesh, &AssemblyParams::default()).unwrap_err();
    assert!(matches!(err, MeshError::DegenerateFace { face: 2, .. }), "{err:?}");
    assert!(err.to_string().contains("face 2"), "{err}");
}

#[test]
fn unreferenced_vertex_is_a_typed_error() {
    let mut positions = square_positions();
    positions.insert(2, [5.0, 5.0, 5.0]); // vertex 2 is in no face
    let mesh = TriMesh::new(positions, vec![[0, 1, 3], [0, 3, 4]]).unwrap();
    let err = assemble(&mesh, &AssemblyParams::default()).unwrap_err();
    assert!(matches!(err, MeshError::UnreferencedVertex { vertex: 2 }), "{err:?}");
    assert!(err.to_string().contains("vertex 2"), "{err}");
}

#[test]
fn mass_registry_is_consistent_and_names_libigls_matrices() {
    use mesh_fem::Mass;
    use wfem_base::Choice;
    wfem_base::check_registry::<Mass>().unwrap();
    assert_eq!(Mass::default(), Mass::Consistent);
    assert_eq!(Mass::parse("wfem").unwrap(), Mass::Consistent);
    assert_eq!(Mass::parse("lumped").unwrap(), Mass::Lumped(Lumping::Barycentric));
    assert_eq!(Mass::parse("VORONOI").unwrap(), Mass::Lumped(Lumping::Voronoi));
    assert_eq!(Mass::parse("linear").unwrap(), Mass::Identity);
    assert_eq!(Mass::Lumped(Lumping::Voronoi).lumping(), Lumping::Voronoi);
    assert_eq!(Mass::Identity.lumping(), Lumping::Barycentric);
    let fem = assemble(
        &icosphere(1),
        &AssemblyParams::for_mass(Mass::parse("voronoi").unwrap()),
    )
    .unwrap();
    assert_eq!(fem.lumping, Lumping::Voronoi);
}
