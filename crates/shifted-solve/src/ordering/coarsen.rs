//! Weighted graphs and their coarsening by matching, the multilevel scheme of METIS (Karypis &
//! Kumar 1998): pairs of neighbours joined by heavy edges are merged into one vertex carrying
//! their summed weight, repeatedly, until the graph is small; a separator found there is
//! projected back and refined level by level.

use wfem_base::rng::SplitMix64;

use super::Graph;

/// A graph with vertex and edge weights, compressed rows without the diagonal.
#[derive(Clone, Debug)]
pub(super) struct WGraph {
    xadj: Vec<usize>,
    adj: Vec<u32>,
    ewgt: Vec<u32>,
    pub(super) vwgt: Vec<u32>,
}

impl WGraph {
    /// `g` with every vertex and edge of weight one.
    pub(super) fn unit(g: &Graph) -> Self {
        Self {
            xadj: g.xadj.clone(),
            adj: g.adj.clone(),
            ewgt: vec![1; g.adj.len()],
            vwgt: vec![1; g.n()],
        }
    }

    pub(super) fn n(&self) -> usize {
        self.vwgt.len()
    }

    pub(super) fn neighbours(&self, v: usize) -> &[u32] {
        &self.adj[self.xadj[v]..self.xadj[v + 1]]
    }

    fn edge_weights(&self, v: usize) -> &[u32] {
        &self.ewgt[self.xadj[v]..self.xadj[v + 1]]
    }

    pub(super) fn total_weight(&self) -> u64 {
        self.vwgt.iter().map(|&w| u64::from(w)).sum()
    }
}

/// One coarsening step: a heavy-edge matching visited in a seeded random order, merged pairs
/// weighing at most `max_vwgt`. Returns the coarse graph and the coarse vertex of each vertex,
/// or `None` when the graph shrinks by less than a tenth (coarsening has stalled).
pub(super) fn coarsen(g: &WGraph, max_vwgt: u32, rng: &mut SplitMix64) -> Option<(WGraph, Vec<u32>)> {
    let n = g.n();
    let mut mate = vec![u32::MAX; n];
    for v in visiting_order(n, rng) {
        if mate[v] != u32::MAX {
            continue;
        }
        let mut best: Option<(u32, u32, usize)> = None;
        for (&u, &w) in g.neighbours(v).iter().zip(g.edge_weights(v)) {
            let u = u as usize;
            if mate[u] != u32::MAX || g.vwgt[u].saturating_add(g.vwgt[v]) > max_vwgt {
                continue;
            }
            // Heaviest edge first, then the lightest partner (keeps coarse weights even).
            let key = (w, u32::MAX - g.vwgt[u], u);
            if best.is_none_or(|b| (key.0, key.1) > (b.0, b.1)) {
                best = Some(key);
            }
        }
        let u = best.map_or(v, |b| b.2);
        mate[v] = u as u32;
        mate[u] = v as u32;
    }
    let mut cmap = vec![u32::MAX; n];
    let mut nc = 0u32;
    for v in 0..n {
        if cmap[v] == u32::MAX {
            cmap[v] = nc;
            cmap[mate[v] as usize] = nc;
            nc += 1;
        }
    }
    let nc = nc as usize;
    if nc * 10 > n * 9 {
        return None;
    }
    Some((contract(g, &mate, &cmap, nc), cmap))
}

/// The order in which the matching visits the vertices: consecutive blocks (the rows of a
/// mesh's matrix are local in memory, and a random visit costs a cache miss per vertex),
/// the blocks themselves in a seeded random order so that tries differ.
fn visiting_order(n: usize, rng: &mut SplitMix64) -> impl Iterator<Item = usize> {
    const BLOCK: usize = 256;
    let n_blocks = n.div_ceil(BLOCK);
    rng.permutation(n_blocks)
        .into_iter()
        .flat_map(move |b| (b as usize * BLOCK)..((b as usize + 1) * BLOCK).min(n))
}

/// The graph of the merged pairs: edge weights summed, edges inside a pair dropped.
fn contract(g: &WGraph, mate: &[u32], cmap: &[u32], nc: usize) -> WGraph {
    let mut xadj = Vec::with_capacity(nc + 1);
    xadj.push(0);
    let mut adj = Vec::with_capacity(g.adj.len() / 2);
    let mut ewgt = Vec::with_capacity(g.adj.len() / 2);
    let mut vwgt = Vec::with_capacity(nc);
    // Position of each coarse neighbour in the row being built.
    let mut pos = vec![usize::MAX; nc];
    for v in 0..g.n() {
        let u = mate[v] as usize;
        if u < v {
            continue; // the pair was written at its smaller vertex
        }
        let c = cmap[v] as usize;
        let start = adj.len();
        let members: &[usize] = if u == v { &[v][..] } else { &[v, u][..] };
        let mut weight = 0u32;
        for &x in members {
            weight = weight.saturating_add(g.vwgt[x]);
            for (&y, &w) in g.neighbours(x).iter().zip(g.edge_weights(x)) {
                let cy = cmap[y as usize] as usize;
                if cy == c {
                    continue;
                }
                if pos[cy] == usize::MAX || pos[cy] < start {
                    pos[cy] = adj.len();
                    adj.push(cy as u32);
                    ewgt.push(w);
                } else {
                    ewgt[pos[cy]] = ewgt[pos[cy]].saturating_add(w);
                }
            }
        }
        vwgt.push(weight);
        xadj.push(adj.len());
    }
    WGraph { xadj, adj, ewgt, vwgt }
}
