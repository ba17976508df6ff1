//! Linear FEM operators on a triangle mesh (paper, Eq. (3) and Eq. (7)).
//!
//! * **Stiffness** L (cotangent weights), symmetric positive semidefinite:
//!   `L_ij = −½ (cot α_ij + cot β_ij)` for an edge ij, `L_ii = −Σ_{j≠i} L_ij`, so `L·1 = 0`.
//!   The paper prints Eq. (3) with the opposite sign (`L_ij = +w_ij`, `L_ii = −Σ w`); wfem
//!   keeps the positive semidefinite convention everywhere (libigl's `cotmatrix` is −L).
//! * **Consistent mass** B, symmetric positive definite: `B_ij = (|T_r| + |T_s|)/12` on an
//!   edge, `B_ii = Σ_{T∋i} |T|/6` (Eq. (3)).
//! * **Lumped mass** D, diagonal: `D_ii = Σ_{T∋i} |T|/3` (barycentric, Eq. (7)), or the
//!   mixed Voronoi areas of Meyer et al. as an option. Every row of B sums to the
//!   barycentric D_ii.
//!
//! On open meshes the boundary terms vanish: this is the natural (Neumann) boundary
//! condition. Assembly is per face, so non-manifold meshes assemble too.
//!
//! All three matrices share one sparsity pattern (vertex–edge graph plus the diagonal; D
//! stores explicit zeros off the diagonal), so one symbolic factorization serves L, B, D and
//! every shifted matrix `tL − zB`. Assembly is O(#faces): a counting sort of the half-edges
//! by column, then a parallel (rayon) merge per column.

use crate::mesh::{cross, dot, norm, sub};
use crate::{MeshError, TriMesh};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;

/// Which diagonal lumped mass D to assemble.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LumpedMassKind {
    /// One third of the incident triangle areas, `D_ii = Σ_{T∋i}|T|/3` (the paper's Eq. (7));
    /// equal to the row sums of the consistent mass B.
    #[default]
    Barycentric,
    /// Mixed Voronoi areas (Meyer, Desbrun, Schröder, Barr 2003): Voronoi regions on
    /// non-obtuse triangles, |T|/2 at an obtuse corner and |T|/4 at the other two.
    Voronoi,
}

/// Options of [`assemble`].
#[derive(Clone, Copy, Debug, Default)]
pub struct AssemblyParams {
    /// Which lumped mass to assemble.
    pub lumped: LumpedMassKind,
}

/// The FEM operators of a mesh, all n × n on one shared sparsity pattern.
#[derive(Clone, Debug)]
pub struct FemOperators {
    /// Cotangent stiffness L: symmetric positive semidefinite, positive diagonal, `L·1 = 0`.
    pub stiffness: SparseColMat<usize, f64>,
    /// Consistent (Galerkin) mass B: symmetric positive definite, `1ᵀB1 = area`.
    pub mass: SparseColMat<usize, f64>,
    /// Lumped mass D on the same pattern (off-diagonal entries are explicit zeros).
    pub lumped_mass: SparseColMat<usize, f64>,
    /// The diagonal of D as a vector.
    pub lumped_diagonal: Vec<f64>,
}

impl FemOperators {
    /// Number of vertices n.
    pub fn n(&self) -> usize {
        self.stiffness.nrows()
    }

    /// Total area, `1ᵀB1`.
    pub fn area(&self) -> f64 {
        self.mass.val().iter().sum()
    }

    /// The identity matrix on the shared pattern (the mass of the "linear FEM" kernel, B = I).
    pub fn identity_mass(&self) -> SparseColMat<usize, f64> {
        let sym = self.stiffness.symbolic();
        let mut val = vec![0.0; sym.row_idx().len()];
        for j in 0..sym.ncols() {
            for p in sym.col_range(j) {
                if sym.row_idx()[p] == j {
                    val[p] = 1.0;
                }
            }
        }
        SparseColMat::new(
            self.stiffness.symbolic().to_owned().expect("clone of a valid pattern"),
            val,
        )
    }
}

