//! Mesh generators for tests, benchmarks and the demo.
//!
//! | generator | vertices | what it is good for |
//! |---|---|---|
//! | [`icosphere`] | 10·4^L + 2 | near-uniform sphere; spectrum l(l+1) with multiplicity 2l+1 |
//! | [`uv_sphere`] | 2 + rings·segments | latitude/longitude sphere, poles with high valence |
//! | [`grid`] | nx·ny | flat unit square with open boundary; spectrum π²(k² + m²) |
//! | [`torus`] | nu·nv | genus-1 closed surface |
//! | [`irregular_sphere`] | 10·4^L + 2 | unit sphere with triangle areas varying by ≈10³ |
//! | [`bumpy`] | 10·4^L + 2 | irregularly sampled bumpy shape (the demo's default mesh) |
//!
//! All generated faces are oriented counter-clockwise seen from outside (closed meshes) or
//! from +z (the grid).

use crate::TriMesh;

fn normalize(p: [f64; 3]) -> [f64; 3] {
    let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    [p[0] / r, p[1] / r, p[2] / r]
}

#[allow(clippy::expect_used)]
fn build(positions: Vec<[f64; 3]>, faces: Vec<[u32; 3]>) -> TriMesh {
    // invariant: generators only produce finite coordinates and in-range indices.
    TriMesh::new(positions, faces).expect("generated meshes are valid by construction")
}

/// Icosphere: the regular icosahedron subdivided `level` times (each triangle into four),
/// with vertices projected on the unit sphere. It has 10·4^level + 2 vertices
/// (level 5: 10,242; 6: 40,962; 7: 163,842; 8: 655,362).
pub fn icosphere(level: u32) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut positions: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|&p| normalize(p))
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        faces = crate::refine::split_with(&mut positions, &faces, |pa, pb| {
            normalize([pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]])
        });
    }
    build(positions, faces)
}

/// Number of vertices of [`icosphere`]`(level)`.
pub fn icosphere_vertex_count(level: u32) -> usize {
    10 * 4usize.pow(level) + 2
}

/// UV (latitude/longitude) unit sphere with `rings` ≥ 2 latitude bands and `segments` ≥ 3
/// longitudes: two poles plus (rings − 1)·segments vertices.
///
/// # Panics
/// If `rings < 2` or `segments < 3` (a programming error, not user input).
pub fn uv_sphere(rings: usize, segments: usize) -> TriMesh {
    assert!(
        rings >= 2 && segments >= 3,
        "uv_sphere needs rings ≥ 2 and segments ≥ 3"
    );
    let mut positions = vec![[0.0, 0.0, 1.0]];
    for r in 1..rings {
        let theta = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..segments {
            let phi = 2.0 * std::f64::consts::PI * s as f64 / segments as f64;
            positions.push([theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]);
        }
    }
    positions.push([0.0, 0.0, -1.0]);
    let south = (positions.len() - 1) as u32;
    let idx = |r: usize, s: usize| (1 + (r - 1) * segments + s % segments) as u32;
    let mut faces = Vec::new();
    for s in 0..segments {
        faces.push([0, idx(1, s), idx(1, s + 1)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (idx(r, s), idx(r + 1, s), idx(r + 1, s + 1), idx(r, s + 1));
            faces.push([a, b, c]);
            faces.push([a, c, d]);
        }
    }
    for s in 0..segments {
        faces.push([south, idx(rings - 1, s + 1), idx(rings - 1, s)]);
    }
    build(positions, faces)
}

/// Flat grid on the unit square \[0,1\]² in the plane z = 0, with `nx` × `ny` vertices and an
/// open boundary. Cells are split along alternating diagonals so the mesh has no preferred
/// direction.
///
/// # Panics
/// If `nx < 2` or `ny < 2`.
pub fn grid(nx: usize, ny: usize) -> TriMesh {
    assert!(nx >= 2 && ny >= 2, "grid needs at least 2×2 vertices");
    let mut positions = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            positions.push([i as f64 / (nx - 1) as f64, j as f64 / (ny - 1) as f64, 0.0]);
        }
    }
    let id = |i: usize, j: usize| (j * nx + i) as u32;
    let mut faces = Vec::with_capacity(2 * (nx - 1) * (ny - 1));
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                faces.push([a, b, c]);
                faces.push([a, c, d]);
            } else {
                faces.push([a, b, d]);
                faces.push([b, c, d]);
            }
        }
    }
    build(positions, faces)
}

