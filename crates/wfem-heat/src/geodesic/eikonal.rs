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

/// One triangle as the marching reads it: its corners, its edge lengths (entry k from corner k
/// to corner k + 1) and each corner unfolded in the frame of the opposite edge — one 64-byte
/// record, so that a vertex's triangles cost one cache line each.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    v: [u32; 3],
    /// The three corners are distinct vertices: the straight path through the triangle applies.
    unfold: bool,
    l: [f64; 3],
    /// Corner c at (x, y), y ≥ 0, in the frame corner c + 1 = (0, 0), corner c + 2 = (ℓ, 0).
    xy: [[f32; 2]; 3],
}

impl Triangle {
    fn new(v: [u32; 3], l: [f64; 3]) -> Self {
        let mut xy = [[0.0f32; 2]; 3];
        for (c, p) in xy.iter_mut().enumerate() {
            // ℓ_ij = l[c], ℓ_jk = l[c + 1], ℓ_ik = l[c + 2].
            let (l_ij, l_jk, l_ik) = (l[c], l[(c + 1) % 3], l[(c + 2) % 3]);
            let x = (l_jk * l_jk + l_ij * l_ij - l_ik * l_ik) / (2.0 * l_jk);
            let y = (l_ij * l_ij - x * x).max(0.0).sqrt();
            *p = [x as f32, y as f32];
        }
        Self {
            v,
            unfold: v[0] != v[1] && v[1] != v[2] && v[2] != v[0],
            l,
            xy,
        }
    }

    /// The candidate distance of corner c from the distances of the other two (∞ when both are).
    #[inline]
    fn update(&self, c: usize, dj: f64, dk: f64) -> f64 {
        let (l_ij, l_jk, l_ik) = (self.l[c], self.l[(c + 1) % 3], self.l[(c + 2) % 3]);
        let mut best = (dj + l_ij).min(dk + l_ik);
        if self.unfold && dj.is_finite() && dk.is_finite() {
            let (x, y) = (f64::from(self.xy[c][0]), f64::from(self.xy[c][1]));
            let sx = (dj * dj - dk * dk + l_jk * l_jk) * (0.5 / l_jk);
            let sy2 = dj * dj - sx * sx;
            if sy2 >= 0.0 {
                let sy = sy2.sqrt();
                let height = y + sy;
                // The segment from S = (sx, −sy) to i = (x, y) crosses the axis at
                // sx + (x − sx)·sy/height; inside the edge [0, ℓ_jk] (without the division).
                let cross = sx * height + (x - sx) * sy;
                if height > 0.0 && cross >= 0.0 && cross <= l_jk * height {
                    let dx = x - sx;
                    best = best.min((dx * dx + height * height).sqrt());
                }
            }
        }
        best
    }
}

/// The usable triangles and the triangles at each vertex, on vertices renumbered in
/// breadth-first order and triangles sorted by their first vertex (the marching is bound by the
/// latency of its reads: neighbours near each other in memory).
#[derive(Clone, Debug)]
pub(crate) struct Eikonal {
    n: usize,
    /// The position of each vertex in the breadth-first numbering.
    order: Vec<u32>,
    triangles: Vec<Triangle>,
    incidence: VertexFaces,
}

impl Eikonal {
    /// The marching on `triangles` (vertex indices below `n`) with edge lengths `lengths(t)`
    /// (entry k from corner k to corner k + 1). A triangle with a non-positive or non-finite
    /// length takes no part; one that repeats a vertex gives its edges only.
    pub(crate) fn new(n: usize, triangles: &[[u32; 3]], lengths: impl Fn(usize) -> [f64; 3]) -> Self {
        let mut kept: Vec<([u32; 3], [f64; 3])> = (0..triangles.len())
            .map(|t| (triangles[t], lengths(t)))
            .filter(|(_, l)| l.iter().all(|x| *x > 0.0 && x.is_finite()))
            .collect();
        let plain: Vec<[u32; 3]> = kept.iter().map(|k| k.0).collect();
        let order = breadth_first(n, &plain);
        for k in &mut kept {
            k.0 = k.0.map(|v| order[v as usize]);
        }
        kept.sort_by_key(|k| *k.0.iter().min().unwrap_or(&0));
        let triangles: Vec<Triangle> = kept.into_iter().map(|(v, l)| Triangle::new(v, l)).collect();
        let plain: Vec<[u32; 3]> = triangles.iter().map(|t| t.v).collect();
        let incidence = VertexFaces::new(&plain, n);
        Self {
            n,
            order,
            triangles,
            incidence,
        }
    }

