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

use crate::mesh::{cross, dot, mul_pow2, neg, norm, scaled_edges};
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
    #[allow(clippy::expect_used)]
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
            // invariant: cloning an existing valid pattern can only fail to allocate.
            self.stiffness.symbolic().to_owned().expect("clone of a valid pattern"),
            val,
        )
    }
}

/// Per-face geometry: area and the cotangent of the angle at each corner.
///
/// Computed on the edges scaled by an exact power of two ([`crate::mesh::scaled_edges`]), so
/// the cotangents are scale invariant and nothing overflows for huge or tiny (but valid)
/// triangles; the area is scaled back exactly. NaN for coincident corners or non-finite
/// edges (such faces are degenerate and never assembled).
#[inline]
fn face_cotangents(p: [[f64; 3]; 3]) -> (f64, [f64; 3]) {
    let Some(([d01, d12, d20], k)) = scaled_edges(p) else {
        return (f64::NAN, [f64::NAN; 3]);
    };
    // The two edges leaving each corner: p_{k+1} − p_k and p_{k+2} − p_k.
    let legs = [(d01, neg(d20)), (d12, neg(d01)), (d20, neg(d12))];
    let double_area = norm(cross(legs[0].0, legs[0].1));
    let mut cots = [0.0; 3];
    for (cot, (e1, e2)) in cots.iter_mut().zip(legs) {
        // cot θ = cos/sin = (e1·e2)/‖e1×e2‖, and ‖e1×e2‖ is twice the area for every corner;
        // using the common value keeps the three cotangents consistent.
        *cot = dot(e1, e2) / double_area;
    }
    (0.5 * mul_pow2(double_area, 2 * k), cots)
}

/// The element of one face (paper Eq. (3)): its area |T| (the consistent mass puts |T|/6 on
/// each vertex and |T|/12 on each edge, the barycentric lumped mass |T|/3 on each vertex), the
/// cotangent of each corner's angle (the stiffness puts −½ cot on the opposite edge) and, for
/// the Voronoi lumped mass, each corner's mixed Voronoi area. `None` for a degenerate face
/// (the test is shared with `validate`, so a mesh validates as usable iff it assembles).
#[derive(Clone, Copy)]
struct FaceElement {
    area: f64,
    cots: [f64; 3],
    voronoi: [f64; 3],
}

fn face_element(p: [[f64; 3]; 3], voronoi: bool) -> Option<FaceElement> {
    let (area, cots) = face_cotangents(p);
    if crate::validate::is_degenerate_triangle(p) || cots.iter().any(|c| !c.is_finite()) {
        return None;
    }
    let voronoi = if voronoi {
        voronoi_corner_areas(p, (area, cots))
    } else {
        [0.0; 3]
    };
    Some(FaceElement { area, cots, voronoi })
}

/// Columns per parallel work item of [`assemble`]: large enough to amortise the task and
/// slice bookkeeping, small enough to balance the load on a few cores.
const COLUMNS_PER_CHUNK: usize = 2048;

/// What one corner of a face contributes to the column of its vertex j: the two half-edges
/// (j, i) to the other corners, with their stiffness values, and the face area.
#[derive(Clone, Copy, Default)]
struct CornerEntries {
    /// The other two vertices of the face.
    rows: [u32; 2],
    /// `−½ cot` of the angle opposite each of the two edges.
    stiffness: [f64; 2],
    /// Face area |T|.
    area: f64,
}

