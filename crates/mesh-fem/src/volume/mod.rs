//! Tetrahedral meshes (the paper's "d-dimensional data", beyond it): [`TetMesh`], its
//! validation ([`validate_volume`]) and repairs, its boundary surface, and the linear FEM
//! operators of paper Eq. (3) on tetrahedra ([`assemble_volume`]): the same [`FemOperators`]
//! as on surfaces, so the heat kernel, distances, signatures and eigenbases of every other crate
//! work on volumes unchanged.
//!
//! On a tetrahedron T with vertices p₀…p₃ the hat functions have constant gradients ∇φᵢ; the
//! element matrices are `L_ij = |T| ∇φᵢ·∇φⱼ` (= −(1/6) ℓ_kl cot θ_kl, θ_kl the dihedral angle at
//! the edge opposite ij; L symmetric positive semidefinite, positive diagonal), the consistent
//! mass `B_ij = |T|/20` (i ≠ j) and `|T|/10` (i = j), and the lumped (barycentric) mass
//! `D_ii = |T|/4`. The gradients come from the signed volume, the measure from its absolute
//! value, so an inverted tetrahedron gives the same matrices as its reoriented copy.

mod assembly;
pub mod cut;
mod validate;

pub use assembly::{assemble_volume, tet_element, TetElement};
pub use validate::{boundary_faces, repair_volume, validate_volume, VolumeProblem, VolumeRepair, VolumeReport};

use crate::MeshError;

/// A tetrahedral mesh: vertex positions and tetrahedra (4 vertex indices each).
///
/// [`TetMesh::new`] checks what every routine relies on: finite coordinates, indices in range;
/// orientation, degenerate tetrahedra and unreferenced vertices are reported by
/// [`validate_volume`].
#[derive(Clone, Debug, PartialEq)]
pub struct TetMesh {
    positions: Vec<[f64; 3]>,
    tets: Vec<[u32; 4]>,
}

impl TetMesh {
    /// Builds a tetrahedral mesh.
    ///
    /// # Errors
    /// [`MeshError::Empty`] without vertices or tetrahedra, [`MeshError::NonFiniteCoordinate`],
    /// [`MeshError::TetIndexOutOfRange`] for an index that names no vertex.
    pub fn new(positions: Vec<[f64; 3]>, tets: Vec<[u32; 4]>) -> Result<Self, MeshError> {
        if positions.is_empty() || tets.is_empty() {
            return Err(MeshError::Empty {
                n_vertices: positions.len(),
                n_faces: tets.len(),
            });
        }
        if let Some((vertex, position)) = crate::vec3::first_non_finite(&positions) {
            return Err(MeshError::NonFiniteCoordinate { vertex, position });
        }
        let n = positions.len();
        for (tet, t) in tets.iter().enumerate() {
            if let Some(&index) = t.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::TetIndexOutOfRange {
                    tet,
                    index,
                    n_vertices: n,
                });
            }
        }
        Ok(Self { positions, tets })
    }

    /// Vertex positions.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }

    /// Tetrahedra as vertex indices.
    pub fn tets(&self) -> &[[u32; 4]] {
        &self.tets
    }

    /// Number of vertices n.
    pub fn n_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of tetrahedra.
    pub fn n_tets(&self) -> usize {
        self.tets.len()
    }

    /// The four corners of tetrahedron `t`.
    pub fn corners(&self, t: usize) -> [[f64; 3]; 4] {
        self.tets[t].map(|v| self.positions[v as usize])
    }

    /// Signed volume of tetrahedron `t`, `((p₁−p₀)×(p₂−p₀))·(p₃−p₀)/6` (positive when p₃ lies
    /// on the side the right-handed triangle p₀p₁p₂ faces).
    pub fn signed_volume(&self, t: usize) -> f64 {
        signed_volume(self.corners(t))
    }

    /// Total volume Σ|T|.
    pub fn volume(&self) -> f64 {
        (0..self.n_tets()).map(|t| self.signed_volume(t).abs()).sum()
    }

    /// Every vertex scaled by `s` about the origin.
    ///
    /// # Errors
    /// [`MeshError::NonFiniteCoordinate`] if a coordinate overflows.
    pub fn scaled(&self, s: f64) -> Result<Self, MeshError> {
        Self::new(
            self.positions.iter().map(|p| p.map(|x| x * s)).collect(),
            self.tets.clone(),
        )
    }

    /// The boundary surface (faces of exactly one tetrahedron, oriented outward) as a triangle
    /// mesh on **all** the vertices (interior ones are referenced by no face), so that a
    /// per-vertex field of the volume is also one of the surface: for figures and PLY files.
    ///
    /// # Errors
    /// [`MeshError::Empty`] for a volume without boundary faces (not a finite solid).
    pub fn boundary_mesh(&self) -> Result<crate::TriMesh, MeshError> {
        crate::TriMesh::new(self.positions.clone(), boundary_faces(self))
    }

    /// Every tetrahedron split into eight at its edge midpoints (Bey's red refinement: the same
    /// solid, a finer mesh): the n vertices first, then one per edge.
    pub fn refined(&self) -> Self {
        assembly::split_tets(self)
    }
}

/// Signed volume of the tetrahedron with corners `p`.
pub fn signed_volume(p: [[f64; 3]; 4]) -> f64 {
    use crate::vec3::{cross, dot, sub};
    dot(cross(sub(p[1], p[0]), sub(p[2], p[0])), sub(p[3], p[0])) / 6.0
}

/// The quality 6√2·|V| / ℓ_rms³ of a tetrahedron (1 for the regular one, → 0 for a sliver).
pub fn tet_quality(p: [[f64; 3]; 4]) -> f64 {
    use crate::vec3::{norm, sub};
    let mut s = 0.0;
    for a in 0..4 {
        for b in a + 1..4 {
            let l = norm(sub(p[a], p[b]));
            s += l * l;
        }
    }
    let rms = (s / 6.0).sqrt();
    if rms > 0.0 {
        6.0 * std::f64::consts::SQRT_2 * signed_volume(p).abs() / (rms * rms * rms)
    } else {
        0.0
    }
}
