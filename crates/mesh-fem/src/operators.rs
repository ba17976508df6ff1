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
//! L and B share one sparsity pattern (vertex–edge graph plus the diagonal), and D is stored
//! as its diagonal ([`FemOperators::lumped_mass`] puts it on that pattern), so one symbolic
//! factorization serves L, B, D and every shifted matrix `tL − zB`. Assembly is O(#faces):
//! the elements in parallel over faces, a counting sort of the faces around each vertex, then
//! a parallel (rayon) merge per column.

use crate::laplacian::Laplacian;
use crate::mesh::{dot, mul_pow2, neg, ScaledTriangle};
use crate::{MeshError, TriMesh};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;

/// How the diagonal lumped mass D is formed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Lumping {
    /// One third of the incident triangle areas, `D_ii = Σ_{T∋i}|T|/3` (the paper's Eq. (7));
    /// equal to the row sums of the consistent mass B.
    #[default]
    Barycentric,
    /// Mixed Voronoi areas (Meyer, Desbrun, Schröder, Barr 2003): Voronoi regions on
    /// non-obtuse triangles, |T|/2 at an obtuse corner and |T|/4 at the other two.
    Voronoi,
}

wfem_base::registry! {
    Lumping as "lumped mass" {
        Lumping::Barycentric = Lumping::Barycentric => "barycentric":
            "one third of the incident triangle areas, the row sums of B: the paper's Eq. (7) (default)",
        Lumping::Voronoi = Lumping::Voronoi => "voronoi" ["mixed-voronoi"]:
            "mixed Voronoi areas (Meyer et al. 2003), libigl's MASSMATRIX_TYPE_VORONOI",
    }
}

/// The mass matrix M of a heat kernel `K_t = exp(−t M⁻¹L)` (paper, Table 1): the one word
/// for "which kernel" in wfem. Every kernel shares the stiffness L.
///
/// The same three matrices as libigl's `MassMatrixType` (FULL, BARYCENTRIC, VORONOI), plus the
/// identity of the linear FEM kernel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Mass {
    /// The consistent (Galerkin) FEM mass B, `B_ij = (|T₁| + |T₂|)/12` on an edge and
    /// `Σ_{T∋i}|T|/6` on the diagonal: the paper's wFEM kernel `K_t = X D_t Xᵀ B` (Eq. (6)).
    #[default]
    Consistent,
    /// A diagonal lumped mass D (Eq. (7)): the kernel `K_t = X D_t Xᵀ D` of most libraries.
    Lumped(Lumping),
    /// M = I: the linear FEM kernel `K̃_t = X D_t Xᵀ` (text after the paper's Eq. (7)).
    Identity,
}

wfem_base::registry! {
    Mass as "mass" {
        Mass::Consistent = Mass::Consistent => "consistent" ["wfem", "full", "fem"]:
            "the consistent FEM mass B: the paper's wFEM kernel, Eq. (6) (default)",
        Mass::Lumped(Lumping::Barycentric) = Mass::Lumped(Lumping::Barycentric) => "barycentric" ["lumped", "lumped-barycentric"]:
            "the lumped mass D, one third of the incident triangle areas: Eq. (7)",
        Mass::Lumped(Lumping::Voronoi) = Mass::Lumped(Lumping::Voronoi) => "voronoi" ["lumped-voronoi", "mixed-voronoi"]:
            "the lumped mass D of mixed Voronoi areas (Meyer et al.): the Voronoi-cot kernel of DHK1",
        Mass::Identity = Mass::Identity => "identity" ["linear"]:
            "M = I: the linear FEM kernel X D_t Xᵀ",
    }
}

impl Mass {
    /// The older two-word spelling of a lumped mass (`--kernel lumped --lumped voronoi`): this
    /// mass with the given lumping when it is lumped, `None` otherwise.
    pub fn with_lumping(self, lumping: Lumping) -> Option<Mass> {
        match self {
            Mass::Lumped(_) => Some(Mass::Lumped(lumping)),
            Mass::Consistent | Mass::Identity => None,
        }
    }

    /// The lumping the operators must be assembled with for this mass (barycentric unless
    /// the mass is the Voronoi one).
    pub fn lumping(self) -> Lumping {
        match self {
            Mass::Lumped(lumping) => lumping,
            Mass::Consistent | Mass::Identity => Lumping::Barycentric,
        }
    }
}

