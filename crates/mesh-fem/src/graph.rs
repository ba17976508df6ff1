//! Graphs of a triangle mesh: corners and faces by vertex ([`corner_offsets`], [`VertexFaces`]),
//! the vertex adjacency ([`VertexNeighbours`]), the edge graph with
//! Euclidean lengths and its shortest paths ([`EdgeGraph`], Dijkstra), and disjoint sets
//! ([`UnionFind`]). The one copy of each in the workspace: validation, Morse analysis, the
//! repairs of `mesh-repair`, the benchmark's transformations and splat rendering use them.

use crate::vec3::{norm, sub};
use crate::{MeshError, TriMesh};
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The first slot of each vertex when the 3F corners are sorted by vertex (counting sort):
/// vertex v owns `offsets[v]..offsets[v + 1]`, one slot per corner at v (a face that repeats v
/// counts twice); `offsets[n]` is the number of corners. Shared by every per-vertex CSR of the
/// workspace (assembly, spike removal, Morse analysis, hole filling).
pub fn corner_offsets<const N: usize>(faces: &[[u32; N]], n: usize) -> Vec<usize> {
    let mut offsets = vec![0usize; n + 1];
    for face in faces {
        for &v in face {
            offsets[v as usize + 1] += 1;
        }
    }
    for i in 0..n {
        offsets[i + 1] += offsets[i];
    }
    offsets
}

/// The faces at each vertex in compressed rows ([`corner_offsets`]; a face that repeats a
/// vertex is listed twice there).
#[derive(Clone, Debug, PartialEq)]
pub struct VertexFaces {
    offsets: Vec<usize>,
    faces: Vec<u32>,
}

impl VertexFaces {
    /// The faces at each vertex of `triangles` (indices below `n`).
    pub fn new(triangles: &[[u32; 3]], n: usize) -> Self {
        let offsets = corner_offsets(triangles, n);
        let mut next = offsets.clone();
        let mut faces = vec![0u32; offsets[n]];
        for (fi, face) in triangles.iter().enumerate() {
            for &v in face {
                faces[next[v as usize]] = fi as u32;
                next[v as usize] += 1;
            }
        }
        Self { offsets, faces }
    }

    /// The faces at vertex `v`. Panics if `v` is out of range.
    #[inline]
    pub fn of(&self, v: u32) -> &[u32] {
        &self.faces[self.offsets[v as usize]..self.offsets[v as usize + 1]]
    }
}

/// The edge graph of triangles on n vertices in compressed rows: the sorted distinct other
/// corners of the triangles at each vertex (no self loops; an isolated vertex has none).
/// Gathered from the triangles around each vertex ([`corner_offsets`]) in parallel:
/// O(F + Σ_v deg(v) log deg(v)). The one adjacency of the workspace (Morse analysis, the
/// benchmark's edge graph, splat rendering).
#[derive(Clone, Debug, PartialEq)]
pub struct VertexNeighbours {
    offsets: Vec<usize>,
    indices: Vec<u32>,
}

impl VertexNeighbours {
    /// The edge graph of `triangles`, whose indices must be below `n` (as in a [`crate::TriMesh`]).
    pub fn new(n: usize, triangles: &[[u32; 3]]) -> Self {
        let incidence = VertexFaces::new(triangles, n);
        let lists: Vec<Vec<u32>> = (0..n)
            .into_par_iter()
            .map(|v| {
                let around = incidence.of(v as u32);
                let mut list = Vec::with_capacity(2 * around.len());
                for &fi in around {
                    list.extend(triangles[fi as usize].iter().copied().filter(|&w| w as usize != v));
                }
                list.sort_unstable();
                list.dedup();
                list
            })
            .collect();
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0);
        for list in &lists {
            offsets.push(offsets[offsets.len() - 1] + list.len());
        }
        Self {
            offsets,
            indices: lists.concat(),
        }
    }

    /// Number of vertices n.
    pub fn n_vertices(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The neighbours of vertex `v`, sorted by index. Panics if `v` is out of range.
    #[inline]
    pub fn of(&self, v: u32) -> &[u32] {
        &self.indices[self.offsets[v as usize]..self.offsets[v as usize + 1]]
    }

    /// Row offsets: vertex v's neighbours are `indices()[offsets()[v]..offsets()[v + 1]]`.
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// All neighbour lists, one after the other.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }
}

/// Disjoint sets with union by size and path halving.
#[derive(Clone, Debug, Default)]
pub struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    /// n singletons {0}, …, {n − 1}.
    pub fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    /// The representative of `x`'s set (path halving).
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = self.parent[x as usize];
        }
        x
    }

    /// Joins the sets of `a` and `b`; returns `true` if they were different.
    pub fn union(&mut self, a: u32, b: u32) -> bool {
        let (mut ra, mut rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        if self.size[ra as usize] < self.size[rb as usize] {
            std::mem::swap(&mut ra, &mut rb);
        }
        self.parent[rb as usize] = ra;
        self.size[ra as usize] += self.size[rb as usize];
        true
    }

    /// Joins the sets of `a` and `b` so that the smaller root stays the representative (every
    /// set is then named by its smallest element: a deterministic choice, e.g. the vertex a class
    /// of welded vertices becomes); returns `true` if they were different.
    pub fn union_min(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        self.parent[hi as usize] = lo;
        self.size[lo as usize] += self.size[hi as usize];
        true
    }

    /// Back to n singletons, reusing the allocation (for many small problems in a loop).
    pub fn reset(&mut self, n: usize) {
        self.parent.clear();
        self.parent.extend(0..n as u32);
        self.size.clear();
        self.size.resize(n, 1);
    }
}

