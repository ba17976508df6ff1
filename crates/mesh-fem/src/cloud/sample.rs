//! Point clouds sampled from a mesh: n points uniformly distributed on its surface.

use crate::cloud::PointCloud;
use crate::{MeshError, TriMesh};

/// n points drawn independently and uniformly from the surface of `mesh` (no normals): a face
/// with probability proportional to its area, then a point of it with uniform barycentric
/// coordinates (u, v drawn in the unit square and reflected into the triangle when
/// u + v > 1). `uniform` yields numbers in [0, 1) — pass the workspace's one seeded generator,
/// `|| rng.next_f64()` with `wfem_base::rng::SplitMix64` — so a seed gives the same cloud
/// on every platform; mesh-fem itself draws nothing. Three numbers are drawn per point.
///
/// Used to turn meshes into the point clouds of the retrieval evaluation (issue #27:
/// TOSCA-76 as clouds of 5,000 points) and of the tests that compare a cloud with the mesh it
/// samples.
///
/// # Errors
/// [`MeshError::TooFewPoints`] for n below [`super::MIN_POINTS`],
/// [`MeshError::InvalidParameter`] for n above 2³² − 1 (points are indexed with 32 bits), and
/// [`MeshError::DegenerateMesh`] for a mesh whose area is zero or not finite.
pub fn sample_surface(mesh: &TriMesh, n: usize, uniform: &mut dyn FnMut() -> f64) -> Result<PointCloud, MeshError> {
    if n < super::MIN_POINTS {
        return Err(MeshError::TooFewPoints {
            n_points: n,
            minimum: super::MIN_POINTS,
        });
    }
    if u32::try_from(n).is_err() {
        return Err(MeshError::InvalidParameter {
            name: "number of points",
            value: n as f64,
            expected: "at most 2³² − 1",
        });
    }
    let mut cumulative = Vec::with_capacity(mesh.n_faces());
    let mut total = 0.0;
    for f in 0..mesh.n_faces() {
        total += mesh.face_area(f);
        cumulative.push(total);
    }
    if !(total > 0.0 && total.is_finite()) {
        return Err(MeshError::DegenerateMesh { area: total });
    }
    let last = cumulative.len() - 1;
    let positions = (0..n)
        .map(|_| {
            let r = uniform() * total;
            // The first face whose cumulative area exceeds r (faces of zero area are never
            // drawn: their cumulative area equals the previous one's).
            let f = cumulative.partition_point(|&c| c <= r).min(last);
            let (mut u, mut v) = (uniform(), uniform());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let w = [1.0 - u - v, u, v];
            let c = mesh.corners(f);
            [0, 1, 2].map(|a| w[0] * c[0][a] + w[1] * c[1][a] + w[2] * c[2][a])
        })
        .collect();
    PointCloud::new(positions, None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate;

    /// A small deterministic stream for the unit tests (the workspace's generator lives in
    /// shifted-solve, which mesh-fem does not depend on).
    fn stream(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn points_lie_on_the_surface_and_spread_by_area() {
        // A unit square of two triangles and a 3 × 1 rectangle beside it: 1/4 of the points
        // should land on the square.
        let mesh = TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [4.0, 0.0, 0.0],
                [4.0, 1.0, 0.0],
            ],
            vec![[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]],
        )
        .unwrap();
        let cloud = sample_surface(&mesh, 4000, &mut stream(1)).unwrap();
        assert_eq!(cloud.n_points(), 4000);
        assert!(cloud.normals().is_none());
        let on_square = cloud.positions().iter().filter(|p| p[0] < 1.0).count() as f64 / 4000.0;
        // Binomial standard deviation √(¼·¾/4000) ≈ 0.007.
        assert!((on_square - 0.25).abs() < 0.03, "{on_square}");
        for p in cloud.positions() {
            assert!(
                p[2] == 0.0 && (0.0..=4.0).contains(&p[0]) && (0.0..=1.0).contains(&p[1]),
                "{p:?}"
            );
        }
    }

    #[test]
    fn a_sphere_sample_has_unit_radius_and_zero_mean() {
        let mesh = generate::icosphere(4);
        let cloud = sample_surface(&mesh, 3000, &mut stream(7)).unwrap();
        let mut mean = [0.0; 3];
        for p in cloud.positions() {
            let r = crate::vec3::norm(*p);
            // Inside the chords of a level-4 icosphere, never outside the sphere.
            assert!(r <= 1.0 + 1e-12 && r > 0.99, "{r}");
            (0..3).for_each(|a| mean[a] += p[a] / 3000.0);
        }
        assert!(mean.iter().all(|m| m.abs() < 0.05), "{mean:?}");
        // Same stream, same cloud.
        assert_eq!(cloud, sample_surface(&mesh, 3000, &mut stream(7)).unwrap());
    }

    #[test]
    fn bad_requests_are_refused() {
        let mesh = generate::icosphere(1);
        assert!(matches!(
            sample_surface(&mesh, 2, &mut stream(0)),
            Err(MeshError::TooFewPoints { n_points: 2, .. })
        ));
        // Refused before anything of that size is allocated.
        assert!(matches!(
            sample_surface(&mesh, u32::MAX as usize + 1, &mut stream(0)),
            Err(MeshError::InvalidParameter { .. })
        ));
        let flat = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], vec![[0, 1, 2]]).unwrap();
        assert!(matches!(
            sample_surface(&flat, 10, &mut stream(0)),
            Err(MeshError::DegenerateMesh { .. })
        ));
    }
}
