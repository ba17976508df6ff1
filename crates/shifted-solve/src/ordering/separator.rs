//! A vertex separator of a connected graph by the multilevel scheme: the graph is coarsened by
//! heavy-edge matchings ([`super::coarsen`]) to about [`COARSE_N`] vertices, split there by
//! breadth-first region growing from several roots, and the separator is projected back level
//! by level, each time improved by Fiduccia–Mattheyses-style moves of single separator
//! vertices (Ashcraft & Liu 1994, as in METIS's node refinement).
//!
//! Sides: 0 and 1 are the two halves, 2 the separator; no edge joins side 0 to side 1.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use wfem_base::rng::SplitMix64;

use super::coarsen::{coarsen, WGraph};
use super::Graph;

/// At most this many refinement passes per level; each keeps its best state, and refinement
/// stops when a pass does not improve the separator.
const MAX_PASSES: usize = 6;

/// Coarsening stops at about this many vertices.
const COARSE_N: usize = 120;

/// Roots tried for the initial separator on the coarsest graph.
const INITIAL_TRIES: usize = 8;

/// Seed of the matchings' visiting order (any fixed value: the ordering is deterministic).
const SEED: u64 = 0x5eed_0039;

/// A 0/1/2 side per vertex with a separator between sides 0 and 1, both non-empty, or `None`
/// when the graph is too small or too dense to split (its caller then orders it whole).
///
/// `max_side` bounds the larger half as a fraction of the vertices (e.g. 0.7); `tries`
/// multilevel bisections with different matchings are made and the best separator kept.
pub(super) fn bisect(g: &Graph, max_side: f64, tries: usize) -> Option<Vec<u8>> {
    let fine = WGraph::unit(g);
    let limit = side_limit(&fine, max_side);
    let attempt = |k: usize| {
        bisect_once(&fine, max_side, SEED.wrapping_add(k as u64))
            .map(|side| (score(&weights(&fine, &side), limit), side))
    };
    // The tries run in parallel (the top of the dissection is otherwise one thread); the best
    // is the first of the smallest score, whatever the scheduling.
    let results: Vec<_> = if tries > 1 {
        use rayon::prelude::*;
        (0..tries).into_par_iter().map(attempt).collect()
    } else {
        vec![attempt(0)]
    };
    let mut best: Option<((bool, u64, u64), Vec<u8>)> = None;
    for (s, side) in results.into_iter().flatten() {
        if best.as_ref().is_none_or(|(b, _)| s < *b) {
            best = Some((s, side));
        }
    }
    best.map(|(_, side)| side)
}

/// One multilevel bisection, its matchings seeded by `seed`.
fn bisect_once(fine: &WGraph, max_side: f64, seed: u64) -> Option<Vec<u8>> {
    let total = fine.total_weight();
    let max_vwgt = u32::try_from((1.5 * total as f64 / COARSE_N as f64).ceil() as u64)
        .unwrap_or(u32::MAX)
        .max(1);
    let mut rng = SplitMix64::new(seed ^ fine.n() as u64);
    // levels[i]: the graph coarsened i + 1 times and the map from the one above it.
    let mut levels: Vec<(WGraph, Vec<u32>)> = Vec::new();
    loop {
        let finer = levels.last().map_or(fine, |(g, _)| g);
        if finer.n() <= COARSE_N {
            break;
        }
        let Some(next) = coarsen(finer, max_vwgt, &mut rng) else {
            break;
        };
        levels.push(next);
    }
    let mut side = initial_separator(levels.last().map_or(fine, |(g, _)| g), max_side)?;
    for i in (0..levels.len()).rev() {
        let finer = if i == 0 { fine } else { &levels[i - 1].0 };
        side = levels[i].1.iter().map(|&c| side[c as usize]).collect();
        refine(finer, &mut side, max_side);
    }
    let mut count = [0usize; 3];
    for &s in &side {
        count[s as usize] += 1;
    }
    (count[0] > 0 && count[1] > 0).then_some(side)
}

/// The best of [`INITIAL_TRIES`] refined region-growing separators of a (small) graph.
fn initial_separator(g: &WGraph, max_side: f64) -> Option<Vec<u8>> {
    let n = g.n();
    if n < 3 {
        return None;
    }
    let limit = side_limit(g, max_side);
    let mut best: Option<((bool, u64, u64), Vec<u8>)> = None;
    for k in 0..INITIAL_TRIES.min(n) {
        let root = pseudo_peripheral(g, k * n / INITIAL_TRIES.min(n));
        let mut side = grown_separator(g, root);
        refine(g, &mut side, max_side);
        let sizes = weights(g, &side);
        if sizes[0] == 0 || sizes[1] == 0 {
            continue;
        }
        let s = score(&sizes, limit);
        if best.as_ref().is_none_or(|(b, _)| s < *b) {
            best = Some((s, side));
        }
    }
    best.map(|(_, side)| side)
}