/// Torus with major radius `major` and minor radius `minor`, `nu` samples around the
/// central circle and `nv` around the tube (nu·nv vertices, genus 1).
///
/// # Panics
/// If `nu < 3`, `nv < 3` or the radii are not `0 < minor < major`.
pub fn torus(major: f64, minor: f64, nu: usize, nv: usize) -> TriMesh {
    assert!(
        nu >= 3 && nv >= 3 && minor > 0.0 && minor < major,
        "invalid torus parameters"
    );
    let mut positions = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        let u = 2.0 * std::f64::consts::PI * i as f64 / nu as f64;
        for j in 0..nv {
            let v = 2.0 * std::f64::consts::PI * j as f64 / nv as f64;
            let r = major + minor * v.cos();
            positions.push([r * u.cos(), r * u.sin(), minor * v.sin()]);
        }
    }
    let id = |i: usize, j: usize| ((i % nu) * nv + j % nv) as u32;
    let mut faces = Vec::with_capacity(2 * nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            faces.push([a, b, c]);
            faces.push([a, c, d]);
        }
    }
    build(positions, faces)
}

/// Moves a point of the unit sphere by the conformal map "stereographic projection from the
/// north pole, dilation by `s`, projection back". Sampling density near the south pole
/// grows by s² and near the north pole shrinks by s², so triangle areas vary by ≈ s⁴.
fn dilate_on_sphere(p: [f64; 3], s: f64) -> [f64; 3] {
    let denom = 1.0 - p[2];
    if denom < 1e-15 {
        return p; // the north pole is a fixed point
    }
    let (x, y) = (s * p[0] / denom, s * p[1] / denom);
    let r2 = x * x + y * y;
    [2.0 * x / (r2 + 1.0), 2.0 * y / (r2 + 1.0), (r2 - 1.0) / (r2 + 1.0)]
}

/// Unit sphere with strongly varying triangle sizes: an icosphere of `level` moved by a
/// conformal dilation of the sphere with factor `s`, so face areas vary by about s⁴
/// (s = 5.6 gives ≈10³). The surface is still the exact sphere (up to the piecewise-linear
/// approximation), so its spectrum still approaches l(l+1).
pub fn irregular_sphere(level: u32, s: f64) -> TriMesh {
    let (positions, faces) = icosphere(level).into_parts();
    build(positions.into_iter().map(|p| dilate_on_sphere(p, s)).collect(), faces)
}

/// The demo's default mesh: an irregularly sampled ([`irregular_sphere`] with s = 4) sphere
/// with smooth radial bumps r = 1 + 0.25·sin(3x)·cos(2y)·cos(z) + 0.15·sin(5z), so it has
/// protrusions, non-uniform curvature and triangle areas varying by ≈10².
pub fn bumpy(level: u32) -> TriMesh {
    let (positions, faces) = irregular_sphere(level, 4.0).into_parts();
    let positions = positions
        .into_iter()
        .map(|p| {
            let r = bump(p);
            [r * p[0], r * p[1], r * p[2]]
        })
        .collect();
    build(positions, faces)
}

/// The radius of [`bumpy`] in the direction of the unit vector `p` (between 0.6 and 1.4).
fn bump(p: [f64; 3]) -> f64 {
    1.0 + 0.25 * (3.0 * p[0]).sin() * (2.0 * p[1]).cos() * p[2].cos() + 0.15 * (5.0 * p[2]).sin()
}

