//! Tests of the point-cloud operators (`mesh_fem::cloud::assemble_cloud`).
//!
//! References, independent of the code under test: closed-form identities (L·1 = 0,
//! symmetry, D = row sums of B, total mass = area of the sampled surface), the exactness of
//! a linear-FEM Laplacian on linear functions in the plane, invariance under rigid motions,
//! and brute-force nearest neighbours. The spectrum against l(l+1) on sphere clouds and the
//! convergence of K_t f are tested in wfem-heat (which has the eigensolver and the kernel).

use crate::operators::{asymmetry, entries, matvec, max_abs};
use mesh_fem::cloud::{assemble_cloud, CloudParams, PointCloud};
use mesh_fem::{AssemblyParams, MeshError};

/// SplitMix64 uniforms in (0, 1).
pub(crate) struct Rng(pub u64);

impl Rng {
    pub(crate) fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        (((z ^ (z >> 31)) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    pub(crate) fn gauss(&mut self) -> f64 {
        (-2.0 * self.uniform().ln()).sqrt() * (2.0 * std::f64::consts::PI * self.uniform()).cos()
    }
}

/// n points uniformly distributed on the unit sphere.
pub(crate) fn sphere_cloud(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| {
            let p = [rng.gauss(), rng.gauss(), rng.gauss()];
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            p.map(|c| c / r)
        })
        .collect()
}

fn cloud_ops(points: Vec<[f64; 3]>) -> mesh_fem::cloud::CloudOperators {
    let cloud = PointCloud::new(points, None).unwrap();
    assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default()).unwrap()
}

#[test]
fn sphere_cloud_operators_satisfy_the_fem_identities() {
    let points = sphere_cloud(3000, 1);
    let c = cloud_ops(points.clone());
    let ops = &c.operators;
    let n = points.len();
    assert_eq!(ops.n(), n);
    let ones = vec![1.0; n];
    assert!(max_abs(&matvec(&ops.stiffness, &ones)) < 1e-12);
    assert_eq!(asymmetry(&ops.stiffness), 0.0);
    assert_eq!(asymmetry(&ops.mass), 0.0);
    for (i, j, v) in entries(&ops.stiffness) {
        assert!(if i == j { v > 0.0 } else { v <= 2e-6 }, "L[{i},{j}] = {v}");
    }
    let rows = matvec(&ops.mass, &ones);
    for (r, d) in rows.iter().zip(&ops.lumped_diagonal) {
        assert!((r - d).abs() <= 1e-13 * d);
    }
    let area: f64 = ops.lumped_diagonal.iter().sum();
    let sphere = 4.0 * std::f64::consts::PI;
    assert!((area - sphere).abs() < 0.01 * sphere, "area {area}");
    // Where the sampling is regular the three corners agree: about 2n triangles (a closed
    // triangulation of the sphere has 2n − 4), from about 6n local ones.
    let r = &c.report;
    assert_eq!(r.n_neighbours, 30);
    assert_eq!(r.n_estimated_normals, n);
    assert!((r.n_triangles as f64 - 2.0 * n as f64).abs() < 0.02 * n as f64, "{r:?}");
    assert!(
        (r.n_local_triangles as f64 - 6.0 * n as f64).abs() < 0.05 * n as f64,
        "{r:?}"
    );
    assert_eq!(c.neighbourhood.n_faces(), r.n_triangles);
    // Estimated normals are radial (up to sign).
    for (p, nrm) in points.iter().zip(&c.normals) {
        let cos = (p[0] * nrm[0] + p[1] * nrm[1] + p[2] * nrm[2]).abs();
        assert!(cos > 0.99, "normal {nrm:?} at {p:?}");
    }
}

