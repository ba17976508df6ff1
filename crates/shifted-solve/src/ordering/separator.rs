//! A vertex separator of a connected graph: the middle of a breadth-first level structure from
//! a pseudo-peripheral vertex, improved by Fiduccia–Mattheyses-style moves of single separator
//! vertices (Ashcraft & Liu 1994, as in METIS's node refinement).
//!
//! Sides: 0 and 1 are the two halves, 2 the separator; no edge joins side 0 to side 1.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::Graph;

/// At most this many refinement passes; each keeps its best state, and refinement stops when
/// a pass does not shrink the separator.
const MAX_PASSES: usize = 8;

/// A 0/1/2 side per vertex with a separator between sides 0 and 1, both non-empty, or `None`
/// when the graph is too small or too dense to split (its caller then orders it whole).
///
/// `max_side` bounds the larger half as a fraction of the vertices (e.g. 0.6).
pub(super) fn bisect(g: &Graph, max_side: f64) -> Option<Vec<u8>> {
    let n = g.n();
    let root = pseudo_peripheral(g, 0);
    let (level, n_levels) = bfs_levels(g, root);
    if n_levels < 3 {
        return None;
    }
    let mut size = vec![0usize; n_levels];
    for &l in &level {
        size[l as usize] += 1;
    }
    let k = separator_level(&size, n, max_side);
    let mut side: Vec<u8> = level
        .iter()
        .map(|&l| match (l as usize).cmp(&k) {
            std::cmp::Ordering::Less => 0,
            std::cmp::Ordering::Equal => 2,
            std::cmp::Ordering::Greater => 1,
        })
        .collect();
    refine(g, &mut side, max_side);
    let mut count = [0usize; 3];
    for &s in &side {
        count[s as usize] += 1;
    }
    (count[0] > 0 && count[1] > 0).then_some(side)
}

/// The level used as the first separator: the smallest one leaving at least `1 − max_side` of
/// the vertices on each side, else the median level (the one holding the n/2-th vertex).
fn separator_level(size: &[usize], n: usize, max_side: f64) -> usize {
    let min_side = ((1.0 - max_side) * n as f64).ceil() as usize;
    let mut best: Option<((usize, usize), usize)> = None;
    let mut median = None;
    let mut before = 0usize;
    for (k, &s) in size.iter().enumerate() {
        let after = n - before - s;
        if median.is_none() && before + s >= n / 2 {
            median = Some(k);
        }
        if k > 0 && k + 1 < size.len() && before >= min_side && after >= min_side {
            let score = (s, before.abs_diff(after));
            if best.is_none_or(|(b, _)| score < b) {
                best = Some((score, k));
            }
        }
        before += s;
    }
    match best {
        Some((_, k)) => k,
        None => median.unwrap_or(1).clamp(1, size.len() - 2),
    }
}

/// Breadth-first levels from `root` (`u32::MAX` for vertices not reached) and their count.
fn bfs_levels(g: &Graph, root: usize) -> (Vec<u32>, usize) {
    let mut level = vec![u32::MAX; g.n()];
    let mut queue = Vec::with_capacity(g.n());
    level[root] = 0;
    queue.push(root as u32);
    let mut head = 0;
    let mut depth = 0;
    while head < queue.len() {
        let v = queue[head] as usize;
        head += 1;
        let l = level[v];
        depth = depth.max(l as usize + 1);
        for &u in g.neighbours(v) {
            if level[u as usize] == u32::MAX {
                level[u as usize] = l + 1;
                queue.push(u);
            }
        }
    }
    (level, depth)
}

/// A vertex of (nearly) greatest eccentricity (Gibbs–Poole–Stockmeyer): repeatedly jump to a
/// smallest-degree vertex of the last BFS level while the number of levels grows.
fn pseudo_peripheral(g: &Graph, start: usize) -> usize {
    let mut root = start;
    let mut depth = 0;
    for _ in 0..8 {
        let (level, n_levels) = bfs_levels(g, root);
        if n_levels <= depth {
            break;
        }
        depth = n_levels;
        let last = (n_levels - 1) as u32;
        let next = (0..g.n())
            .filter(|&v| level[v] == last)
            .min_by_key(|&v| (g.neighbours(v).len(), v));
        match next {
            Some(v) if v != root => root = v,
            _ => break,
        }
    }
    root
}

/// Gain of moving separator vertex `v` to side `to`: it leaves the separator, and its
/// neighbours on the other side join it.
fn gain(g: &Graph, side: &[u8], v: usize, to: u8) -> i32 {
    let other = 1 - to;
    1 - g.neighbours(v).iter().filter(|&&u| side[u as usize] == other).count() as i32
}