/// Options of [`crate::assemble`].
#[derive(Clone, Copy, Debug, Default)]
pub struct AssemblyParams {
    /// Which lumped mass D to assemble.
    pub lumping: Lumping,
    /// Which Laplacian (and so which triangulation B and D live on): the mesh's cotangent L
    /// (the default) or the robust intrinsic Delaunay L of its tufted cover.
    pub laplacian: Laplacian,
}

impl AssemblyParams {
    /// The assembly that provides `mass` ([`Mass::lumping`]), with the default Laplacian.
    pub fn for_mass(mass: Mass) -> Self {
        Self {
            lumping: mass.lumping(),
            laplacian: Laplacian::default(),
        }
    }
}

/// The FEM operators of a mesh, all n × n on one shared sparsity pattern (the vertex–edge
/// graph plus the diagonal).
///
/// L and B are stored; the lumped mass D is diagonal and kept as [`Self::lumped_diagonal`],
/// with [`Self::lumped_mass`] building it on the shared pattern when a solver wants one
/// symbolic factorization for L, B and D (as [`Self::identity_mass`] does for B = I).
#[derive(Clone, Debug)]
pub struct FemOperators {
    /// Cotangent stiffness L: symmetric positive semidefinite, positive diagonal, `L·1 = 0`.
    pub stiffness: SparseColMat<usize, f64>,
    /// Consistent (Galerkin) mass B: symmetric positive definite, `1ᵀB1 = area`; same pattern
    /// as L.
    pub mass: SparseColMat<usize, f64>,
    /// The diagonal of the lumped mass D (paper Eq. (7); barycentric or mixed Voronoi areas,
    /// [`Self::lumping`]).
    pub lumped_diagonal: Vec<f64>,
    /// How [`Self::lumped_diagonal`] was formed.
    pub lumping: Lumping,
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

    /// The lumped mass D as a matrix on the shared pattern: [`Self::lumped_diagonal`] on the
    /// diagonal, explicit zeros elsewhere. Built on each call (O(nnz)).
    pub fn lumped_mass(&self) -> SparseColMat<usize, f64> {
        self.diagonal_on_pattern(|j| self.lumped_diagonal[j])
    }

    /// The identity matrix on the shared pattern (the mass of the "linear FEM" kernel, B = I).
    pub fn identity_mass(&self) -> SparseColMat<usize, f64> {
        self.diagonal_on_pattern(|_| 1.0)
    }

    /// A diagonal matrix on the shared pattern (explicit zeros off the diagonal).
    #[allow(clippy::expect_used)]
    fn diagonal_on_pattern(&self, diagonal: impl Fn(usize) -> f64) -> SparseColMat<usize, f64> {
        let sym = self.stiffness.symbolic();
        let mut val = vec![0.0; sym.row_idx().len()];
        for j in 0..sym.ncols() {
            for p in sym.col_range(j) {
                if sym.row_idx()[p] == j {
                    val[p] = diagonal(j);
                }
            }
        }
        SparseColMat::new(
            // invariant: cloning an existing valid pattern can only fail to allocate.
            sym.to_owned().expect("clone of a valid pattern"),
            val,
        )
    }
}

/// The element of one face (paper Eq. (3)): its area |T| (the consistent mass puts |T|/6 on
/// each vertex and |T|/12 on each edge, the barycentric lumped mass |T|/3 on each vertex) and
/// the cotangent of each corner's angle (the stiffness puts −½ cot on the opposite edge).
///
/// Computed on the edges scaled by an exact power of two ([`ScaledTriangle`]), so the
/// cotangents are scale invariant and nothing overflows for huge or tiny (but valid)
/// triangles; the area is scaled back exactly.
#[derive(Clone, Copy, Default)]
struct FaceElement {
    area: f64,
    cots: [f64; 3],
}