/// Breadth-first region growing from `root` until half the weight: side 0 is the region,
/// side 1 the rest, and the lighter of the two boundaries becomes the separator.
fn grown_separator(g: &WGraph, root: usize) -> Vec<u8> {
    let n = g.n();
    let half = g.total_weight() / 2;
    let (order, _) = bfs_order(g, root);
    let mut side = vec![1u8; n];
    let mut grown = 0u64;
    for &v in &order {
        if grown >= half {
            break;
        }
        side[v as usize] = 0;
        grown += u64::from(g.vwgt[v as usize]);
    }
    let boundary = |s: u8| -> Vec<usize> {
        (0..n)
            .filter(|&v| side[v] == s && g.neighbours(v).iter().any(|&u| side[u as usize] == 1 - s))
            .collect()
    };
    let (b0, b1) = (boundary(0), boundary(1));
    let w = |b: &[usize]| b.iter().map(|&v| u64::from(g.vwgt[v])).sum::<u64>();
    for v in if w(&b0) <= w(&b1) { b0 } else { b1 } {
        side[v] = 2;
    }
    side
}

/// Vertices in breadth-first order from `root` and the number of levels.
fn bfs_order(g: &WGraph, root: usize) -> (Vec<u32>, Vec<u32>) {
    let mut level = vec![u32::MAX; g.n()];
    let mut queue = Vec::with_capacity(g.n());
    level[root] = 0;
    queue.push(root as u32);
    let mut head = 0;
    while head < queue.len() {
        let v = queue[head] as usize;
        head += 1;
        for &u in g.neighbours(v) {
            if level[u as usize] == u32::MAX {
                level[u as usize] = level[v] + 1;
                queue.push(u);
            }
        }
    }
    (queue, level)
}

/// A vertex of (nearly) greatest eccentricity (Gibbs–Poole–Stockmeyer): repeatedly jump to a
/// smallest-degree vertex of the last BFS level while the number of levels grows.
fn pseudo_peripheral(g: &WGraph, start: usize) -> usize {
    let mut root = start;
    let mut depth = 0;
    for _ in 0..8 {
        let (order, level) = bfs_order(g, root);
        let Some(&far) = order.last() else { break };
        let last = level[far as usize];
        if (last as usize) < depth {
            break;
        }
        depth = last as usize + 1;
        let next = order
            .iter()
            .map(|&v| v as usize)
            .filter(|&v| level[v] == last)
            .min_by_key(|&v| (g.neighbours(v).len(), v));
        match next {
            Some(v) if v != root => root = v,
            _ => break,
        }
    }
    root
}

fn side_limit(g: &WGraph, max_side: f64) -> u64 {
    ((max_side * g.total_weight() as f64) as u64).max(1)
}

fn weights(g: &WGraph, side: &[u8]) -> [u64; 3] {
    let mut sizes = [0u64; 3];
    for (v, &s) in side.iter().enumerate() {
        sizes[s as usize] += u64::from(g.vwgt[v]);
    }
    sizes
}

/// Gain of moving separator vertex `v` to side `to`: it leaves the separator, and its
/// neighbours on the other side join it.
fn gain(g: &WGraph, side: &[u8], v: usize, to: u8) -> i64 {
    let other = 1 - to;
    let pulled: u64 = g
        .neighbours(v)
        .iter()
        .filter(|&&u| side[u as usize] == other)
        .map(|&u| u64::from(g.vwgt[u as usize]))
        .sum();
    i64::from(g.vwgt[v]) - pulled as i64
}

/// Fiduccia–Mattheyses passes on the vertex separator, keeping each side at most
/// `max_side` of the weight.
fn refine(g: &WGraph, side: &mut [u8], max_side: f64) {
    let limit = side_limit(g, max_side);
    let mut sizes = weights(g, side);
    let n = g.n();
    let mut work = Work {
        locked: vec![false; n],
        pulled: vec![false; n],
        gains: [vec![0; n], vec![0; n]],
    };
    for _ in 0..MAX_PASSES {
        let before = score(&sizes, limit);
        fm_pass(g, side, &mut sizes, &mut work, limit);
        if score(&sizes, limit) >= before {
            break;
        }
    }
}

