//! Tests of `shrec_bench::transform` against independent brute-force references.

use mesh_fem::generate::{bumpy, grid, icosphere, irregular_sphere};
use mesh_fem::graph::EdgeGraph;
use mesh_fem::{assemble, AssemblyParams, MeshError, TriMesh};
use shrec_bench::transform::{
    close_pairs, largest_component, qem_decimate, remesh, submesh, vertex_normals, weld_vertices, QemDecimator,
    QemParams,
};
use shrec_bench::BenchError;
use std::collections::{BTreeMap, HashMap};

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn face_normal(m: &TriMesh, f: usize) -> [f64; 3] {
    let [a, b, c] = m.corners(f);
    cross(
        [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
        [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
    )
}

/// Floyd–Warshall on the edge graph built directly from the faces (independent of EdgeGraph).
fn floyd(m: &TriMesh, unit: bool) -> Vec<Vec<f64>> {
    let n = m.n_vertices();
    let mut d = vec![vec![f64::INFINITY; n]; n];
    for (i, row) in d.iter_mut().enumerate() {
        row[i] = 0.0;
    }
    let p = m.positions();
    for f in m.faces() {
        for k in 0..3 {
            let (a, b) = (f[k] as usize, f[(k + 1) % 3] as usize);
            let w = if unit { 1.0 } else { dist(p[a], p[b]) };
            d[a][b] = d[a][b].min(w);
            d[b][a] = d[b][a].min(w);
        }
    }
    for k in 0..n {
        for i in 0..n {
            for j in 0..n {
                let via = d[i][k] + d[k][j];
                if via < d[i][j] {
                    d[i][j] = via;
                }
            }
        }
    }
    d
}

/// Edge → number of faces.
fn edge_counts(m: &TriMesh) -> BTreeMap<(u32, u32), usize> {
    let mut e = BTreeMap::new();
    for f in m.faces() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *e.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    e
}

/// Closed 2-manifold check: every edge in exactly two faces with opposite orientation, every
/// vertex link one cycle.
fn assert_closed_manifold(m: &TriMesh) {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for f in m.faces() {
        for k in 0..3 {
            *directed.entry((f[k], f[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(a, b), &c) in &directed {
        assert_eq!(c, 1, "directed edge ({a},{b}) used {c} times");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "edge ({a},{b}) has no opposite half-edge"
        );
    }
    // Vertex links: the opposite edges of the faces around v form one cycle.
    let mut link: Vec<HashMap<u32, u32>> = vec![HashMap::new(); m.n_vertices()];
    for f in m.faces() {
        for k in 0..3 {
            let (v, a, b) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
            assert!(
                link[v as usize].insert(a, b).is_none(),
                "vertex {v} has a non-manifold link"
            );
        }
    }
    for (v, l) in link.iter().enumerate() {
        assert!(l.len() >= 3, "vertex {v} has valence {}", l.len());
        let start = *l.keys().next().unwrap();
        let (mut cur, mut steps) = (start, 0);
        loop {
            cur = l[&cur];
            steps += 1;
            if cur == start {
                break;
            }
            assert!(steps <= l.len(), "link of vertex {v} is not a cycle");
        }
        assert_eq!(steps, l.len(), "link of vertex {v} has several cycles");
    }
}

#[test]
fn dijkstra_matches_floyd_warshall() {
    for m in [icosphere(1), irregular_sphere(1, 3.0), grid(6, 5)] {
        let g = EdgeGraph::new(&m);
        let reference = floyd(&m, false);
        for s in [0u32, 7, (m.n_vertices() - 1) as u32] {
            let d = g.distances(&[s], f64::INFINITY).unwrap();
            for (v, &dv) in d.iter().enumerate() {
                assert!((dv - reference[s as usize][v]).abs() <= 1e-12, "source {s}, vertex {v}");
            }
        }
        // Multi-source = pointwise minimum; a cutoff leaves farther vertices at infinity.
        let d = g.distances(&[1, 5], f64::INFINITY).unwrap();
        let cut = 0.5 * d.iter().cloned().fold(0.0, f64::max);
        let dc = g.distances(&[1, 5], cut).unwrap();
        for v in 0..m.n_vertices() {
            let want = reference[1][v].min(reference[5][v]);
            assert!((d[v] - want).abs() <= 1e-12);
            if want <= cut {
                assert!((dc[v] - want).abs() <= 1e-12);
            } else {
                assert!(dc[v].is_infinite());
            }
        }
        // Hop counts against unit-weight Floyd.
        let hops_ref = floyd(&m, true);
        let h = g.hops(&[3], 2).unwrap();
        for v in 0..m.n_vertices() {
            let want = hops_ref[3][v];
            if want <= 2.0 {
                assert_eq!(h[v] as f64, want);
            } else {
                assert_eq!(h[v], u32::MAX);
            }
        }
    }
}

#[test]
fn edge_graph_basics_and_errors() {
    let m = icosphere(2);
    let g = EdgeGraph::new(&m);
    // Closed triangle mesh: E = 3F/2.
    assert_eq!(g.n_edges(), 3 * m.n_faces() / 2);
    assert_eq!(g.neighbors(0).len(), 5); // icosahedron corners keep valence 5
    assert!(matches!(
        g.distances(&[m.n_vertices() as u32], 1.0),
        Err(MeshError::VertexOutOfRange { .. })
    ));
    assert!(matches!(
        g.hops(&[u32::MAX], 1),
        Err(MeshError::VertexOutOfRange { .. })
    ));
}

#[test]
fn submesh_keeps_faces_inside_the_mask() {
    let m = bumpy(2);
    let keep: Vec<bool> = m.positions().iter().map(|p| p[2] > -0.2).collect();
    let d = submesh(&m, &keep).unwrap();
    let expected: Vec<[u32; 3]> = m
        .faces()
        .iter()
        .filter(|f| f.iter().all(|&v| keep[v as usize]))
        .copied()
        .collect();
    assert_eq!(d.mesh.n_faces(), expected.len());
    for (new_f, old_f) in d.mesh.faces().iter().zip(&expected) {
        assert_eq!(new_f.map(|v| d.source_vertex[v as usize]), *old_f);
    }
    for (i, &s) in d.source_vertex.iter().enumerate() {
        assert!(keep[s as usize]);
        assert_eq!(d.mesh.positions()[i], m.positions()[s as usize]);
    }
    assert!(d.source_vertex.windows(2).all(|w| w[0] < w[1]));
    assert!(assemble(&d.mesh, &AssemblyParams::default()).is_ok());
    assert!(matches!(submesh(&m, &keep[1..]), Err(BenchError::MaskLength { .. })));
    assert!(matches!(
        submesh(&m, &vec![false; m.n_vertices()]),
        Err(BenchError::Mesh(MeshError::Empty { .. }))
    ));
}

#[test]
fn largest_component_of_two_spheres() {
    let (pa, fa) = icosphere(1).into_parts();
    let (pb, fb) = icosphere(2).into_parts();
    let off = pa.len() as u32;
    let positions: Vec<[f64; 3]> = pa
        .iter()
        .copied()
        .chain(pb.iter().map(|p| [p[0] + 5.0, p[1], p[2]]))
        .collect();
    let faces: Vec<[u32; 3]> = fa
        .iter()
        .copied()
        .chain(fb.iter().map(|f| f.map(|v| v + off)))
        .collect();
    let m = TriMesh::new(positions, faces).unwrap();
    let d = largest_component(&m).unwrap();
    assert_eq!(d.mesh.n_vertices(), pb.len());
    assert_eq!(d.mesh.n_faces(), fb.len());
    assert!(d.source_vertex.iter().all(|&v| v >= off));
}

#[test]
fn close_pairs_match_brute_force() {
    let m = bumpy(3);
    let p = m.positions();
    for eps in [0.02, 0.1] {
        let got = close_pairs(p, eps);
        let mut want = Vec::new();
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                if dist(p[i], p[j]) < eps {
                    want.push([i as u32, j as u32]);
                }
            }
        }
        assert_eq!(got, want, "eps {eps}");
    }
    assert!(close_pairs(p, 0.0).is_empty());
}

#[test]
fn welding_merges_pairs_and_drops_collapsed_faces() {
    // Two antipodal vertices of a sphere: welding makes a pinch, no face disappears.
    let m = icosphere(2);
    let p = m.positions();
    let a = 0u32;
    let b = (0..p.len())
        .min_by(|&i, &j| {
            dist(p[i], [-p[0][0], -p[0][1], -p[0][2]]).total_cmp(&dist(p[j], [-p[0][0], -p[0][1], -p[0][2]]))
        })
        .unwrap() as u32;
    let d = weld_vertices(&m, &[[b, a]]).unwrap();
    assert_eq!(d.mesh.n_vertices(), m.n_vertices() - 1);
    assert_eq!(d.mesh.n_faces(), m.n_faces());
    assert!(!d.source_vertex.contains(&b));
    for (i, &s) in d.source_vertex.iter().enumerate() {
        assert_eq!(d.mesh.positions()[i], p[s as usize]);
    }
    // Welding the two ends of an edge kills its two faces.
    let e = EdgeGraph::new(&m).neighbors(3)[0];
    let d = weld_vertices(&m, &[[3, e]]).unwrap();
    assert_eq!(d.mesh.n_faces(), m.n_faces() - 2);
    assert!(d
        .mesh
        .faces()
        .iter()
        .all(|f| f[0] != f[1] && f[1] != f[2] && f[0] != f[2]));
    // Transitive classes collapse to the smallest index.
    let d = weld_vertices(&m, &[[40, 20], [20, 30]]).unwrap();
    assert!(d.source_vertex.contains(&20));
    assert!(!d.source_vertex.contains(&30) && !d.source_vertex.contains(&40));
    assert!(matches!(
        weld_vertices(&m, &[[0, 10_000]]),
        Err(BenchError::VertexIndex { .. })
    ));
}

fn check_decimation(m: &TriMesh, d: &shrec_bench::transform::DerivedMesh) {
    assert!(d.source_vertex.windows(2).all(|w| w[0] < w[1]));
    for (i, &s) in d.source_vertex.iter().enumerate() {
        assert_eq!(d.mesh.positions()[i], m.positions()[s as usize], "survivor {s} moved");
    }
    for f in 0..d.mesh.n_faces() {
        assert!(d.mesh.face_area(f) > 0.0, "face {f} degenerate");
    }
    assert!(assemble(&d.mesh, &AssemblyParams::default()).is_ok());
}

#[test]
fn qem_on_sphere_keeps_outward_manifold_and_positions() {
    let m = icosphere(3);
    let n = m.n_vertices();
    for keep in [0.8, 0.4, 0.15] {
        let target = (keep * n as f64) as usize;
        let d = qem_decimate(&m, target).unwrap();
        assert_eq!(d.mesh.n_vertices(), target);
        check_decimation(&m, &d);
        assert_closed_manifold(&d.mesh);
        // Euler characteristic of the sphere.
        let e = edge_counts(&d.mesh).len() as i64;
        assert_eq!(d.mesh.n_vertices() as i64 - e + d.mesh.n_faces() as i64, 2);
        // Convex surface: every face normal points outward (no flip).
        for f in 0..d.mesh.n_faces() {
            let nrm = face_normal(&d.mesh, f);
            let [a, b, c] = d.mesh.corners(f);
            let centroid = [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0);
            assert!(
                nrm.iter().zip(&centroid).map(|(x, y)| x * y).sum::<f64>() > 0.0,
                "face {f} flipped"
            );
        }
    }
}

#[test]
fn qem_on_bumpy_sphere_and_open_grid() {
    let m = bumpy(3);
    let normals = vertex_normals(&m);
    let d = qem_decimate(&m, m.n_vertices() / 5).unwrap();
    assert!(
        d.mesh.n_vertices() <= m.n_vertices() / 5 + m.n_vertices() / 50,
        "stalled at {}",
        d.mesh.n_vertices()
    );
    check_decimation(&m, &d);
    assert_closed_manifold(&d.mesh);
    // No face turned against the original surface: its normal agrees with the input vertex
    // normals of its corners.
    for f in 0..d.mesh.n_faces() {
        let nrm = face_normal(&d.mesh, f);
        let avg = d.mesh.faces()[f]
            .iter()
            .map(|&v| normals[d.source_vertex[v as usize] as usize])
            .fold([0.0; 3], |s, n| [s[0] + n[0], s[1] + n[1], s[2] + n[2]]);
        assert!(
            nrm.iter().zip(&avg).map(|(x, y)| x * y).sum::<f64>() > 0.0,
            "face {f} flipped"
        );
    }

    // Open grid: boundary vertices are never removed and the boundary stays a single loop.
    let g = grid(12, 12);
    let boundary: Vec<u32> = (0..g.n_vertices() as u32)
        .filter(|&v| {
            let p = g.positions()[v as usize];
            p[0] == 0.0 || p[0] == 1.0 || p[1] == 0.0 || p[1] == 1.0
        })
        .collect();
    let mut dec = QemDecimator::new(&g, QemParams::default()).unwrap();
    dec.collapse_to(60);
    let d = dec.snapshot().unwrap();
    check_decimation(&g, &d);
    for b in &boundary {
        assert!(d.source_vertex.contains(b), "boundary vertex {b} removed");
    }
    let boundary_edges = edge_counts(&d.mesh).values().filter(|&&c| c == 1).count();
    assert_eq!(boundary_edges, boundary.len());
    assert!(edge_counts(&d.mesh).values().all(|&c| c <= 2));
    for f in 0..d.mesh.n_faces() {
        assert!(face_normal(&d.mesh, f)[2] > 0.0, "grid face {f} flipped");
    }
}

#[test]
fn qem_is_nested_and_rejects_bad_parameters() {
    let m = icosphere(3);
    let mut dec = QemDecimator::new(&m, QemParams::default()).unwrap();
    dec.collapse_to(400);
    let a = dec.snapshot().unwrap();
    dec.collapse_to(200);
    let b = dec.snapshot().unwrap();
    assert!(b.source_vertex.iter().all(|v| a.source_vertex.contains(v)));
    assert_eq!(b, qem_decimate(&m, 200).unwrap());
    let bad = QemParams {
        min_normal_cos: 2.0,
        ..QemParams::default()
    };
    assert!(matches!(QemDecimator::new(&m, bad), Err(BenchError::Argument(_))));
}

/// The nearest distance from `p` to the triangle (a, b, c) (brute force over its plane, edges
/// and corners).
fn point_triangle_distance(p: [f64; 3], [a, b, c]: [[f64; 3]; 3]) -> f64 {
    let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
    let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let segment = |x: [f64; 3], y: [f64; 3]| {
        let d = sub(y, x);
        let s = (dot(sub(p, x), d) / dot(d, d)).clamp(0.0, 1.0);
        dist(p, [x[0] + s * d[0], x[1] + s * d[1], x[2] + s * d[2]])
    };
    let n = cross(sub(b, a), sub(c, a));
    let h = dot(sub(p, a), n) / dot(n, n);
    let q = [p[0] - h * n[0], p[1] - h * n[1], p[2] - h * n[2]];
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(x, y)| dot(cross(sub(y, x), sub(q, x)), n) >= 0.0);
    if inside {
        dist(p, q)
    } else {
        segment(a, b).min(segment(b, c)).min(segment(c, a))
    }
}

#[test]
fn remesh_gives_each_seed_its_own_triangulation_of_the_same_surface() {
    let m = bumpy(3);
    let target = 1500;
    let a = remesh(&m, target, 1).unwrap();
    let b = remesh(&m, target, 2).unwrap();
    for r in [&a, &b] {
        assert!(
            r.n_vertices() <= target && r.n_vertices() >= target - target / 50,
            "{}",
            r.n_vertices()
        );
        assert_closed_manifold(r);
        // Every vertex is a point of the input surface (the split keeps it; QEM keeps
        // positions).
        for &p in r.positions() {
            let d = (0..m.n_faces())
                .map(|f| point_triangle_distance(p, m.corners(f)))
                .fold(f64::INFINITY, f64::min);
            assert!(d < 1e-12, "vertex {p:?} is {d} off the surface");
        }
        assert!(assemble(r, &AssemblyParams::default()).is_ok());
    }
    // The same seed, the same mesh; another seed, other points: two seeds share (at most) the
    // input's own vertices, and the points each adds on the edges are its own.
    assert_eq!(remesh(&m, target, 1).unwrap(), a);
    let shared = a.positions().iter().filter(|p| b.positions().contains(p)).count();
    let own = a.positions().iter().filter(|p| m.positions().contains(p)).count();
    assert!(
        a.n_vertices() - own > target / 2,
        "only {} new points",
        a.n_vertices() - own
    );
    assert!(shared <= own + target / 100, "{shared} shared, {own} of the input's");
    assert!(matches!(remesh(&m, 3, 1), Err(BenchError::Argument(_))));
}