/// The undirected edge graph of a triangle mesh with Euclidean edge lengths ‖x_i − x_j‖, in
/// compressed adjacency form (each vertex's neighbours sorted by index, as [`VertexNeighbours`]).
#[derive(Clone, Debug)]
pub struct EdgeGraph {
    offsets: Vec<usize>,
    neighbors: Vec<u32>,
    lengths: Vec<f64>,
}

/// No parent: a source, or a vertex not reached ([`EdgeGraph::shortest_paths`]).
pub const NO_PARENT: u32 = u32::MAX;

impl EdgeGraph {
    /// Builds the edge graph of `mesh` in O(F log F) time. Isolated vertices have no
    /// neighbours.
    pub fn new(mesh: &TriMesh) -> Self {
        let graph = VertexNeighbours::new(mesh.n_vertices(), mesh.faces());
        let p = mesh.positions();
        let lengths = (0..mesh.n_vertices() as u32)
            .flat_map(|i| graph.of(i).iter().map(move |&j| (i, j)))
            .map(|(i, j)| norm(sub(p[i as usize], p[j as usize])))
            .collect();
        Self {
            offsets: graph.offsets,
            neighbors: graph.indices,
            lengths,
        }
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of undirected edges.
    pub fn n_edges(&self) -> usize {
        self.neighbors.len() / 2
    }

    /// The neighbours of vertex `v`, sorted by index. Panics if `v` is out of range.
    pub fn neighbors(&self, v: u32) -> &[u32] {
        &self.neighbors[self.offsets[v as usize]..self.offsets[v as usize + 1]]
    }

    /// The lengths of the edges to [`EdgeGraph::neighbors`]`(v)`, in the same order.
    pub fn lengths(&self, v: u32) -> &[f64] {
        &self.lengths[self.offsets[v as usize]..self.offsets[v as usize + 1]]
    }

    /// Mean length of the undirected edges (0 for a graph without edges).
    pub fn mean_edge_length(&self) -> f64 {
        if self.lengths.is_empty() {
            0.0
        } else {
            self.lengths.iter().sum::<f64>() / self.lengths.len() as f64
        }
    }

    fn check(&self, sources: &[u32]) -> Result<(), MeshError> {
        let n = self.n_vertices();
        match sources.iter().find(|&&s| s as usize >= n) {
            Some(&index) => Err(MeshError::VertexOutOfRange {
                what: "source",
                index: u64::from(index),
                n_vertices: n,
            }),
            None => Ok(()),
        }
    }

    /// Multi-source Dijkstra: d(v) = min over sources s of the shortest edge path length
    /// from s to v. Vertices farther than `cutoff` (or unreachable) get `f64::INFINITY`;
    /// pass `f64::INFINITY` for no cutoff. Runs in O((V + E) log V) over the visited part.
    ///
    /// # Errors
    /// [`MeshError::VertexOutOfRange`] if a source is out of range.
    pub fn distances(&self, sources: &[u32], cutoff: f64) -> Result<Vec<f64>, MeshError> {
        self.check(sources)?;
        Ok(self.dijkstra(sources, cutoff).0)
    }

    /// Multi-source Dijkstra with the shortest-path tree: the distances and, per vertex, the
    /// previous vertex on its shortest path ([`NO_PARENT`] for a source or an unreached vertex).
    /// Ties are broken by vertex index, so the tree is deterministic.
    ///
    /// # Errors
    /// [`MeshError::VertexOutOfRange`] if a source is out of range.
    pub fn shortest_paths(&self, sources: &[u32]) -> Result<(Vec<f64>, Vec<u32>), MeshError> {
        self.check(sources)?;
        Ok(self.dijkstra(sources, f64::INFINITY))
    }

    fn dijkstra(&self, sources: &[u32], cutoff: f64) -> (Vec<f64>, Vec<u32>) {
        let n = self.n_vertices();
        let mut dist = vec![f64::INFINITY; n];
        let mut parent = vec![NO_PARENT; n];
        let mut heap = BinaryHeap::new();
        for &s in sources {
            dist[s as usize] = 0.0;
            heap.push(Reverse((0.0f64.to_bits(), s)));
        }
        // Non-negative floats order like their bit patterns.
        while let Some(Reverse((bits, v))) = heap.pop() {
            let d = f64::from_bits(bits);
            if d > dist[v as usize] {
                continue;
            }
            let range = self.offsets[v as usize]..self.offsets[v as usize + 1];
            for (&w, &l) in self.neighbors[range.clone()].iter().zip(&self.lengths[range]) {
                let nd = d + l;
                if nd < dist[w as usize] && nd <= cutoff {
                    dist[w as usize] = nd;
                    parent[w as usize] = v;
                    heap.push(Reverse((nd.to_bits(), w)));
                }
            }
        }
        (dist, parent)
    }

    /// Breadth-first hop counts from the sources, up to `max_hops`; vertices farther away get
    /// `u32::MAX`.
    ///
    /// # Errors
    /// [`MeshError::VertexOutOfRange`] if a source is out of range.
    pub fn hops(&self, sources: &[u32], max_hops: u32) -> Result<Vec<u32>, MeshError> {
        self.check(sources)?;
        let n = self.n_vertices();
        let mut hop = vec![u32::MAX; n];
        let mut frontier = Vec::new();
        for &s in sources {
            if hop[s as usize] != 0 {
                hop[s as usize] = 0;
                frontier.push(s);
            }
        }
        let mut level = 0;
        while !frontier.is_empty() && level < max_hops {
            level += 1;
            let mut next = Vec::new();
            for &v in &frontier {
                for &w in self.neighbors(v) {
                    if hop[w as usize] == u32::MAX {
                        hop[w as usize] = level;
                        next.push(w);
                    }
                }
            }
            frontier = next;
        }
        Ok(hop)
    }
}
