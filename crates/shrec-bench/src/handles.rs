//! The `handles` transformation: tubes between two surface points that are close in space but
//! far apart on the surface (a hand glued to a hip by a thin bridge, as scanning or mesh repair
//! can produce). Each handle raises the genus by one.
//!
//! Recipe for one handle between vertices a and b: remove the edge-graph balls of
//! [`HANDLE_BALL_HOPS`] hops around a and b (two disks), then join the two rims by a tube of
//! rings interpolated linearly between them, about one mean edge apart. The rims are aligned by
//! arc length from their points nearest to a common direction and zipped to the rings in
//! arc-length order, with faces oriented like the surface (the rim edges are used in the
//! direction of the removed faces). The tube's vertices are new (ground truth −1); every other
//! vertex keeps its identity.
//!
//! Endpoints: a random vertex a (seeded permutation), then among the vertices within
//! [`HANDLE_MAX_DISTANCE`]·D of it and at edge-graph distance at least
//! [`HANDLE_MIN_GRAPH_DISTANCE`]·D the nearest b whose normal faces a while a's faces b
//! (`n_a·u > 0` and `n_b·u < 0`, u = b − a normalised), so that the tube runs through the
//! air between them; the balls of all handles stay at least four hops apart.

use crate::transform::{submesh, vertex_normals, Transformed};
use crate::BenchError;
use mesh_fem::graph::EdgeGraph;
use mesh_fem::vec3::{dot, lerp, norm, sub};
use mesh_fem::TriMesh;
use serde_json::json;
use wfem_base::rng::SplitMix64;

/// Largest Euclidean distance between the endpoints of a handle, as a fraction of D.
pub const HANDLE_MAX_DISTANCE: f64 = 0.15;
/// Smallest edge-graph distance between the endpoints, as a fraction of D.
pub const HANDLE_MIN_GRAPH_DISTANCE: f64 = 0.25;
/// Hops of the disk removed around each endpoint (the tube's mouth).
pub const HANDLE_BALL_HOPS: u32 = 2;

/// Number of handles at strength s.
pub fn handle_count(s: u8) -> usize {
    s as usize
}

/// A rim in the orientation the tube needs, with its arc-length parameter in [0, 1).
struct Rim {
    vertices: Vec<u32>,
    param: Vec<f64>,
}

impl Rim {
    /// Rotates the loop to start at the vertex closest to the direction `e` from its centre and
    /// computes the arc-length parameters.
    fn new(mut vertices: Vec<u32>, p: &[[f64; 3]], e: [f64; 3]) -> Self {
        let c = centroid(&vertices, p);
        let start = (0..vertices.len())
            .max_by(|&i, &j| {
                let di = dot(sub(p[vertices[i] as usize], c), e);
                let dj = dot(sub(p[vertices[j] as usize], c), e);
                di.total_cmp(&dj)
            })
            .unwrap_or(0);
        vertices.rotate_left(start);
        let m = vertices.len();
        let mut param = Vec::with_capacity(m);
        let mut s = 0.0;
        for i in 0..m {
            param.push(s);
            s += norm(sub(p[vertices[(i + 1) % m] as usize], p[vertices[i] as usize]));
        }
        param.iter_mut().for_each(|x| *x /= s);
        Self { vertices, param }
    }

    /// The point at arc-length parameter t ∈ [0, 1).
    fn at(&self, p: &[[f64; 3]], t: f64) -> [f64; 3] {
        let m = self.vertices.len();
        let i = self.param.partition_point(|&x| x <= t).saturating_sub(1);
        let (t0, t1) = (self.param[i], if i + 1 < m { self.param[i + 1] } else { 1.0 });
        let s = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
        lerp(p[self.vertices[i] as usize], p[self.vertices[(i + 1) % m] as usize], s)
    }
}

fn centroid(vertices: &[u32], p: &[[f64; 3]]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for &v in vertices {
        for k in 0..3 {
            c[k] += p[v as usize][k] / vertices.len() as f64;
        }
    }
    c
}

