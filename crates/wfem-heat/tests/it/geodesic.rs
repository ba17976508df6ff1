//! Geodesic distances (`wfem_heat::geodesic`) against closed forms: the Euclidean distance on a
//! flat grid (also from several sources and from a point on a face), the great-circle distance
//! on a fine sphere, the helix-free distance on an open cylinder, a 200-edge strip for the far
//! field; the one-ring at its exact edge lengths; unreachable components; every bad input.

use mesh_fem::generate::{grid, icosphere};
use mesh_fem::{Laplacian, TriMesh};
use wfem_heat::geodesic::{geodesic_distance, GeodesicMethod, GeodesicParams, GeodesicSolver, Source};
use wfem_heat::HeatError;

fn params(method: GeodesicMethod) -> GeodesicParams {
    GeodesicParams {
        method,
        ..GeodesicParams::default()
    }
}

/// Mean and max relative error against `exact`, leaving out the vertices where it is 0.
fn relative(d: &[f64], exact: &[f64]) -> (f64, f64) {
    let pairs: Vec<f64> = d
        .iter()
        .zip(exact)
        .filter(|(_, e)| **e > 1e-12)
        .map(|(x, e)| (x - e).abs() / e)
        .collect();
    (
        pairs.iter().sum::<f64>() / pairs.len() as f64,
        pairs.iter().cloned().fold(0.0, f64::max),
    )
}

fn euclidean(mesh: &TriMesh, from: [f64; 3]) -> Vec<f64> {
    mesh.positions()
        .iter()
        .map(|p| ((p[0] - from[0]).powi(2) + (p[1] - from[1]).powi(2) + (p[2] - from[2]).powi(2)).sqrt())
        .collect()
}

#[test]
fn flat_grid_distances_are_euclidean() {
    let mesh = grid(41, 41);
    let s = 20 * 41 + 20; // the centre
    let exact = euclidean(&mesh, mesh.positions()[s]);
    for (method, mean_bound, max_bound) in [
        (GeodesicMethod::FastMarching, 0.01, 0.05),
        (GeodesicMethod::Heat, 0.03, 0.2),
    ] {
        let d = geodesic_distance(&mesh, &[s as u32], &params(method)).unwrap();
        assert_eq!(d[s], 0.0);
        let (mean, max) = relative(&d, &exact);
        assert!(
            mean < mean_bound && max < max_bound,
            "{method:?}: mean {mean}, max {max}"
        );
    }
}

#[test]
fn the_one_ring_is_at_its_exact_edge_lengths() {
    let mesh = icosphere(4);
    let solver = GeodesicSolver::new(&mesh, &GeodesicParams::default()).unwrap();
    let d = solver.distance(&[7]).unwrap();
    let p = mesh.positions();
    let ring = mesh_fem::graph::VertexNeighbours::new(mesh.n_vertices(), mesh.faces());
    for &j in ring.of(7) {
        let edge = euclidean(&mesh, p[7])[j as usize];
        assert!(
            (d[j as usize] - edge).abs() <= 1e-12 * edge,
            "{} vs {edge}",
            d[j as usize]
        );
    }
}

#[test]
fn sphere_distances_are_great_circles() {
    let mesh = icosphere(5); // 10,242 vertices on the unit sphere
    let p = mesh.positions();
    let exact: Vec<f64> = p
        .iter()
        .map(|q| {
            (q[0] * p[0][0] + q[1] * p[0][1] + q[2] * p[0][2])
                .clamp(-1.0, 1.0)
                .acos()
        })
        .collect();
    let fmm = geodesic_distance(&mesh, &[0], &GeodesicParams::default()).unwrap();
    let heat = geodesic_distance(&mesh, &[0], &params(GeodesicMethod::Heat)).unwrap();
    let (fm, _) = relative(&fmm, &exact);
    let (hm, _) = relative(&heat, &exact);
    // The polyhedron is inscribed: its geodesics are up to ~0.1 % shorter than the sphere's.
    assert!(fm < 0.006, "fast marching {fm}");
    assert!(hm < 0.02, "heat {hm}");
    assert!(fm < hm, "fast marching {fm} should beat the heat method {hm}");
}