#[test]
fn planar_cloud_laplacian_is_exact_on_linear_functions() {
    // A jittered grid in the plane z = 0: away from the boundary, a linear-FEM Laplacian of a
    // triangulation covering the plane once annihilates linear functions. Overlapping or
    // missing triangles would not.
    let mut rng = Rng(5);
    let m = 40;
    let mut points = Vec::new();
    for i in 0..m {
        for j in 0..m {
            let jitter = |r: &mut Rng| 0.3 * (r.uniform() - 0.5);
            points.push([i as f64 + jitter(&mut rng), j as f64 + jitter(&mut rng), 0.0]);
        }
    }
    let c = cloud_ops(points.clone());
    for coordinate in 0..2 {
        let f: Vec<f64> = points.iter().map(|p| p[coordinate]).collect();
        let lf = matvec(&c.operators.stiffness, &f);
        let mut worst = 0.0f64;
        for (p, v) in points.iter().zip(&lf) {
            if p[0] > 5.0 && p[0] < m as f64 - 6.0 && p[1] > 5.0 && p[1] < m as f64 - 6.0 {
                worst = worst.max(v.abs());
            }
        }
        assert!(worst < 1e-9, "interior |L x_{coordinate}| = {worst:e}");
    }
    // The area of the covered region: the jittered square's convex hull, give or take the
    // boundary.
    let area: f64 = c.operators.lumped_diagonal.iter().sum();
    let square = ((m - 1) * (m - 1)) as f64;
    assert!((area - square).abs() < 0.03 * square, "area {area} vs {square}");
}

#[test]
fn cloud_operators_are_invariant_under_rigid_motions() {
    // robust_laplacian's normals depend on the distance to the coordinate origin; ours must
    // not: the cloud moved far away and rotated gives the same L and D.
    let points = sphere_cloud(1500, 2);
    let base = cloud_ops(points.clone());
    let (c, s) = (0.6, 0.8);
    let moved: Vec<[f64; 3]> = points
        .iter()
        .map(|p| [c * p[0] - s * p[1] + 1000.0, s * p[0] + c * p[1] - 250.0, p[2] + 40.0])
        .collect();
    let other = cloud_ops(moved);
    let dense = |a: &faer::sparse::SparseColMat<usize, f64>| {
        let mut m = std::collections::HashMap::new();
        for (i, j, v) in entries(a) {
            m.insert((i, j), v);
        }
        m
    };
    let (a, b) = (dense(&base.operators.stiffness), dense(&other.operators.stiffness));
    let diff = a
        .iter()
        .map(|(k, v)| (v - b.get(k).copied().unwrap_or(0.0)).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-8, "L changes by {diff:e} under a rigid motion");
    let d = max_abs(
        &base
            .operators
            .lumped_diagonal
            .iter()
            .zip(&other.operators.lumped_diagonal)
            .map(|(x, y)| x - y)
            .collect::<Vec<_>>(),
    );
    assert!(d < 1e-10, "D changes by {d:e}");
}

#[test]
fn given_normals_are_used_and_small_clouds_use_fewer_neighbours() {
    let points = sphere_cloud(800, 3);
    let normals = points.clone();
    let cloud = PointCloud::new(points.clone(), Some(normals)).unwrap();
    let c = assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default()).unwrap();
    assert_eq!(c.report.n_estimated_normals, 0);
    assert!((0..3).all(|a| (c.normals[7][a] - points[7][a]).abs() < 1e-15));
    let area: f64 = c.operators.lumped_diagonal.iter().sum();
    assert!((area - 4.0 * std::f64::consts::PI).abs() < 0.03 * 4.0 * std::f64::consts::PI);
    // Twelve points of a jittered 4 × 3 grid in a plane: k = 11, and the merged triangles
    // cover the grid's convex hull.
    let mut rng = Rng(8);
    let grid: Vec<[f64; 3]> = (0..12)
        .map(|i| {
            [
                (i % 4) as f64 + 0.1 * rng.uniform(),
                (i / 4) as f64 + 0.1 * rng.uniform(),
                0.0,
            ]
        })
        .collect();
    let cloud = PointCloud::new(grid.clone(), None).unwrap();
    let c = assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default()).unwrap();
    assert_eq!(c.report.n_neighbours, 11);
    let area: f64 = c.operators.lumped_diagonal.iter().sum();
    assert!((area - 6.0).abs() < 0.4, "area {area}");
}

