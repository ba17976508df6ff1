//! Thin handles (topological noise): finding short non-separating cycles and cutting them.
//!
//! A closed surface of genus g has non-separating cycles: loops along which it can be cut
//! without falling apart. A *thin handle* — a tube glued between two parts that touch, a
//! bridge left by a scan or a simplification — has a short one, around the tube. Cutting it
//! and closing the two rims gives back the surface without the handle, up to two small stubs.
//!
//! **Shortest non-separating loop through a vertex x** (Erickson & Whittlesey, "Greedy optimal
//! homotopy and homology generators", SODA 2005): with T the shortest-path tree of x (edge
//! lengths), every edge e = ab outside T closes the loop `σ(e)` = path(x, a) + e + path(b, x)
//! of length `ℓ(e) = d(a) + |ab| + d(b)`. A maximum spanning tree C of the dual graph on the
//! edges outside T, weighted by ℓ, leaves exactly 2g edges; their loops form the shortest
//! system of loops through x, and the shortest of them is the shortest non-separating loop
//! through x. Its simple part (from the branch point of the two paths) is a non-separating
//! cycle.
//!
//! **Search.** From a few seed vertices spread over the surface (farthest-point order), the
//! shortest cycle found is tightened: the loops through vertices sampled along it are computed
//! and the shortest kept, until no sample improves it. A loop through a vertex on a tube,
//! around the tube, is then found from any loop that runs through the tube. Each loop costs one
//! Dijkstra and one sort, O(n log n).
//!
//! **Which cycle.** The shortest cycle may run around a limb as thin as the tube that is glued
//! to it (cutting there also kills the handle, but takes the limb). So the repair tries the
//! short cycles around the handle (`around_handle`: the loops through a vertex of the
//! shortest one include one through the handle, and the shortest loop through a point of
//! that one goes around the tube there) and keeps the one whose tube removal (below) takes
//! the least area.
//!
//! **Removal.** The surface is cut along the cycle and the handle's tube delimited from the
//! two rims: the level sets of the distance from a rim run around the tube with about the
//! rim's length, and start to grow (like circles, 2π per unit of distance) where they pass the
//! tube's mouth onto the surface it is glued to. The tube is deleted with the faces touching it
//! and the two openings are closed by [`crate::holes::fill_holes`]: what is left is the surface
//! without the handle, not two stubs. Should the tube not separate cleanly (the result must be
//! closed, manifold and of genus one less), or should the level sets keep their length for
//! longer than the cycle (a tube that ends on an arm as thin as itself: removing "the tube"
//! would take the arm) for every cycle tried, the surface is cut across the shortest cycle
//! instead — every vertex of the cycle split in two, the faces on its left taking new copies —
//! and the two rims closed. Only closed, manifold, consistently oriented meshes are touched;
//! anything else comes back unchanged. Each loop costs one Dijkstra and one sort,
//! O(n log n); a handle costs the search's loops plus 8 per loop of the system (2g) and up to
//! six tube removals (measured: 0.2–0.4 s per handle on a 5,000-vertex shape).

use crate::holes::fill_holes;
use mesh_fem::graph::{EdgeGraph, UnionFind, NO_PARENT};
use mesh_fem::topology::Topology;
use mesh_fem::vec3::{norm, sub};
use mesh_fem::{MeshError, TriMesh};

/// Seeds of the search.
const SEEDS: usize = 4;
/// Vertices sampled along a cycle per tightening round.
const SAMPLES: usize = 8;
/// Tightening rounds.
const ROUNDS: usize = 6;
/// Cycles tried around each handle ([`around_handle`]).
const CANDIDATES: usize = 6;
/// A handle's tube ends where the level sets of the distance from its cycle start to grow
/// faster than this per unit of distance (π: half the growth of a circle on a plane).
const TUBE_GROWTH: f64 = std::f64::consts::PI;

/// The result of [`cut_handles`].
#[derive(Clone, Debug)]
pub struct CutHandles {
    /// The mesh without its thin handles: the old vertices that are kept first, in their order
    /// and at their positions, then the new ones (patches, and copies of cut vertices).
    pub mesh: TriMesh,
    /// The number of old vertices kept (they come first, in their order).
    pub original_vertices: usize,
    /// The old vertices removed with the handles' tubes, increasing.
    pub removed: Vec<u32>,
    /// For every handle removed, in order, the length of the shortest non-separating cycle
    /// found at that step (the one `max_length` bounds; the tube may have been delimited from
    /// another short cycle, see the module docs), in units of √A.
    pub cut: Vec<f64>,
}

