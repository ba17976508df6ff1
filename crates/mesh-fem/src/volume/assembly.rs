//! L, B, D on tetrahedra (module docs of [`super`]), assembled column by column in parallel
//! with the same passes as the surface operators ([`crate::operators`]): the tetrahedra around
//! each vertex, the column layout, then every column's merged entries written in place.

use super::{signed_volume, TetMesh};
use crate::operators::{column_layout, faces_around_vertices, write_columns, ColumnDiagonal, FemOperators, Lumping};
use crate::vec3::{cross, dot, norm, sub};
use crate::{AssemblyParams, Laplacian, MeshError};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;
use std::collections::HashMap;

/// The element of one tetrahedron: its volume |T| and the hat-function gradients of its
/// corners (from the signed volume: the products L_ij are independent of the orientation).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TetElement {
    /// |T| (≥ 0).
    pub volume: f64,
    /// ∇φᵢ of the four corners.
    pub gradients: [[f64; 3]; 4],
}

/// Relative size below which a tetrahedron counts as flat: |6V| ≤ this · ℓ_max³.
pub(crate) const FLAT: f64 = 1e-12;

/// The element of a tetrahedron with corners `p`, or `None` when it is flat (|6V| ≤ 1e−12·ℓ³_max)
/// or not finite.
pub fn tet_element(p: [[f64; 3]; 4]) -> Option<TetElement> {
    let (e1, e2, e3) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    let det = 6.0 * signed_volume(p);
    let mut longest = 0.0f64;
    for a in 0..4 {
        for b in a + 1..4 {
            longest = longest.max(norm(sub(p[a], p[b])));
        }
    }
    if !(det.abs() > FLAT * longest * longest * longest) || !det.is_finite() {
        return None;
    }
    let g1 = cross(e2, e3).map(|x| x / det);
    let g2 = cross(e3, e1).map(|x| x / det);
    let g3 = cross(e1, e2).map(|x| x / det);
    let g0 = [
        -(g1[0] + g2[0] + g3[0]),
        -(g1[1] + g2[1] + g3[1]),
        -(g1[2] + g2[2] + g3[2]),
    ];
    let gradients = [g0, g1, g2, g3];
    gradients.iter().flatten().all(|x| x.is_finite()).then_some(TetElement {
        volume: det.abs() / 6.0,
        gradients,
    })
}

impl TetElement {
    /// `L_ij = |T| ∇φᵢ·∇φⱼ` of corners i and j.
    #[inline]
    fn stiffness(&self, i: usize, j: usize) -> f64 {
        self.volume * dot(self.gradients[i], self.gradients[j])
    }
}