#[test]
fn duplicates_are_an_error_and_merging_them_repairs_the_cloud() {
    let mut points = sphere_cloud(500, 4);
    points.push(points[17]);
    points.push([-0.0 + points[3][0], points[3][1], points[3][2]]);
    let cloud = PointCloud::new(points.clone(), None).unwrap();
    let err = assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default()).unwrap_err();
    assert!(
        matches!(
            err,
            MeshError::DuplicatePoint {
                point: 500,
                duplicate_of: 17
            } | MeshError::DuplicatePoint {
                point: 501,
                duplicate_of: 3
            }
        ),
        "{err}"
    );
    let (merged, map) = cloud.merge_duplicates().unwrap();
    assert_eq!(merged.n_points(), 500);
    assert_eq!(map[500], 17);
    assert_eq!(map[501], 3);
    assert_eq!(map[42], 42);
    assemble_cloud(&merged, &CloudParams::default(), &AssemblyParams::default()).unwrap();
}

#[test]
fn every_cloud_error_names_its_culprit() {
    assert!(matches!(
        PointCloud::new(vec![[0.0; 3], [1.0, 0.0, 0.0]], None),
        Err(MeshError::TooFewPoints {
            n_points: 2,
            minimum: 3
        })
    ));
    let mut points = sphere_cloud(50, 6);
    points[9][1] = f64::NAN;
    assert!(matches!(
        PointCloud::new(points, None),
        Err(MeshError::NonFinitePoint {
            point: 9,
            what: "coordinate",
            ..
        })
    ));
    let points = sphere_cloud(50, 6);
    assert!(matches!(
        PointCloud::new(points.clone(), Some(vec![[0.0, 0.0, 1.0]; 49])),
        Err(MeshError::NormalsLength {
            found: 49,
            expected: 50
        })
    ));
    let mut normals = points.clone();
    normals[4] = [f64::INFINITY, 0.0, 0.0];
    assert!(matches!(
        PointCloud::new(points.clone(), Some(normals)),
        Err(MeshError::NonFinitePoint {
            point: 4,
            what: "normal",
            ..
        })
    ));
    let cloud = PointCloud::new(points, None).unwrap();
    let bad_k = CloudParams {
        n_neighbours: 1,
        ..CloudParams::default()
    };
    assert!(matches!(
        assemble_cloud(&cloud, &bad_k, &AssemblyParams::default()),
        Err(MeshError::InvalidParameter {
            name: "n_neighbours",
            ..
        })
    ));
    let bad_mollify = CloudParams {
        mollify_factor: f64::NAN,
        ..CloudParams::default()
    };
    assert!(matches!(
        assemble_cloud(&cloud, &bad_mollify, &AssemblyParams::default()),
        Err(MeshError::InvalidParameter {
            name: "mollify_factor",
            ..
        })
    ));
    // Points on a line have no tangent plane.
    let line: Vec<[f64; 3]> = (0..40).map(|i| [i as f64, 2.0 * i as f64, 0.5]).collect();
    let cloud = PointCloud::new(line, None).unwrap();
    assert!(matches!(
        assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default()),
        Err(MeshError::DegenerateNeighbourhood { n_neighbours: 30, .. })
    ));
}

/// Issue #41: a cloud too large for its squared lengths is refused as such (it was refused as
/// "collinear neighbours"); one of ~1e150 still assembles.
#[test]
fn a_cloud_whose_lengths_overflow_is_named_as_such() {
    let scaled = |s: f64| -> Vec<[f64; 3]> { sphere_cloud(200, 6).iter().map(|p| p.map(|c| c * s)).collect() };
    match PointCloud::new(scaled(1e300), None) {
        Err(MeshError::Invalid { reason }) => assert!(reason.contains("overflow"), "{reason}"),
        other => panic!("{other:?}"),
    }
    let cloud = PointCloud::new(scaled(1e150), None).unwrap();
    assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default()).unwrap();
}