/// Assembles the stiffness L, the consistent mass B and the lumped mass D of `mesh`
/// (paper, Eq. (3) and Eq. (7)).
///
/// Runs in O(#faces) time and memory, in parallel (rayon):
/// 1. a counting sort of the 3·#faces corners by vertex: in parallel over vertex ranges,
///    every face's area and cotangents are computed and each corner's two half-edges are
///    written to its vertex's segment, in face order (all later reads are sequential);
/// 2. per column j, sort the half-edges of j by row (stably, so face order is kept) and
///    merge duplicates: a first pass only counts the distinct rows to lay out the column
///    pointers, the second writes the entries of L, B and D directly into their final
///    arrays (each of the three matrices owns a copy of the shared pattern).
///
/// Contributions to an entry are summed in face order on both sides of the diagonal, so L
/// and B are exactly symmetric, even on non-manifold meshes.
///
/// # Errors
/// * [`MeshError::DegenerateFace`] for a face of zero or numerically zero area (its
///   cotangents are undefined; the test is [`crate::validate::is_degenerate_triangle`]), the
///   first one in face order; drop such faces first with [`crate::validate::repair`].
/// * [`MeshError::UnreferencedVertex`] for a vertex that belongs to no face (B would be
///   singular); drop such vertices first with [`crate::validate::repair`].
/// * [`MeshError::DegenerateMesh`] if the total area Σ|T| overflows (coordinates beyond
///   ~1e154): B and D would hold infinities; scale the mesh down first.
pub fn assemble(mesh: &TriMesh, params: &AssemblyParams) -> Result<FemOperators, MeshError> {
    let n = mesh.n_vertices();
    let faces = mesh.faces();

    // 1a. Column segments: corners[first[j]..first[j + 1]] belong to vertex j.
    let mut first = vec![0usize; n + 1];
    for face in faces {
        for &v in face {
            first[v as usize + 1] += 1;
        }
    }
    for j in 0..n {
        first[j + 1] += first[j];
    }

    let voronoi = params.lumped == LumpedMassKind::Voronoi;
    let (corners, corner_mass) = scatter_corners(mesh, &first, voronoi).map_err(|f| MeshError::DegenerateFace {
        face: f,
        vertices: faces[f],
    })?;
    if let Some(v) = (0..n).find(|&j| first[j + 1] == first[j]) {
        return Err(MeshError::UnreferencedVertex { vertex: v });
    }
    // Every entry of B and D is a partial sum of the face areas, so a finite total keeps them
    // all finite (L is scale free). Same test, same order as `validate`.
    let total_area = mesh.area();
    if !total_area.is_finite() {
        return Err(MeshError::DegenerateMesh { area: total_area });
    }

    let columns = merge_columns(&first, &corners, &corner_mass, voronoi);

    // faer checks that every column's rows are sorted and in range (O(nnz) each); the three
    // checks run in parallel, and meanwhile the corner records are freed (unmapping 32 bytes
    // per corner takes a while too).
    let [r0, r1, r2] = columns.rows;
    let col_ptr = columns.col_ptr;
    let pattern = |row_idx: Vec<usize>| SymbolicSparseColMat::new_checked(n, n, col_ptr.clone(), None, row_idx);
    let (((s0, s1), s2), ()) = rayon::join(
        || rayon::join(|| rayon::join(|| pattern(r0), || pattern(r1)), || pattern(r2)),
        || drop(corners),
    );
    Ok(FemOperators {
        stiffness: SparseColMat::new(s0, columns.l_val),
        mass: SparseColMat::new(s1, columns.b_val),
        lumped_mass: SparseColMat::new(s2, columns.d_val),
        lumped_diagonal: columns.lumped_diagonal,
    })
}

/// The three matrices as column arrays on one pattern (three copies of the row indices, one
/// per matrix) and the lumped diagonal.
struct Columns {
    col_ptr: Vec<usize>,
    rows: [Vec<usize>; 3],
    l_val: Vec<f64>,
    b_val: Vec<f64>,
    d_val: Vec<f64>,
    lumped_diagonal: Vec<f64>,
}

