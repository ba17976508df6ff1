//! The P1 gradient and divergence of a simplicial mesh: per element, the gradients ∇φ_i of
//! the hat functions of its corners (constant on the element) and its measure |T|.
//!
//! For a function u with vertex values uᵢ the gradient on element T is `∇u|_T = Σ_{i∈T} uᵢ ∇φᵢ`;
//! for a field X constant per element the (integrated) divergence at vertex i is
//! `bᵢ = Σ_{T∋i} |T| X_T · ∇φᵢ`, the weak form `∫ X·∇φᵢ` (so `b = Gᵀ diag(|T|) X`, and
//! `Gᵀ diag(|T|) G = L`, the stiffness of paper Eq. (3), with L positive semidefinite).
//!
//! Triangles are laid out in the plane from their three edge lengths (so the same code serves an
//! extrinsic mesh and an intrinsic triangulation, whose triangles have no embedding); the
//! gradients then have a zero third component. Each element's gradients are in its own frame:
//! only per-element quantities (a normalised gradient, a dot product with ∇φᵢ) are meaningful.

use crate::intrinsic::IntrinsicTriangulation;
use crate::vec3::{norm, sub};
use crate::{MeshError, TriMesh};

/// Per-element hat-function gradients and measures of a triangulation (see the module docs).
#[derive(Clone, Debug)]
pub struct ElementGradients {
    n_vertices: usize,
    /// Corners per element (3 for triangles).
    arity: usize,
    /// `arity` corners per element.
    corners: Vec<u32>,
    /// `arity` gradients per element, in the element's frame.
    basis: Vec<[f64; 3]>,
    /// The measure |T| of each element, times the weight given at construction.
    measure: Vec<f64>,
}

/// The hat-function gradients of a triangle with edge lengths `l` (l[k] from corner k to
/// corner k + 1), laid out as a = (0, 0), b = (l₀, 0), c above the x axis, and its area;
/// `None` for a triangle of zero or non-finite area.
pub fn triangle_gradients(l: [f64; 3]) -> Option<([[f64; 3]; 3], f64)> {
    let area = crate::intrinsic::triangle_area(l[0], l[1], l[2]);
    if !(area > 0.0 && area.is_finite() && l[0] > 0.0) {
        return None;
    }
    // c = (cx, cy): |ac| = l₂, |bc| = l₁.
    let cx = (l[0] * l[0] + l[2] * l[2] - l[1] * l[1]) / (2.0 * l[0]);
    let cy = 2.0 * area / l[0];
    let (a, b, c) = ([0.0, 0.0], [l[0], 0.0], [cx, cy]);
    // ∇φ_a = n × (c − b) / 2|T| with n = +z: perpendicular to bc, towards a.
    let perp = |p: [f64; 2], q: [f64; 2]| [-(q[1] - p[1]) / (2.0 * area), (q[0] - p[0]) / (2.0 * area), 0.0];
    let g = [perp(b, c), perp(c, a), perp(a, b)];
    g.iter().flatten().all(|x| x.is_finite()).then_some((g, area))
}

impl ElementGradients {
    /// The gradients of triangles given by their corners and edge lengths, every measure times
    /// `weight` (½ on a tufted cover, whose faces are there twice). A triangle of zero area
    /// gets zero gradients and measure (it contributes nothing, as to L).
    ///
    /// # Errors
    /// [`MeshError::InvalidParameter`] for a non-finite or non-positive weight.
    pub fn from_triangles(
        n_vertices: usize,
        triangles: &[[u32; 3]],
        lengths: impl Fn(usize) -> [f64; 3],
        weight: f64,
    ) -> Result<Self, MeshError> {
        if !(weight > 0.0 && weight.is_finite()) {
            return Err(MeshError::InvalidParameter {
                name: "weight",
                value: weight,
                expected: "a finite number > 0",
            });
        }
        let m = triangles.len();
        let mut basis = Vec::with_capacity(3 * m);
        let mut measure = Vec::with_capacity(m);
        for (t, _) in triangles.iter().enumerate() {
            match triangle_gradients(lengths(t)) {
                Some((g, area)) => {
                    basis.extend_from_slice(&g);
                    measure.push(weight * area);
                }
                None => {
                    basis.extend_from_slice(&[[0.0; 3]; 3]);
                    measure.push(0.0);
                }
            }
        }
        Ok(Self {
            n_vertices,
            arity: 3,
            corners: triangles.iter().flatten().copied().collect(),
            basis,
            measure,
        })
    }

