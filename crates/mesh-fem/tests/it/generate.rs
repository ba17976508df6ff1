//! Tests of the mesh generators in `mesh_fem::generate`: counts, geometry (unit sphere, unit
//! square), orientation (positive signed volume, +z normals), closedness and the face-area
//! spread of the irregular sphere.

use mesh_fem::generate::{bumpy, grid, icosphere, icosphere_vertex_count, irregular_sphere, torus, uv_sphere};
use mesh_fem::TriMesh;
use std::collections::HashMap;

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Signed volume enclosed by a closed mesh, Σ_T p0·(p1 × p2)/6 (positive if oriented outward).
fn signed_volume(mesh: &TriMesh) -> f64 {
    (0..mesh.n_faces())
        .map(|f| {
            let [a, b, c] = mesh.corners(f);
            dot(a, cross(b, c)) / 6.0
        })
        .sum()
}

/// Directed edge counts: a closed, consistently oriented 2-manifold uses each directed edge
/// exactly once and its reverse exactly once.
fn assert_closed_oriented_manifold(name: &str, mesh: &TriMesh) {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for f in mesh.faces() {
        for k in 0..3 {
            *directed.entry((f[k], f[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(a, b), &count) in &directed {
        assert_eq!(count, 1, "{name}: directed edge ({a},{b}) used {count} times");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "{name}: edge ({a},{b}) is a boundary edge or inconsistently oriented"
        );
    }
}

/// Euler characteristic V − E + F.
fn euler_characteristic(mesh: &TriMesh) -> i64 {
    let mut edges = std::collections::HashSet::new();
    for f in mesh.faces() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    mesh.n_vertices() as i64 - edges.len() as i64 + mesh.n_faces() as i64
}

fn face_areas(mesh: &TriMesh) -> Vec<f64> {
    (0..mesh.n_faces()).map(|f| mesh.face_area(f)).collect()
}

fn assert_on_unit_sphere(name: &str, mesh: &TriMesh) {
    for (i, p) in mesh.positions().iter().enumerate() {
        let r = dot(*p, *p).sqrt();
        assert!((r - 1.0).abs() < 1e-14, "{name}: |p{i}| = {r}");
    }
}

#[test]
fn icosphere_counts_geometry_and_orientation() {
    for level in 0..=4 {
        let mesh = icosphere(level);
        let name = format!("icosphere({level})");
        assert_eq!(mesh.n_vertices(), 10 * 4usize.pow(level) + 2, "{name}");
        assert_eq!(mesh.n_vertices(), icosphere_vertex_count(level), "{name}");
        assert_eq!(mesh.n_faces(), 20 * 4usize.pow(level), "{name}");
        assert_on_unit_sphere(&name, &mesh);
        assert_closed_oriented_manifold(&name, &mesh);
        assert_eq!(euler_characteristic(&mesh), 2, "{name}");
        // Inscribed polyhedron: its volume is below 4π/3 and approaches it.
        let v = signed_volume(&mesh);
        let ball = 4.0 * std::f64::consts::PI / 3.0;
        assert!(v > 0.0 && v < ball, "{name}: volume {v}");
        if level == 4 {
            // Measured: relative deficit 2.2e-3 at level 4 (it falls by ≈4 per level).
            assert!((v - ball) / ball > -4e-3, "{name}: volume {v}");
        }
        // Every face is oriented outward, not only the total.
        for f in 0..mesh.n_faces() {
            let [a, b, c] = mesh.corners(f);
            let n = cross(sub(b, a), sub(c, a));
            assert!(dot(n, a) > 0.0, "{name}: face {f} points inward");
        }
    }
    // Near-uniform: face areas vary by less than a factor 2 at level 4.
    let areas = face_areas(&icosphere(4));
    let (lo, hi) = areas.iter().fold((f64::MAX, 0.0f64), |(l, h), &a| (l.min(a), h.max(a)));
    assert!(hi / lo < 2.0, "icosphere(4) area ratio {}", hi / lo);
}

#[test]
fn uv_sphere_counts_geometry_and_orientation() {
    for (rings, segments) in [(2, 3), (8, 12), (16, 24)] {
        let mesh = uv_sphere(rings, segments);
        let name = format!("uv_sphere({rings}, {segments})");
        assert_eq!(mesh.n_vertices(), 2 + (rings - 1) * segments, "{name}");
        assert_eq!(mesh.n_faces(), 2 * (rings - 1) * segments, "{name}");
        assert_on_unit_sphere(&name, &mesh);
        assert_closed_oriented_manifold(&name, &mesh);
        assert_eq!(euler_characteristic(&mesh), 2, "{name}");
        assert!(signed_volume(&mesh) > 0.0, "{name}");
    }
}

#[test]
fn grid_covers_the_unit_square_facing_up() {
    for (nx, ny) in [(2, 2), (3, 3), (20, 15)] {
        let mesh = grid(nx, ny);
        let name = format!("grid({nx}, {ny})");
        assert_eq!(mesh.n_vertices(), nx * ny, "{name}");
        assert_eq!(mesh.n_faces(), 2 * (nx - 1) * (ny - 1), "{name}");
        assert!((mesh.area() - 1.0).abs() < 1e-14, "{name}: area {}", mesh.area());
        for p in mesh.positions() {
            assert!(p[2] == 0.0 && (0.0..=1.0).contains(&p[0]) && (0.0..=1.0).contains(&p[1]));
        }
        for f in 0..mesh.n_faces() {
            let [a, b, c] = mesh.corners(f);
            assert!(cross(sub(b, a), sub(c, a))[2] > 0.0, "{name}: face {f} faces down");
        }
        // A disc: Euler characteristic 1.
        assert_eq!(euler_characteristic(&mesh), 1, "{name}");
    }
}

#[test]
fn torus_is_closed_genus_one_and_outward() {
    let (major, minor) = (1.0, 0.3);
    let mesh = torus(major, minor, 40, 16);
    assert_eq!(mesh.n_vertices(), 40 * 16);
    assert_eq!(mesh.n_faces(), 2 * 40 * 16);
    assert_closed_oriented_manifold("torus", &mesh);
    assert_eq!(euler_characteristic(&mesh), 0, "genus 1");
    // Volume 2π²Rr² (the inscribed polyhedron is a little smaller).
    let exact = 2.0 * std::f64::consts::PI.powi(2) * major * minor * minor;
    let v = signed_volume(&mesh);
    assert!(
        v > 0.0 && (v - exact).abs() / exact < 0.03,
        "torus volume {v} vs {exact}"
    );
    // Area 4π²Rr.
    let exact_area = 4.0 * std::f64::consts::PI.powi(2) * major * minor;
    assert!((mesh.area() - exact_area).abs() / exact_area < 0.02);
}

#[test]
fn irregular_sphere_has_face_areas_varying_by_a_thousand() {
    for level in [3, 4] {
        let mesh = irregular_sphere(level, 5.6);
        let name = format!("irregular_sphere({level}, 5.6)");
        assert_eq!(mesh.n_vertices(), icosphere_vertex_count(level), "{name}");
        assert_on_unit_sphere(&name, &mesh);
        assert_closed_oriented_manifold(&name, &mesh);
        assert!(signed_volume(&mesh) > 0.0, "{name}");
        let areas = face_areas(&mesh);
        let (lo, hi) = areas.iter().fold((f64::MAX, 0.0f64), |(l, h), &a| (l.min(a), h.max(a)));
        let ratio = hi / lo;
        eprintln!("{name}: max/min face area {ratio:.1}");
        // Measured: 927.5 at level 3 and 1103.1 at level 4. The conformal dilation scales areas
        // by s⁴ ≈ 983 between the poles; the discrete ratio also sees the icosphere's own
        // spread, so the band is [700, 1500].
        assert!((700.0..1500.0).contains(&ratio), "{name}: area ratio {ratio}");
    }
    // s = 1 is the identity map.
    let a = irregular_sphere(2, 1.0);
    let b = icosphere(2);
    for (p, q) in a.positions().iter().zip(b.positions()) {
        assert!(sub(*p, *q).iter().all(|c| c.abs() < 1e-14));
    }
}

#[test]
fn bumpy_is_a_closed_outward_sphere_like_surface() {
    let mesh = bumpy(3);
    assert_eq!(mesh.n_vertices(), icosphere_vertex_count(3));
    assert_closed_oriented_manifold("bumpy", &mesh);
    assert_eq!(euler_characteristic(&mesh), 2);
    assert!(signed_volume(&mesh) > 0.0);
    for p in mesh.positions() {
        let r = dot(*p, *p).sqrt();
        // r = 1 + 0.25·(…) + 0.15·(…) lies in [0.6, 1.4].
        assert!((0.6..=1.4).contains(&r), "radius {r}");
    }
    let areas = face_areas(&mesh);
    let (lo, hi) = areas.iter().fold((f64::MAX, 0.0f64), |(l, h), &a| (l.min(a), h.max(a)));
    assert!(
        hi / lo > 20.0,
        "bumpy should be irregularly sampled (ratio {})",
        hi / lo
    );
}