/// Step 2 of [`assemble`]: per column j, the half-edges of j's corners merged by row (stably,
/// in face order) into the entries of L, B and D, in parallel over chunks of columns.
fn merge_columns(first: &[usize], corners: &[CornerEntries], corner_mass: &[f64], voronoi: bool) -> Columns {
    let n = first.len() - 1;
    // 2a. Count the distinct rows of each column, then lay out the column pointers.
    let chunks: Vec<(usize, usize)> = (0..n)
        .step_by(COLUMNS_PER_CHUNK)
        .map(|c| (c, (c + COLUMNS_PER_CHUNK).min(n)))
        .collect();
    let mut col_ptr = vec![0usize; n + 1];
    col_ptr[1..]
        .par_chunks_mut(COLUMNS_PER_CHUNK)
        .zip(&chunks)
        .for_each(|(out, &(col_start, _))| {
            let mut rows: Vec<u32> = Vec::new();
            for (jj, count) in out.iter_mut().enumerate() {
                let j = col_start + jj;
                rows.clear();
                rows.extend(corners[first[j]..first[j + 1]].iter().flat_map(|c| c.rows));
                rows.sort_unstable();
                // Distinct off-diagonal rows plus the diagonal.
                *count = 1 + rows.len() - rows.windows(2).filter(|w| w[0] == w[1]).count();
            }
        });
    for j in 0..n {
        col_ptr[j + 1] += col_ptr[j];
    }
    let nnz = col_ptr[n];

    // 2b. Write the merged entries of L, B, D and the three copies of the row indices into
    //     disjoint per-chunk slices of the final arrays, in parallel.
    let mut rows = [vec![0usize; nnz], vec![0usize; nnz], vec![0usize; nnz]];
    let mut l_val = vec![0.0f64; nnz];
    let mut b_val = vec![0.0f64; nnz];
    let mut d_val = vec![0.0f64; nnz];
    let mut lumped_diagonal = vec![0.0f64; n];
    {
        let bounds: Vec<usize> = chunks.iter().map(|&(_, end)| col_ptr[end]).collect();
        let [r0, r1, r2] = &mut rows;
        let work: Vec<_> = split_at_bounds(r0, &bounds)
            .into_iter()
            .zip(split_at_bounds(r1, &bounds))
            .zip(split_at_bounds(r2, &bounds))
            .zip(split_at_bounds(&mut l_val, &bounds))
            .zip(split_at_bounds(&mut b_val, &bounds))
            .zip(split_at_bounds(&mut d_val, &bounds))
            .zip(lumped_diagonal.chunks_mut(COLUMNS_PER_CHUNK))
            .zip(&chunks)
            .collect();
        work.into_par_iter()
            .for_each(|(((((((r0, r1), r2), l), b), d), diag), &(col_start, col_end))| {
                // Half-edges (row i, L value, B value) of column j.
                let mut buf: Vec<(u32, f64, f64)> = Vec::new();
                let base = col_ptr[col_start];
                for j in col_start..col_end {
                    let segment = first[j]..first[j + 1];
                    buf.clear();
                    let mut d_jj = 0.0;
                    for c in &corners[segment.clone()] {
                        // B_ij = Σ|T|/12 over the faces of edge ij.
                        let b = c.area / 12.0;
                        buf.push((c.rows[0], c.stiffness[0], b));
                        buf.push((c.rows[1], c.stiffness[1], b));
                        d_jj += c.area / 3.0;
                    }
                    if voronoi {
                        d_jj = corner_mass[segment].iter().sum();
                    }
                    // Stable: equal rows stay in face order, the same order as on the other
                    // side of the diagonal, so the merged sums are bitwise symmetric.
                    buf.sort_by_key(|e| e.0);
                    diag[j - col_start] = d_jj;
                    // Merge duplicates (an interior edge appears once per incident face).
                    let mut w = 0;
                    for r in 0..buf.len() {
                        if w > 0 && buf[w - 1].0 == buf[r].0 {
                            buf[w - 1].1 += buf[r].1;
                            buf[w - 1].2 += buf[r].2;
                        } else {
                            buf[w] = buf[r];
                            w += 1;
                        }
                    }
                    let merged = &buf[..w];
                    let l_diag = -merged.iter().map(|e| e.1).sum::<f64>();
                    // Each incident face puts |T|/12 on two edges at j, so the off-diagonal
                    // sum of column j of B is Σ_{T∋j}|T|/6 = B_jj.
                    let b_diag = merged.iter().map(|e| e.2).sum::<f64>();
                    let split = merged.partition_point(|e| (e.0 as usize) < j);
                    let mut p = col_ptr[j] - base;
                    let mut put = |i: usize, lv: f64, bv: f64, dv: f64| {
                        r0[p] = i;
                        r1[p] = i;
                        r2[p] = i;
                        l[p] = lv;
                        b[p] = bv;
                        d[p] = dv;
                        p += 1;
                    };
                    for e in &merged[..split] {
                        put(e.0 as usize, e.1, e.2, 0.0);
                    }
                    put(j, l_diag, b_diag, d_jj);
                    for e in &merged[split..] {
                        put(e.0 as usize, e.1, e.2, 0.0);
                    }
                }
            });
    }

    Columns {
        col_ptr,
        rows,
        l_val,
        b_val,
        d_val,
        lumped_diagonal,
    }
}