/// The element of a face, or `None` for a degenerate face (the test is shared with
/// `validate`, so a mesh validates as usable iff it assembles); with the mixed Voronoi area of
/// each corner when asked.
#[inline]
fn face_element(p: [[f64; 3]; 3], voronoi: bool) -> Option<(FaceElement, [f64; 3])> {
    let t = ScaledTriangle::new(p)?;
    if crate::validate::is_degenerate_scaled(&t) {
        return None;
    }
    let element = FaceElement {
        area: t.area(),
        cots: t.cotangents(),
    };
    if element.cots.iter().any(|c| !c.is_finite()) {
        return None;
    }
    let masses = if voronoi {
        voronoi_corner_areas(&t, element)
    } else {
        [0.0; 3]
    };
    Some((element, masses))
}

/// Faces per parallel work item of the element pass, and columns per work item of the merge:
/// large enough to amortise the task and slice bookkeeping, small enough to balance the load
/// on a few cores.
const FACES_PER_CHUNK: usize = 8192;
pub(crate) const COLUMNS_PER_CHUNK: usize = 2048;

/// Assembles the cotangent stiffness L, the consistent mass B and the lumped mass D of
/// `mesh` (paper, Eq. (3) and Eq. (7)): [`crate::assemble`] with [`Laplacian::Cotan`].
///
/// Runs in O(#faces) time and memory, in parallel (rayon), in three passes:
/// 1. every face's element (area and cotangents, measured once) in parallel over faces;
/// 2. the faces around each vertex, in face order (a counting sort of the corners by vertex,
///    4 bytes per corner);
/// 3. per column j, the half-edges of the faces around j sorted by row (stably, so face order
///    is kept) and merged: a first pass only counts the distinct rows to lay out the column
///    pointers, the second writes the entries of L, B and D directly into their final arrays
///    (each of the three matrices owns a copy of the shared pattern).
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
/// * [`MeshError::Invalid`] for a mesh of 2³² faces or more.
pub(crate) fn assemble_cotan(mesh: &TriMesh, params: &AssemblyParams) -> Result<FemOperators, MeshError> {
    let n = mesh.n_vertices();
    let faces = mesh.faces();
    if u32::try_from(faces.len()).is_err() {
        return Err(MeshError::Invalid {
            reason: format!("{} faces: assembly indexes faces with 32 bits", faces.len()),
        });
    }
    let voronoi = params.lumping == Lumping::Voronoi;

    // 1. Elements.
    let (elements, corner_mass) = face_elements(mesh, voronoi).map_err(|f| MeshError::DegenerateFace {
        face: f,
        vertices: faces[f],
    })?;
    // Every entry of B and D is a partial sum of the face areas, so a finite total keeps them
    // all finite (L is scale free). Same areas, same order as `TriMesh::area` and `validate`.
    let total_area: f64 = elements.iter().map(|e| e.area).sum();
    if !total_area.is_finite() {
        return Err(MeshError::DegenerateMesh { area: total_area });
    }

    // 2. The faces around each vertex: around[first[j]..first[j + 1]] for vertex j.
    let first = crate::graph::corner_offsets(faces, n);
    if let Some(v) = (0..n).find(|&j| first[j + 1] == first[j]) {
        return Err(MeshError::UnreferencedVertex { vertex: v });
    }
    let around = faces_around_vertices(faces, &first);

    // 3. Columns.
    let columns = merge_columns(faces, &first, &around, &elements, &corner_mass);

    // faer checks once that every column's rows are sorted and in range (O(nnz)); B gets a
    // copy of the checked pattern (each matrix owns one). Meanwhile the per-face records are
    // freed.
    let col_ptr = columns.col_ptr;
    let pattern = |row_idx: Vec<usize>| SymbolicSparseColMat::new_checked(n, n, col_ptr.clone(), None, row_idx);
    let [l_rows, b_rows] = columns.row_idx;
    let ((stiffness_pattern, mass_pattern), ()) = rayon::join(
        || rayon::join(|| pattern(l_rows), || pattern(b_rows)),
        || drop((elements, corner_mass, around)),
    );
    Ok(FemOperators {
        stiffness: SparseColMat::new(stiffness_pattern, columns.l_val),
        mass: SparseColMat::new(mass_pattern, columns.b_val),
        lumped_diagonal: columns.lumped_diagonal,
        lumping: params.lumping,
    })
}

