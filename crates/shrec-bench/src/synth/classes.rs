//! One function per transformation class (the arms of [`super::transform`]).

use super::{
    bend_angle_deg, big_hole_radius, local_scale_factor, micro_hole_count, noise_sigma, pose_index, shot_fraction,
    weld_pair_count, BaseShape, BEND_HALF_WIDTH, BIG_HOLE_COUNT, BIG_HOLE_SEPARATION, LOCAL_SCALE_WIDTH,
    MICRO_HOLE_SEPARATION, SAMPLING_KEEP, SCALE_FACTORS, SHOT_AMPLITUDE, WELD_MAX_DISTANCE, WELD_MIN_GRAPH_DISTANCE,
};
use crate::transform::{
    close_pairs, largest_component, submesh, vertex_normals, weld_vertices, DerivedMesh, QemDecimator, QemParams,
    Transformed,
};
use crate::BenchError;
use mesh_fem::vec3::{cross, dot, norm, sub};
use mesh_fem::TriMesh;
use rayon::prelude::*;
use serde_json::json;
use wfem_base::rng::SplitMix64;

pub(super) fn identity_gt(n: usize) -> Vec<i64> {
    (0..n as i64).collect()
}

fn from_derived(d: DerivedMesh, params: serde_json::Value) -> Transformed {
    Transformed {
        ground_truth: d.source_vertex.iter().map(|&v| v as i64).collect(),
        mesh: d.mesh,
        params,
    }
}

fn moved(base: &BaseShape, positions: Vec<[f64; 3]>, params: serde_json::Value) -> Result<Transformed, BenchError> {
    let n = positions.len();
    Ok(Transformed {
        mesh: TriMesh::new(positions, base.mesh.faces().to_vec())?,
        ground_truth: identity_gt(n),
        params,
    })
}

/// Rotation of `p` by `angle` about the unit axis `a` (Rodrigues).
fn rotate(p: [f64; 3], a: [f64; 3], angle: f64) -> [f64; 3] {
    let (s, c) = angle.sin_cos();
    let axp = cross(a, p);
    let adp = dot(a, p);
    [0, 1, 2].map(|k| p[k] * c + axp[k] * s + a[k] * adp * (1.0 - c))
}

fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The `pose` class at strength s.
pub(super) fn pose(base: &BaseShape, s: u8, _rng: &mut SplitMix64) -> Result<Transformed, BenchError> {
    let m = base.poses.len();
    if m == 0 {
        return Err(BenchError::Argument(format!(
            "{}: no other poses with ground truth were loaded (see BaseShape::load_poses)",
            base.name
        )));
    }
    let k = pose_index(s, m);
    let pose = &base.poses[k];
    Ok(Transformed {
        mesh: pose.mesh.clone(),
        ground_truth: pose.ground_truth.clone(),
        params: json!({"pose": pose.name, "deformation_D": pose.deformation, "rank": k, "poses_available": m}),
    })
}

/// The `isometry` class at strength s.
pub(super) fn isometry(base: &BaseShape, s: u8, rng: &mut SplitMix64) -> Result<Transformed, BenchError> {
    let p = base.mesh.positions();
    let n = p.len();
    let d = base.diameter;
    let c = p[rng.next_below(n)];
    let m = rng.unit_vector();
    // Axis: a random direction projected into the joint plane.
    let axis = loop {
        let r = rng.unit_vector();
        let t = sub(r, m.map(|x| x * dot(r, m)));
        if norm(t) > 0.1 {
            break t.map(|x| x / norm(t));
        }
    };
    let h = BEND_HALF_WIDTH * d;
    let theta = bend_angle_deg(s).to_radians();
    let positions = p
        .iter()
        .map(|&x| {
            let w = smoothstep((dot(sub(x, c), m) + h) / (2.0 * h));
            let r = rotate(sub(x, c), axis, w * theta);
            [c[0] + r[0], c[1] + r[1], c[2] + r[2]]
        })
        .collect();
    moved(
        base,
        positions,
        json!({"theta_deg": bend_angle_deg(s), "joint_point": c, "plane_normal": m, "axis": axis, "half_width": h}),
    )
}