/// The edge graph with the two faces of every edge.
struct Graph {
    /// Per vertex: (neighbour, edge id).
    adjacency: Vec<Vec<(u32, u32)>>,
    /// Per edge: its two faces.
    faces: Vec<[u32; 2]>,
    /// Per edge: its length.
    length: Vec<f64>,
    /// Per edge: its ends, sorted (the topology's edge list).
    ends: Vec<[u32; 2]>,
    /// The same graph for the shortest paths (mesh-fem's one Dijkstra).
    paths: EdgeGraph,
}

impl Graph {
    /// The graph of a closed manifold mesh (every edge in exactly two faces).
    fn new(mesh: &TriMesh, topology: &Topology) -> Self {
        let n = mesh.n_vertices();
        let p = mesh.positions();
        let mut faces = vec![[u32::MAX; 2]; topology.edges.len()];
        for (f, face) in mesh.faces().iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (face[k].min(face[(k + 1) % 3]), face[k].max(face[(k + 1) % 3]));
                if let Ok(e) = topology.edges.binary_search(&[a, b]) {
                    let slot = if faces[e][0] == u32::MAX { 0 } else { 1 };
                    faces[e][slot] = f as u32;
                }
            }
        }
        let mut adjacency = vec![Vec::new(); n];
        let mut length = Vec::with_capacity(topology.edges.len());
        for (e, &[a, b]) in topology.edges.iter().enumerate() {
            adjacency[a as usize].push((b, e as u32));
            adjacency[b as usize].push((a, e as u32));
            length.push(norm(sub(p[a as usize], p[b as usize])));
        }
        Self {
            adjacency,
            faces,
            length,
            ends: topology.edges.clone(),
            paths: EdgeGraph::new(mesh),
        }
    }

    /// Shortest-path distances from a set of vertices.
    fn distances(&self, sources: &[u32]) -> Vec<f64> {
        self.dijkstra_from(sources).0
    }

    /// Shortest-path distances and parent edges from `x`.
    fn dijkstra(&self, x: u32) -> (Vec<f64>, Vec<u32>) {
        self.dijkstra_from(&[x])
    }

    /// Shortest-path distances and, per vertex, the edge to its parent in the shortest-path
    /// tree (`u32::MAX` for a source or an unreached vertex).
    fn dijkstra_from(&self, sources: &[u32]) -> (Vec<f64>, Vec<u32>) {
        // invariant: every source is a vertex of the mesh the graph was built from.
        let Ok((dist, parent)) = self.paths.shortest_paths(sources) else {
            return (
                vec![f64::INFINITY; self.adjacency.len()],
                vec![u32::MAX; self.adjacency.len()],
            );
        };
        let edge = |(w, &v): (usize, &u32)| {
            if v == NO_PARENT {
                return u32::MAX;
            }
            let key = [v.min(w as u32), v.max(w as u32)];
            self.ends.binary_search(&key).map_or(u32::MAX, |e| e as u32)
        };
        (dist, parent.iter().enumerate().map(edge).collect())
    }

    fn other(&self, e: u32, v: u32, edges: &[[u32; 2]]) -> u32 {
        let [a, b] = edges[e as usize];
        if a == v {
            b
        } else {
            a
        }
    }

    /// The shortest non-separating loop through `x` (see the module docs): its simple part
    /// (the cycle) and the cycle's length; `None` on a component of genus 0.
    fn cycle_through(&self, x: u32, edges: &[[u32; 2]], n_faces: usize) -> Option<Through> {
        self.loops_through(x, edges, n_faces, 1).into_iter().next()
    }

    /// The shortest system of loops through `x` (module docs), at most `most` of them, shortest
    /// first: each loop's simple part and its length. Empty on a component of genus 0.
    fn loops_through(&self, x: u32, edges: &[[u32; 2]], n_faces: usize, most: usize) -> Vec<Through> {
        let (dist, parent) = self.dijkstra(x);
        let mut candidates: Vec<(f64, u32)> = edges
            .iter()
            .enumerate()
            .filter(|(e, [a, b])| {
                dist[*a as usize].is_finite()
                    && dist[*b as usize].is_finite()
                    && parent[*a as usize] != *e as u32
                    && parent[*b as usize] != *e as u32
            })
            .map(|(e, [a, b])| (dist[*a as usize] + self.length[e] + dist[*b as usize], e as u32))
            .collect();
        // Maximum spanning tree of the dual: the longest loops first; the edges left out close
        // the system's loops, the last one the shortest.
        candidates.sort_by(|p, q| q.0.total_cmp(&p.0).then(p.1.cmp(&q.1)));
        let mut dual = UnionFind::new(n_faces);
        let mut left_out: Vec<u32> = Vec::new();
        for &(_, e) in &candidates {
            let [f, g] = self.faces[e as usize];
            if !dual.union(f, g) {
                left_out.push(e);
            }
        }
        left_out
            .iter()
            .rev()
            .take(most)
            .map(|&e| self.simple_loop(x, e, &parent, edges))
            .collect()
    }

    /// The simple part of the loop through `x` closed by the edge `e` (tree `parent` of `x`).
    fn simple_loop(&self, x: u32, e: u32, parent: &[u32], edges: &[[u32; 2]]) -> Through {
        let [a, b] = edges[e as usize];
        let path = |mut v: u32| {
            let mut out = vec![v];
            while v != x {
                v = self.other(parent[v as usize], v, edges);
                out.push(v);
            }
            out
        };
        let (pa, pb) = (path(a), path(b));
        // Drop the common stem: the cycle runs from the branch point to a, across e, and back
        // from b.
        let mut common = 0;
        while common < pa.len().min(pb.len()) && pa[pa.len() - 1 - common] == pb[pb.len() - 1 - common] {
            common += 1;
        }
        let mut cycle: Vec<u32> = pa[..pa.len() - common + 1].iter().rev().copied().collect();
        cycle.extend(pb[..pb.len() - common].iter().copied());
        let length = (0..cycle.len())
            .map(|i| {
                let (u, v) = (cycle[i], cycle[(i + 1) % cycle.len()]);
                self.adjacency[u as usize]
                    .iter()
                    .find(|&&(w, _)| w == v)
                    .map_or(f64::INFINITY, |&(_, e)| self.length[e as usize])
            })
            .sum();
        Through { cycle, length }
    }
}