/// Step 1 of [`crate::assemble`]: the element of every face and, for the Voronoi lumped mass, the
/// mixed Voronoi area of each corner (empty otherwise), in parallel over faces; the first
/// degenerate face (in face order) as the error.
fn face_elements(mesh: &TriMesh, voronoi: bool) -> Result<(Vec<FaceElement>, Vec<[f64; 3]>), usize> {
    let n_faces = mesh.n_faces();
    let mut elements = vec![FaceElement::default(); n_faces];
    let mut corner_mass = vec![[0.0f64; 3]; if voronoi { n_faces } else { 0 }];
    let mass_chunk = if voronoi { FACES_PER_CHUNK } else { 1 };
    let mut mass_chunks: Vec<&mut [[f64; 3]]> = corner_mass.chunks_mut(mass_chunk).collect();
    mass_chunks.resize_with(n_faces.div_ceil(FACES_PER_CHUNK), Default::default);
    let degenerate = elements
        .par_chunks_mut(FACES_PER_CHUNK)
        .zip(mass_chunks)
        .enumerate()
        .map(|(c, (out, masses))| {
            let start = c * FACES_PER_CHUNK;
            let mut degenerate = None;
            for (i, e) in out.iter_mut().enumerate() {
                match face_element(mesh.corners(start + i), voronoi) {
                    Some((element, m)) => {
                        *e = element;
                        if voronoi {
                            masses[i] = m;
                        }
                    }
                    None => {
                        degenerate.get_or_insert(start + i);
                    }
                }
            }
            degenerate
        })
        .reduce(|| None, |a, b| a.into_iter().chain(b).min());
    match degenerate {
        Some(f) => Err(f),
        None => Ok((elements, corner_mass)),
    }
}

/// Step 2 of [`crate::assemble`]: the faces around every vertex j in the segment
/// `first[j]..first[j + 1]`, in face order, in parallel over vertex ranges of about equal
/// corner counts (one per thread): each range scans all faces (cheap, sequential) and records
/// the corners it owns, so every task writes only its own slice.
pub(crate) fn faces_around_vertices<const N: usize>(faces: &[[u32; N]], first: &[usize]) -> Vec<u32> {
    let n = first.len() - 1;
    let n_corners = first[n];
    let n_ranges = rayon::current_num_threads().clamp(1, n);
    let vertex_bounds: Vec<usize> = (0..=n_ranges)
        .map(|r| {
            let target = n_corners * r / n_ranges;
            first.partition_point(|&c| c < target).min(n)
        })
        .collect();
    let corner_bounds: Vec<usize> = vertex_bounds[1..].iter().map(|&v| first[v]).collect();
    let mut around = vec![0u32; n_corners];
    split_at_bounds(&mut around, &corner_bounds)
        .into_par_iter()
        .zip(vertex_bounds.par_windows(2))
        .for_each(|(out, range)| {
            let (v0, v1) = (range[0], range[1]);
            let base = first[v0];
            let mut cursor: Vec<usize> = first[v0..v1].iter().map(|&c| c - base).collect();
            for (f, face) in faces.iter().enumerate() {
                for &v in face {
                    let v = v as usize;
                    if (v0..v1).contains(&v) {
                        let c = &mut cursor[v - v0];
                        // `assemble` checked that face indices fit in 32 bits.
                        out[*c] = f as u32;
                        *c += 1;
                    }
                }
            }
        });
    around
}

/// L and B as column arrays on one pattern, and the lumped diagonal.
pub(crate) struct Columns {
    pub col_ptr: Vec<usize>,
    /// The row indices, once for L and once for B (each matrix owns a copy).
    pub row_idx: [Vec<usize>; 2],
    pub l_val: Vec<f64>,
    pub b_val: Vec<f64>,
    pub lumped_diagonal: Vec<f64>,
}

/// The half-edges (j, i) of face `f` at its corner j, with their stiffness values: the edge
/// to each other corner is opposite the third one, `L_ij = −½ cot`.
#[inline]
fn corner_half_edges(face: [u32; 3], j: usize, cots: [f64; 3]) -> (usize, [(u32, f64); 2]) {
    // A face names three distinct vertices (a repeated one makes it degenerate).
    let k = if face[0] as usize == j {
        0
    } else if face[1] as usize == j {
        1
    } else {
        2
    };
    let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
    (k, [(face[k1], -0.5 * cots[k2]), (face[k2], -0.5 * cots[k1])])
}

