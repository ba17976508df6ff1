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
//!
//! The marching is bound by its reads: accepting v touches each triangle at v once. So each
//! vertex keeps its triangles as *wedges* — the two other corners with the two edge lengths
//! from v and both corners unfolded, 40 bytes, contiguous per vertex — instead of indices into
//! a shared triangle list; a query's state (distances, flags, heap) is kept between queries
//! instead of allocated and zeroed for each. Issue #38: against the shared triangles, 1.5×
//! fewer instructions per query (callgrind, 41K icosphere) and 2–2.5× less time, the rest
//! from the memory reads (docs/BENCHMARKS.md).

use mesh_fem::graph::VertexNeighbours;
use std::sync::Mutex;

/// One triangle (v, a, b) as its corner v reads it when v is accepted: a and b are the corners
/// after v in the triangle's order, with the edge lengths from v and each of them unfolded in
/// the frame of the other two — 40 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Wedge {
    a: u32,
    b: u32,
    l_va: f64,
    l_vb: f64,
    /// a at (x, y), y ≥ 0, in the frame b = (0, 0), v = (ℓ_vb, 0); NaN on a triangle that
    /// repeats a vertex (its edges are its only paths).
    a_xy: [f32; 2],
    /// b in the frame v = (0, 0), a = (ℓ_va, 0); NaN likewise.
    b_xy: [f32; 2],
}

impl Wedge {
    /// The wedge at corner c of the triangle `v` with edge lengths `l` (entry k from corner k
    /// to corner k + 1).
    fn new(v: [u32; 3], l: [f64; 3], c: usize) -> Self {
        let (a, b) = ((c + 1) % 3, (c + 2) % 3);
        let distinct = v[0] != v[1] && v[1] != v[2] && v[2] != v[0];
        let (l_va, l_ab, l_bv) = (l[c], l[a], l[b]);
        let (a_xy, b_xy) = if distinct {
            (unfold(l_ab, l_bv, l_va), unfold(l_bv, l_va, l_ab))
        } else {
            ([f32::NAN; 2], [f32::NAN; 2])
        };
        Self {
            a: v[a],
            b: v[b],
            l_va,
            l_vb: l_bv,
            a_xy,
            b_xy,
        }
    }
}

/// Corner i of a triangle (i, j, k) at (x, y), y ≥ 0, in the frame j = (0, 0), k = (ℓ_jk, 0).
fn unfold(l_ij: f64, l_jk: f64, l_ik: f64) -> [f32; 2] {
    let x = (l_jk * l_jk + l_ij * l_ij - l_ik * l_ik) / (2.0 * l_jk);
    let y = (l_ij * l_ij - x * x).max(0.0).sqrt();
    [x as f32, y as f32]
}

/// The straight path through a triangle to the corner at `xy` (frame of [`unfold`]) from the
/// virtual source at distances `dj`, `dk` of the other two corners, or ∞ when the path misses
/// the edge jk (or the corner is NaN: a triangle that repeats a vertex).
#[inline(always)]
fn straight(dj: f64, dk: f64, l_jk: f64, xy: [f32; 2]) -> f64 {
    let (x, y) = (f64::from(xy[0]), f64::from(xy[1]));
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
            return (dx * dx + height * height).sqrt();
        }
    }
    f64::INFINITY
}

/// A vertex of a query: not reached or tentative, fixed (its value given, accepted in its
/// turn), or accepted (its distance final).
const OPEN: u8 = 0;
const FIXED: u8 = 1;
const ACCEPTED: u8 = 2;

/// The state of one query, in the internal numbering: kept between queries.
struct Front {
    dist: Vec<f64>,
    state: Vec<u8>,
    heap: RadixHeap,
}

impl Front {
    fn new(n: usize) -> Self {
        Self {
            dist: vec![f64::INFINITY; n],
            state: vec![OPEN; n],
            heap: RadixHeap::default(),
        }
    }

    fn reset(&mut self) {
        self.dist.fill(f64::INFINITY);
        self.state.fill(OPEN);
        self.heap.clear();
    }

    fn bytes(&self) -> usize {
        self.dist.len() * 9 + self.heap.bytes()
    }
}

