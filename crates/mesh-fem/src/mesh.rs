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
        if let Some((vertex, position)) = crate::vec3::first_non_finite(&positions) {
            return Err(MeshError::NonFiniteCoordinate { vertex, position });
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
        triangle_area(self.corners(f))
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

pub(crate) use crate::vec3::{cross, dot, norm, sub};

// ---------------------------------------------------------------- overflow-free triangle geometry
// (added with the fuzzing work of issue #8: a valid triangle with edges beyond ~1e154 or below
// ~1e-154 overflowed or underflowed in ‖e₁×e₂‖ and was reported as having zero area.)

/// `x · 2ⁿ`, exact unless the result over- or underflows (the power is applied in steps that
/// are each representable).
#[inline]
pub(crate) fn mul_pow2(mut x: f64, mut n: i32) -> f64 {
    while n != 0 {
        let step = n.clamp(-1000, 1000);
        // 2^step as a normal double: biased exponent step + 1023 ∈ [23, 2023].
        x *= f64::from_bits(((step + 1023) as u64) << 52);
        n -= step;
    }
    x
}

/// The edge vectors `[p₁−p₀, p₂−p₁, p₀−p₂]` of a triangle multiplied by the power of two
/// 2⁻ᵏ that brings their largest component into [1, 2), together with k; k = 0 (no scaling)
/// when that component is already between 1e−60 and 1e60, where scaling changes nothing.
///
/// Multiplying by a power of two is exact, so dot products, cross products and norms of the
/// scaled edges are the unscaled ones times 2⁻²ᵏ exactly, with neither overflow (edges beyond
/// ~1e154) nor underflow (edges below ~1e−154), and scale-free ratios such as cotangents are
/// bitwise the values an unscaled computation gives whenever that one does not overflow.
/// `None` if an edge is not finite or all three edges are zero.
#[inline]
pub(crate) fn scaled_edges(p: [[f64; 3]; 3]) -> Option<([[f64; 3]; 3], i32)> {
    let edges = [sub(p[1], p[0]), sub(p[2], p[1]), sub(p[0], p[2])];
    let m = edges.iter().flatten().fold(0.0f64, |m, c| m.max(c.abs()));
    if !m.is_finite() || m == 0.0 || edges.iter().flatten().any(|c| !c.is_finite()) {
        return None;
    }
    // Between 1e-60 and 1e60 everything computed from the edges, up to the fourth powers in
    // the squared norm of a cross product, stays in the normal range (only terms more than
    // 2⁻²⁰⁰ below the leading ones could become subnormal), so the scaled computation would
    // give the same bits: k = 0.
    if (1e-60..1e60).contains(&m) {
        return Some((edges, 0));
    }
    // Binary exponent of m (subnormals first lifted by 2⁶⁴).
    let k = if m >= f64::MIN_POSITIVE {
        ((m.to_bits() >> 52) & 0x7ff) as i32 - 1023
    } else {
        (((m * 18446744073709551616.0).to_bits() >> 52) & 0x7ff) as i32 - 1023 - 64
    };
    let s = |e: [f64; 3]| e.map(|c| mul_pow2(c, -k));
    Some((edges.map(s), k))
}

#[inline]
pub(crate) fn neg(a: [f64; 3]) -> [f64; 3] {
    [-a[0], -a[1], -a[2]]
}

/// A triangle measured on its exactly scaled edges ([`scaled_edges`]): everything the
/// degeneracy test, the area and the cotangents need, computed once.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScaledTriangle {
    /// `[p₁−p₀, p₂−p₁, p₀−p₂] · 2⁻ᵏ`.
    pub(crate) edges: [[f64; 3]; 3],
    /// The power of two k.
    pub(crate) k: i32,
    /// `‖(p₁−p₀) × (p₂−p₀)‖ · 2⁻²ᵏ`, twice the scaled area.
    pub(crate) double_area: f64,
}

impl ScaledTriangle {
    /// `None` if an edge is not finite or all three edges are zero.
    #[inline]
    pub(crate) fn new(p: [[f64; 3]; 3]) -> Option<Self> {
        let (edges, k) = scaled_edges(p)?;
        // p₂ − p₀ = −(p₀ − p₂) exactly.
        let double_area = norm(cross(edges[0], neg(edges[2])));
        Some(Self { edges, k, double_area })
    }

    /// The area |T| (exact scaling back; overflows only if the area does).
    #[inline]
    pub(crate) fn area(&self) -> f64 {
        0.5 * mul_pow2(self.double_area, 2 * self.k)
    }

    /// The cotangent of the angle at each corner, `(e₁·e₂)/‖e₁×e₂‖` with the two edges leaving
    /// the corner; ‖e₁×e₂‖ is twice the area at every corner, and the common value keeps the
    /// three cotangents consistent. Scale invariant.
    #[inline]
    pub(crate) fn cotangents(&self) -> [f64; 3] {
        let [d01, d12, d20] = self.edges;
        // The two edges leaving each corner: p_{k+1} − p_k and p_{k+2} − p_k.
        [(d01, neg(d20)), (d12, neg(d01)), (d20, neg(d12))].map(|(e1, e2)| dot(e1, e2) / self.double_area)
    }
}

/// Area of a triangle, computed on exactly scaled edges ([`scaled_edges`]) so that it neither
/// overflows nor underflows unless the area itself does; 0 for coincident corners, +∞ for
/// non-finite edges.
#[inline]
pub(crate) fn triangle_area(p: [[f64; 3]; 3]) -> f64 {
    match ScaledTriangle::new(p) {
        Some(t) => t.area(),
        None if p[0] == p[1] && p[1] == p[2] => 0.0,
        None => f64::INFINITY,
    }
}