/// Zips two closed polylines with parameters increasing in [0, 1) into a band of triangles:
/// `lower` is used forward (its edges lower[i] → lower[i+1]), `upper` backward.
fn zip(lower: &[u32], lp: &[f64], upper: &[u32], up: &[f64], faces: &mut Vec<[u32; 3]>) {
    let (m, n) = (lower.len(), upper.len());
    let (mut i, mut j) = (0usize, 0usize);
    while i < m || j < n {
        let next_l = if i + 1 < m { lp[i + 1] } else { 1.0 };
        let next_u = if j + 1 < n { up[j + 1] } else { 1.0 };
        if j == n || (i < m && next_l <= next_u) {
            faces.push([lower[i % m], lower[(i + 1) % m], upper[j % n]]);
            i += 1;
        } else {
            faces.push([lower[i % m], upper[(j + 1) % n], upper[j % n]]);
            j += 1;
        }
    }
}

/// Whether removing the ball of [`HANDLE_BALL_HOPS`] around `v` opens one disk-shaped hole with
/// a simple rim: the faces touching the ball have Euler characteristic 1 and their boundary
/// edges meet two at each rim vertex.
fn is_disk(mesh: &TriMesh, graph: &EdgeGraph, v: u32) -> Result<bool, BenchError> {
    let ball = graph.hops(&[v], HANDLE_BALL_HOPS)?;
    let faces: Vec<[u32; 3]> = mesh
        .faces()
        .iter()
        .filter(|f| f.iter().any(|&x| ball[x as usize] != u32::MAX))
        .copied()
        .collect();
    let mut edges: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    let mut vertices = std::collections::HashSet::new();
    for f in &faces {
        for k in 0..3 {
            let (x, y) = (f[k], f[(k + 1) % 3]);
            *edges.entry((x.min(y), x.max(y))).or_insert(0) += 1;
            vertices.insert(x);
        }
    }
    let chi = vertices.len() as i64 - edges.len() as i64 + faces.len() as i64;
    let mut rim_degree: std::collections::HashMap<u32, u32> = std::collections::HashMap::new();
    for (&(x, y), &c) in &edges {
        if c == 1 {
            *rim_degree.entry(x).or_insert(0) += 1;
            *rim_degree.entry(y).or_insert(0) += 1;
        }
    }
    Ok(chi == 1 && !rim_degree.is_empty() && rim_degree.values().all(|&d| d == 2))
}

/// Picks up to `count` endpoint pairs (see the module docs).
fn endpoints(surface: &Surface<'_>, count: usize, rng: &mut SplitMix64) -> Result<Vec<[u32; 2]>, BenchError> {
    let (mesh, graph) = (surface.mesh, surface.graph);
    let p = mesh.positions();
    let n = p.len();
    let normals = vertex_normals(mesh);
    let d = surface.diameter;
    let mut blocked = vec![false; n];
    let mut pairs = Vec::new();
    for a in rng.permutation(n) {
        if pairs.len() == count {
            break;
        }
        if blocked[a as usize] {
            continue;
        }
        let pa = p[a as usize];
        let near = graph.distances(&[a], HANDLE_MIN_GRAPH_DISTANCE * d)?;
        let best = (0..n)
            .filter(|&b| !blocked[b] && near[b].is_infinite())
            .filter_map(|b| {
                let v = sub(p[b], pa);
                let dist = norm(v);
                if dist > HANDLE_MAX_DISTANCE * d || dist < 3.0 * surface.mean_edge {
                    return None;
                }
                let u = v.map(|x| x / dist);
                (dot(normals[a as usize], u) > 0.0 && dot(normals[b], u) < 0.0).then_some((dist, b as u32))
            })
            .min_by(|x, y| x.0.total_cmp(&y.0));
        let Some((_, b)) = best else { continue };
        if is_disk(mesh, graph, a)? && is_disk(mesh, graph, b)? {
            pairs.push([a, b]);
            let ball = graph.hops(&[a, b], 2 * HANDLE_BALL_HOPS + 4)?;
            for (x, h) in blocked.iter_mut().zip(&ball) {
                *x |= *h != u32::MAX;
            }
        }
    }
    Ok(pairs)
}

/// The surface handles are added to, with the measures the recipe is scaled by.
struct Surface<'a> {
    mesh: &'a TriMesh,
    graph: &'a EdgeGraph,
    /// D, the bounding-box diagonal.
    diameter: f64,
    /// The mean edge length.
    mean_edge: f64,
}

