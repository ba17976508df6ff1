//! Combinatorial topology of a triangle mesh, shared by [`crate::validate`], [`crate::stats`]
//! and the repairs of the `mesh-repair` crate.
//!
//! One pass builds everything both modules need, in O(F log F) time for F faces:
//!
//! * the **edge map**: the 3F half-edges sorted by their undirected edge, grouped into unique
//!   edges with the list of half-edges (faces) on each edge;
//! * **fans**: corners (face, local corner) at the same vertex are joined by a union-find
//!   whenever their faces share an edge through that vertex; a vertex whose corners form more
//!   than one fan is a non-manifold ("pinched") vertex;
//! * **boundary loops**: boundary edges (one face) are joined where they meet inside the same
//!   fan of a vertex, so two loops touching at a pinched vertex stay two loops, and the count
//!   does not depend on the face orientation;
//! * **connected components** of the referenced vertices;
//! * **orientation**: an edge with two faces is consistently oriented when the faces traverse
//!   it in opposite directions; a union-find with parity over faces decides whether each
//!   component can be oriented consistently at all (a Möbius strip cannot).
//!
//! Self-loop half-edges (from faces that repeat a vertex) are left out of the edge map.

use crate::graph::UnionFind;
use rayon::prelude::*;

/// Marker for "no index".
pub(crate) const NONE: u32 = u32::MAX;

/// Disjoint sets where each element carries a parity (0/1) relative to its root, used to
/// decide whether faces can be oriented consistently.
struct ParityUnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
    /// Parity of an element relative to its parent.
    parity: Vec<u8>,
}

impl ParityUnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
            parity: vec![0; n],
        }
    }

    /// Root of `x` and the parity of `x` relative to it (with full path compression).
    fn find(&mut self, x: u32) -> (u32, u8) {
        let mut root = x;
        let mut par = 0u8;
        while self.parent[root as usize] != root {
            par ^= self.parity[root as usize];
            root = self.parent[root as usize];
        }
        // Second pass: point every node of the path straight at the root.
        let mut y = x;
        let mut py = par;
        while self.parent[y as usize] != root && y != root {
            let next = self.parent[y as usize];
            let next_par = py ^ self.parity[y as usize];
            self.parent[y as usize] = root;
            self.parity[y as usize] = py;
            y = next;
            py = next_par;
        }
        (root, par)
    }

    /// Requires parity(a) ⊕ parity(b) = `rel`. Returns `false` if that contradicts the
    /// constraints seen so far.
    fn constrain(&mut self, a: u32, b: u32, rel: u8) -> bool {
        let (ra, pa) = self.find(a);
        let (rb, pb) = self.find(b);
        if ra == rb {
            return pa ^ pb == rel;
        }
        let (big, small) = if self.size[ra as usize] >= self.size[rb as usize] {
            (ra, rb)
        } else {
            (rb, ra)
        };
        self.parent[small as usize] = big;
        self.parity[small as usize] = pa ^ pb ^ rel;
        self.size[big as usize] += self.size[small as usize];
        true
    }
}

/// Everything validation and statistics need about the connectivity of a mesh.
pub struct Topology {
    /// Unique undirected edges `[a, b]` with `a < b`, sorted.
    pub edges: Vec<[u32; 2]>,
    /// CSR offsets: edge `e` has `edge_ptr[e + 1] − edge_ptr[e]` faces.
    pub edge_ptr: Vec<usize>,
    /// Number of face corners at each vertex (0 for an unreferenced vertex).
    pub vertex_valence: Vec<u32>,
    /// Number of connected components of the referenced vertices.
    pub n_components: usize,
    /// Vertices whose incident faces form more than one fan, ascending.
    pub non_manifold_vertices: Vec<u32>,
    /// Number of edges with exactly one face.
    pub n_boundary_edges: usize,
    /// Number of boundary loops.
    pub n_boundary_loops: usize,
    /// Edges (ids into `edges`) with more than two faces.
    pub non_manifold_edges: Vec<u32>,
    /// Edges with two faces that traverse them in the same direction.
    pub inconsistent_edges: Vec<u32>,
    /// One edge per non-orientable component: the edge that closed an orientation conflict.
    pub non_orientable_edges: Vec<u32>,
    /// Per component: `true` if it cannot be oriented consistently.
    pub component_non_orientable: Vec<bool>,
    /// Per face: flipping exactly the faces marked here orients every orientable component
    /// consistently (the majority orientation of each component is kept).
    pub face_flip: Vec<bool>,
}

impl Topology {
    /// Number of faces on edge `e`.
    pub fn edge_face_count(&self, e: usize) -> usize {
        self.edge_ptr[e + 1] - self.edge_ptr[e]
    }