/// A shortest non-separating loop through a vertex.
struct Through {
    /// Its simple part, from the branch point of the two tree paths.
    cycle: Vec<u32>,
    /// The cycle's length.
    length: f64,
}

/// The shortest non-separating cycle the search of the module docs finds (vertices in order,
/// its length), or `None` if the mesh is not closed, manifold and oriented, or has genus 0.
pub fn short_handle_cycle(mesh: &TriMesh) -> Option<(Vec<u32>, f64)> {
    let topology = Topology::new(mesh.n_vertices(), mesh.faces());
    if !cuttable(&topology) || genus(mesh, &topology) == 0 {
        return None;
    }
    let graph = Graph::new(mesh, &topology);
    search(&graph, &topology.edges, mesh.n_faces()).map(|t| (t.cycle, t.length))
}

/// The search of the module docs on a prepared graph.
fn search(graph: &Graph, edges: &[[u32; 2]], n_faces: usize) -> Option<Through> {
    let through = |x: u32| graph.cycle_through(x, edges, n_faces);
    let mut best: Option<Through> = None;
    for seed in seeds(graph, graph.adjacency.len()) {
        let Some(mut current) = through(seed) else { continue };
        for _ in 0..ROUNDS {
            let m = current.cycle.len();
            let better = (0..SAMPLES.min(m))
                .map(|k| current.cycle[k * m / SAMPLES.min(m)])
                .filter_map(through)
                .min_by(|p, q| p.length.total_cmp(&q.length));
            match better {
                Some(b) if b.length < current.length * (1.0 - 1e-9) => current = b,
                _ => break,
            }
        }
        if best.as_ref().is_none_or(|b| current.length < b.length) {
            best = Some(current);
        }
    }
    best
}

