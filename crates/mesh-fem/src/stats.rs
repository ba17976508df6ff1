//! Mesh statistics: counts, topology (Euler characteristic, genus, boundary loops,
//! components) and geometry (area, bounding box, edge lengths, angles).
//!
//! Definitions (they match the columns of the corpus table `SOURCES.md`):
//!
//! * χ = V_used − E + F, with V_used the vertices that belong to a face and E the number of
//!   distinct undirected edges;
//! * a **boundary edge** has exactly one face; **boundary loops** are the cycles of boundary
//!   edges, joined where they meet inside one fan of faces around a vertex. On a manifold
//!   mesh this is the usual count; where loops touch at a pinched (non-manifold) vertex they
//!   stay separate loops, so on such meshes the count can exceed the number of connected
//!   components of the boundary-edge graph that `SOURCES.md` lists (teapot.obj: 25 vs 10);
//! * **manifold**: every edge has at most two faces and the faces around every vertex form
//!   a single fan; **closed**: no boundary edge and no non-manifold edge;
//! * genus g = (2 − χ − b)/2 for a connected, manifold, orientable mesh with b boundary loops.

use crate::mesh::{cross, dot, norm, sub};
use crate::topology::Topology;
use crate::vec3::bbox_diagonal;
use crate::TriMesh;
use rayon::prelude::*;
use serde::Serialize;

/// Counts, topology and geometry of a mesh, from [`stats`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeshStats {
    /// Number of vertices (including unreferenced ones).
    pub n_vertices: usize,
    /// Number of vertices that belong to no face.
    pub n_unreferenced_vertices: usize,
    /// Number of faces.
    pub n_faces: usize,
    /// Number of distinct undirected edges.
    pub n_edges: usize,
    /// Number of edges with exactly one face.
    pub n_boundary_edges: usize,
    /// Number of edges with more than two faces.
    pub n_non_manifold_edges: usize,
    /// Number of vertices whose faces form more than one fan.
    pub n_non_manifold_vertices: usize,
    /// Number of boundary loops b.
    pub n_boundary_loops: usize,
    /// Number of connected components (of referenced vertices).
    pub n_components: usize,
    /// Euler characteristic χ = V_used − E + F.
    pub euler_characteristic: i64,
    /// Genus (2 − χ − b)/2, for a single-component manifold orientable mesh; else `None`.
    pub genus: Option<i64>,
    /// Total area Σ|T|.
    pub area: f64,
    /// Length of the diagonal of the axis-aligned bounding box.
    pub bbox_diagonal: f64,
    /// Mean length of the distinct edges.
    pub mean_edge_length: f64,
    /// Smallest interior angle of any face, in degrees.
    pub min_angle_deg: f64,
    /// Largest interior angle of any face, in degrees.
    pub max_angle_deg: f64,
    /// Every edge has ≤ 2 faces and every vertex a single fan.
    pub is_manifold: bool,
    /// Every component can be oriented consistently.
    pub is_orientable: bool,
    /// Every edge with two faces is traversed in opposite directions by them.
    pub is_consistently_oriented: bool,
    /// No boundary edge and no non-manifold edge.
    pub is_closed: bool,
}

/// The mean length of the distinct undirected edges of `mesh` (0 without edges), as in
/// [`MeshStats::mean_edge_length`]; O(F log F).
pub fn mean_edge_length(mesh: &TriMesh) -> f64 {
    let topo = Topology::new(mesh.n_vertices(), mesh.faces());
    mean_length(&topo, mesh.positions())
}

fn mean_length(topo: &Topology, positions: &[[f64; 3]]) -> f64 {
    let total: f64 = topo
        .edges
        .par_iter()
        .map(|&[a, b]| norm(sub(positions[a as usize], positions[b as usize])))
        .sum();
    if topo.edges.is_empty() {
        0.0
    } else {
        total / topo.edges.len() as f64
    }
}

/// Computes the [`MeshStats`] of `mesh` in O(F log F).
///
/// ```
/// use mesh_fem::stats::stats;
/// use mesh_fem::generate;
/// let s = stats(&generate::torus(2.0, 0.5, 24, 12));
/// assert_eq!((s.euler_characteristic, s.genus, s.is_closed), (0, Some(1), true));
/// ```
pub fn stats(mesh: &TriMesh) -> MeshStats {
    let topo = Topology::new(mesh.n_vertices(), mesh.faces());
    let positions = mesh.positions();
    let n_used = topo.n_referenced();
    let n_edges = topo.edges.len();
    let chi = n_used as i64 - n_edges as i64 + mesh.n_faces() as i64;
    let is_manifold = topo.non_manifold_edges.is_empty() && topo.non_manifold_vertices.is_empty();
    let is_orientable = topo.non_orientable_edges.is_empty();
    let b = topo.n_boundary_loops as i64;
    let genus =
        (topo.n_components == 1 && is_manifold && is_orientable && (2 - chi - b) % 2 == 0).then_some((2 - chi - b) / 2);

    let (min_angle, max_angle) = (0..mesh.n_faces())
        .into_par_iter()
        .map(|f| {
            let p = mesh.corners(f);
            let mut lo = f64::INFINITY;
            let mut hi = f64::NEG_INFINITY;
            for k in 0..3 {
                let e1 = sub(p[(k + 1) % 3], p[k]);
                let e2 = sub(p[(k + 2) % 3], p[k]);
                // atan2(|e1×e2|, e1·e2) is accurate for all angles, unlike acos.
                let angle = norm(cross(e1, e2)).atan2(dot(e1, e2));
                lo = lo.min(angle);
                hi = hi.max(angle);
            }
            (lo, hi)
        })
        .reduce(
            || (f64::INFINITY, f64::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );

    MeshStats {
        n_vertices: mesh.n_vertices(),
        n_unreferenced_vertices: mesh.n_vertices() - n_used,
        n_faces: mesh.n_faces(),
        n_edges,
        n_boundary_edges: topo.n_boundary_edges,
        n_non_manifold_edges: topo.non_manifold_edges.len(),
        n_non_manifold_vertices: topo.non_manifold_vertices.len(),
        n_boundary_loops: topo.n_boundary_loops,
        n_components: topo.n_components,
        euler_characteristic: chi,
        genus,
        area: mesh.area(),
        bbox_diagonal: bbox_diagonal(positions),
        mean_edge_length: mean_length(&topo, positions),
        min_angle_deg: min_angle.to_degrees(),
        max_angle_deg: max_angle.to_degrees(),
        is_manifold,
        is_orientable,
        is_consistently_oriented: topo.inconsistent_edges.is_empty(),
        is_closed: topo.n_boundary_edges == 0 && topo.non_manifold_edges.is_empty(),
    }
}
