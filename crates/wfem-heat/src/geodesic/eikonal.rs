//! Fast marching on a triangulation (Kimmel & Sethian 1998; beyond the paper): the discrete
//! eikonal equation |∇d| = 1 solved by accepting vertices in increasing order of distance, each
//! with the update of an unfolded triangle from its accepted neighbours.
//!
//! For a vertex i of a triangle (i, j, k) laid out with j = (0, 0), k = (ℓ_jk, 0) and i above
//! the axis at (x_i, y_i), the distances d_j, d_k place a virtual source S below the axis at
//! `(s_x, −√(d_j² − s_x²))`, `s_x = (d_j² − d_k² + ℓ_jk²) / 2ℓ_jk`; when the segment S → i
//! crosses the edge jk, `|i − S|` is the length of a straight path through the triangle;
//! otherwise — and always on a triangle that repeats a vertex — the candidates are the paths
//! along the edges, `d_j + ℓ_ij` and `d_k + ℓ_ik`. The update is the least candidate over the
//! triangles at i. The fixed values (0 at the sources, the exact edge lengths on their
//! one-rings, the exact in-face distances on the corners of a source point) never change.
//!
//! On an intrinsic Delaunay triangulation obtuse angles are rare, which is what the update
//! needs; its mean relative error against exact polyhedral geodesics is 0.1–0.3 times the heat
//! method's on the shared corpus (docs/BENCHMARKS.md), at O(n log n) per query with no
//! factorization.

use mesh_fem::graph::VertexFaces;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// One corner i of a triangle (i, j, k), unfolded.
#[derive(Clone, Copy, Debug)]
struct Corner {
    /// ℓ_ij, ℓ_ik, ℓ_jk.
    l_ij: f64,
    l_ik: f64,
    l_jk: f64,
    /// i in the frame j = (0, 0), k = (ℓ_jk, 0), above the axis.
    x: f64,
    y: f64,
}

/// The usable triangles with their three unfolded corners, and the triangles at each vertex,
/// on vertices renumbered in breadth-first order (neighbours near each other in memory: the
/// marching is bound by the latency of its random reads).
#[derive(Clone, Debug)]
pub(crate) struct Eikonal {
    n: usize,
    /// The position of each vertex in the breadth-first numbering.
    order: Vec<u32>,
    triangles: Vec<[u32; 3]>,
    /// Corner c of triangle t is `corners[3t + c]` (j, k the next two corners).
    corners: Vec<Corner>,
    /// The three corners are distinct vertices: the straight path through the triangle applies.
    unfold: Vec<bool>,
    incidence: VertexFaces,
}

impl Corner {
    fn new(l_ij: f64, l_jk: f64, l_ik: f64) -> Self {
        let x = (l_jk * l_jk + l_ij * l_ij - l_ik * l_ik) / (2.0 * l_jk);
        let y = (l_ij * l_ij - x * x).max(0.0).sqrt();
        Self { l_ij, l_ik, l_jk, x, y }
    }

    /// The candidate distance of i from d_j and d_k (∞ when both are).
    #[inline]
    fn update(&self, dj: f64, dk: f64, unfold: bool) -> f64 {
        let mut best = (dj + self.l_ij).min(dk + self.l_ik);
        if unfold && dj.is_finite() && dk.is_finite() {
            let sx = (dj * dj - dk * dk + self.l_jk * self.l_jk) / (2.0 * self.l_jk);
            let sy2 = dj * dj - sx * sx;
            if sy2 >= 0.0 {
                let sy = sy2.sqrt();
                let height = self.y + sy;
                if height > 0.0 {
                    // Where the segment from S = (sx, −sy) to i = (x, y) crosses the axis.
                    let cross = sx + (self.x - sx) * sy / height;
                    if (0.0..=self.l_jk).contains(&cross) {
                        let dx = self.x - sx;
                        best = best.min((dx * dx + height * height).sqrt());
                    }
                }
            }
        }
        best
    }
}