    /// Number of referenced vertices.
    pub fn n_referenced(&self) -> usize {
        self.vertex_valence.iter().filter(|&&d| d > 0).count()
    }

    /// Builds the topology of `faces` on `n_vertices` vertices (indices must be in range).
    pub fn new(n_vertices: usize, faces: &[[u32; 3]]) -> Self {
        let n_faces = faces.len();

        // Edge map: sort the half-edges by their undirected edge key.
        let mut keyed: Vec<(u64, u32)> = Vec::with_capacity(3 * n_faces);
        for (f, face) in faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (face[k], face[(k + 1) % 3]);
                if a != b {
                    let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
                    keyed.push((key, (3 * f + k) as u32));
                }
            }
        }
        keyed.par_sort_unstable();
        let mut edges = Vec::with_capacity(keyed.len() / 2 + 1);
        let mut edge_ptr = Vec::with_capacity(keyed.len() / 2 + 2);
        let mut half_edges = Vec::with_capacity(keyed.len());
        for (i, &(key, h)) in keyed.iter().enumerate() {
            if i == 0 || keyed[i - 1].0 != key {
                edge_ptr.push(i);
                edges.push([(key >> 32) as u32, key as u32]);
            }
            half_edges.push(h);
        }
        edge_ptr.push(keyed.len());
        drop(keyed);
        let n_edges = edges.len();

        let corner_vertex = |c: u32| faces[(c / 3) as usize][(c % 3) as usize];
        // The corner of the face of half-edge h that sits at vertex v (v is an end of h).
        let corner_at = |h: u32, v: u32| -> u32 {
            let (f, k) = (h / 3, h % 3);
            if faces[f as usize][k as usize] == v {
                h
            } else {
                3 * f + (k + 1) % 3
            }
        };

        let mut vertex_valence = vec![0u32; n_vertices];
        for face in faces {
            for &v in face {
                vertex_valence[v as usize] += 1;
            }
        }

        // Fans: join the corners at each end of every edge, and corners of one face that sit
        // at the same vertex (faces repeating an index).
        let mut fans = UnionFind::new(3 * n_faces);
        for (f, face) in faces.iter().enumerate() {
            for k in 0..3 {
                if face[k] == face[(k + 1) % 3] {
                    fans.union((3 * f + k) as u32, (3 * f + (k + 1) % 3) as u32);
                }
            }
        }
        for e in 0..n_edges {
            let hs = &half_edges[edge_ptr[e]..edge_ptr[e + 1]];
            let [a, b] = edges[e];
            for &h in &hs[1..] {
                fans.union(corner_at(hs[0], a), corner_at(h, a));
                fans.union(corner_at(hs[0], b), corner_at(h, b));
            }
        }
        let mut first_fan = vec![NONE; n_vertices];
        let mut pinched = vec![false; n_vertices];
        for c in 0..(3 * n_faces) as u32 {
            let v = corner_vertex(c) as usize;
            let r = fans.find(c);
            if first_fan[v] == NONE {
                first_fan[v] = r;
            } else if first_fan[v] != r {
                pinched[v] = true;
            }
        }
        drop(first_fan);
        let non_manifold_vertices: Vec<u32> = (0..n_vertices as u32).filter(|&v| pinched[v as usize]).collect();

        // Boundary loops: boundary edges meeting in the same fan belong to the same loop.
        let boundary: Vec<u32> = (0..n_edges as u32)
            .filter(|&e| edge_ptr[e as usize + 1] - edge_ptr[e as usize] == 1)
            .collect();
        let mut loops = UnionFind::new(boundary.len());
        let mut fan_edge = vec![NONE; 3 * n_faces];
        for (i, &e) in boundary.iter().enumerate() {
            let h = half_edges[edge_ptr[e as usize]];
            for v in edges[e as usize] {
                let fan = fans.find(corner_at(h, v)) as usize;
                if fan_edge[fan] == NONE {
                    fan_edge[fan] = i as u32;
                } else {
                    loops.union(fan_edge[fan], i as u32);
                }
            }
        }
        drop(fan_edge);
        let n_boundary_loops = (0..boundary.len() as u32).filter(|&i| loops.find(i) == i).count();

        // Connected components of the referenced vertices.
        let mut comps = UnionFind::new(n_vertices);
        for face in faces {
            comps.union(face[0], face[1]);
            comps.union(face[0], face[2]);
        }
        let mut vertex_component = vec![NONE; n_vertices];
        let mut root_label = vec![NONE; n_vertices];
        let mut n_components = 0usize;
        for v in 0..n_vertices {
            if vertex_valence[v] == 0 {
                continue;
            }
            let r = comps.find(v as u32) as usize;
            if root_label[r] == NONE {
                root_label[r] = n_components as u32;
                n_components += 1;
            }
            vertex_component[v] = root_label[r];
        }
        drop(root_label);

        // Orientation.
        let mut non_manifold_edges = Vec::new();
        let mut inconsistent_edges = Vec::new();
        let mut non_orientable_edges = Vec::new();
        let mut component_non_orientable = vec![false; n_components];
        let mut orient = ParityUnionFind::new(n_faces);
        for e in 0..n_edges {
            let hs = &half_edges[edge_ptr[e]..edge_ptr[e + 1]];
            if hs.len() > 2 {
                non_manifold_edges.push(e as u32);
            }
            if hs.len() != 2 {
                continue;
            }
            let forward = |h: u32| faces[(h / 3) as usize][(h % 3) as usize] == edges[e][0];
            let same_direction = forward(hs[0]) == forward(hs[1]);
            if same_direction {
                inconsistent_edges.push(e as u32);
            }
            if !orient.constrain(hs[0] / 3, hs[1] / 3, same_direction as u8) {
                let c = vertex_component[edges[e][0] as usize] as usize;
                if !component_non_orientable[c] {
                    component_non_orientable[c] = true;
                    non_orientable_edges.push(e as u32);
                }
            }
        }
        // Keep the majority orientation of every orientation class.
        let classes: Vec<(u32, u8)> = (0..n_faces as u32).map(|f| orient.find(f)).collect();
        let mut votes = vec![0i64; n_faces];
        for &(r, p) in &classes {
            votes[r as usize] += if p == 0 { 1 } else { -1 };
        }
        let face_flip: Vec<bool> = classes
            .iter()
            .enumerate()
            .map(|(f, &(r, p))| {
                let c = vertex_component[faces[f][0] as usize] as usize;
                // Parity 1 is the minority when the vote is positive (ties keep parity 0).
                !component_non_orientable[c] && ((p == 1) == (votes[r as usize] >= 0))
            })
            .collect();

        Self {
            edges,
            edge_ptr,
            vertex_valence,
            n_components,
            non_manifold_vertices,
            n_boundary_edges: boundary.len(),
            n_boundary_loops,
            non_manifold_edges,
            inconsistent_edges,
            non_orientable_edges,
            component_non_orientable,
            face_flip,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::VertexNeighbours;

    #[test]
    fn parity_union_find_detects_odd_cycle() {
        let mut p = ParityUnionFind::new(3);
        assert!(p.constrain(0, 1, 1));
        assert!(p.constrain(1, 2, 1));
        // 0 and 2 have equal parity, so requiring them to differ is a contradiction.
        assert!(!p.constrain(0, 2, 1));
        assert!(p.constrain(0, 2, 0));
    }

    #[test]
    fn two_triangles_share_one_edge() {
        let t = Topology::new(4, &[[0, 1, 2], [2, 1, 3]]);
        assert_eq!(t.edges.len(), 5);
        assert_eq!(t.n_boundary_edges, 4);
        assert_eq!(t.n_boundary_loops, 1);
        assert_eq!(t.n_components, 1);
        assert!(t.inconsistent_edges.is_empty());
        assert!(t.non_manifold_vertices.is_empty());
        let t = Topology::new(4, &[[0, 1, 2], [1, 2, 3]]);
        assert_eq!(t.inconsistent_edges.len(), 1);
        assert_eq!(t.face_flip.iter().filter(|&&x| x).count(), 1);
    }

    #[test]
    fn vertex_neighbours_are_the_sorted_distinct_edge_ends() {
        // Two triangles on the edge 1–2, a degenerate one repeating vertex 4, and an isolated
        // vertex 5: against the edge set listed by hand.
        let g = VertexNeighbours::new(6, &[[0, 1, 2], [2, 1, 3], [4, 4, 3]]);
        assert_eq!(g.n_vertices(), 6);
        let expected: [&[u32]; 6] = [&[1, 2], &[0, 2, 3], &[0, 1, 3], &[1, 2, 4], &[3], &[]];
        for (v, e) in expected.iter().enumerate() {
            assert_eq!(g.of(v as u32), *e, "vertex {v}");
        }
        assert_eq!(g.offsets(), &[0, 2, 5, 8, 11, 12, 12]);
        // On a closed icosphere every edge is seen from both ends: 2E entries, E = 3F/2.
        let mesh = crate::generate::icosphere(2);
        let g = VertexNeighbours::new(mesh.n_vertices(), mesh.faces());
        assert_eq!(g.indices().len(), 3 * mesh.n_faces());
    }
}