/// Removes every thin handle — one whose shortest non-separating cycle is at most
/// `max_length · √A` long (A the area) — shortest first, and closes the openings
/// ([`crate::holes::fill_holes`]); see the module docs. A mesh of genus 0, with a boundary or
/// not manifold comes back unchanged.
///
/// # Errors
/// [`MeshError::Invalid`] for a `max_length` that is negative or not finite.
pub fn cut_handles(mesh: &TriMesh, max_length: f64) -> Result<CutHandles, MeshError> {
    if !(max_length.is_finite() && max_length >= 0.0) {
        return Err(MeshError::Invalid {
            reason: format!("the longest handle cycle must be finite and non-negative, got {max_length}"),
        });
    }
    let scale = mesh.area().sqrt();
    let mut current = mesh.clone();
    // The input vertex each current vertex is (None: new).
    let mut origin: Vec<Option<u32>> = (0..mesh.n_vertices() as u32).map(Some).collect();
    let mut cut = Vec::new();
    loop {
        let topology = Topology::new(current.n_vertices(), current.faces());
        if !cuttable(&topology) || genus(&current, &topology) == 0 {
            break;
        }
        let graph = Graph::new(&current, &topology);
        let n_faces = current.n_faces();
        let Some(best) = search(&graph, &topology.edges, n_faces) else {
            break;
        };
        if best.length > max_length * scale {
            break;
        }
        let genus_before = genus(&current, &topology);
        let first_copy = current.n_vertices() as u32;
        // Of the short cycles around this handle (the shortest may run around a limb as thin
        // as the tube), the one whose tube removal takes the least area.
        let mut removal: Option<(TriMesh, Vec<Option<u32>>, f64)> = None;
        for candidate in around_handle(&graph, &topology.edges, n_faces, &best, max_length * scale) {
            let Some(opened) = cut_along(&current, &candidate.cycle) else {
                continue;
            };
            let Some((m, kept, area)) =
                remove_tube(&opened, &candidate.cycle, candidate.length, first_copy, genus_before)
            else {
                continue;
            };
            if removal.as_ref().is_none_or(|r| area < r.2) {
                let mut o: Vec<Option<u32>> = kept
                    .iter()
                    .map(|&v| origin.get(v as usize).copied().flatten())
                    .collect();
                o.resize(m.n_vertices(), None);
                removal = Some((m, o, area));
            }
        }
        let (next, next_origin) = match removal {
            Some((m, o, _)) => (m, o),
            // No tube could be delimited: close the cut across the shortest cycle instead.
            None => {
                let Some(opened) = cut_along(&current, &best.cycle) else {
                    break;
                };
                let closed = fill_holes(&opened, 1.01 * best.length / opened.area().sqrt())?;
                if closed.filled != 2 {
                    break;
                }
                let mut o = origin.clone();
                o.resize(closed.mesh.n_vertices(), None);
                (closed.mesh, o)
            }
        };
        current = next;
        origin = next_origin;
        cut.push(best.length / scale);
    }
    let original_vertices = origin.iter().take_while(|o| o.is_some()).count();
    let mut kept = vec![false; mesh.n_vertices()];
    for o in origin.iter().flatten() {
        kept[*o as usize] = true;
    }
    Ok(CutHandles {
        mesh: current,
        original_vertices,
        removed: (0..mesh.n_vertices() as u32).filter(|&v| !kept[v as usize]).collect(),
        cut,
    })
}