/// Step 3 of [`crate::assemble`]: per column j, the half-edges of the faces around j merged by row
/// (stably, in face order) into the entries of L, B and D, in parallel over chunks of columns.
fn merge_columns(
    faces: &[[u32; 3]],
    first: &[usize],
    around: &[u32],
    elements: &[FaceElement],
    corner_mass: &[[f64; 3]],
) -> Columns {
    let voronoi = !corner_mass.is_empty();
    // 3a. Count the distinct rows of each column, then lay out the column pointers.
    let (chunks, col_ptr) = column_layout(around, first, faces);

    // 3b. Write the merged entries (shared pass: `write_columns`).
    write_columns(&chunks, col_ptr, |j, buf| {
        let mut d_jj = 0.0;
        for &f in &around[first[j]..first[j + 1]] {
            let f = f as usize;
            let e = elements[f];
            let (k, half_edges) = corner_half_edges(faces[f], j, e.cots);
            // B_ij = Σ|T|/12 over the faces of edge ij.
            let b = e.area / 12.0;
            // Merge duplicates as they come (an interior edge appears once per incident
            // face), so each entry is summed in face order, the same order as on the other
            // side of the diagonal: L and B come out bitwise symmetric.
            for (i, lv) in half_edges {
                match buf.iter_mut().find(|e| e.0 == i) {
                    Some(e) => {
                        e.1 += lv;
                        e.2 += b;
                    }
                    None => buf.push((i, lv, b)),
                }
            }
            d_jj += if voronoi { corner_mass[f][k] } else { e.area / 3.0 };
        }
        // Each incident face puts |T|/12 on two edges at j, so the off-diagonal sum of column
        // j of B is Σ_{T∋j}|T|/6 = B_jj.
        ColumnDiagonal {
            lumped: d_jj,
            mass: None,
        }
    })
}

/// The diagonal entries of one column (what [`write_columns`] cannot derive).
pub(crate) struct ColumnDiagonal {
    /// D_jj.
    pub lumped: f64,
    /// B_jj, or `None` for the sum of the column's off-diagonal B entries.
    pub mass: Option<f64>,
}

/// One chunk's columns as a write pass fills them: its own disjoint slices of the final
/// arrays (the entries of columns `columns.0..columns.1`, from `col_ptr[columns.0]`, and their
/// D_jj), the chunk's index in `chunks`, and the column pointers.
pub(crate) struct ChunkSlices<'a> {
    pub l_rows: &'a mut [usize],
    pub b_rows: &'a mut [usize],
    pub l: &'a mut [f64],
    pub b: &'a mut [f64],
    pub lumped: &'a mut [f64],
    pub columns: (usize, usize),
    pub index: usize,
    pub col_ptr: &'a [usize],
}

