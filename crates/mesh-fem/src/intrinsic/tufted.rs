//! The tufted cover of a triangle soup and intrinsic mollification (Sharp & Crane 2020,
//! Sect. 4.3–4.5).
//!
//! Every face f = (v₀, v₁, v₂) becomes two triangles of the cover: the front sheet 2f with
//! the face's orientation and the back sheet 2f + 1 = (v₀, v₂, v₁). Around an edge ab with
//! faces f₀ … f_{k−1} sorted by the angle of their third vertex about the axis b − a
//! (decreasing, i.e. clockwise seen from b), the sheet of f_i that faces f_{i+1} is glued to
//! the sheet of f_{i+1} that faces f_i: with orientations, the sheet of f_i running b → a is
//! glued to the sheet of f_{i+1} running a → b. An edge with one face glues the face's two
//! sheets (the cover folds over the boundary); an edge with two faces of consistent
//! orientation glues front to front and back to back. The result is a closed oriented
//! manifold whatever the input: non-manifold edges and vertices, inconsistent orientation,
//! boundary. (The gluing is geometry-central's `buildIntrinsicTuftedCover`.)

use super::IntrinsicTriangulation;
use crate::vec3::{dot, norm, sub, tangent_basis};
use crate::MeshError;
use rayon::prelude::*;

/// The binary exponent k of the largest absolute coordinate, so that positions × 2⁻ᵏ have
/// coordinates below 2 and edge lengths neither overflow nor underflow (0 for a cloud at the
/// origin only).
pub(crate) fn coordinate_exponent(positions: &[[f64; 3]]) -> i32 {
    let m = positions.iter().flatten().fold(0.0f64, |m, c| m.max(c.abs()));
    if m == 0.0 || !m.is_finite() {
        return 0;
    }
    // frexp: m = f · 2^e with f in [0.5, 1); m · 2^-e < 1.
    let bits = m.to_bits();
    let e = ((bits >> 52) & 0x7ff) as i32;
    if e == 0 {
        // Subnormal: lift by 2^64 first.
        let lifted = m * 18446744073709551616.0;
        (((lifted.to_bits() >> 52) & 0x7ff) as i32) - 1022 - 64
    } else {
        e - 1022
    }
}

/// Positions multiplied by 2⁻ᵏ (exact).
pub(crate) fn scaled_positions(positions: &[[f64; 3]], k: i32) -> Vec<[f64; 3]> {
    positions
        .par_iter()
        .map(|p| p.map(|c| crate::mesh::mul_pow2(c, -k)))
        .collect()
}

/// Intrinsic mollification (Sharp & Crane 2020, Sect. 4.5; geometry-central's
/// `mollifyIntrinsic`): with δ = `factor` × the mean length of the distinct edges, every
/// length grows by `ε = max(0, max over triangles and corners of (l_c − l_a − l_b + δ))`, the
/// smallest uniform increase after which each triangle satisfies its triangle inequalities
/// with a margin δ. `lengths` holds three lengths per face (edge k from corner k to k + 1);
/// returns ε.
pub(crate) fn mollify(lengths: &mut [[f64; 3]], mean_edge: f64, factor: f64) -> f64 {
    let delta = factor * mean_edge;
    let eps = lengths
        .par_iter()
        .map(|l| {
            (0..3)
                .map(|k| l[k] - l[(k + 1) % 3] - l[(k + 2) % 3] + delta)
                .fold(0.0f64, f64::max)
        })
        .reduce(|| 0.0, f64::max);
    if eps > 0.0 {
        lengths
            .par_iter_mut()
            .for_each(|l| l.iter_mut().for_each(|x| *x += eps));
    }
    eps
}

