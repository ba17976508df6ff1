//! A generated **mixed** collection (issue #42): 20 classes of objects of every kind in the
//! corpus — man-made parts (fandisk, rocker arm, wing nut, screwdriver), objects of genus 1–4
//! (rocker arm, bob, skull, 3holes, elephant, fertility), busts and heads (homer, goat head),
//! animals and toys (bunny, spot, cheburashka, armadillo, penguin, koala, scorpion, lion), a
//! hand — each class one corpus object in [`MIXED_MEMBERS`] individual variants, as the
//! held-out mixed collection of issue #42 (400 shapes in 20 classes, articulated and rigid:
//! plane, table, bust, chair, mech …) has classes of different objects of one kind rather than
//! one object in poses.
//!
//! A member is its object (1) stretched along three random orthogonal axes by factors
//! e^u, u uniform in ±[`MIXED_STRETCH`], (2) bulged by [`MIXED_BUMPS`] smooth Gaussian bumps
//! along the vertex normals (radius [`MIXED_BUMP_RADIUS`] and height up to
//! [`MIXED_BUMP_HEIGHT`] of the bounding-box diagonal, at random vertices) and (3) remeshed
//! with a triangulation of its own ([`crate::transform::remesh`]) to a random number of
//! vertices in [`MIXED_VERTICES`]. Every random number comes from
//! [`wfem_base::rng::SplitMix64`] seeded with [`MIXED_SEED`], the class and the member.

use crate::protocol::ShapeFile;
use crate::BenchError;
use mesh_fem::vec3::{cross, dot, norm};
use mesh_fem::TriMesh;
use rayon::prelude::*;
use std::path::Path;
use wfem_base::rng::SplitMix64;

/// The classes: (name, the corpus file).
pub const MIXED_CLASSES: [(&str, &str); 20] = [
    ("fandisk", "common-3d-test-models/fandisk.obj"),
    ("rocker-arm", "common-3d-test-models/rocker-arm.obj"),
    ("wingnut", "odedstein-meshes/wingnut/wingnut.obj"),
    ("screwdriver", "libigl-tutorial-data/screwdriver.off"),
    ("3holes", "libigl-tutorial-data/3holes.off"),
    ("fertility", "libigl-tutorial-data/fertility.off"),
    ("skull", "odedstein-meshes/skull/skull_low_resolution.obj"),
    ("bob", "keenan-crane-bob/bob_tri.obj"),
    ("elephant", "pmp-data/elephant.off"),
    ("homer", "common-3d-test-models/homer.obj"),
    ("goathead", "odedstein-meshes/goathead/goathead.obj"),
    ("bunny", "odedstein-meshes/bunny/bunny.obj"),
    ("spot", "common-3d-test-models/spot.obj"),
    ("cheburashka", "common-3d-test-models/cheburashka.obj"),
    ("armadillo", "odedstein-meshes/armadillo/armadillo.obj"),
    ("penguin", "odedstein-meshes/penguin/penguin.obj"),
    ("koala", "odedstein-meshes/koala/koala_low_resolution.obj"),
    ("scorpion", "odedstein-meshes/scorpion/scorpion_low_resolution.obj"),
    ("lion", "deftransfer-pyfm/lion-00.off"),
    ("hand", "odedstein-meshes/hand/hand_closed.obj"),
];

/// Members per class.
pub const MIXED_MEMBERS: usize = 8;
/// The largest stretch exponent (factors from e^−0.25 ≈ 0.78 to e^0.25 ≈ 1.28).
pub const MIXED_STRETCH: f64 = 0.25;
/// Bumps per member.
pub const MIXED_BUMPS: usize = 3;
/// A bump's Gaussian radius, in bounding-box diagonals.
pub const MIXED_BUMP_RADIUS: f64 = 0.15;
/// A bump's largest height (either sign), in bounding-box diagonals.
pub const MIXED_BUMP_HEIGHT: f64 = 0.03;
/// The range of a member's vertex count.
pub const MIXED_VERTICES: (usize, usize) = (4_000, 8_000);
/// The seed of the collection.
pub const MIXED_SEED: u64 = 4207;