/// A solid shaped like [`bumpy`], filled with tetrahedra: `shells` concentric copies of
/// [`icosphere`]`(level)` at radii k/shells (k = 1 … shells), each triangle joined to the one
/// above it by a prism cut into three tetrahedra, and a cone from the centre (vertex 0) to each
/// triangle of the innermost sphere; then every vertex is moved radially to the bump radius of
/// its direction. A prism's quadrilateral sides are cut from the bottom of the lower-numbered
/// vertex to the top of the higher-numbered one, so neighbouring prisms agree; every
/// tetrahedron is positively oriented (radial moves by a positive factor keep the order of the
/// shells). 1 + shells · (10·4^level + 2) vertices, 3·shells − 2 tetrahedra per icosphere face.
///
/// # Panics
/// If `shells` is 0.
pub fn tet_bumpy(level: u32, shells: usize) -> crate::volume::TetMesh {
    assert!(shells >= 1, "tet_bumpy needs at least one shell");
    let sphere = icosphere(level);
    let m = sphere.n_vertices() as u32;
    let mut positions = vec![[0.0; 3]];
    for k in 1..=shells {
        let r = k as f64 / shells as f64;
        positions.extend(sphere.positions().iter().map(|&p| {
            let u = normalize(p);
            let s = r * bump(u);
            u.map(|x| s * x)
        }));
    }
    // Vertex v of shell k (1-based) is 1 + (k − 1)·m + v.
    let at = |k: usize, v: u32| 1 + (k as u32 - 1) * m + v;
    let mut tets = Vec::with_capacity(sphere.n_faces() * (3 * shells - 2));
    for f in sphere.faces() {
        tets.push([0, at(1, f[0]), at(1, f[1]), at(1, f[2])]);
        let mut v = *f;
        v.sort_unstable();
        for k in 1..shells {
            let (lo, hi) = (|i: usize| at(k, v[i]), |i: usize| at(k + 1, v[i]));
            tets.push([lo(0), lo(1), lo(2), hi(2)]);
            tets.push([lo(0), lo(1), hi(1), hi(2)]);
            tets.push([lo(0), hi(0), hi(1), hi(2)]);
        }
    }
    for t in &mut tets {
        if crate::volume::signed_volume(t.map(|v| positions[v as usize])) < 0.0 {
            t.swap(0, 1);
        }
    }
    #[allow(clippy::expect_used)]
    // invariant: finite positions and indices below 1 + shells·m by construction.
    crate::volume::TetMesh::new(positions, tets).expect("a generated solid is a valid mesh")
}

/// The unit cube \[0,1\]³ as a tetrahedral mesh: `n` cells per side, each split into six
/// tetrahedra around its main diagonal (Kuhn), all positively oriented; (n + 1)³ vertices.
///
/// # Panics
/// If `n` is 0.
pub fn tet_cube(n: usize) -> crate::volume::TetMesh {
    assert!(n >= 1, "tet_cube needs at least one cell per side");
    let m = n + 1;
    let id = |i: usize, j: usize, k: usize| ((k * m + j) * m + i) as u32;
    let mut positions = Vec::with_capacity(m * m * m);
    for k in 0..m {
        for j in 0..m {
            for i in 0..m {
                positions.push([i as f64 / n as f64, j as f64 / n as f64, k as f64 / n as f64]);
            }
        }
    }
    let mut tets = Vec::with_capacity(6 * n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let c = |a: usize, b: usize, d: usize| id(i + a, j + b, k + d);
                let (v0, v7) = (c(0, 0, 0), c(1, 1, 1));
                // The six paths from corner 0 to corner 7 along the axes.
                for (x, y) in [
                    (c(1, 0, 0), c(1, 1, 0)),
                    (c(1, 0, 0), c(1, 0, 1)),
                    (c(0, 1, 0), c(1, 1, 0)),
                    (c(0, 1, 0), c(0, 1, 1)),
                    (c(0, 0, 1), c(1, 0, 1)),
                    (c(0, 0, 1), c(0, 1, 1)),
                ] {
                    let mut t = [v0, x, y, v7];
                    let p = t.map(|v| positions[v as usize]);
                    if crate::volume::signed_volume(p) < 0.0 {
                        t.swap(1, 2);
                    }
                    tets.push(t);
                }
            }
        }
    }
    #[allow(clippy::expect_used)]
    // invariant: finite positions, indices in range.
    crate::volume::TetMesh::new(positions, tets).expect("a valid cube")
}