/// An open cylinder of radius 1 and height 2, `nu` × `nz` vertices.
fn cylinder(nu: usize, nz: usize) -> TriMesh {
    let mut positions = Vec::new();
    for k in 0..nz {
        for i in 0..nu {
            let a = 2.0 * std::f64::consts::PI * i as f64 / nu as f64;
            positions.push([a.cos(), a.sin(), 2.0 * k as f64 / (nz - 1) as f64]);
        }
    }
    let id = |i: usize, k: usize| (k * nu + i % nu) as u32;
    let mut faces = Vec::new();
    for k in 0..nz - 1 {
        for i in 0..nu {
            faces.push([id(i, k), id(i + 1, k), id(i + 1, k + 1)]);
            faces.push([id(i, k), id(i + 1, k + 1), id(i, k + 1)]);
        }
    }
    TriMesh::new(positions, faces).unwrap()
}

#[test]
fn cylinder_distances_unroll_to_the_plane() {
    let (nu, nz) = (96, 31);
    let mesh = cylinder(nu, nz);
    let s = 15 * nu; // angle 0, height 1
    let exact: Vec<f64> = mesh
        .positions()
        .iter()
        .map(|q| {
            let angle = q[1].atan2(q[0]).abs(); // the shorter way round
            (angle * angle + (q[2] - 1.0).powi(2)).sqrt()
        })
        .collect();
    let d = geodesic_distance(&mesh, &[s as u32], &GeodesicParams::default()).unwrap();
    let (mean, _) = relative(&d, &exact);
    assert!(mean < 0.01, "mean {mean}");
}

#[test]
fn far_field_of_a_long_strip_stays_finite_and_right() {
    // 200 edges long: the exact kernel e^{−d²/4t} would underflow, the resolvent does not.
    let mesh = {
        let g = grid(201, 3);
        let p: Vec<[f64; 3]> = g.positions().iter().map(|q| [q[0] * 200.0, q[1] * 2.0, 0.0]).collect();
        TriMesh::new(p, g.faces().to_vec()).unwrap()
    };
    let exact = euclidean(&mesh, mesh.positions()[201]);
    for method in [GeodesicMethod::FastMarching, GeodesicMethod::Heat] {
        let solver = GeodesicSolver::new(&mesh, &params(method)).unwrap();
        let (d, report) = solver.distance_from(&[Source::Vertex(201)]).unwrap();
        assert!(d.iter().all(|x| x.is_finite()));
        assert_eq!(report.heat_underflow, 0);
        let far = mesh.n_vertices() - 1;
        assert!(
            (d[far] - exact[far]).abs() < 0.02 * exact[far],
            "{method:?}: {} vs {}",
            d[far],
            exact[far]
        );
    }
}

