//! L, B, D on tetrahedra (module docs of [`super`]), assembled column by column in parallel
//! with the same passes as the surface operators ([`crate::operators`]): the tetrahedra around
//! each vertex, the column layout, then every column's merged entries written in place.

use super::{signed_volume, TetMesh};
use crate::operators::{faces_around_vertices, fill_columns, Columns, FemOperators, Lumping, COLUMNS_PER_CHUNK};
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

/// |T| and the stiffness `L_ab = |T| ∇φ_a·∇φ_b` of the six edges (a, b) of [`EDGES`]: all the
/// column pass reads of a tetrahedron (56 bytes, against 104 for its gradients).
#[derive(Clone, Copy, Debug, Default)]
struct TetEntries {
    volume: f64,
    stiffness: [f64; 6],
}

/// The six edges of a tetrahedron as pairs of its corners.
const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// `EDGE[a][b]`: the index in [`EDGES`] of the edge between corners a ≠ b (the diagonal is
/// never read).
const EDGE: [[usize; 4]; 4] = [[0, 0, 1, 2], [0, 0, 3, 4], [1, 3, 0, 5], [2, 4, 5, 0]];

/// Tetrahedra per parallel work item of the element pass.
const TETS_PER_CHUNK: usize = 8192;

/// Assembles L, B and D of a tetrahedral mesh (module docs of [`super`]): the same
/// [`FemOperators`] as [`crate::assemble`] on a surface, with the barycentric lumping.
///
/// Three passes in parallel, as on surfaces ([`crate::operators`]): every tetrahedron's volume
/// and six edge entries; the tetrahedra around each vertex (a counting sort of the corners);
/// then, per chunk of columns, the sorted distinct rows of every column (a mark per vertex, so
/// each corner costs O(1)), the column pointers, and the entries scattered into their final
/// places through a per-worker position table. The surfaces' write pass merges each column by
/// a linear search, O(deg²) per column, cheap at a triangle mesh's degree 6 but not at a
/// tetrahedral mesh's 13–15. Contributions to an entry are summed in tetrahedron order on both
/// sides of the diagonal (L and B bitwise symmetric) and `L_jj = −Σ_{i≠j} L_ij` in row order.
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
    let entries = tet_entries(mesh).map_err(|t| MeshError::DegenerateTet {
        tet: t,
        vertices: tets[t],
        volume: mesh.signed_volume(t),
    })?;
    let total: f64 = entries.iter().map(|e| e.volume).sum();
    if !total.is_finite() {
        return Err(MeshError::DegenerateMesh { area: total });
    }
    let first = crate::graph::corner_offsets(tets, n);
    if let Some(v) = (0..n).find(|&j| first[j + 1] == first[j]) {
        return Err(MeshError::UnreferencedVertex { vertex: v });
    }
    let around = faces_around_vertices(tets, &first);
    let (chunks, col_ptr, rows) = column_rows(tets, &first, &around);
    let columns = scatter_columns(tets, &first, &around, &entries, &chunks, col_ptr, &rows);
    drop((entries, around, rows));
    let col = columns.col_ptr;
    let pattern = |rows: Vec<usize>| SymbolicSparseColMat::new_checked(n, n, col.clone(), None, rows);
    let [l_rows, b_rows] = columns.row_idx;
    let (stiffness_pattern, mass_pattern) = rayon::join(|| pattern(l_rows), || pattern(b_rows));
    Ok(FemOperators {
        stiffness: SparseColMat::new(stiffness_pattern, columns.l_val),
        mass: SparseColMat::new(mass_pattern, columns.b_val),
        lumped_diagonal: columns.lumped_diagonal,
        lumping: Lumping::Barycentric,
    })
}

/// The entries of every tetrahedron ([`tet_element`] measured once), in parallel; the first
/// flat one as the error.
fn tet_entries(mesh: &TetMesh) -> Result<Vec<TetEntries>, usize> {
    let mut entries = vec![TetEntries::default(); mesh.n_tets()];
    let flat = entries
        .par_chunks_mut(TETS_PER_CHUNK)
        .enumerate()
        .map(|(c, out)| {
            let start = c * TETS_PER_CHUNK;
            let mut flat = None;
            for (i, e) in out.iter_mut().enumerate() {
                match tet_element(mesh.corners(start + i)) {
                    Some(element) => {
                        *e = TetEntries {
                            volume: element.volume,
                            stiffness: EDGES.map(|(a, b)| element.stiffness(a, b)),
                        }
                    }
                    None => {
                        flat.get_or_insert(start + i);
                    }
                }
            }
            flat
        })
        .reduce(|| None, |a, b| a.into_iter().chain(b).min());
    match flat {
        Some(t) => Err(t),
        None => Ok(entries),
    }
}