/// The tufted cover of `faces` on `positions` with mollified lengths (module documentation).
/// Lengths are stored scaled by a power of two ([`coordinate_exponent`]).
///
/// # Errors
/// * [`MeshError::UnreferencedVertex`] for a vertex in no face;
/// * [`MeshError::DegenerateMesh`] when every edge has length zero;
/// * [`MeshError::DegenerateIntrinsicTriangle`] for a face that is flat after mollification
///   (only with `mollify_factor` = 0);
/// * [`MeshError::Invalid`] for 2³² / 6 faces or more.
///
/// Faces must not repeat a vertex (the caller checks).
pub(crate) fn tufted_cover(
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
    mollify_factor: f64,
) -> Result<IntrinsicTriangulation, MeshError> {
    let n = positions.len();
    let n_faces = faces.len();
    if n_faces.checked_mul(6).is_none_or(|h| h > u32::MAX as usize) {
        return Err(MeshError::Invalid {
            reason: format!("{n_faces} faces: the tufted cover indexes its 6 half-edges per face with 32 bits"),
        });
    }
    let mut referenced = vec![false; n];
    faces.iter().flatten().for_each(|&v| referenced[v as usize] = true);
    if let Some(vertex) = referenced.iter().position(|&r| !r) {
        return Err(MeshError::UnreferencedVertex { vertex });
    }
    let scale = coordinate_exponent(positions);
    let q = scaled_positions(positions, scale);

    // The half-edges of the input grouped by undirected edge.
    let mut keyed: Vec<(u64, u32)> = faces
        .par_iter()
        .enumerate()
        .flat_map_iter(|(f, face)| {
            (0..3).map(move |k| {
                let (a, b) = (face[k], face[(k + 1) % 3]);
                (((a.min(b) as u64) << 32) | a.max(b) as u64, (3 * f + k) as u32)
            })
        })
        .collect();
    keyed.par_sort_unstable();
    let mut group_start: Vec<usize> = (0..keyed.len())
        .filter(|&i| i == 0 || keyed[i - 1].0 != keyed[i].0)
        .collect();
    let n_edges = group_start.len();
    group_start.push(keyed.len());

    // Lengths of the distinct edges, then per face corner.
    let edge_length = |key: u64| norm(sub(q[(key & 0xffff_ffff) as usize], q[(key >> 32) as usize]));
    let mean_edge = group_start[..n_edges]
        .par_iter()
        .map(|&i| edge_length(keyed[i].0))
        .sum::<f64>()
        / n_edges as f64;
    if !(mean_edge > 0.0 && mean_edge.is_finite()) {
        return Err(MeshError::DegenerateMesh { area: 0.0 });
    }
    let mut lengths: Vec<[f64; 3]> = faces
        .par_iter()
        .map(|f| [0, 1, 2].map(|k| norm(sub(q[f[(k + 1) % 3] as usize], q[f[k] as usize]))))
        .collect();
    mollify(&mut lengths, mean_edge, mollify_factor);
    if let Some((f, l)) = lengths
        .iter()
        .enumerate()
        .find(|(_, l)| super::triangle_area(l[0], l[1], l[2]) <= 0.0)
    {
        return Err(MeshError::DegenerateIntrinsicTriangle {
            triangle: 2 * f,
            lengths: l.map(|x| crate::mesh::mul_pow2(x, scale)),
        });
    }

    // Cover half-edges: front slot 6f + k carries input edge k of face f, back slot
    // 6f + 5 − k the same edge reversed.
    let triangles: Vec<[u32; 3]> = faces.par_iter().flat_map_iter(|f| [*f, [f[0], f[2], f[1]]]).collect();
    let lengths: Vec<[f64; 3]> = lengths
        .into_par_iter()
        .flat_map_iter(|l| [l, [l[2], l[1], l[0]]])
        .collect();

    // Glue the sheets around every edge.
    let pairs: Vec<[u32; 2]> = group_start
        .par_windows(2)
        .flat_map_iter(|w| glue_edge(&keyed[w[0]..w[1]], faces, &q))
        .collect();
    drop(keyed);
    let mut twin = vec![u32::MAX; 6 * n_faces];
    for [x, y] in pairs {
        twin[x as usize] = y;
        twin[y as usize] = x;
    }
    Ok(IntrinsicTriangulation::from_parts(n, triangles, twin, lengths, scale))
}

/// The gluing around one input edge: the (false sheet, true sheet) pairs of consecutive
/// faces, where the true sheet of a face runs a → b (a < b the edge's vertices).
fn glue_edge(group: &[(u64, u32)], faces: &[[u32; 3]], q: &[[f64; 3]]) -> Vec<[u32; 2]> {
    let key = group[0].0;
    let (a, b) = ((key >> 32) as u32, (key & 0xffff_ffff) as u32);
    // Each input half-edge 3f + k: its (true, false) sheets.
    let sheets = |h: u32| -> (u32, u32, usize) {
        let (f, k) = (h as usize / 3, h as usize % 3);
        let (front, back) = ((6 * f + k) as u32, (6 * f + 5 - k) as u32);
        if faces[f][k] == a {
            (front, back, f)
        } else {
            (back, front, f)
        }
    };
    let mut around: Vec<(u32, u32, usize)> = group.iter().map(|&(_, h)| sheets(h)).collect();
    if around.len() >= 3 {
        // Angle of each face's third vertex about the axis b − a, in a right-handed basis
        // (x, y, axis); sorted decreasing (ties keep the input order).
        let pa = q[a as usize];
        let axis = sub(q[b as usize], pa);
        let axis_len = norm(axis);
        let (x, y) = tangent_basis(axis.map(|c| c / axis_len));
        let angle = |f: usize| {
            let face = faces[f];
            let w = face.iter().copied().find(|&v| v != a && v != b).unwrap_or(a);
            let out = sub(q[w as usize], pa);
            dot(y, out).atan2(dot(x, out))
        };
        let mut keyed: Vec<(f64, (u32, u32, usize))> = around
            .iter()
            .map(|&s| {
                let theta = angle(s.2);
                // A NaN angle (a zero-length edge) sorts last; any order glues validly.
                (if theta.is_nan() { f64::NEG_INFINITY } else { theta }, s)
            })
            .collect();
        keyed.sort_by(|p, q| q.0.total_cmp(&p.0));
        around = keyed.into_iter().map(|(_, s)| s).collect();
    }
    let k = around.len();
    (0..k).map(|i| [around[i].1, around[(i + 1) % k].0]).collect()
}