/// Removes the handle around a short cycle, on the mesh `opened` along it by [`cut_along`]
/// (whose rims are the cycle's vertices, right, and their copies from `first_copy` on,
/// left): on each side, the level sets of the distance from the rim run around the tube,
/// about as long as the cycle, until they reach the surface the tube is glued to and grow;
/// the vertices closer to the rim than where the growth exceeds `TUBE_GROWTH` per unit of
/// distance are the tube's. `None` if no growth is met within the cycle's length `around` of
/// a rim (or 0.5 √A): the tube ends on a part as thin as itself, which is not removed. Both
/// halves are deleted with the faces touching them and the openings
/// closed. `Some` only if the result is closed, manifold, connected as before and of genus one
/// less; with, for its old vertices (first), their indices in `opened`, and the area removed.
fn remove_tube(
    opened: &TriMesh,
    cycle: &[u32],
    around: f64,
    first_copy: u32,
    genus_before: i64,
) -> Option<(TriMesh, Vec<u32>, f64)> {
    let n = opened.n_vertices();
    let topology = Topology::new(n, opened.faces());
    let graph = Graph::new(opened, &topology);
    let h = graph.length.iter().sum::<f64>() / graph.length.len().max(1) as f64;
    // A tube is at most as long as it is around (on each side of the cut): past that the level
    // sets run along a part of the shape as thin as the tube (an arm the tube ends on), which
    // is not the tube's to remove; the cycle is then cut across instead.
    let limit = (0.5 * opened.area().sqrt()).min(around);
    let mut drop = vec![false; n];
    let copies: Vec<u32> = (first_copy..first_copy + cycle.len() as u32).collect();
    for rim in [cycle, &copies[..]] {
        let d = graph.distances(rim);
        // Along the tube the level sets keep about the rim's length; past its mouth they
        // spread over the surface and grow like a circle, 2π per unit of distance.
        let step = 0.5 * h;
        let mut previous = level_length(opened, &d, step);
        let mut r = step;
        let stop = loop {
            if r > limit {
                return None;
            }
            let next = level_length(opened, &d, r + 2.0 * step);
            if next - previous > TUBE_GROWTH * 2.0 * step {
                break r;
            }
            previous = level_length(opened, &d, r + step);
            r += step;
        };
        for (x, &dv) in drop.iter_mut().zip(&d) {
            *x |= dv < stop;
        }
    }
    let kept_faces: Vec<[u32; 3]> = opened
        .faces()
        .iter()
        .filter(|f| f.iter().all(|&v| !drop[v as usize]))
        .copied()
        .collect();
    let mut used = vec![false; n];
    kept_faces.iter().flatten().for_each(|&v| used[v as usize] = true);
    let kept: Vec<u32> = (0..n as u32).filter(|&v| used[v as usize]).collect();
    let mut index = vec![u32::MAX; n];
    for (i, &v) in kept.iter().enumerate() {
        index[v as usize] = i as u32;
    }
    let positions = kept.iter().map(|&v| opened.positions()[v as usize]).collect();
    let faces = kept_faces.into_iter().map(|f| f.map(|v| index[v as usize])).collect();
    let holed = TriMesh::new(positions, faces).ok()?;
    let removed_area = opened.area() - holed.area();
    // The openings are the tube's two mouths (the mesh was closed but for the cut): close them.
    let closed = fill_holes(&holed, f64::MAX.sqrt()).ok()?;
    let t = Topology::new(closed.mesh.n_vertices(), closed.mesh.faces());
    let ok = cuttable(&t) && t.n_components == topology.n_components && genus(&closed.mesh, &t) == genus_before - 1;
    ok.then_some((closed.mesh, kept, removed_area))
}

/// The length of the level set `{d = r}` of the piecewise-linear interpolation of `d`.
fn level_length(mesh: &TriMesh, d: &[f64], r: f64) -> f64 {
    let p = mesh.positions();
    let mut total = 0.0;
    for f in mesh.faces() {
        let mut points = Vec::with_capacity(2);
        for k in 0..3 {
            let (a, b) = (f[k] as usize, f[(k + 1) % 3] as usize);
            let (da, db) = (d[a], d[b]);
            if (da < r) != (db < r) && da.is_finite() && db.is_finite() {
                let s = (r - da) / (db - da);
                points.push(mesh_fem::vec3::lerp(p[a], p[b], s));
            }
        }
        if points.len() == 2 {
            total += norm(sub(points[0], points[1]));
        }
    }
    total
}

/// The result of [`unweld`].
#[derive(Clone, Debug)]
pub struct Unwelded {
    /// The mesh with every pinched vertex split: the old vertices first, in their order and at
    /// their positions, then the copies.
    pub mesh: TriMesh,
    /// For each copy (vertex `n + i` of `mesh`), the old vertex it copies.
    pub copies: Vec<u32>,
}

