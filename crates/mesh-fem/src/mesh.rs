use crate::MeshError;

/// A triangle mesh: vertex positions and counter-clockwise (outward) oriented triangles.
///
/// The constructor [`TriMesh::new`] checks the two invariants every routine in wfem relies
/// on: all coordinates are finite and every face index is in range. Everything else
/// (degenerate faces, non-manifold edges, several components, …) is reported by
/// [`crate::validate::validate`], because many of those meshes are still usable.
#[derive(Clone, Debug, PartialEq)]
pub struct TriMesh {
    positions: Vec<[f64; 3]>,
    faces: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Builds a mesh from positions and triangles.
    ///
    /// # Errors
    /// [`MeshError::Empty`] if there are no vertices or no faces,
    /// [`MeshError::NonFiniteCoordinate`] for a NaN or infinite coordinate, and
    /// [`MeshError::IndexOutOfRange`] for a face that names a vertex that does not exist.
    pub fn new(positions: Vec<[f64; 3]>, faces: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        if positions.is_empty() || faces.is_empty() {
            return Err(MeshError::Empty {
                n_vertices: positions.len(),
                n_faces: faces.len(),
            });
        }
        if let Some((vertex, p)) = positions
            .iter()
            .enumerate()
            .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
        {
            return Err(MeshError::NonFiniteCoordinate { vertex, position: *p });
        }
        let n = positions.len();
        for (face, f) in faces.iter().enumerate() {
            if let Some(&index) = f.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    face,
                    index,
                    n_vertices: n,
                });
            }
        }
        Ok(Self { positions, faces })
    }

    /// Vertex positions, one `[x, y, z]` per vertex.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }

    /// Triangles as vertex indices.
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Number of vertices n.
    pub fn n_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    /// Consumes the mesh and returns `(positions, faces)`.
    pub fn into_parts(self) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        (self.positions, self.faces)
    }

    /// The three corner positions of face `f`.
    #[inline]
    pub fn corners(&self, f: usize) -> [[f64; 3]; 3] {
        let [a, b, c] = self.faces[f];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Area of face `f`, |T| = ½‖(b − a) × (c − a)‖.
    #[inline]
    pub fn face_area(&self, f: usize) -> f64 {
        let [a, b, c] = self.corners(f);
        0.5 * norm(cross(sub(b, a), sub(c, a)))
    }

    /// Total surface area Σ|T|.
    pub fn area(&self) -> f64 {
        (0..self.n_faces()).map(|f| self.face_area(f)).sum()
    }

    /// Returns the mesh scaled by `alpha` about the origin (x ↦ αx). Faces are unchanged.
    ///
    /// # Errors
    /// [`MeshError::NonFiniteCoordinate`] if the scaled coordinates overflow.
    pub fn scaled(&self, alpha: f64) -> Result<Self, MeshError> {
        let positions = self
            .positions
            .iter()
            .map(|p| [p[0] * alpha, p[1] * alpha, p[2] * alpha])
            .collect();
        Self::new(positions, self.faces.clone())
    }

    /// Returns the mesh scaled uniformly about the origin so that its surface area is `area`.
    ///
    /// # Errors
    /// [`MeshError::DegenerateMesh`] if the mesh has zero area.
    pub fn with_area(&self, area: f64) -> Result<Self, MeshError> {
        let a = self.area();
        if a <= 0.0 || !a.is_finite() {
            return Err(MeshError::DegenerateMesh { area: a });
        }
        self.scaled((area / a).sqrt())
    }
}

#[inline]
pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
#[inline]
pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