/// The column chunks ([`COLUMNS_PER_CHUNK`] columns each), the column pointers, and per chunk
/// the sorted distinct rows of its columns one after the other (row j itself included): every
/// corner of the tetrahedra around j, kept once by a mark per vertex (one table of n marks per
/// worker).
#[allow(clippy::type_complexity)]
fn column_rows(tets: &[[u32; 4]], first: &[usize], around: &[u32]) -> (Vec<(usize, usize)>, Vec<usize>, Vec<Vec<u32>>) {
    let n = first.len() - 1;
    let chunks: Vec<(usize, usize)> = (0..n)
        .step_by(COLUMNS_PER_CHUNK)
        .map(|c| (c, (c + COLUMNS_PER_CHUNK).min(n)))
        .collect();
    let mut counts = vec![0usize; n + 1];
    let rows: Vec<Vec<u32>> = counts[1..]
        .par_chunks_mut(COLUMNS_PER_CHUNK)
        .zip(&chunks)
        .map_init(
            || vec![u32::MAX; n],
            |mark, (out, &(c0, _))| {
                let mut rows: Vec<u32> = Vec::with_capacity(16 * out.len());
                for (jj, count) in out.iter_mut().enumerate() {
                    let j = c0 + jj;
                    let start = rows.len();
                    for &t in &around[first[j]..first[j + 1]] {
                        for &v in &tets[t as usize] {
                            // `assemble_volume` checked that n fits in 32 bits (indices are u32).
                            if mark[v as usize] != j as u32 {
                                mark[v as usize] = j as u32;
                                rows.push(v);
                            }
                        }
                    }
                    rows[start..].sort_unstable();
                    *count = rows.len() - start;
                }
                rows
            },
        )
        .collect();
    for j in 0..n {
        counts[j + 1] += counts[j];
    }
    (chunks, counts, rows)
}

/// The write pass: per chunk of columns (in parallel, each into its own slices of the final
/// arrays), the rows of every column from [`column_rows`], then the contributions of the
/// tetrahedra around it added at their places (a position table of n entries per worker).
fn scatter_columns(
    tets: &[[u32; 4]],
    first: &[usize],
    around: &[u32],
    entries: &[TetEntries],
    chunks: &[(usize, usize)],
    col_ptr: Vec<usize>,
    rows: &[Vec<u32>],
) -> Columns {
    let n = col_ptr.len() - 1;
    fill_columns(
        chunks,
        col_ptr,
        || vec![0u32; n],
        |pos, s| {
            let (c0, c1) = s.columns;
            let rows = &rows[s.index];
            let base = s.col_ptr[c0];
            for j in c0..c1 {
                let (p0, p1) = (s.col_ptr[j] - base, s.col_ptr[j + 1] - base);
                let column = &rows[p0..p1];
                for (q, &i) in column.iter().enumerate() {
                    pos[i as usize] = q as u32;
                    s.l_rows[p0 + q] = i as usize;
                    s.b_rows[p0 + q] = i as usize;
                }
                let (mut d_jj, mut b_jj) = (0.0, 0.0);
                for &t in &around[first[j]..first[j + 1]] {
                    let (tet, e) = (&tets[t as usize], &entries[t as usize]);
                    let Some(k) = tet.iter().position(|&v| v as usize == j) else {
                        continue;
                    };
                    let bv = e.volume / 20.0;
                    for (c, &i) in tet.iter().enumerate() {
                        if c != k {
                            let q = p0 + pos[i as usize] as usize;
                            s.l[q] += e.stiffness[EDGE[k][c]];
                            s.b[q] += bv;
                        }
                    }
                    d_jj += e.volume / 4.0;
                    b_jj += e.volume / 10.0;
                }
                let qd = p0 + pos[j] as usize;
                let off: f64 = (p0..p1).filter(|&q| q != qd).map(|q| s.l[q]).sum();
                s.l[qd] = -off;
                s.b[qd] = b_jj;
                s.lumped[j - c0] = d_jj;
            }
        },
    )
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