/// The `topology` class at strength s.
pub(super) fn topology(base: &BaseShape, s: u8, _rng: &mut SplitMix64) -> Result<Transformed, BenchError> {
    let p = base.mesh.positions();
    let n = p.len();
    let d = base.diameter;
    let radius = WELD_MAX_DISTANCE * d;
    let min_graph = WELD_MIN_GRAPH_DISTANCE * d;
    let wanted = weld_pair_count(s);
    let pairs = close_pairs(p, radius);
    let mut firsts: Vec<u32> = pairs.iter().map(|pr| pr[0]).collect();
    firsts.dedup();
    let far: Vec<Vec<[u32; 2]>> = firsts
        .par_iter()
        .map(|&i| -> Result<Vec<[u32; 2]>, BenchError> {
            let dist = base.graph.distances(&[i], min_graph)?;
            let lo = pairs.partition_point(|pr| pr[0] < i);
            let hi = pairs.partition_point(|pr| pr[0] <= i);
            Ok(pairs[lo..hi]
                .iter()
                .filter(|pr| dist[pr[1] as usize].is_infinite())
                .copied()
                .collect())
        })
        .collect::<Result<_, _>>()?;
    let mut candidates: Vec<(f64, [u32; 2])> = far
        .into_iter()
        .flatten()
        .map(|[i, j]| (norm(sub(p[i as usize], p[j as usize])), [i, j]))
        .collect();
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    // Greedy in order of distance: a pair is taken only if the welded mesh keeps every
    // face clearly non-degenerate (a weld can make three corners collinear).
    let min_area = 1e-6 * base.mesh.area() / base.mesh.n_faces() as f64;
    let mut welds: Vec<[u32; 2]> = Vec::new();
    let mut last_distance = 0.0;
    for (tries, &(dist_ij, pair)) in candidates.iter().enumerate() {
        if welds.len() == wanted || tries >= 4 * wanted + 100 {
            break;
        }
        welds.push(pair);
        let trial = weld_vertices(&base.mesh, &welds)?;
        if (0..trial.mesh.n_faces()).all(|f| trial.mesh.face_area(f) > min_area) {
            last_distance = dist_ij;
        } else {
            welds.pop();
        }
    }
    let eps = last_distance;
    let derived = weld_vertices(&base.mesh, &welds)?;
    let merged = n - derived.mesh.n_vertices();
    Ok(from_derived(
        derived,
        json!({"pairs_requested": wanted, "welded_pairs": welds, "largest_weld_distance": eps,
               "max_distance": radius, "min_graph_distance": min_graph, "vertices_merged": merged}),
    ))
}

/// The `micro_holes` class at strength s.
pub(super) fn micro_holes(base: &BaseShape, s: u8, rng: &mut SplitMix64) -> Result<Transformed, BenchError> {
    let p = base.mesh.positions();
    let n = p.len();
    let wanted = micro_hole_count(s);
    let mut blocked = vec![false; n];
    let mut seeds = Vec::new();
    for v in rng.permutation(n) {
        if seeds.len() == wanted {
            break;
        }
        if blocked[v as usize] {
            continue;
        }
        seeds.push(v);
        let hop = base.graph.hops(&[v], MICRO_HOLE_SEPARATION - 1)?;
        for (b, h) in blocked.iter_mut().zip(&hop) {
            *b |= *h != u32::MAX;
        }
    }
    let hop = base.graph.hops(&seeds, 1)?;
    let keep: Vec<bool> = hop.iter().map(|&h| h == u32::MAX).collect();
    let cut = submesh(&base.mesh, &keep)?;
    let piece = cut.then(largest_component(&cut.mesh)?);
    let removed = n - piece.mesh.n_vertices();
    Ok(from_derived(
        piece,
        json!({"holes_requested": wanted, "holes": seeds.len(), "seeds": seeds, "vertices_removed": removed}),
    ))
}

/// The `holes` class at strength s.
pub(super) fn holes(base: &BaseShape, s: u8, rng: &mut SplitMix64) -> Result<Transformed, BenchError> {
    let p = base.mesh.positions();
    let n = p.len();
    let d = base.diameter;
    let radius = big_hole_radius(s) * d;
    let sep = BIG_HOLE_SEPARATION * d;
    let mut seeds: Vec<u32> = Vec::new();
    let mut to_seeds = vec![f64::INFINITY; n];
    for v in rng.permutation(n) {
        if seeds.len() == BIG_HOLE_COUNT {
            break;
        }
        if to_seeds[v as usize] < sep {
            continue;
        }
        seeds.push(v);
        to_seeds = base.graph.distances(&seeds, sep)?;
    }
    let dist = base.graph.distances(&seeds, radius)?;
    let keep: Vec<bool> = dist.iter().map(|&x| x >= radius).collect();
    let cut = submesh(&base.mesh, &keep)?;
    let piece = cut.then(largest_component(&cut.mesh)?);
    let removed = n - piece.mesh.n_vertices();
    Ok(from_derived(
        piece,
        json!({"radius": radius, "seeds": seeds, "vertices_removed": removed}),
    ))
}