/// The wedges at each vertex, on vertices renumbered in breadth-first order (a vertex's
/// neighbours near it in memory).
pub(crate) struct Eikonal {
    n: usize,
    /// The position of each vertex in the breadth-first numbering.
    order: Vec<u32>,
    /// Vertex v's wedges are `wedges[first[v]..first[v + 1]]` (internal numbering).
    first: Vec<usize>,
    wedges: Vec<Wedge>,
    /// The state of finished queries, reused by the next ones (at most one per thread).
    spare: Mutex<Vec<Front>>,
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
        let first = mesh_fem::graph::corner_offsets(&kept.iter().map(|k| k.0).collect::<Vec<_>>(), n);
        let mut next = first.clone();
        let mut wedges = vec![Wedge::new([0, 1, 2], [1.0; 3], 0); first[n]];
        for &(v, l) in &kept {
            for c in 0..3 {
                let slot = &mut next[v[c] as usize];
                wedges[*slot] = Wedge::new(v, l, c);
                *slot += 1;
            }
        }
        Self {
            n,
            order,
            first,
            wedges,
            spare: Mutex::new(Vec::new()),
        }
    }

    /// Approximate memory in bytes: the wedges and the numbering, and one query's state (more
    /// are kept while queries run in parallel, one per thread).
    pub(crate) fn memory_bytes(&self) -> usize {
        let spare = self
            .spare
            .lock()
            .map_or(0, |s| s.iter().map(Front::bytes).max().unwrap_or(0));
        self.wedges.len() * std::mem::size_of::<Wedge>() + self.n * (8 + 4) + spare.max(self.n * 9)
    }

    /// Fast marching from the fixed values `(vertex, value)`: `out[v]` becomes the distance of
    /// every vertex v (∞ where no fixed vertex reaches it; the fixed values where given). Each
    /// vertex is accepted once, in increasing order; accepting v updates, through each wedge at
    /// v, the corners that are neither accepted nor fixed, from the accepted values only.
    pub(crate) fn march(&self, fixed: &[(usize, f64)], out: &mut [f64]) {
        // Scalar work after whatever the thread ran before (module docs of wfem_base::simd).
        wfem_base::simd::clear_upper_state();
        let spare = self.spare.lock().ok().and_then(|mut s| s.pop());
        let mut front = match spare {
            Some(mut front) => {
                front.reset();
                front
            }
            None => Front::new(self.n),
        };
        self.march_on(&mut front, fixed);
        for (x, &v) in out.iter_mut().zip(&self.order) {
            *x = front.dist[v as usize];
        }
        if let Ok(mut s) = self.spare.lock() {
            if s.len() < rayon::current_num_threads().max(1) {
                s.push(front);
            }
        }
    }

    fn march_on(&self, front: &mut Front, fixed: &[(usize, f64)]) {
        let Front { dist, state, heap } = front;
        for &(i, value) in fixed {
            let v = self.order[i] as usize;
            dist[v] = value;
            state[v] = FIXED;
            heap.push(key(value), v as u32);
        }
        while let Some(v) = heap.pop() {
            let v = v as usize;
            if state[v] == ACCEPTED {
                // A value this vertex had before a smaller one was pushed.
                continue;
            }
            state[v] = ACCEPTED;
            let dv = dist[v];
            for w in &self.wedges[self.first[v]..self.first[v + 1]] {
                let (a, b) = (w.a as usize, w.b as usize);
                let (sa, sb) = (state[a], state[b]);
                // The edge path from v, and the straight path when the third corner is accepted
                // too (never shorter than the edge: |a − S| ≤ |a − v| + |v − S|). The edge path
                // from the third corner was offered when that corner was accepted.
                if sa == OPEN {
                    let mut u = dv + w.l_va;
                    if sb == ACCEPTED {
                        u = u.min(straight(dist[b], dv, w.l_vb, w.a_xy));
                    }
                    if u < dist[a] {
                        if dist[a] == f64::INFINITY {
                            self.prefetch(a);
                        }
                        dist[a] = u;
                        heap.push(key(u), a as u32);
                    }
                }
                if sb == OPEN {
                    let mut u = dv + w.l_vb;
                    if sa == ACCEPTED {
                        u = u.min(straight(dv, dist[a], w.l_va, w.b_xy));
                    }
                    if u < dist[b] {
                        if dist[b] == f64::INFINITY {
                            self.prefetch(b);
                        }
                        dist[b] = u;
                        heap.push(key(u), b as u32);
                    }
                }
            }
        }
    }
}