#[test]
fn every_source_is_at_zero_and_the_nearest_one_counts() {
    let mesh = grid(31, 31);
    let sources = [0u32, 30, 31 * 31 - 1];
    let p = mesh.positions().to_vec();
    let exact: Vec<f64> = (0..mesh.n_vertices())
        .map(|v| {
            sources
                .iter()
                .map(|&s| euclidean(&mesh, p[s as usize])[v])
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    for method in [GeodesicMethod::FastMarching, GeodesicMethod::Heat] {
        let d = geodesic_distance(&mesh, &sources, &params(method)).unwrap();
        for &s in &sources {
            assert_eq!(d[s as usize], 0.0, "{method:?}");
        }
        let (mean, _) = relative(&d, &exact);
        assert!(mean < 0.03, "{method:?}: mean {mean}");
    }
}

#[test]
fn a_point_on_a_face_is_measured_from_where_it_is() {
    let mesh = grid(21, 21);
    let solver = GeodesicSolver::new(&mesh, &GeodesicParams::default()).unwrap();
    let face = 2 * (10 * 20 + 10);
    let corners = mesh.faces()[face];
    let w = [0.2, 0.5, 0.3];
    let p = mesh.positions();
    let x = (0..3).fold([0.0; 3], |a, k| {
        let c = p[corners[k] as usize];
        [a[0] + w[k] * c[0], a[1] + w[k] * c[1], a[2] + w[k] * c[2]]
    });
    let (d, _) = solver
        .distance_from(&[Source::Point {
            face: face as u32,
            barycentric: w,
        }])
        .unwrap();
    let (mean, _) = relative(&d, &euclidean(&mesh, x));
    assert!(mean < 0.01, "mean {mean}");
    // A point at a corner is that vertex.
    let (at_corner, _) = solver
        .distance_from(&[Source::Point {
            face: face as u32,
            barycentric: [1.0, 0.0, 0.0],
        }])
        .unwrap();
    let vertex = solver.distance(&[corners[0]]).unwrap();
    let (diff, _) = relative(&at_corner, &vertex);
    assert!(diff < 1e-9, "{diff}");
}

#[test]
fn refinement_is_more_accurate_and_points_map_to_the_refined_faces() {
    let mesh = icosphere(3);
    let p = mesh.positions();
    let exact: Vec<f64> = p
        .iter()
        .map(|q| {
            (q[0] * p[0][0] + q[1] * p[0][1] + q[2] * p[0][2])
                .clamp(-1.0, 1.0)
                .acos()
        })
        .collect();
    let coarse = geodesic_distance(&mesh, &[0], &GeodesicParams::default()).unwrap();
    let refined = GeodesicSolver::new(
        &mesh,
        &GeodesicParams {
            refine: 1,
            ..GeodesicParams::default()
        },
    )
    .unwrap();
    let fine = refined.distance(&[0]).unwrap();
    assert_eq!(fine.len(), mesh.n_vertices());
    // The refined polyhedron has the coarse one's geodesics: compare with the coarse exact
    // distances' sphere value only loosely, and with each other.
    let (c, _) = relative(&coarse, &exact);
    let (f, _) = relative(&fine, &exact);
    assert!(f < c, "refined {f} vs coarse {c}");
    // A point in the middle of a face lands in the refined middle triangle.
    let third = [1.0 / 3.0; 3];
    let (d, _) = refined
        .distance_from(&[Source::Point {
            face: 5,
            barycentric: third,
        }])
        .unwrap();
    assert!(d.iter().all(|x| x.is_finite() && *x >= 0.0));
}

#[test]
fn unreachable_components_are_infinite_never_nan() {
    let a = grid(6, 6);
    let mut positions = a.positions().to_vec();
    let mut faces = a.faces().to_vec();
    let offset = positions.len() as u32;
    positions.extend(a.positions().iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
    faces.extend(a.faces().iter().map(|f| f.map(|v| v + offset)));
    let mesh = TriMesh::new(positions, faces).unwrap();
    for method in [GeodesicMethod::FastMarching, GeodesicMethod::Heat] {
        let solver = GeodesicSolver::new(&mesh, &params(method)).unwrap();
        let (d, report) = solver.distance_from(&[Source::Vertex(0)]).unwrap();
        assert_eq!(report.unreachable, 36, "{method:?}");
        assert!(d[..36].iter().all(|x| x.is_finite()));
        assert!(d[36..].iter().all(|x| *x == f64::INFINITY));
        // One source in each component reaches everything.
        assert!(solver.distance(&[0, 40]).unwrap().iter().all(|x| x.is_finite()));
    }
}

#[test]
fn many_sources_give_one_row_each() {
    let mesh = icosphere(3);
    let solver = GeodesicSolver::new(&mesh, &GeodesicParams::default()).unwrap();
    let rows = solver.distance_each(&[0, 5, 9]).unwrap();
    assert_eq!(rows.len(), 3);
    for (row, &s) in rows.iter().zip(&[0u32, 5, 9]) {
        assert_eq!(row, &solver.distance(&[s]).unwrap());
    }
    // Symmetric up to the discretisation: d(a, b) ≈ d(b, a).
    assert!((rows[0][5] - rows[1][0]).abs() < 0.02 * rows[0][5]);
}

/// Fast marching keeps a query's state for the next query; queries from several threads at once
/// (plain threads sharing one solver, and rayon's distance_each) give the serial rows bit for
/// bit, and a later serial query is unchanged by them.
#[test]
fn concurrent_queries_equal_serial_ones() {
    let mesh = icosphere(4);
    let solver = GeodesicSolver::new(&mesh, &GeodesicParams::default()).unwrap();
    let sources: Vec<u32> = (0..12).map(|k| k * 211).collect();
    let serial: Vec<Vec<f64>> = sources.iter().map(|&s| solver.distance(&[s]).unwrap()).collect();
    std::thread::scope(|scope| {
        for t in 0..4 {
            let (solver, sources, serial) = (&solver, &sources, &serial);
            scope.spawn(move || {
                for round in 0..3 {
                    for k in 0..sources.len() {
                        // Each thread in its own order, so that the queries overlap differently.
                        let k = (k * (t + 1) + round) % sources.len();
                        let d = solver.distance(&[sources[k]]).unwrap();
                        assert!(d == serial[k], "thread {t}, source {}", sources[k]);
                    }
                }
            });
        }
    });
    assert_eq!(solver.distance_each(&sources).unwrap(), serial);
    assert_eq!(solver.distance(&[sources[3]]).unwrap(), serial[3]);
    // Several sources in one query after single-source ones: no state carried over.
    let both = solver.distance(&[sources[1], sources[7]]).unwrap();
    let fresh = GeodesicSolver::new(&mesh, &GeodesicParams::default()).unwrap();
    assert_eq!(both, fresh.distance(&[sources[1], sources[7]]).unwrap());
}

#[test]
fn the_cotangent_triangulation_is_selectable() {
    let mesh = icosphere(4);
    for method in [GeodesicMethod::FastMarching, GeodesicMethod::Heat] {
        let p = GeodesicParams {
            method,
            laplacian: Laplacian::Cotan,
            ..GeodesicParams::default()
        };
        // A Delaunay sphere: the same distances as the robust triangulation, to rounding.
        let a = geodesic_distance(&mesh, &[3], &p).unwrap();
        let b = geodesic_distance(&mesh, &[3], &params(method)).unwrap();
        let (diff, _) = relative(&a, &b);
        assert!(diff < 1e-4, "{method:?}: {diff}");
    }
}

#[test]
fn bad_input_gets_typed_errors() {
    let mesh = icosphere(2);
    let solver = GeodesicSolver::new(&mesh, &GeodesicParams::default()).unwrap();
    let n = mesh.n_vertices();
    assert!(matches!(
        solver.distance(&[]),
        Err(HeatError::InvalidParameter { name: "sources", .. })
    ));
    assert!(matches!(
        solver.distance(&[n as u32]),
        Err(HeatError::VertexOutOfRange { index, n_vertices }) if index == n && n_vertices == n
    ));
    for (face, w) in [
        (mesh.n_faces() as u32, [1.0, 0.0, 0.0]),
        (0, [f64::NAN, 0.5, 0.5]),
        (0, [-0.5, 1.0, 0.5]),
        (0, [0.2, 0.2, 0.2]),
    ] {
        let err = solver
            .distance_from(&[Source::Point { face, barycentric: w }])
            .unwrap_err();
        assert!(
            matches!(err, HeatError::InvalidParameter { name: "sources", .. }),
            "{err}"
        );
    }
    for t_coef in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let p = GeodesicParams {
            t_coef,
            ..GeodesicParams::default()
        };
        assert!(matches!(
            GeodesicSolver::new(&mesh, &p),
            Err(HeatError::InvalidParameter { name: "t_coef", .. })
        ));
    }
    let p = GeodesicParams {
        refine: 9,
        ..GeodesicParams::default()
    };
    assert!(matches!(
        GeodesicSolver::new(&mesh, &p),
        Err(HeatError::InvalidParameter { name: "refine", .. })
    ));
    // A degenerate face: refused by the cotangent triangulation, a point on it refused always.
    let mut positions = mesh.positions().to_vec();
    let f0 = mesh.faces()[0];
    positions[f0[2] as usize] = positions[f0[0] as usize];
    let flat = TriMesh::new(positions, mesh.faces().to_vec()).unwrap();
    let cotan = GeodesicParams {
        laplacian: Laplacian::Cotan,
        ..GeodesicParams::default()
    };
    assert!(matches!(GeodesicSolver::new(&flat, &cotan), Err(HeatError::Mesh(_))));
    let robust = GeodesicSolver::new(&flat, &GeodesicParams::default()).unwrap();
    let err = robust
        .distance_from(&[Source::Point {
            face: 0,
            barycentric: [0.3, 0.3, 0.4],
        }])
        .unwrap_err();
    assert!(err.to_string().contains("zero area"), "{err}");
}