/// Fiduccia–Mattheyses passes on the vertex separator, keeping each side at most
/// `max_side · n` vertices.
fn refine(g: &Graph, side: &mut [u8], max_side: f64) {
    let n = g.n();
    let limit = ((max_side * n as f64) as usize).max(1);
    let mut sizes = [0usize; 3];
    for &s in side.iter() {
        sizes[s as usize] += 1;
    }
    let mut locked = vec![false; n];
    for _ in 0..MAX_PASSES {
        let before = (sizes[0].max(sizes[1]) > limit, sizes[2]);
        fm_pass(g, side, &mut sizes, &mut locked, limit);
        if (sizes[0].max(sizes[1]) > limit, sizes[2]) >= before {
            break;
        }
    }
}

type Heap = BinaryHeap<(i32, Reverse<u32>)>;

/// The best valid entry of a move queue (stale entries — vertex moved, locked, or gain since
/// changed, for which a fresh entry was pushed — are dropped).
fn top(heap: &mut Heap, g: &Graph, side: &[u8], locked: &[bool], to: u8) -> Option<(i32, usize)> {
    while let Some(&(gn, Reverse(v))) = heap.peek() {
        let v = v as usize;
        if side[v] == 2 && !locked[v] && gain(g, side, v, to) == gn {
            return Some((gn, v));
        }
        heap.pop();
    }
    None
}

/// Lexicographic quality of a state: balanced first, then separator size, then imbalance.
fn score(sizes: &[usize; 3], limit: usize) -> (bool, usize, usize) {
    (sizes[0].max(sizes[1]) > limit, sizes[2], sizes[0].abs_diff(sizes[1]))
}

/// One pass: moves separator vertices (each at most once) by best gain, allowing a run of
/// non-improving moves, then rolls back to the best state seen.
fn fm_pass(g: &Graph, side: &mut [u8], sizes: &mut [usize; 3], locked: &mut [bool], limit: usize) {
    let n = g.n();
    let mut heaps: [Heap; 2] = [BinaryHeap::new(), BinaryHeap::new()];
    for v in (0..n).filter(|&v| side[v] == 2) {
        for to in 0..2u8 {
            heaps[to as usize].push((gain(g, side, v, to), Reverse(v as u32)));
        }
    }
    let patience = (n / 100).clamp(20, 200);
    let mut log: Vec<(u32, u8)> = Vec::new();
    let mut moved: Vec<u32> = Vec::new();
    let mut best = (score(sizes, limit), 0usize);
    let mut since_best = 0;
    let mut affected = Vec::new();
    while since_best < patience {
        let t0 = top(&mut heaps[0], g, side, locked, 0);
        let t1 = top(&mut heaps[1], g, side, locked, 1);
        let fits = |to: usize| sizes[to] < limit;
        let prefer = if sizes[0] > limit {
            1
        } else if sizes[1] > limit {
            0
        } else {
            match (t0, t1) {
                (Some((a, _)), Some((b, _))) if a != b => usize::from(b > a),
                _ => usize::from(sizes[1] < sizes[0]),
            }
        };
        let cands = [prefer, 1 - prefer];
        let Some((to, v)) = cands
            .iter()
            .find_map(|&to| [t0, t1][to].filter(|_| fits(to)).map(|(_, v)| (to, v)))
        else {
            break;
        };
        heaps[to].pop();
        let other = (1 - to) as u8;
        locked[v] = true;
        moved.push(v as u32);
        log.push((v as u32, 2));
        side[v] = to as u8;
        sizes[2] -= 1;
        sizes[to] += 1;
        affected.clear();
        for &u in g.neighbours(v) {
            let u = u as usize;
            if side[u] == other {
                log.push((u as u32, other));
                side[u] = 2;
                sizes[other as usize] -= 1;
                sizes[2] += 1;
                affected.push(u);
                affected.extend(g.neighbours(u).iter().map(|&w| w as usize).filter(|&w| side[w] == 2));
            } else if side[u] == 2 {
                affected.push(u);
            }
        }
        for &w in &affected {
            if side[w] == 2 && !locked[w] {
                for t in 0..2u8 {
                    heaps[t as usize].push((gain(g, side, w, t), Reverse(w as u32)));
                }
            }
        }
        let s = score(sizes, limit);
        if s < best.0 {
            best = (s, log.len());
            since_best = 0;
        } else {
            since_best += 1;
        }
    }
    while log.len() > best.1 {
        let Some((v, old)) = log.pop() else { break };
        let v = v as usize;
        sizes[side[v] as usize] -= 1;
        sizes[old as usize] += 1;
        side[v] = old;
    }
    for v in moved {
        locked[v as usize] = false;
    }
}