/// Step 1b of [`assemble`]: the corners of every face, sorted by vertex into the column
/// segments `first[j]..first[j + 1]` (in face order within a segment), with the Voronoi
/// corner masses when asked; the first degenerate face (in face order) as the error.
fn scatter_corners(mesh: &TriMesh, first: &[usize], voronoi: bool) -> Result<(Vec<CornerEntries>, Vec<f64>), usize> {
    let n = mesh.n_vertices();
    let faces = mesh.faces();
    let n_corners = first[n];
    // 1b. Scatter, in parallel over vertex ranges of about equal corner counts (one per
    //     thread): each range scans all faces (cheap, sequential) and handles the corners it
    //     owns, so every task writes only its own slice without locks or `unsafe`. A face is
    //     measured once per range it touches, so at most three times.
    let n_ranges = rayon::current_num_threads().clamp(1, n);
    let vertex_bounds: Vec<usize> = (0..=n_ranges)
        .map(|r| {
            let target = n_corners * r / n_ranges;
            first.partition_point(|&c| c < target).min(n)
        })
        .collect();
    let mut corners = vec![CornerEntries::default(); n_corners];
    let mut corner_mass = vec![0.0f64; if voronoi { n_corners } else { 0 }];
    let corner_bounds: Vec<usize> = vertex_bounds[1..].iter().map(|&v| first[v]).collect();
    let mass_bounds: Vec<usize> = if voronoi {
        corner_bounds.clone()
    } else {
        vec![0; n_ranges]
    };
    let degenerate: Option<usize> = split_at_bounds(&mut corners, &corner_bounds)
        .into_iter()
        .zip(split_at_bounds(&mut corner_mass, &mass_bounds))
        .zip(vertex_bounds.windows(2))
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|((out, mass_out), range)| {
            let (v0, v1) = (range[0], range[1]);
            let base = first[v0];
            let mut cursor: Vec<usize> = first[v0..v1].iter().map(|&c| c - base).collect();
            let mut degenerate = None;
            for (f, face) in faces.iter().enumerate() {
                if !face.iter().any(|&v| (v0..v1).contains(&(v as usize))) {
                    continue;
                }
                let Some(FaceElement {
                    area,
                    cots,
                    voronoi: masses,
                }) = face_element(mesh.corners(f), voronoi)
                else {
                    degenerate.get_or_insert(f);
                    continue;
                };
                for k in 0..3 {
                    let v = face[k] as usize;
                    if !(v0..v1).contains(&v) {
                        continue;
                    }
                    let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
                    let c = &mut cursor[v - v0];
                    // Edge v–face[k1] is opposite corner k2, edge v–face[k2] opposite k1.
                    out[*c] = CornerEntries {
                        rows: [face[k1], face[k2]],
                        stiffness: [-0.5 * cots[k2], -0.5 * cots[k1]],
                        area,
                    };
                    if voronoi {
                        mass_out[*c] = masses[k];
                    }
                    *c += 1;
                }
            }
            degenerate
        })
        .reduce(|| None, |a, b| a.into_iter().chain(b).min());
    match degenerate {
        Some(f) => Err(f),
        None => Ok((corners, corner_mass)),
    }
}

/// Splits `v` into consecutive pieces ending at the increasing offsets `bounds` (the last
/// bound must be `v.len()`).
fn split_at_bounds<'a, T>(mut v: &'a mut [T], bounds: &[usize]) -> Vec<&'a mut [T]> {
    let mut pieces = Vec::with_capacity(bounds.len());
    let mut done = 0;
    for &end in bounds {
        let (head, tail) = v.split_at_mut(end - done);
        pieces.push(head);
        v = tail;
        done = end;
    }
    pieces
}

/// Mixed Voronoi area of each corner of one triangle (Meyer, Desbrun, Schröder, Barr 2003,
/// Fig. 4): the Voronoi region `(|e_kj|² cot θ_l + |e_kl|² cot θ_j)/8` on a non-obtuse
/// triangle, otherwise |T|/2 at the obtuse corner and |T|/4 at the other two.
///
/// Squared edge lengths are taken on exactly scaled edges ([`crate::mesh::scaled_edges`]) and
/// scaled back, so they do not overflow for huge triangles whose areas are finite.
fn voronoi_corner_areas(p: [[f64; 3]; 3], (area, cots): (f64, [f64; 3])) -> [f64; 3] {
    let Some(([d01, d12, d20], scale)) = scaled_edges(p) else {
        return [f64::NAN; 3];
    };
    let legs = [(d01, neg(d20)), (d12, neg(d01)), (d20, neg(d12))];
    let obtuse = (0..3).find(|&k| cots[k] < 0.0);
    let mut out = [0.0; 3];
    for (k, a) in out.iter_mut().enumerate() {
        *a = match obtuse {
            None => {
                // The edge k→k+1 is opposite corner k+2 and the edge k→k+2 is opposite k+1.
                let (e1, e2) = legs[k];
                let scaled = (dot(e1, e1) * cots[(k + 2) % 3] + dot(e2, e2) * cots[(k + 1) % 3]) / 8.0;
                mul_pow2(scaled, 2 * scale)
            }
            Some(o) if o == k => area / 2.0,
            Some(_) => area / 4.0,
        };
    }
    out
}