/// Assembles L, B and D of a tetrahedral mesh (module docs of [`super`]): the same
/// [`FemOperators`] as [`crate::assemble`] on a surface, with the barycentric lumping.
///
/// # Errors
/// * [`MeshError::DegenerateTet`] for a flat tetrahedron (the first one), [`MeshError::UnreferencedVertex`]
///   for a vertex in no tetrahedron (B would be singular): [`super::repair_volume`] drops both;
/// * [`MeshError::InvalidParameter`] for the Voronoi lumping or the robust Laplacian, which are
///   defined on triangles only;
/// * [`MeshError::DegenerateMesh`] if the total volume overflows; [`MeshError::Invalid`] for
///   2³² tetrahedra or more.
pub fn assemble_volume(mesh: &TetMesh, params: &AssemblyParams) -> Result<FemOperators, MeshError> {
    if params.lumping != Lumping::Barycentric {
        return Err(MeshError::InvalidParameter {
            name: "lumping",
            value: 0.0,
            expected: "the barycentric lumping on tetrahedra (the Voronoi one is defined on triangles)",
        });
    }
    if params.laplacian != Laplacian::Cotan {
        return Err(MeshError::InvalidParameter {
            name: "laplacian",
            value: 0.0,
            expected: "the cotangent (P1 FEM) Laplacian on tetrahedra (the robust one is for triangle meshes)",
        });
    }
    let n = mesh.n_vertices();
    let tets = mesh.tets();
    if u32::try_from(tets.len()).is_err() {
        return Err(MeshError::Invalid {
            reason: format!("{} tetrahedra: assembly indexes them with 32 bits", tets.len()),
        });
    }
    let elements: Vec<Option<TetElement>> = (0..tets.len())
        .into_par_iter()
        .map(|t| tet_element(mesh.corners(t)))
        .collect();
    if let Some(t) = elements.iter().position(Option::is_none) {
        return Err(MeshError::DegenerateTet {
            tet: t,
            vertices: tets[t],
            volume: mesh.signed_volume(t),
        });
    }
    let elements: Vec<TetElement> = elements.into_iter().flatten().collect();
    let total: f64 = elements.iter().map(|e| e.volume).sum();
    if !total.is_finite() {
        return Err(MeshError::DegenerateMesh { area: total });
    }
    let first = crate::graph::corner_offsets(tets, n);
    if let Some(v) = (0..n).find(|&j| first[j + 1] == first[j]) {
        return Err(MeshError::UnreferencedVertex { vertex: v });
    }
    let around = faces_around_vertices(tets, &first);
    let (chunks, col_ptr) = column_layout(&around, &first, tets);
    let columns = write_columns(&chunks, col_ptr, |j, buf| {
        let (mut d_jj, mut b_jj) = (0.0, 0.0);
        for &t in &around[first[j]..first[j + 1]] {
            let t = t as usize;
            let (tet, e) = (tets[t], &elements[t]);
            let Some(k) = tet.iter().position(|&v| v as usize == j) else {
                continue;
            };
            let b = e.volume / 20.0;
            for (c, &i) in tet.iter().enumerate() {
                if c == k {
                    continue;
                }
                let lv = e.stiffness(k, c);
                match buf.iter_mut().find(|x| x.0 == i) {
                    Some(x) => {
                        x.1 += lv;
                        x.2 += b;
                    }
                    None => buf.push((i, lv, b)),
                }
            }
            d_jj += e.volume / 4.0;
            b_jj += e.volume / 10.0;
        }
        ColumnDiagonal {
            lumped: d_jj,
            mass: Some(b_jj),
        }
    });
    let col = columns.col_ptr;
    let pattern = |rows: Vec<usize>| SymbolicSparseColMat::new_checked(n, n, col.clone(), None, rows);
    let [l_rows, b_rows] = columns.row_idx;
    Ok(FemOperators {
        stiffness: SparseColMat::new(pattern(l_rows), columns.l_val),
        mass: SparseColMat::new(pattern(b_rows), columns.b_val),
        lumped_diagonal: columns.lumped_diagonal,
        lumping: Lumping::Barycentric,
    })
}

/// Red refinement of every tetrahedron into eight (Bey 1995): four at the corners, four in the
/// inner octahedron cut along its diagonal between the midpoints of edges 02 and 13. Each child
/// keeps its parent's orientation.
pub(crate) fn split_tets(mesh: &TetMesh) -> TetMesh {
    let mut positions = mesh.positions().to_vec();
    let mut mid: HashMap<(u32, u32), u32> = HashMap::with_capacity(mesh.n_tets() * 2);
    let mut tets = Vec::with_capacity(8 * mesh.n_tets());
    for (t, &[a, b, c, d]) in mesh.tets().iter().enumerate() {
        let mut m = |x: u32, y: u32| -> u32 {
            let key = (x.min(y), x.max(y));
            *mid.entry(key).or_insert_with(|| {
                let (p, q) = (positions[x as usize], positions[y as usize]);
                positions.push([(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0, (p[2] + q[2]) / 2.0]);
                (positions.len() - 1) as u32
            })
        };
        let (ab, ac, ad, bc, bd, cd) = (m(a, b), m(a, c), m(a, d), m(b, c), m(b, d), m(c, d));
        let parent = mesh.signed_volume(t) >= 0.0;
        for mut child in [
            [a, ab, ac, ad],
            [ab, b, bc, bd],
            [ac, bc, c, cd],
            [ad, bd, cd, d],
            [ab, ac, ad, bd],
            [ab, ac, bc, bd],
            [ac, ad, bd, cd],
            [ac, bc, bd, cd],
        ] {
            let p = child.map(|v| positions[v as usize]);
            if (signed_volume(p) >= 0.0) != parent {
                child.swap(0, 1);
            }
            tets.push(child);
        }
    }
    #[allow(clippy::expect_used)]
    // invariant: midpoints of finite positions are finite and every index is in range.
    TetMesh::new(positions, tets).expect("a refinement of a valid mesh is valid")
}