impl Eikonal {
    /// The marching on `triangles` (vertex indices below `n`) with edge lengths `lengths(t)`
    /// (entry k from corner k to corner k + 1). A triangle with a non-positive or non-finite
    /// length takes no part; one that repeats a vertex gives its edges only.
    pub(crate) fn new(n: usize, triangles: &[[u32; 3]], lengths: impl Fn(usize) -> [f64; 3]) -> Self {
        let mut kept = Vec::with_capacity(triangles.len());
        let mut corners = Vec::with_capacity(3 * triangles.len());
        let mut unfold = Vec::with_capacity(triangles.len());
        for (t, &tri) in triangles.iter().enumerate() {
            let l = lengths(t);
            if !l.iter().all(|x| *x > 0.0 && x.is_finite()) {
                continue;
            }
            kept.push(tri);
            unfold.push(tri[0] != tri[1] && tri[1] != tri[2] && tri[2] != tri[0]);
            // Corner c: ℓ_ij = l[c], ℓ_jk = l[c + 1], ℓ_ik = l[c + 2].
            for c in 0..3 {
                corners.push(Corner::new(l[c], l[(c + 1) % 3], l[(c + 2) % 3]));
            }
        }
        let order = breadth_first(n, &kept);
        for tri in &mut kept {
            *tri = tri.map(|v| order[v as usize]);
        }
        // Triangles in the order of their first vertex too, so that the triangles and corners
        // read around a vertex lie together in memory.
        let mut by_vertex: Vec<usize> = (0..kept.len()).collect();
        by_vertex.sort_by_key(|&t| *kept[t].iter().min().unwrap_or(&0));
        let kept: Vec<[u32; 3]> = by_vertex.iter().map(|&t| kept[t]).collect();
        let unfold: Vec<bool> = by_vertex.iter().map(|&t| unfold[t]).collect();
        let corners: Vec<Corner> = by_vertex
            .iter()
            .flat_map(|&t| corners[3 * t..3 * t + 3].iter().copied())
            .collect();
        let incidence = VertexFaces::new(&kept, n);
        Self {
            n,
            order,
            triangles: kept,
            corners,
            unfold,
            incidence,
        }
    }

    /// Approximate memory in bytes.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.corners.len() * std::mem::size_of::<Corner>()
            + self.triangles.len() * 13
            + (2 * self.n + 3 * self.triangles.len()) * 8
    }

    /// Fast marching from the fixed values: `d` holds them where `fixed`; every other vertex gets
    /// its distance (∞ where no fixed vertex reaches it). Each vertex is accepted once, in
    /// increasing order; accepting v updates, through each triangle at v, the triangle's other
    /// corners that are not accepted, from the accepted values only.
    pub(crate) fn march(&self, d: &mut [f64], fixed: &[bool]) {
        let n = self.n;
        let mut heap: BinaryHeap<Reverse<(u64, u32)>> = BinaryHeap::new();
        // In the internal numbering: `best` the tentative values, `view` the accepted ones (∞
        // until accepted; the updates read only those), `frozen` the fixed vertices.
        let mut best = vec![f64::INFINITY; n];
        let mut view = vec![f64::INFINITY; n];
        let mut frozen = vec![false; n];
        for i in 0..n {
            if fixed[i] {
                let v = self.order[i] as usize;
                best[v] = d[i];
                frozen[v] = true;
                heap.push(Reverse((key(d[i]), v as u32)));
            }
        }
        while let Some(Reverse((k, v))) = heap.pop() {
            let v = v as usize;
            if view[v].is_finite() || k != key(best[v]) {
                continue;
            }
            view[v] = best[v];
            for &t in self.incidence.of(v as u32) {
                let t = t as usize;
                let tri = self.triangles[t];
                for c in 0..3 {
                    let w = tri[c] as usize;
                    if view[w].is_finite() || frozen[w] {
                        continue;
                    }
                    let (j, k) = (tri[(c + 1) % 3] as usize, tri[(c + 2) % 3] as usize);
                    let u = self.corners[3 * t + c].update(view[j], view[k], self.unfold[t]);
                    if u < best[w] {
                        best[w] = u;
                        heap.push(Reverse((key(u), w as u32)));
                    }
                }
            }
        }
        for (i, x) in d.iter_mut().enumerate() {
            *x = best[self.order[i] as usize];
        }
    }
}

/// A breadth-first numbering of the vertices over the triangles' edges (each component from its
/// lowest vertex; isolated vertices last in their turn): `order[v]` is v's new index.
fn breadth_first(n: usize, triangles: &[[u32; 3]]) -> Vec<u32> {
    let neighbours = mesh_fem::graph::VertexNeighbours::new(n, triangles);
    let mut order = vec![u32::MAX; n];
    let mut next = 0u32;
    let mut queue = std::collections::VecDeque::new();
    for start in 0..n {
        if order[start] != u32::MAX {
            continue;
        }
        order[start] = next;
        next += 1;
        queue.push_back(start as u32);
        while let Some(v) = queue.pop_front() {
            for &w in neighbours.of(v) {
                if order[w as usize] == u32::MAX {
                    order[w as usize] = next;
                    next += 1;
                    queue.push_back(w);
                }
            }
        }
    }
    order
}

/// A heap key that orders non-negative floats (and ∞) like their values.
#[inline]
fn key(x: f64) -> u64 {
    if x.is_nan() {
        u64::MAX
    } else {
        x.max(0.0).to_bits()
    }
}