    /// The gradients of a mesh's own triangles (extrinsic edge lengths): `Gᵀ diag|T| G` is the
    /// cotangent stiffness of [`crate::assemble`].
    pub fn of_mesh(mesh: &TriMesh) -> Self {
        let p = mesh.positions();
        let faces = mesh.faces();
        let lengths = |t: usize| {
            let [a, b, c] = faces[t].map(|v| p[v as usize]);
            [norm(sub(b, a)), norm(sub(c, b)), norm(sub(a, c))]
        };
        #[allow(clippy::expect_used)]
        // invariant: the weight 1 is valid.
        Self::from_triangles(mesh.n_vertices(), faces, lengths, 1.0).expect("weight 1 is valid")
    }

    /// The gradients of an intrinsic triangulation, every measure times `weight` (½ for a
    /// tufted cover): `Gᵀ diag|T| G` is the L of [`IntrinsicTriangulation::operators`] with the
    /// same weight.
    ///
    /// # Errors
    /// As [`Self::from_triangles`].
    pub fn of_intrinsic(triangulation: &IntrinsicTriangulation, weight: f64) -> Result<Self, MeshError> {
        let triangles: Vec<[u32; 3]> = (0..triangulation.n_triangles())
            .map(|t| triangulation.triangle(t))
            .collect();
        Self::from_triangles(
            triangulation.n_vertices(),
            &triangles,
            |t| triangulation.triangle_lengths(t),
            weight,
        )
    }

    /// The gradients of a tetrahedral mesh (in the ambient frame): `Gᵀ diag|T| G` is the L of
    /// [`crate::volume::assemble_volume`].
    ///
    /// # Errors
    /// [`MeshError::DegenerateTet`] for a flat tetrahedron.
    pub fn of_volume(mesh: &crate::volume::TetMesh) -> Result<Self, MeshError> {
        let mut basis = Vec::with_capacity(4 * mesh.n_tets());
        let mut measure = Vec::with_capacity(mesh.n_tets());
        for t in 0..mesh.n_tets() {
            let e = crate::volume::tet_element(mesh.corners(t)).ok_or(MeshError::DegenerateTet {
                tet: t,
                vertices: mesh.tets()[t],
                volume: mesh.signed_volume(t),
            })?;
            basis.extend_from_slice(&e.gradients);
            measure.push(e.volume);
        }
        Ok(Self {
            n_vertices: mesh.n_vertices(),
            arity: 4,
            corners: mesh.tets().iter().flatten().copied().collect(),
            basis,
            measure,
        })
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }

    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.measure.len()
    }

    /// Corners per element.
    pub fn arity(&self) -> usize {
        self.arity
    }

    /// The corners of element `e`.
    pub fn corners(&self, e: usize) -> &[u32] {
        &self.corners[e * self.arity..(e + 1) * self.arity]
    }

    /// The hat-function gradients of element `e`'s corners, in the element's frame.
    pub fn basis(&self, e: usize) -> &[[f64; 3]] {
        &self.basis[e * self.arity..(e + 1) * self.arity]
    }

    /// The (weighted) measure of element `e`.
    pub fn measure(&self, e: usize) -> f64 {
        self.measure[e]
    }

    /// `∇u` on element `e`, `Σ_i value(i) ∇φ_i`, in the element's frame.
    #[inline]
    pub fn gradient_on(&self, e: usize, value: impl Fn(u32) -> f64) -> [f64; 3] {
        let mut g = [0.0; 3];
        for (&v, b) in self.corners(e).iter().zip(self.basis(e)) {
            let x = value(v);
            for k in 0..3 {
                g[k] += x * b[k];
            }
        }
        g
    }

    /// The integrated divergence `bᵢ = Σ_{T∋i} |T| X_T·∇φᵢ` of a field constant per element
    /// (`field[e]` in element e's frame); `b` sums to zero.
    ///
    /// # Errors
    /// [`MeshError::ElementFieldLength`] when `field` does not have one vector per element.
    pub fn divergence(&self, field: &[[f64; 3]]) -> Result<Vec<f64>, MeshError> {
        if field.len() != self.n_elements() {
            return Err(MeshError::ElementFieldLength {
                found: field.len(),
                expected: self.n_elements(),
            });
        }
        let mut b = vec![0.0; self.n_vertices];
        for (e, x) in field.iter().enumerate() {
            let w = self.measure[e];
            if w == 0.0 {
                continue;
            }
            for (&v, g) in self.corners(e).iter().zip(self.basis(e)) {
                b[v as usize] += w * (x[0] * g[0] + x[1] * g[1] + x[2] * g[2]);
            }
        }
        Ok(b)
    }
}