/// `count` handles on `mesh` (a base shape: its edge graph, its bounding-box diagonal D and
/// its mean edge length; fewer handles if the shape offers fewer endpoint pairs, the
/// parameters record how many).
///
/// # Errors
/// Mesh errors of the surgery; [`BenchError::Argument`] if a removed disk does not leave one
/// simple rim (a ball that is not a disk).
pub fn add_handles(
    mesh: &TriMesh,
    graph: &EdgeGraph,
    diameter: f64,
    mean_edge: f64,
    count: usize,
    rng: &mut SplitMix64,
) -> Result<Transformed, BenchError> {
    let surface = Surface {
        mesh,
        graph,
        diameter,
        mean_edge,
    };
    let pairs = endpoints(&surface, count, rng)?;
    let n = mesh.n_vertices();
    let ends: Vec<u32> = pairs.iter().flatten().copied().collect();
    let mut keep = vec![true; n];
    for &v in &ends {
        let ball = graph.hops(&[v], HANDLE_BALL_HOPS)?;
        for (k, h) in keep.iter_mut().zip(&ball) {
            *k &= *h == u32::MAX;
        }
    }
    let cut = submesh(mesh, &keep)?;
    let mut positions = cut.mesh.positions().to_vec();
    let mut faces = cut.mesh.faces().to_vec();
    let mut ground_truth: Vec<i64> = cut.source_vertex.iter().map(|&v| v as i64).collect();
    let rims = mesh_repair::holes::boundary_loops(&cut.mesh);
    // Each rim belongs to the endpoint within HANDLE_BALL_HOPS + 1 hops of its vertices.
    let rim_of = |end: u32| -> Result<Vec<u32>, BenchError> {
        let near = graph.hops(&[end], HANDLE_BALL_HOPS + 1)?;
        rims.iter()
            .filter(|r| r.closed && r.is_simple())
            .find(|r| {
                r.vertices
                    .iter()
                    .all(|&v| near[cut.source_vertex[v as usize] as usize] != u32::MAX)
            })
            .map(|r| r.vertices.clone())
            .ok_or_else(|| BenchError::Argument(format!("handle end {end}: no simple rim around it")))
    };
    let mut lengths = Vec::new();
    for &[a, b] in &pairs {
        let (rim_a, rim_b) = (rim_of(a)?, rim_of(b)?);
        if rims.len() != 2 * pairs.len() {
            return Err(BenchError::Argument(format!(
                "{} rims for {} handle ends (a removed ball is not a disk)",
                rims.len(),
                2 * pairs.len()
            )));
        }
        // The tube needs the rim edges in the direction of the removed faces: reversed at a
        // (used forward by `zip`), as found at b (used backward).
        let mut lower: Vec<u32> = rim_a;
        lower.reverse();
        let (ca, cb) = (centroid(&lower, &positions), centroid(&rim_b, &positions));
        let axis = sub(cb, ca);
        let length = norm(axis);
        // A direction across the tube, common to both rims.
        let e = {
            let u = axis.map(|x| x / length);
            let t = if u[0].abs() < 0.9 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            let w = sub(t, u.map(|x| x * dot(t, u)));
            w.map(|x| x / norm(w))
        };
        let ra = Rim::new(lower, &positions, e);
        let rb = Rim::new(rim_b, &positions, e);
        let m = ra.vertices.len().max(rb.vertices.len());
        let rings = ((length / mean_edge).round() as usize).max(2);
        let ring_param: Vec<f64> = (0..m).map(|i| i as f64 / m as f64).collect();
        let mut previous = (ra.vertices.clone(), ra.param.clone());
        for k in 1..rings {
            let s = k as f64 / rings as f64;
            let first = positions.len() as u32;
            for &t in &ring_param {
                positions.push(lerp(ra.at(&positions, t), rb.at(&positions, t), s));
                ground_truth.push(-1);
            }
            let ring: Vec<u32> = (0..m as u32).map(|i| first + i).collect();
            zip(&previous.0, &previous.1, &ring, &ring_param, &mut faces);
            previous = (ring, ring_param.clone());
        }
        zip(&previous.0, &previous.1, &rb.vertices, &rb.param, &mut faces);
        lengths.push(length);
    }
    Ok(Transformed {
        mesh: TriMesh::new(positions, faces)?,
        ground_truth,
        params: json!({"handles_requested": count, "handles": pairs, "tube_lengths": lengths,
                       "ball_hops": HANDLE_BALL_HOPS}),
    })
}