/// One member: `mesh` stretched, bulged and remeshed as the module docs say, by `rng`.
///
/// # Errors
/// Those of [`crate::transform::remesh`].
pub fn member(mesh: &TriMesh, rng: &mut SplitMix64) -> Result<TriMesh, BenchError> {
    let p = mesh.positions();
    let n = p.len().max(1) as f64;
    let centre = p
        .iter()
        .fold([0.0; 3], |c, x| [c[0] + x[0] / n, c[1] + x[1] / n, c[2] + x[2] / n]);
    // Three orthonormal axes from two random directions.
    let a = rng.unit_vector();
    let b = normalised(cross(a, rng.unit_vector()));
    let axes = [a, b, cross(a, b)];
    let factors: Vec<f64> = (0..3)
        .map(|_| (MIXED_STRETCH * (2.0 * rng.next_f64() - 1.0)).exp())
        .collect();
    let stretched: Vec<[f64; 3]> = p
        .iter()
        .map(|x| {
            let d = [x[0] - centre[0], x[1] - centre[1], x[2] - centre[2]];
            let mut y = centre;
            for (axis, f) in axes.iter().zip(&factors) {
                let s = f * dot(d, *axis);
                for k in 0..3 {
                    y[k] += s * axis[k];
                }
            }
            y
        })
        .collect();
    let mesh = TriMesh::new(stretched, mesh.faces().to_vec())?;
    let diagonal = crate::transform::bounding_box_diagonal(&mesh);
    let normals = crate::transform::vertex_normals(&mesh);
    let bumps: Vec<([f64; 3], f64)> = (0..MIXED_BUMPS)
        .map(|_| {
            let at = mesh.positions()[rng.next_below(mesh.n_vertices())];
            (at, MIXED_BUMP_HEIGHT * diagonal * (2.0 * rng.next_f64() - 1.0))
        })
        .collect();
    let r2 = (MIXED_BUMP_RADIUS * diagonal).powi(2);
    let bulged: Vec<[f64; 3]> = mesh
        .positions()
        .iter()
        .zip(&normals)
        .map(|(x, nrm)| {
            let h: f64 = bumps
                .iter()
                .map(|(c, height)| {
                    let d2 = (x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2) + (x[2] - c[2]).powi(2);
                    height * (-d2 / (2.0 * r2)).exp()
                })
                .sum();
            [x[0] + h * nrm[0], x[1] + h * nrm[1], x[2] + h * nrm[2]]
        })
        .collect();
    let mesh = TriMesh::new(bulged, mesh.faces().to_vec())?;
    let (lo, hi) = MIXED_VERTICES;
    let target = lo + rng.next_below(hi - lo + 1);
    crate::transform::remesh(&mesh, target, rng.next_u64())
}

/// The collection's files (`CLASS-MEMBER.off`, family = the class), written to `dir` unless
/// already there, in class order: [`mixed_files_of`] the [`MIXED_CLASSES`] with
/// [`MIXED_MEMBERS`] members each.
///
/// # Errors
/// Those of [`mixed_files_of`].
pub fn mixed_files(meshes_dir: &Path, dir: &Path) -> Result<Vec<ShapeFile>, BenchError> {
    mixed_files_of(meshes_dir, dir, &MIXED_CLASSES, MIXED_MEMBERS)
}

/// A mixed collection of `members` members of each of `classes` ((name, corpus file), the
/// member of class c and index m seeded by [`MIXED_SEED`], c and m), written to `dir` as
/// `CLASS-MEMBER.off` unless already there, in class order.
///
/// # Errors
/// [`BenchError::Data`] naming an unreadable corpus file or a folder that cannot be written;
/// those of [`member`].
pub fn mixed_files_of(
    meshes_dir: &Path,
    dir: &Path,
    classes: &[(&str, &str)],
    members: usize,
) -> Result<Vec<ShapeFile>, BenchError> {
    std::fs::create_dir_all(dir).map_err(|e| BenchError::Data(format!("{}: {e}", dir.display())))?;
    let jobs: Vec<(usize, usize)> = (0..classes.len())
        .flat_map(|c| (0..members).map(move |m| (c, m)))
        .collect();
    jobs.par_iter()
        .map(|&(c, m)| {
            let (class, file) = classes[c];
            let name = format!("{class}-{m}");
            let path = dir.join(format!("{name}.off"));
            if !path.is_file() {
                let source = meshes_dir.join(file);
                let (mesh, _): (TriMesh, _) = mesh_fem::io::load(&source, &Default::default())
                    .map_err(|e| BenchError::Data(format!("{}: {e}", source.display())))?;
                let mut rng = SplitMix64::new(MIXED_SEED ^ ((c as u64) << 32) ^ m as u64);
                // Decorrelate the neighbouring seeds before use.
                let mut rng = SplitMix64::new(rng.next_u64());
                let shape = member(&mesh, &mut rng).map_err(|e| BenchError::Data(format!("{name}: {e}")))?;
                mesh_fem::io::write_mesh(&path, &shape).map_err(|e| BenchError::Data(e.to_string()))?;
            }
            Ok(ShapeFile {
                path,
                name,
                family: class.to_string(),
                transform: None,
                strength: 0,
                cloud: None,
            })
        })
        .collect()
}

fn normalised(a: [f64; 3]) -> [f64; 3] {
    let l = norm(a);
    if l > 0.0 {
        [a[0] / l, a[1] / l, a[2] / l]
    } else {
        [1.0, 0.0, 0.0]
    }
}