/// Per-face geometry: area and the cotangent of the angle at each corner.
#[inline]
fn face_cotangents(p: [[f64; 3]; 3]) -> (f64, [f64; 3]) {
    let mut cots = [0.0; 3];
    let double_area = norm(cross(sub(p[1], p[0]), sub(p[2], p[0])));
    for k in 0..3 {
        let e1 = sub(p[(k + 1) % 3], p[k]);
        let e2 = sub(p[(k + 2) % 3], p[k]);
        // cot θ = cos/sin = (e1·e2)/‖e1×e2‖, and ‖e1×e2‖ is twice the area for every corner;
        // using the common value keeps the three cotangents consistent.
        cots[k] = dot(e1, e2) / double_area;
    }
    (0.5 * double_area, cots)
}

/// Assembles the stiffness L, the consistent mass B and the lumped mass D of `mesh`
/// (paper, Eq. (3) and Eq. (7)).
///
/// Runs in O(#faces) time, in parallel over columns.
///
/// # Errors
/// * [`MeshError::DegenerateFace`] for a face of zero area (its cotangents are undefined);
///   drop such faces first with [`crate::validate::repair`].
/// * [`MeshError::UnreferencedVertex`] for a vertex that belongs to no face (B would be
///   singular); drop such vertices first with [`crate::validate::repair`].
pub fn assemble(mesh: &TriMesh, params: &AssemblyParams) -> Result<FemOperators, MeshError> {
    let n = mesh.n_vertices();
    let faces = mesh.faces();

    // Per-face area and cotangents, in parallel.
    let geometry: Vec<(f64, [f64; 3])> = (0..faces.len())
        .into_par_iter()
        .map(|f| face_cotangents(mesh.corners(f)))
        .collect();
    // The degeneracy test is shared with `validate` (relative threshold, see
    // `validate::is_degenerate_triangle`), so a mesh validates as usable iff it assembles.
    if let Some(f) = (0..faces.len()).into_par_iter().find_first(|&f| {
        crate::validate::is_degenerate_triangle(mesh.corners(f)) || geometry[f].1.iter().any(|x| !x.is_finite())
    }) {
        return Err(MeshError::DegenerateFace {
            face: f,
            vertices: faces[f],
        });
    }

    // Counting sort of the six directed half-entries (row, col) of each face by column.
    let mut col_count = vec![0usize; n + 1];
    for f in faces {
        for &v in f {
            col_count[v as usize + 1] += 2;
        }
    }
    for j in 0..n {
        col_count[j + 1] += col_count[j];
    }
    if let Some(v) = (0..n).find(|&j| col_count[j + 1] == col_count[j]) {
        return Err(MeshError::UnreferencedVertex { vertex: v });
    }
    let total = col_count[n];
    let mut cursor = col_count.clone();
    // (row, L value, B value) in column order.
    let mut entries: Vec<(u32, f64, f64)> = vec![(0, 0.0, 0.0); total];
    for (f, face) in faces.iter().enumerate() {
        let (area, cots) = geometry[f];
        let b = area / 12.0;
        for k in 0..3 {
            // The edge opposite corner k joins the other two corners.
            let i = face[(k + 1) % 3];
            let j = face[(k + 2) % 3];
            let l = -0.5 * cots[k];
            let pj = &mut cursor[j as usize];
            entries[*pj] = (i, l, b);
            *pj += 1;
            let pi = &mut cursor[i as usize];
            entries[*pi] = (j, l, b);
            *pi += 1;
        }
    }
    drop(cursor);

    // Sort each column by row and merge the entries of an edge shared by several faces.
    let mut segments: Vec<&mut [(u32, f64, f64)]> = Vec::with_capacity(n);
    {
        let mut rest: &mut [(u32, f64, f64)] = &mut entries;
        for j in 0..n {
            let (head, tail) = rest.split_at_mut(col_count[j + 1] - col_count[j]);
            segments.push(head);
            rest = tail;
        }
    }
    let unique: Vec<usize> = segments
        .par_iter_mut()
        .map(|seg| {
            seg.sort_unstable_by_key(|e| e.0);
            let mut w = 0;
            for r in 0..seg.len() {
                if w > 0 && seg[w - 1].0 == seg[r].0 {
                    seg[w - 1].1 += seg[r].1;
                    seg[w - 1].2 += seg[r].2;
                } else {
                    seg[w] = seg[r];
                    w += 1;
                }
            }
            w
        })
        .collect();

    // Final CSC arrays: the merged off-diagonal entries plus the diagonal, rows sorted.
    let mut col_ptr = vec![0usize; n + 1];
    for j in 0..n {
        col_ptr[j + 1] = col_ptr[j] + unique[j] + 1;
    }
    let nnz = col_ptr[n];
    let mut row_idx = vec![0usize; nnz];
    let mut l_val = vec![0.0f64; nnz];
    let mut b_val = vec![0.0f64; nnz];
    let mut d_val = vec![0.0f64; nnz];
    let mut lumped_diagonal = vec![0.0f64; n];
    {
        let mut outs = Vec::with_capacity(n);
        let (mut r, mut l, mut b, mut d): (&mut [usize], &mut [f64], &mut [f64], &mut [f64]) =
            (&mut row_idx, &mut l_val, &mut b_val, &mut d_val);
        for j in 0..n {
            let len = col_ptr[j + 1] - col_ptr[j];
            let (r0, r1) = r.split_at_mut(len);
            let (l0, l1) = l.split_at_mut(len);
            let (b0, b1) = b.split_at_mut(len);
            let (d0, d1) = d.split_at_mut(len);
            outs.push((r0, l0, b0, d0));
            (r, l, b, d) = (r1, l1, b1, d1);
        }
        outs.par_iter_mut()
            .zip(segments.par_iter())
            .zip(unique.par_iter())
            .zip(lumped_diagonal.par_iter_mut())
            .enumerate()
            .for_each(|(j, ((((r, l, b, d), seg), &u), dj))| {
                let seg = &seg[..u];
                let l_diag: f64 = -seg.iter().map(|e| e.1).sum::<f64>();
                // Each incident face contributes |T|/12 on two edges at vertex j, so the
                // off-diagonal column sum of B is Σ|T|/6 = B_jj and the row sum is Σ|T|/3 = D_jj.
                let b_diag: f64 = seg.iter().map(|e| e.2).sum::<f64>();
                *dj = 2.0 * b_diag;
                let mut w = 0;
                let mut diag_done = false;
                for e in seg {
                    if !diag_done && (e.0 as usize) > j {
                        r[w] = j;
                        l[w] = l_diag;
                        b[w] = b_diag;
                        d[w] = 2.0 * b_diag;
                        w += 1;
                        diag_done = true;
                    }
                    r[w] = e.0 as usize;
                    l[w] = e.1;
                    b[w] = e.2;
                    d[w] = 0.0;
                    w += 1;
                }
                if !diag_done {
                    r[w] = j;
                    l[w] = l_diag;
                    b[w] = b_diag;
                    d[w] = 2.0 * b_diag;
                }
            });
    }

    if params.lumped == LumpedMassKind::Voronoi {
        lumped_diagonal = voronoi_areas(mesh, &geometry);
        for j in 0..n {
            for p in col_ptr[j]..col_ptr[j + 1] {
                if row_idx[p] == j {
                    d_val[p] = lumped_diagonal[j];
                }
            }
        }
    }

    let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
    Ok(FemOperators {
        stiffness: SparseColMat::new(symbolic.clone(), l_val),
        mass: SparseColMat::new(symbolic.clone(), b_val),
        lumped_mass: SparseColMat::new(symbolic, d_val),
        lumped_diagonal,
    })
}

/// Mixed Voronoi areas per vertex (Meyer et al. 2003, Fig. 4).
fn voronoi_areas(mesh: &TriMesh, geometry: &[(f64, [f64; 3])]) -> Vec<f64> {
    let mut areas = vec![0.0; mesh.n_vertices()];
    for (f, face) in mesh.faces().iter().enumerate() {
        let (area, cots) = geometry[f];
        let p = mesh.corners(f);
        let obtuse = (0..3).find(|&k| cots[k] < 0.0);
        for k in 0..3 {
            let a = match obtuse {
                None => {
                    // Voronoi area at corner k: (|e_kj|² cot θ_l + |e_kl|² cot θ_j)/8, where the
                    // edge k→k+1 is opposite corner k+2 and the edge k→k+2 is opposite corner k+1.
                    let e1 = sub(p[(k + 1) % 3], p[k]);
                    let e2 = sub(p[(k + 2) % 3], p[k]);
                    (dot(e1, e1) * cots[(k + 2) % 3] + dot(e2, e2) * cots[(k + 1) % 3]) / 8.0
                }
                Some(o) if o == k => area / 2.0,
                Some(_) => area / 4.0,
            };
            areas[face[k] as usize] += a;
        }
    }
    areas
}
