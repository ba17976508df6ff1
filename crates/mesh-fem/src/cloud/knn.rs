//! k nearest neighbours of every point with a static kd-tree (median splits on the widest
//! axis, leaves of at most [`LEAF`] points), built and queried in parallel.
//!
//! The tree is implicit: `order` is a permutation of the points in which every node covers a
//! contiguous range `lo..hi`, split at its middle `mid` (left child `lo..mid`, right child
//! `mid..hi`) on the axis stored at `axis[mid]` at the value `value[mid]`. Distinct inner
//! nodes have distinct middles (a node's children split strictly inside their own ranges),
//! so the splits fit in two arrays of n entries, and the two halves of a range own disjoint
//! slices of them (the right half's first slot is its parent's).

/// Points per leaf.
const LEAF: usize = 8;

/// Ranges above this size build their two halves in parallel.
const PARALLEL_BUILD: usize = 16384;

/// A kd-tree over a fixed set of points (module documentation).
pub(crate) struct KdTree<'a> {
    points: &'a [[f64; 3]],
    order: Vec<u32>,
    axis: Vec<u8>,
    value: Vec<f64>,
}

impl<'a> KdTree<'a> {
    /// Builds the tree (O(n log n), parallel).
    pub(crate) fn new(points: &'a [[f64; 3]]) -> Self {
        let n = points.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut axis = vec![0u8; n];
        let mut value = vec![0.0f64; n];
        build(points, &mut order, &mut axis, &mut value);
        Self {
            points,
            order,
            axis,
            value,
        }
    }

    /// The `k` nearest points of point `i` other than `i` itself, nearest first (ties by
    /// index), written to `out` as (squared distance, index).
    pub(crate) fn nearest_of(&self, i: usize, k: usize, out: &mut Vec<(f64, u32)>) {
        out.clear();
        if k == 0 {
            return;
        }
        let q = self.points[i];
        self.search(0, self.order.len(), q, i as u32, k, out);
    }

    fn search(&self, lo: usize, hi: usize, q: [f64; 3], skip: u32, k: usize, best: &mut Vec<(f64, u32)>) {
        if hi - lo <= LEAF {
            for &j in &self.order[lo..hi] {
                if j == skip {
                    continue;
                }
                let p = self.points[j as usize];
                let d = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
                let candidate = (d, j);
                if best.len() < k || less(candidate, best[best.len() - 1]) {
                    let at = best.partition_point(|&b| less(b, candidate));
                    if best.len() == k {
                        best.pop();
                    }
                    best.insert(at, candidate);
                }
            }
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let axis = self.axis[mid] as usize;
        let diff = q[axis] - self.value[mid];
        let (near, far) = if diff <= 0.0 {
            ((lo, mid), (mid, hi))
        } else {
            ((mid, hi), (lo, mid))
        };
        self.search(near.0, near.1, q, skip, k, best);
        if best.len() < k || diff * diff <= best[best.len() - 1].0 {
            self.search(far.0, far.1, q, skip, k, best);
        }
    }
}

/// Order of candidates: by squared distance, then by index.
#[inline]
fn less(a: (f64, u32), b: (f64, u32)) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
}

/// Splits `order` (and the matching slice of `axis`) recursively.
fn build(points: &[[f64; 3]], order: &mut [u32], axis: &mut [u8], value: &mut [f64]) {
    let n = order.len();
    if n <= LEAF {
        return;
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &j in order.iter() {
        let p = points[j as usize];
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let a = (0..3)
        .max_by(|&x, &y| (hi[x] - lo[x]).total_cmp(&(hi[y] - lo[y])))
        .unwrap_or(0);
    let mid = n / 2;
    // Left of mid: coordinates ≤ the split value; right (from mid on): ≥.
    order.select_nth_unstable_by(mid, |&x, &y| points[x as usize][a].total_cmp(&points[y as usize][a]));
    axis[mid] = a as u8;
    value[mid] = points[order[mid] as usize][a];
    let (left, right) = order.split_at_mut(mid);
    let (left_axis, right_axis) = axis.split_at_mut(mid);
    let (left_value, right_value) = value.split_at_mut(mid);
    if n > PARALLEL_BUILD {
        rayon::join(
            || build(points, left, left_axis, left_value),
            || build(points, right, right_axis, right_value),
        );
    } else {
        build(points, left, left_axis, left_value);
        build(points, right, right_axis, right_value);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SplitMix64 (a test-local copy; mesh-fem depends on no RNG).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn nearest_neighbours_match_brute_force() {
        let mut rng = Rng(7);
        // Clustered points with exact duplicates of coordinates along one axis.
        let points: Vec<[f64; 3]> = (0..3000)
            .map(|i| {
                let c = (i % 5) as f64;
                [c + rng.next(), (rng.next() * 4.0).floor() / 4.0, rng.next() * 0.1]
            })
            .collect();
        let tree = KdTree::new(&points);
        let mut out = Vec::new();
        for i in (0..points.len()).step_by(37) {
            tree.nearest_of(i, 12, &mut out);
            let mut all: Vec<(f64, u32)> = (0..points.len() as u32)
                .filter(|&j| j as usize != i)
                .map(|j| {
                    let (p, q) = (points[j as usize], points[i]);
                    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2), j)
                })
                .collect();
            all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            assert_eq!(out, all[..12].to_vec(), "point {i}");
        }
    }
}
