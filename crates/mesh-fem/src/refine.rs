//! Refinement of a triangle mesh without changing its geometry: every triangle split into four
//! at its edge midpoints ([`split_faces`]), so the piecewise-flat surface stays exactly the same
//! while linear FEM gets four times the vertices — its eigenpairs converge to those of the
//! surface as the mesh is refined (the error of the i-th eigenvalue is O(λᵢ² h²)). Used by the
//! [`crate::generate::icosphere`] (with the midpoints projected on the sphere) and by retrieval
//! to describe coarse meshes on an accurate eigenbasis.

use crate::{MeshError, TriMesh};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A fast hasher for the `(u32, u32)` edge keys of [`split_with`] (the default SipHash made
/// generation of a 655K-vertex icosphere several times slower than assembling its operators).
/// Keys are vertex indices, not attacker-controlled, so a multiplicative hash is enough.
#[derive(Default)]
struct EdgeHasher(u64);

impl Hasher for EdgeHasher {
    fn finish(&self) -> u64 {
        // hashbrown takes the bucket from the low bits: fold the well-mixed high half in.
        self.0 ^ (self.0 >> 32)
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(v as u64);
    }
    fn write_u64(&mut self, v: u64) {
        // Fibonacci hashing, mixed so that both key halves reach the high bits.
        self.0 = (self.0.rotate_left(29) ^ v).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// The mesh with every triangle split into four at its edge midpoints: the n vertices first,
/// unchanged and in their order, then one vertex per edge (n + E vertices, 4F faces, the same
/// surface and orientation). Boundary and non-manifold edges get one midpoint each, like any
/// other edge.
pub fn split_faces(mesh: &TriMesh) -> TriMesh {
    let mut positions = mesh.positions().to_vec();
    let faces = split_with(&mut positions, mesh.faces(), |a, b| {
        [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, (a[2] + b[2]) / 2.0]
    });
    #[allow(clippy::expect_used)]
    // invariant: midpoints of finite positions are finite and every index is in range.
    TriMesh::new(positions, faces).expect("a split of a valid mesh is valid")
}

/// [`split_faces`] with each edge's new vertex anywhere on the edge: vertex a + s (b − a) of
/// the edge between vertices a < b, with s = `fraction(a, b)` in (0, 1). The four triangles
/// of each face still tile it, so the surface is exactly the same as with midpoints, but its
/// triangulation is another: a seeded `fraction` gives each copy of a shape a triangulation of
/// its own (shrec-bench's remeshing, `shrec_bench::transform::remesh`).
///
/// # Errors
/// [`MeshError::InvalidParameter`] if a fraction is not in (0, 1) (the edge's new vertex would
/// fold its triangles over).
pub fn split_faces_at(mesh: &TriMesh, fraction: impl Fn(u32, u32) -> f64) -> Result<TriMesh, MeshError> {
    let mut positions = mesh.positions().to_vec();
    let mut bad = None;
    let faces = split_indexed(&mut positions, mesh.faces(), |a, b, pa, pb| {
        let s = fraction(a, b);
        if !(s > 0.0 && s < 1.0) {
            bad.get_or_insert(s);
        }
        [
            pa[0] + s * (pb[0] - pa[0]),
            pa[1] + s * (pb[1] - pa[1]),
            pa[2] + s * (pb[2] - pa[2]),
        ]
    });
    if let Some(value) = bad {
        return Err(MeshError::InvalidParameter {
            name: "edge fraction",
            value,
            expected: "a number in (0, 1)",
        });
    }
    TriMesh::new(positions, faces)
}

/// One split of `faces` (each triangle into four, orientation kept): a new vertex per edge is
/// appended to `positions` at `place(a, b)` of the edge's end points, in the order the edges
/// are first met; returns the new faces.
pub(crate) fn split_with(
    positions: &mut Vec<[f64; 3]>,
    faces: &[[u32; 3]],
    place: impl Fn([f64; 3], [f64; 3]) -> [f64; 3],
) -> Vec<[u32; 3]> {
    split_indexed(positions, faces, |_, _, pa, pb| place(pa, pb))
}

/// [`split_with`] whose `place(a, b, pa, pb)` also gets the edge's vertices, a < b, and their
/// positions in that order.
fn split_indexed(
    positions: &mut Vec<[f64; 3]>,
    faces: &[[u32; 3]],
    mut place: impl FnMut(u32, u32, [f64; 3], [f64; 3]) -> [f64; 3],
) -> Vec<[u32; 3]> {
    let mut midpoint: HashMap<(u32, u32), u32, BuildHasherDefault<EdgeHasher>> =
        HashMap::with_capacity_and_hasher(faces.len() * 3 / 2, Default::default());
    let mut mid = |a: u32, b: u32, positions: &mut Vec<[f64; 3]>| -> u32 {
        let key = if a < b { (a, b) } else { (b, a) };
        *midpoint.entry(key).or_insert_with(|| {
            let p = place(key.0, key.1, positions[key.0 as usize], positions[key.1 as usize]);
            positions.push(p);
            (positions.len() - 1) as u32
        })
    };
    let mut next = Vec::with_capacity(faces.len() * 4);
    for &[a, b, c] in faces {
        let ab = mid(a, b, positions);
        let bc = mid(b, c, positions);
        let ca = mid(c, a, positions);
        next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    next
}