/// The `scale` class at strength s.
pub(super) fn scale(base: &BaseShape, s: u8, _rng: &mut SplitMix64) -> Result<Transformed, BenchError> {
    let p = base.mesh.positions();
    let n = p.len();
    let beta = SCALE_FACTORS[s as usize - 1];
    Ok(Transformed {
        mesh: base.mesh.scaled(beta)?,
        ground_truth: identity_gt(n),
        params: json!({"beta": beta}),
    })
}

/// The `local_scale` class at strength s.
pub(super) fn local_scale(base: &BaseShape, s: u8, rng: &mut SplitMix64) -> Result<Transformed, BenchError> {
    let p = base.mesh.positions();
    let n = p.len();
    let d = base.diameter;
    let ci = rng.next_below(n) as u32;
    let c = p[ci as usize];
    let beta = local_scale_factor(s);
    let rho = LOCAL_SCALE_WIDTH * d;
    let dg = base.graph.distances(&[ci], f64::INFINITY)?;
    let positions = p
        .iter()
        .zip(&dg)
        .map(|(&x, &g)| {
            let w = if g.is_finite() {
                (-g * g / (2.0 * rho * rho)).exp()
            } else {
                0.0
            };
            let f = 1.0 + (beta - 1.0) * w;
            [0, 1, 2].map(|k| c[k] + f * (x[k] - c[k]))
        })
        .collect();
    moved(base, positions, json!({"beta": beta, "rho": rho, "center_vertex": ci}))
}

/// The `noise` class at strength s.
pub(super) fn noise(base: &BaseShape, s: u8, rng: &mut SplitMix64) -> Result<Transformed, BenchError> {
    let p = base.mesh.positions();
    let sigma = noise_sigma(s) * base.mean_edge;
    let positions = p
        .iter()
        .map(|&x| {
            let z = [rng.next_normal(), rng.next_normal(), rng.next_normal()];
            [0, 1, 2].map(|k| x[k] + sigma * z[k])
        })
        .collect();
    moved(base, positions, json!({"sigma": sigma}))
}

/// The `shot_noise` class at strength s.
pub(super) fn shot_noise(base: &BaseShape, s: u8, rng: &mut SplitMix64) -> Result<Transformed, BenchError> {
    let p = base.mesh.positions();
    let n = p.len();
    let count = (shot_fraction(s) * n as f64).round().max(1.0) as usize;
    let a = SHOT_AMPLITUDE * base.mean_edge;
    let normals = vertex_normals(&base.mesh);
    let order = rng.permutation(n);
    let signs: Vec<f64> = (0..n)
        .map(|_| if rng.next_u64() & 1 == 0 { 1.0 } else { -1.0 })
        .collect();
    let mut positions = p.to_vec();
    let hit = &order[..count.min(n)];
    for (k, &v) in hit.iter().enumerate() {
        let nv = normals[v as usize];
        for j in 0..3 {
            positions[v as usize][j] += signs[k] * a * nv[j];
        }
    }
    moved(base, positions, json!({"amplitude": a, "vertices_hit": hit.len()}))
}

/// The `sampling` class at strength s.
pub(super) fn sampling(base: &BaseShape, s: u8, _rng: &mut SplitMix64) -> Result<Transformed, BenchError> {
    let p = base.mesh.positions();
    let n = p.len();
    let keep = SAMPLING_KEEP[s as usize - 1];
    let target = (keep * n as f64).round() as usize;
    let mut dec = QemDecimator::new(&base.mesh, QemParams::default())?;
    let reached = dec.collapse_to(target);
    Ok(from_derived(
        dec.snapshot()?,
        json!({"keep_fraction": keep, "target_vertices": target, "vertices": reached}),
    ))
}
