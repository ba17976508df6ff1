//! Local triangulations of point neighbourhoods (Sharp & Crane 2020, Sect. 5): the tangent
//! plane of each point from its neighbours, and the triangles at the point of the Delaunay
//! triangulation of the point and its neighbours projected onto that plane.

use crate::vec3::{dot, norm, sub, tangent_basis};

/// The eigenvalues (ascending) and unit eigenvectors of a symmetric 3 × 3 matrix, by cyclic
/// Jacobi rotations (accurate to rounding for every symmetric matrix, cheap at 3 × 3).
pub(crate) fn symmetric_eigen3(mut a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        let scale = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
        if off <= 1e-300 || off <= 1e-17 * scale {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            // The rotation that zeroes a[p][q] (Golub & Van Loan, Alg. 8.4.1).
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (row_p, row_q) = (a[p], a[q]);
            for k in 0..3 {
                a[p][k] = c * row_p[k] - s * row_q[k];
                a[q][k] = s * row_p[k] + c * row_q[k];
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&x, &y| a[x][x].total_cmp(&a[y][y]));
    let values = idx.map(|k| a[k][k]);
    let vectors = idx.map(|k| [v[0][k], v[1][k], v[2][k]]);
    (values, vectors)
}

/// The unit normal of the least-squares plane through `center` and its neighbours: the
/// eigenvector of the smallest eigenvalue of their covariance about their centroid (all
/// k + 1 points). `None` if the points do not span a plane (the two largest eigenvalues are
/// not both clearly positive).
pub(crate) fn pca_normal(points: &[[f64; 3]], center: usize, neighbours: &[u32]) -> Option<[f64; 3]> {
    let m = (neighbours.len() + 1) as f64;
    let origin = points[center];
    // Coordinates relative to the center keep the covariance accurate far from the origin.
    let rel = |j: u32| sub(points[j as usize], origin);
    let mut c = [0.0; 3];
    for &j in neighbours {
        let d = rel(j);
        (0..3).for_each(|a| c[a] += d[a]);
    }
    let c = c.map(|x| x / m);
    let mut cov = [[0.0; 3]; 3];
    let mut add = |d: [f64; 3]| {
        let e = sub(d, c);
        for a in 0..3 {
            for b in 0..3 {
                cov[a][b] += e[a] * e[b];
            }
        }
    };
    add([0.0; 3]);
    for &j in neighbours {
        add(rel(j));
    }
    let (values, vectors) = symmetric_eigen3(cov);
    if !(values[1] > 1e-12 * values[2] && values[2] > 0.0) {
        return None;
    }
    let n = vectors[0];
    let len = norm(n);
    (len > 0.0).then(|| n.map(|x| x / len))
}

/// Scratch space of [`one_ring`], reused across points.
#[derive(Default)]
pub(crate) struct Scratch {
    /// (dual point, neighbour slot) pairs; the center is slot `u32::MAX` at the origin.
    dual: Vec<([f64; 2], u32)>,
    hull: Vec<([f64; 2], u32)>,
    planar: Vec<[f64; 2]>,
}

/// Appends to `out` the triangles at `center` of the Delaunay triangulation of the center
/// and its neighbours projected onto the plane through the center with unit normal `normal`:
/// `[center, a, b]` for consecutive Delaunay neighbours a, b counter-clockwise about the
/// normal.
///
/// The Delaunay neighbours of the center are the neighbours whose perpendicular bisectors
/// bound its Voronoi cell `{x : x·q ≤ |q|²/2}`; by polarity they are the vertices of the
/// convex hull of the origin and the dual points `q/|q|²`, in the same angular order, and two
/// consecutive hull vertices (neither the origin) share a Voronoi vertex, i.e. a Delaunay
/// triangle with the center. When the origin is itself a hull vertex the center lies on the
/// boundary of its neighbourhood and no triangle spans the gap. O(k log k) per point; a
/// neighbour that projects onto the center is left out, and a triangle whose angle at the
/// center is not strictly between 0 and π (collinear projections) is not emitted.
pub(crate) fn one_ring(
    points: &[[f64; 3]],
    center: usize,
    neighbours: &[u32],
    normal: [f64; 3],
    scratch: &mut Scratch,
    out: &mut Vec<[u32; 3]>,
) {
    let (x, y) = tangent_basis(normal);
    let p = points[center];
    scratch.dual.clear();
    scratch.planar.clear();
    scratch.dual.push(([0.0, 0.0], u32::MAX));
    for (slot, &j) in neighbours.iter().enumerate() {
        let d = sub(points[j as usize], p);
        let q = [dot(x, d), dot(y, d)];
        scratch.planar.push(q);
        let r2 = q[0] * q[0] + q[1] * q[1];
        if r2 > 0.0 && r2.is_finite() {
            scratch.dual.push(([q[0] / r2, q[1] / r2], slot as u32));
        }
    }
    convex_hull(&mut scratch.dual, &mut scratch.hull);
    let h = scratch.hull.len();
    if h < 3 {
        return;
    }
    for i in 0..h {
        let (a, b) = (scratch.hull[i].1, scratch.hull[(i + 1) % h].1);
        if a == u32::MAX || b == u32::MAX {
            continue;
        }
        let (qa, qb) = (scratch.planar[a as usize], scratch.planar[b as usize]);
        let s = qa[0] * qb[1] - qa[1] * qb[0];
        let scale = (qa[0].hypot(qa[1])) * (qb[0].hypot(qb[1]));
        if s > 1e-12 * scale {
            out.push([center as u32, neighbours[a as usize], neighbours[b as usize]]);
        }
    }
}

/// The convex hull of `pts` counter-clockwise, without collinear points (Andrew's monotone
/// chain); `pts` is sorted in place.
fn convex_hull(pts: &mut [([f64; 2], u32)], hull: &mut Vec<([f64; 2], u32)>) {
    hull.clear();
    pts.sort_by(|a, b| a.0[0].total_cmp(&b.0[0]).then(a.0[1].total_cmp(&b.0[1])));
    if pts.len() < 3 {
        hull.extend_from_slice(pts);
        return;
    }
    let turn = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    for &p in pts.iter() {
        while hull.len() >= 2 && turn(hull[hull.len() - 2].0, hull[hull.len() - 1].0, p.0) <= 0.0 {
            hull.pop();
        }
        hull.push(p);
    }
    let lower = hull.len() + 1;
    for &p in pts.iter().rev().skip(1) {
        while hull.len() >= lower && turn(hull[hull.len() - 2].0, hull[hull.len() - 1].0, p.0) <= 0.0 {
            hull.pop();
        }
        hull.push(p);
    }
    hull.pop();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_eigen_of_a_rotated_diagonal_matrix() {
        // R diag(1, 4, 9) Rᵀ for a rotation about (1, 2, 2)/3.
        let (c, s) = (0.6f64, 0.8f64);
        let u = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let cross_term = match (i, j) {
                    (0, 1) => -u[2],
                    (1, 0) => u[2],
                    (0, 2) => u[1],
                    (2, 0) => -u[1],
                    (1, 2) => -u[0],
                    (2, 1) => u[0],
                    _ => 0.0,
                };
                r[i][j] = if i == j { c } else { 0.0 } + (1.0 - c) * u[i] * u[j] + s * cross_term;
            }
        }
        let d = [1.0, 4.0, 9.0];
        let mut a = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] = (0..3).map(|k| r[i][k] * d[k] * r[j][k]).sum();
            }
        }
        let (values, vectors) = symmetric_eigen3(a);
        for k in 0..3 {
            assert!((values[k] - d[k]).abs() < 1e-13, "{values:?}");
            let col = [r[0][k], r[1][k], r[2][k]];
            assert!((dot(col, vectors[k]).abs() - 1.0).abs() < 1e-13);
        }
    }

    #[test]
    fn one_ring_of_a_hexagon_center_is_six_triangles() {
        let mut points = vec![[0.0, 0.0, 0.0]];
        for k in 0..6 {
            let a = k as f64 * std::f64::consts::PI / 3.0;
            points.push([a.cos(), a.sin(), 0.0]);
        }
        // Farther points that are not Delaunay neighbours of the center.
        for k in 0..6 {
            let a = (k as f64 + 0.5) * std::f64::consts::PI / 3.0;
            points.push([2.0 * a.cos(), 2.0 * a.sin(), 0.0]);
        }
        let neighbours: Vec<u32> = (1..13).collect();
        let normal = pca_normal(&points, 0, &neighbours).unwrap();
        assert!((normal[2].abs() - 1.0).abs() < 1e-14);
        let mut out = Vec::new();
        one_ring(
            &points,
            0,
            &neighbours,
            [0.0, 0.0, 1.0],
            &mut Scratch::default(),
            &mut out,
        );
        assert_eq!(out.len(), 6);
        for t in &out {
            assert!(t[1] <= 6 && t[2] <= 6, "{t:?}");
            // Counter-clockwise about +z: consecutive hexagon vertices.
            assert_eq!(t[2], t[1] % 6 + 1, "{t:?}");
        }
        // A boundary point (the first hexagon vertex with only the hexagon around it on one
        // side) gets no triangle across its gap.
        let half: Vec<u32> = vec![0, 2, 6];
        let mut out = Vec::new();
        one_ring(&points, 1, &half, [0.0, 0.0, 1.0], &mut Scratch::default(), &mut out);
        assert_eq!(out.len(), 2, "{out:?}");
    }

    #[test]
    fn collinear_neighbours_give_no_triangle() {
        let points: Vec<[f64; 3]> = (0..8).map(|i| [i as f64, 0.0, 0.0]).collect();
        let neighbours: Vec<u32> = (1..8).collect();
        assert_eq!(pca_normal(&points, 0, &neighbours), None);
        let mut out = Vec::new();
        one_ring(
            &points,
            3,
            &[0, 1, 2, 4, 5],
            [0.0, 0.0, 1.0],
            &mut Scratch::default(),
            &mut out,
        );
        assert!(out.is_empty());
    }
}