impl Eikonal {
    /// Brings the wedges of v towards the cache: v, just reached, is accepted some hundreds of
    /// vertices later, when its wedges are read once; without the hint that read waits on
    /// memory (a fifth of a query's time at 41K vertices, more beyond the caches).
    #[inline]
    fn prefetch(&self, v: usize) {
        wfem_base::simd::prefetch(&self.wedges[self.first[v]..self.first[v + 1]]);
    }
}

/// A breadth-first numbering of the vertices over the triangles' edges (each component from its
/// lowest vertex; isolated vertices last in their turn): `order[v]` is v's new index.
fn breadth_first(n: usize, triangles: &[[u32; 3]]) -> Vec<u32> {
    let neighbours = VertexNeighbours::new(n, triangles);
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

/// Bits of a key per level of the [`RadixHeap`].
const RADIX_BITS: u32 = 4;
const DIGITS: usize = 1 << RADIX_BITS;
const LEVELS: usize = 64usize.div_ceil(RADIX_BITS as usize);

/// A monotone radix heap on u64 keys (Ahuja et al. 1990), with a digit of several bits per level
/// (the multi-level buckets of Cherkassky, Goldberg & Silverstein 1999): every key pushed is at
/// least the last one popped — the order of fast marching, which accepts vertices in increasing
/// distance (a key below the last popped one, from rounding, is taken as equal to it).
///
/// A key that differs from the last popped one first in digit `level` waits in the bucket
/// (level, its digit there); when the lowest bucket is taken, its keys share every higher
/// digit with its least one and move to lower levels. With one bit per level a key moved about
/// log₂ of the front's size times (12 per vertex on a 41K sphere); with four, about a quarter
/// of that. Pushes and pops cost O(1) amortised.
struct RadixHeap {
    last: u64,
    len: usize,
    /// The values whose key equals `last`.
    equal: Vec<u32>,
    /// Bucket `level · DIGITS + digit`.
    buckets: Vec<Vec<(u64, u32)>>,
    /// Per level, bit `digit` set when that bucket holds something.
    digits: [u64; LEVELS],
    /// Bit `level` set when any bucket of that level holds something.
    levels: u64,
}

impl Default for RadixHeap {
    fn default() -> Self {
        Self {
            last: 0,
            len: 0,
            equal: Vec::new(),
            buckets: (0..LEVELS * DIGITS).map(|_| Vec::new()).collect(),
            digits: [0; LEVELS],
            levels: 0,
        }
    }
}

impl RadixHeap {
    /// Empty, keeping the buckets' allocations.
    fn clear(&mut self) {
        self.last = 0;
        self.len = 0;
        self.equal.clear();
        for b in &mut self.buckets {
            b.clear();
        }
        self.digits = [0; LEVELS];
        self.levels = 0;
    }

    fn bytes(&self) -> usize {
        self.equal.capacity() * 4 + self.buckets.iter().map(|b| b.capacity() * 16 + 24).sum::<usize>()
    }

    /// Files a key at least `last` (without counting it).
    #[inline]
    fn file(&mut self, key: u64, value: u32) {
        let differ = key ^ self.last;
        if differ == 0 {
            self.equal.push(value);
            return;
        }
        let level = (63 - differ.leading_zeros()) / RADIX_BITS;
        let digit = ((key >> (level * RADIX_BITS)) as usize) & (DIGITS - 1);
        self.buckets[level as usize * DIGITS + digit].push((key, value));
        self.digits[level as usize] |= 1 << digit;
        self.levels |= 1 << level;
    }

    #[inline]
    fn push(&mut self, key: u64, value: u32) {
        // Never below the last popped key.
        self.file(key.max(self.last), value);
        self.len += 1;
    }

    /// The value of a least key.
    fn pop(&mut self) -> Option<u32> {
        if self.len == 0 {
            return None;
        }
        if self.equal.is_empty() {
            let level = self.levels.trailing_zeros() as usize;
            let digit = self.digits[level].trailing_zeros() as usize;
            self.digits[level] &= !(1 << digit);
            if self.digits[level] == 0 {
                self.levels &= !(1 << level);
            }
            let slot = level * DIGITS + digit;
            let mut items = std::mem::take(&mut self.buckets[slot]);
            self.last = items.iter().map(|e| e.0).min().unwrap_or(self.last);
            for &(key, value) in &items {
                self.file(key, value);
            }
            // Keep the emptied bucket's allocation for later (its keys all moved lower).
            items.clear();
            self.buckets[slot] = items;
        }
        self.len -= 1;
        self.equal.pop()
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

#[cfg(test)]
mod tests {
    use super::*;

    fn dist(p: [f64; 2], q: [f64; 2]) -> f64 {
        (p[0] - q[0]).hypot(p[1] - q[1])
    }

    /// Corner i in the frame j = (0, 0), k = (|jk|, 0), computed from the positions.
    fn frame(i: [f64; 2], j: [f64; 2], k: [f64; 2]) -> [f64; 2] {
        let (ex, ey) = ((k[0] - j[0]) / dist(j, k), (k[1] - j[1]) / dist(j, k));
        let (dx, dy) = (i[0] - j[0], i[1] - j[1]);
        [dx * ex + dy * ey, (dx * ey - dy * ex).abs()]
    }

    #[test]
    fn a_wedge_holds_its_corners_lengths_and_unfoldings() {
        let p = [[0.0, 0.0], [3.0, 0.0], [1.0, 2.0]];
        let v = [7u32, 11, 13];
        let l = [dist(p[0], p[1]), dist(p[1], p[2]), dist(p[2], p[0])];
        for c in 0..3 {
            let (a, b) = ((c + 1) % 3, (c + 2) % 3);
            let w = Wedge::new(v, l, c);
            assert_eq!((w.a, w.b), (v[a], v[b]), "corner {c}");
            assert_eq!((w.l_va, w.l_vb), (dist(p[c], p[a]), dist(p[c], p[b])), "corner {c}");
            // a in the frame b = (0, 0), v = (ℓ_vb, 0); b in the frame v = (0, 0), a = (ℓ_va, 0).
            let (a_xy, b_xy) = (frame(p[a], p[b], p[c]), frame(p[b], p[c], p[a]));
            for k in 0..2 {
                assert!(
                    (f64::from(w.a_xy[k]) - a_xy[k]).abs() < 1e-6,
                    "corner {c}: {:?} vs {a_xy:?}",
                    w.a_xy
                );
                assert!(
                    (f64::from(w.b_xy[k]) - b_xy[k]).abs() < 1e-6,
                    "corner {c}: {:?} vs {b_xy:?}",
                    w.b_xy
                );
            }
        }
        // A triangle that repeats a vertex has no straight path: NaN corners, ∞ from `straight`.
        let w = Wedge::new([4, 4, 5], [1.0, 1.0, 1.0], 0);
        assert!(w.a_xy.iter().chain(&w.b_xy).all(|x| x.is_nan()));
        assert_eq!(straight(1.0, 1.0, w.l_vb, w.a_xy), f64::INFINITY);
    }

    #[test]
    fn the_straight_update_is_exact_for_a_planar_source() {
        // j = (0, 0), k = (2, 0), i above the edge; sources below it.
        let (j, k, i) = ([0.0, 0.0], [2.0, 0.0], [0.8, 1.5]);
        let xy = unfold(dist(i, j), 2.0, dist(i, k));
        let xy32 = [f64::from(xy[0]), f64::from(xy[1])];
        for s in [[1.0, -3.0], [0.3, -0.5], [1.9, -1.0]] {
            let got = straight(dist(s, j), dist(s, k), 2.0, xy);
            assert!(
                (got - dist(s, xy32)).abs() < 1e-12,
                "source {s:?}: {got} vs {}",
                dist(s, xy32)
            );
        }
        // The segment from a source far to the side misses the edge jk: no straight path.
        assert_eq!(
            straight(dist([9.0, -0.2], j), dist([9.0, -0.2], k), 2.0, xy),
            f64::INFINITY
        );
    }

    #[test]
    fn each_vertex_gets_one_wedge_per_triangle_and_degenerate_ones_are_dropped() {
        // A fan of 6 triangles around vertex 0 on the plane, and one triangle of zero length.
        let mut p = vec![[0.0, 0.0]];
        for k in 0..6 {
            let a = std::f64::consts::PI / 3.0 * f64::from(k);
            p.push([a.cos(), a.sin()]);
        }
        p.push([5.0, 5.0]);
        let mut triangles: Vec<[u32; 3]> = (0..6).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect();
        triangles.push([7, 7, 1]);
        let lengths = |t: usize| {
            let v = triangles[t];
            [0, 1, 2].map(|c| dist(p[v[c] as usize], p[v[(c + 1) % 3] as usize]))
        };
        let e = Eikonal::new(8, &triangles, lengths);
        assert_eq!(e.wedges.len(), 18);
        let count = |v: usize| {
            let i = e.order[v] as usize;
            e.first[i + 1] - e.first[i]
        };
        assert_eq!(count(0), 6);
        assert!((1..7).all(|v| count(v) == 2));
        assert_eq!(count(7), 0);
        for w in &e.wedges[e.first[e.order[0] as usize]..e.first[e.order[0] as usize + 1]] {
            assert!((w.l_va - 1.0).abs() < 1e-15 && (w.l_vb - 1.0).abs() < 1e-15);
        }
        // From the centre: the ring at 1 (to the f32 rounding of the unfolded corners, through
        // which a straight path can come out a few 1e-8 shorter than the edge); vertex 7 is
        // unreachable.
        let mut out = vec![0.0; 8];
        e.march(&[(0, 0.0)], &mut out);
        assert_eq!(out[0], 0.0);
        assert!(out[1..7].iter().all(|d| (d - 1.0).abs() < 1e-7), "{out:?}");
        assert_eq!(out[7], f64::INFINITY);
        // From two opposite ring vertices with their values fixed: the centre through the edge
        // (1), the others through the straight paths of the unfolded triangles, exact on a plane.
        e.march(&[(1, 0.0), (2, 1.0)], &mut out);
        for v in 1..7 {
            let exact = dist(p[v], p[1]);
            assert!((out[v] - exact).abs() < 1e-6, "{v}: {} vs {exact}", out[v]);
        }
        assert_eq!(out[2], 1.0);
    }

    #[test]
    fn the_radix_heap_pops_in_order_of_key() {
        let mut heap = RadixHeap::default();
        let mut reference = std::collections::BinaryHeap::new();
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut random = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for round in 0..2 {
            // The key of each value pushed, and the last key popped.
            let mut keys = Vec::new();
            let mut last = 0.0f64;
            let pop = |heap: &mut RadixHeap, keys: &[u64], k: u64| {
                let value = heap.pop().expect("as many values as the reference");
                // A least key (ties in any order).
                assert_eq!(keys[value as usize], k, "round {round}");
                f64::from_bits(k)
            };
            for _ in 0..20_000 {
                if random() % 3 != 0 || reference.is_empty() {
                    // Keys at least the last popped one, often equal to it or to each other, as
                    // distances are; now and then far beyond.
                    let x = match random() % 4 {
                        0 => last,
                        1 => last + (random() % 8) as f64 * 0.125,
                        2 => last + (random() % 1000) as f64 * 1e-3,
                        _ => last * 2.0 + 1.0,
                    };
                    heap.push(key(x), keys.len() as u32);
                    keys.push(key(x));
                    reference.push(std::cmp::Reverse(key(x)));
                } else {
                    let std::cmp::Reverse(k) = reference.pop().unwrap();
                    last = pop(&mut heap, &keys, k);
                }
            }
            while let Some(std::cmp::Reverse(k)) = reference.pop() {
                pop(&mut heap, &keys, k);
            }
            assert_eq!(heap.pop(), None);
            heap.clear();
        }
    }
}