/// Splits every vertex where several sheets of faces meet (a pinch: two parts welded at a
/// point or along edges): the faces around a vertex are grouped into fans joined across edges
/// that have exactly two faces; the largest fan keeps the vertex, every other fan gets its own
/// copy (at the same position). Two sheets welded along an edge (an edge with four faces) are
/// separated too, since fans never join across such an edge. A manifold mesh comes back
/// unchanged.
pub fn unweld(mesh: &TriMesh) -> Unwelded {
    let faces = mesh.faces();
    let n = mesh.n_vertices();
    let mut edge_faces: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *edge_faces.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let offsets = mesh_fem::graph::corner_offsets(faces, n);
    let mut at = vec![0u32; offsets[n]];
    let mut cursor = offsets.clone();
    for (fi, f) in faces.iter().enumerate() {
        for &v in f {
            at[cursor[v as usize]] = fi as u32;
            cursor[v as usize] += 1;
        }
    }
    let mut positions = mesh.positions().to_vec();
    let mut new_faces = faces.to_vec();
    let mut copies = Vec::new();
    for v in 0..n {
        let fan = &at[offsets[v]..offsets[v + 1]];
        if fan.len() < 2 {
            continue;
        }
        let mut uf = UnionFind::new(fan.len());
        for x in 0..fan.len() {
            for y in x + 1..fan.len() {
                let (fx, fy) = (faces[fan[x] as usize], faces[fan[y] as usize]);
                let joined = fx.iter().any(|&w| {
                    w != v as u32
                        && fy.contains(&w)
                        && edge_faces.get(&((v as u32).min(w), (v as u32).max(w))) == Some(&2)
                });
                if joined {
                    uf.union(x as u32, y as u32);
                }
            }
        }
        let roots: Vec<u32> = (0..fan.len() as u32).map(|x| uf.find(x)).collect();
        let mut groups: Vec<u32> = roots.clone();
        groups.sort_unstable();
        groups.dedup();
        if groups.len() < 2 {
            continue;
        }
        let size = |g: u32| roots.iter().filter(|&&r| r == g).count();
        let keep = groups
            .iter()
            .copied()
            .max_by_key(|&g| (size(g), std::cmp::Reverse(g)))
            .unwrap_or(groups[0]);
        for g in groups.into_iter().filter(|&g| g != keep) {
            let copy = positions.len() as u32;
            positions.push(positions[v]);
            copies.push(v as u32);
            for (x, &f) in fan.iter().enumerate() {
                if roots[x] == g {
                    for c in new_faces[f as usize].iter_mut() {
                        if *c == v as u32 {
                            *c = copy;
                        }
                    }
                }
            }
        }
    }
    match TriMesh::new(positions, new_faces) {
        Ok(m) => Unwelded { mesh: m, copies },
        // invariant: the same faces on a superset of the positions always form a mesh.
        Err(_) => Unwelded {
            mesh: mesh.clone(),
            copies: Vec::new(),
        },
    }
}

fn cuttable(t: &Topology) -> bool {
    t.n_boundary_edges == 0
        && t.non_manifold_edges.is_empty()
        && t.non_manifold_vertices.is_empty()
        && t.inconsistent_edges.is_empty()
        && t.non_orientable_edges.is_empty()
}

/// The total genus of a closed mesh: Σ over components of (2 − χ_c)/2 = (2c − χ)/2.
fn genus(mesh: &TriMesh, t: &Topology) -> i64 {
    let chi = t.n_referenced() as i64 - t.edges.len() as i64 + mesh.n_faces() as i64;
    (2 * t.n_components as i64 - chi) / 2
}

/// Seeds spread over the surface: vertex 0, then repeatedly the vertex farthest from the seeds
/// so far (within reach).
fn seeds(graph: &Graph, n: usize) -> Vec<u32> {
    let mut out = Vec::new();
    let mut nearest = vec![f64::INFINITY; n];
    let mut next = 0u32;
    while out.len() < SEEDS.min(n) {
        out.push(next);
        let (d, _) = graph.dijkstra(next);
        for (m, x) in nearest.iter_mut().zip(d) {
            if x.is_finite() {
                *m = m.min(x);
            }
        }
        match (0..n)
            .filter(|&v| nearest[v].is_finite())
            .max_by(|&a, &b| nearest[a].total_cmp(&nearest[b]))
        {
            Some(v) if nearest[v] > 0.0 => next = v as u32,
            _ => break,
        }
    }
    out
}