    /// Approximate memory in bytes.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.triangles.len() * (std::mem::size_of::<Triangle>() + 12) + 2 * self.n * 8
    }

    /// Fast marching from the fixed values: `d` holds them where `fixed`; every other vertex gets
    /// its distance (∞ where no fixed vertex reaches it). Each vertex is accepted once, in
    /// increasing order; accepting v updates, through each triangle at v, the triangle's other
    /// corners that are not accepted, from the accepted values only.
    pub(crate) fn march(&self, d: &mut [f64], fixed: &[bool]) {
        let n = self.n;
        let mut heap = RadixHeap::default();
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
                heap.push(key(d[i]), v as u32);
            }
        }
        while let Some((k, v)) = heap.pop() {
            let v = v as usize;
            if view[v].is_finite() || k != heap.clamped(key(best[v])) {
                continue;
            }
            view[v] = best[v];
            for &t in self.incidence.of(v as u32) {
                let tri = &self.triangles[t as usize];
                for c in 0..3 {
                    let w = tri.v[c] as usize;
                    if view[w].is_finite() || frozen[w] {
                        continue;
                    }
                    let (dj, dk) = (view[tri.v[(c + 1) % 3] as usize], view[tri.v[(c + 2) % 3] as usize]);
                    let u = tri.update(c, dj, dk);
                    if u < best[w] {
                        best[w] = u;
                        heap.push(key(u), w as u32);
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

/// A monotone radix heap on u64 keys (Ahuja et al. 1990): every key pushed is at least the last
/// one popped — the order of fast marching, which accepts vertices in increasing distance (a
/// key below the last popped one, from rounding, is taken as equal to it). Pushes and pops cost
/// O(1) amortised, about three times less than a binary heap here.
struct RadixHeap {
    last: u64,
    len: usize,
    buckets: [Vec<(u64, u32)>; 65],
}

impl Default for RadixHeap {
    fn default() -> Self {
        Self {
            last: 0,
            len: 0,
            buckets: std::array::from_fn(|_| Vec::new()),
        }
    }
}

impl RadixHeap {
    #[inline]
    fn bucket(&self, key: u64) -> usize {
        (64 - (key ^ self.last).leading_zeros()) as usize
    }

    /// The key as stored: never below the last popped one.
    #[inline]
    fn clamped(&self, key: u64) -> u64 {
        key.max(self.last)
    }

    #[inline]
    fn push(&mut self, key: u64, value: u32) {
        let key = self.clamped(key);
        let b = self.bucket(key);
        self.buckets[b].push((key, value));
        self.len += 1;
    }

    fn pop(&mut self) -> Option<(u64, u32)> {
        if self.len == 0 {
            return None;
        }
        if self.buckets[0].is_empty() {
            let i = (1..65).find(|&i| !self.buckets[i].is_empty())?;
            let items = std::mem::take(&mut self.buckets[i]);
            self.last = items.iter().map(|e| e.0).min().unwrap_or(self.last);
            for e in &items {
                let b = self.bucket(e.0);
                self.buckets[b].push(*e);
            }
            // Keep the emptied bucket's allocation for later.
            let mut items = items;
            items.clear();
            if self.buckets[i].is_empty() {
                self.buckets[i] = items;
            }
        }
        self.len -= 1;
        self.buckets[0].pop()
    }
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