/// Per-vertex state of the refinement passes on one graph.
struct Work {
    /// Moved in this pass (a vertex leaves the separator at most once per pass).
    locked: Vec<bool>,
    /// Pulled into the separator by the current move.
    pulled: Vec<bool>,
    /// `gains[to][v]`: the gain of moving separator vertex v to side `to`, kept up to date.
    gains: [Vec<i64>; 2],
}

type Heap = BinaryHeap<(i64, Reverse<u32>)>;

/// The best valid entry of a move queue (stale entries — vertex moved, locked, or gain since
/// changed, for which a fresh entry was pushed — are dropped).
fn top(heap: &mut Heap, side: &[u8], work: &Work, to: usize) -> Option<(i64, usize)> {
    while let Some(&(gn, Reverse(v))) = heap.peek() {
        let v = v as usize;
        if side[v] == 2 && !work.locked[v] && work.gains[to][v] == gn {
            return Some((gn, v));
        }
        heap.pop();
    }
    None
}

/// Lexicographic quality of a state: balanced first, then separator weight, then imbalance.
fn score(sizes: &[u64; 3], limit: u64) -> (bool, u64, u64) {
    (sizes[0].max(sizes[1]) > limit, sizes[2], sizes[0].abs_diff(sizes[1]))
}

/// One pass: moves separator vertices (each at most once) by best gain, allowing a run of
/// non-improving moves, then rolls back to the best state seen.
fn fm_pass(g: &WGraph, side: &mut [u8], sizes: &mut [u64; 3], work: &mut Work, limit: u64) {
    let n = g.n();
    let mut heaps: [Heap; 2] = [BinaryHeap::new(), BinaryHeap::new()];
    for v in (0..n).filter(|&v| side[v] == 2) {
        for (to, heap) in heaps.iter_mut().enumerate() {
            work.gains[to][v] = gain(g, side, v, to as u8);
            heap.push((work.gains[to][v], Reverse(v as u32)));
        }
    }
    let patience = (n / 200).clamp(16, 100);
    let mut log: Vec<(u32, u8)> = Vec::new();
    let mut moved: Vec<u32> = Vec::new();
    let mut best = (score(sizes, limit), 0usize);
    let mut since_best = 0;
    let mut pulled = Vec::new();
    while since_best < patience {
        let t0 = top(&mut heaps[0], side, work, 0);
        let t1 = top(&mut heaps[1], side, work, 1);
        let fits = |to: usize, v: usize| sizes[to] + u64::from(g.vwgt[v]) <= limit;
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
        let Some((to, v)) = [prefer, 1 - prefer]
            .iter()
            .find_map(|&to| [t0, t1][to].filter(|&(_, v)| fits(to, v)).map(|(_, v)| (to, v)))
        else {
            break;
        };
        heaps[to].pop();
        let other = 1 - to;
        let wv = u64::from(g.vwgt[v]);
        work.locked[v] = true;
        moved.push(v as u32);
        log.push((v as u32, 2));
        side[v] = to as u8;
        sizes[2] -= wv;
        sizes[to] += wv;
        pulled.clear();
        for &u in g.neighbours(v) {
            let u = u as usize;
            if side[u] == other as u8 {
                log.push((u as u32, other as u8));
                side[u] = 2;
                sizes[other] -= u64::from(g.vwgt[u]);
                sizes[2] += u64::from(g.vwgt[u]);
                work.pulled[u] = true;
                pulled.push(u);
            }
        }
        // v joined side `to`: its separator neighbours now pull it when they move to `other`.
        for &w in g.neighbours(v) {
            let w = w as usize;
            if side[w] == 2 && !work.pulled[w] {
                work.gains[other][w] -= wv as i64;
                if !work.locked[w] {
                    heaps[other].push((work.gains[other][w], Reverse(w as u32)));
                }
            }
        }
        // Each pulled u left side `other`: its old separator neighbours no longer pull it.
        for &u in &pulled {
            let wu = i64::from(g.vwgt[u]);
            for &w in g.neighbours(u) {
                let w = w as usize;
                if side[w] == 2 && !work.pulled[w] {
                    work.gains[to][w] += wu;
                    if !work.locked[w] {
                        heaps[to].push((work.gains[to][w], Reverse(w as u32)));
                    }
                }
            }
        }
        for &u in &pulled {
            work.pulled[u] = false;
            for (t, heap) in heaps.iter_mut().enumerate() {
                work.gains[t][u] = gain(g, side, u, t as u8);
                if !work.locked[u] {
                    heap.push((work.gains[t][u], Reverse(u as u32)));
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
        sizes[side[v] as usize] -= u64::from(g.vwgt[v]);
        sizes[old as usize] += u64::from(g.vwgt[v]);
        side[v] = old;
    }
    for v in moved {
        work.locked[v as usize] = false;
    }
}