/// Short cycles around the handle of `best` (a shortest non-separating cycle), shortest first,
/// `best` among them: the loops through a vertex of `best` include one through the handle
/// (its "longitude"), and the shortest non-separating loop through a point of that one is the
/// cycle around the tube there — even where a limb the tube is glued to is thinner. At most
/// [`CANDIDATES`], each at most `limit` long, no two with the same vertices.
fn around_handle(graph: &Graph, edges: &[[u32; 2]], n_faces: usize, best: &Through, limit: f64) -> Vec<Through> {
    let mut out = vec![Through {
        cycle: best.cycle.clone(),
        length: best.length,
    }];
    for other in graph.loops_through(best.cycle[0], edges, n_faces, usize::MAX) {
        let m = other.cycle.len();
        for k in 0..SAMPLES.min(m) {
            if let Some(t) = graph.cycle_through(other.cycle[k * m / SAMPLES.min(m)], edges, n_faces) {
                if t.length <= limit {
                    out.push(t);
                }
            }
        }
    }
    out.sort_by(|p, q| p.length.total_cmp(&q.length));
    let mut seen: Vec<Vec<u32>> = Vec::new();
    out.retain(|t| {
        let mut key = t.cycle.clone();
        key.sort_unstable();
        let new = !seen.contains(&key);
        if new {
            seen.push(key);
        }
        new
    });
    out.truncate(CANDIDATES);
    out
}

/// Splits the vertices of a simple cycle: the faces on its left (those traversing a cycle
/// edge forwards, and their fans around each cycle vertex) take new copies. `None` if the cycle
/// is not simple or a vertex's fan does not split in two.
fn cut_along(mesh: &TriMesh, cycle: &[u32]) -> Option<TriMesh> {
    let m = cycle.len();
    if m < 3 {
        return None;
    }
    let mut sorted = cycle.to_vec();
    sorted.sort_unstable();
    if sorted.windows(2).any(|w| w[0] == w[1]) {
        return None;
    }
    let faces = mesh.faces();
    let mut positions = mesh.positions().to_vec();
    let mut new_faces = faces.to_vec();
    // Faces at each cycle vertex.
    let on_cycle: std::collections::HashMap<u32, usize> = cycle.iter().enumerate().map(|(i, &v)| (v, i)).collect();
    let mut at: Vec<Vec<u32>> = vec![Vec::new(); m];
    for (f, face) in faces.iter().enumerate() {
        for &v in face {
            if let Some(&i) = on_cycle.get(&v) {
                at[i].push(f as u32);
            }
        }
    }
    let has_directed = |face: &[u32; 3], a: u32, b: u32| (0..3).any(|k| face[k] == a && face[(k + 1) % 3] == b);
    for i in 0..m {
        let (v, prev, next) = (cycle[i], cycle[(i + m - 1) % m], cycle[(i + 1) % m]);
        let fan = &at[i];
        // Join faces of the fan across edges (v, w), w not a cycle neighbour.
        let mut uf = UnionFind::new(fan.len());
        for x in 0..fan.len() {
            for y in x + 1..fan.len() {
                let (fx, fy) = (faces[fan[x] as usize], faces[fan[y] as usize]);
                let shared = fx.iter().any(|&w| w != v && w != prev && w != next && fy.contains(&w));
                if shared {
                    uf.union(x as u32, y as u32);
                }
            }
        }
        let left = fan.iter().position(|&f| has_directed(&faces[f as usize], v, next))?;
        let right = fan.iter().position(|&f| has_directed(&faces[f as usize], next, v))?;
        let (l, r) = (uf.find(left as u32), uf.find(right as u32));
        if l == r {
            return None;
        }
        let copy = positions.len() as u32;
        positions.push(positions[v as usize]);
        for (x, &f) in fan.iter().enumerate() {
            if uf.find(x as u32) == l {
                for c in new_faces[f as usize].iter_mut() {
                    if *c == v {
                        *c = copy;
                    }
                }
            }
        }
    }
    TriMesh::new(positions, new_faces).ok()
}