/// The arrays of the operators at `col_ptr`, filled chunk by chunk in parallel: `fill(state,
/// slices)` writes the rows and values of one chunk's columns into its own slices, with a
/// per-worker scratch `state` from `init`. Shared by the surface assemblies ([`write_columns`])
/// and the tetrahedral one.
pub(crate) fn fill_columns<S>(
    chunks: &[(usize, usize)],
    col_ptr: Vec<usize>,
    init: impl Fn() -> S + Sync + Send,
    fill: impl Fn(&mut S, ChunkSlices<'_>) + Sync + Send,
) -> Columns {
    let n = col_ptr.len() - 1;
    let nnz = col_ptr[n];
    let mut row_idx = [vec![0usize; nnz], vec![0usize; nnz]];
    let mut l_val = vec![0.0f64; nnz];
    let mut b_val = vec![0.0f64; nnz];
    let mut lumped_diagonal = vec![0.0f64; n];
    {
        let bounds: Vec<usize> = chunks.iter().map(|&(_, end)| col_ptr[end]).collect();
        let [l_rows, b_rows] = &mut row_idx;
        let work: Vec<_> = split_at_bounds(l_rows, &bounds)
            .into_iter()
            .zip(split_at_bounds(b_rows, &bounds))
            .zip(split_at_bounds(&mut l_val, &bounds))
            .zip(split_at_bounds(&mut b_val, &bounds))
            .zip(lumped_diagonal.chunks_mut(COLUMNS_PER_CHUNK))
            .zip(chunks.iter().enumerate())
            .collect();
        let col_ptr = &col_ptr;
        work.into_par_iter().for_each_init(
            &init,
            |state, (((((l_rows, b_rows), l), b), lumped), (index, &columns))| {
                let slices = ChunkSlices {
                    l_rows,
                    b_rows,
                    l,
                    b,
                    lumped,
                    columns,
                    index,
                    col_ptr,
                };
                fill(state, slices);
            },
        );
    }
    Columns {
        col_ptr,
        row_idx,
        l_val,
        b_val,
        lumped_diagonal,
    }
}

/// The write pass shared by the cotangent and the intrinsic assembly: for every column j (in
/// parallel over `chunks`), `column(j, buf)` fills `buf` with the merged off-diagonal entries
/// `(row, L, B)` of column j (distinct rows, any order) and returns its diagonal entries; the
/// rows are sorted, `L_jj = −Σ_i L_ij` (so `L·1 = 0`), and the entries are written into disjoint
/// per-chunk slices of the final arrays at `col_ptr`.
pub(crate) fn write_columns(
    chunks: &[(usize, usize)],
    col_ptr: Vec<usize>,
    column: impl Fn(usize, &mut Vec<(u32, f64, f64)>) -> ColumnDiagonal + Sync,
) -> Columns {
    // Half-edges (row i, L value, B value) of a column.
    fill_columns(chunks, col_ptr, Vec::<(u32, f64, f64)>::new, |buf, s| {
        let (col_start, col_end) = s.columns;
        let base = s.col_ptr[col_start];
        for j in col_start..col_end {
            buf.clear();
            let d = column(j, buf);
            // The rows are distinct now.
            buf.sort_unstable_by_key(|e| e.0);
            s.lumped[j - col_start] = d.lumped;
            let merged = &buf[..];
            let l_diag = -merged.iter().map(|e| e.1).sum::<f64>();
            let b_diag = d.mass.unwrap_or_else(|| merged.iter().map(|e| e.2).sum::<f64>());
            let split = merged.partition_point(|e| (e.0 as usize) < j);
            let mut p = s.col_ptr[j] - base;
            let mut put = |i: usize, lv: f64, bv: f64| {
                s.l_rows[p] = i;
                s.b_rows[p] = i;
                s.l[p] = lv;
                s.b[p] = bv;
                p += 1;
            };
            for e in &merged[..split] {
                put(e.0 as usize, e.1, e.2);
            }
            put(j, l_diag, b_diag);
            for e in &merged[split..] {
                put(e.0 as usize, e.1, e.2);
            }
        }
    })
}

/// The column chunks (`COLUMNS_PER_CHUNK` columns each) and the column pointers of the
/// vertex–edge pattern plus diagonal: column j holds j and every other corner of the triangles
/// `around[first[j]..first[j + 1]]` (each once). Shared by the cotangent and the intrinsic
/// assembly.
pub(crate) fn column_layout<const N: usize>(
    around: &[u32],
    first: &[usize],
    triangles: &[[u32; N]],
) -> (Vec<(usize, usize)>, Vec<usize>) {
    let n = first.len() - 1;
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
                for &f in &around[first[j]..first[j + 1]] {
                    for &v in &triangles[f as usize] {
                        if v as usize != j && !rows.contains(&v) {
                            rows.push(v);
                        }
                    }
                }
                *count = 1 + rows.len();
            }
        });
    for j in 0..n {
        col_ptr[j + 1] += col_ptr[j];
    }
    (chunks, col_ptr)
}

/// Splits `v` into consecutive pieces ending at the increasing offsets `bounds` (the last
/// bound must be `v.len()`).
pub(crate) fn split_at_bounds<'a, T>(mut v: &'a mut [T], bounds: &[usize]) -> Vec<&'a mut [T]> {
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
fn voronoi_corner_areas(t: &ScaledTriangle, FaceElement { area, cots }: FaceElement) -> [f64; 3] {
    let ([d01, d12, d20], scale) = (t.edges, t.k);
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
