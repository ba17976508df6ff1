//! Shared helpers of the wfem-heat tests: meshes normalised to area 4π and error norms.
#![allow(dead_code)]

use mesh_fem::{assemble, generate, AssemblyParams, FemOperators, TriMesh};
use std::f64::consts::PI;

pub fn ops_of(mesh: &TriMesh) -> (TriMesh, FemOperators) {
    let mesh = mesh.with_area(4.0 * PI).expect("positive area");
    let ops = assemble(&mesh, &AssemblyParams::default()).expect("assembly");
    (mesh, ops)
}

/// The small test meshes: name, mesh (area 4π), operators.
pub fn meshes() -> Vec<(&'static str, TriMesh, FemOperators)> {
    let mut out = Vec::new();
    for (name, m) in [
        ("icosphere3", generate::icosphere(3)),
        ("irregular_sphere3", generate::irregular_sphere(3, 5.6)),
        ("grid20", generate::grid(20, 20)),
    ] {
        let (m, o) = ops_of(&m);
        out.push((name, m, o));
    }
    out
}

pub fn x_coordinate(mesh: &TriMesh) -> Vec<f64> {
    mesh.positions().iter().map(|p| p[0]).collect()
}

pub fn unit(n: usize, i: usize) -> Vec<f64> {
    let mut e = vec![0.0; n];
    e[i] = 1.0;
    e
}

pub fn norm(a: &[f64]) -> f64 {
    a.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// ‖a − b‖₂ / ‖b‖₂.
pub fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    norm(&d) / norm(b)
}

/// The wFEM operator context of assembled operators (L, B).
pub fn wfem(fem: &FemOperators) -> wfem_heat::Operators {
    wfem_heat::Operators::new(fem, mesh_fem::Mass::Consistent).expect("valid operators")
}

pub fn matvec(a: impl wfem_heat::AsSparse, x: &[f64]) -> Vec<f64> {
    let a = a.as_sparse();
    let mut y = vec![0.0; a.nrows()];
    let s = a.symbolic();
    for (j, xj) in x.iter().enumerate() {
        for p in s.col_range(j) {
            y[s.row_idx()[p]] += a.val()[p] * xj;
        }
    }
    y
}

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A real mesh: Spot (low resolution, 829 vertices) from the odedstein-meshes collection,
/// read with tobj from the corpus (`wfem_corpus`; `$WFEM_MESHES` overrides it). Returns `None`
/// Panics when the corpus is missing: `.ci/run` guarantees it.
pub fn spot() -> Option<(TriMesh, FemOperators)> {
    let path = wfem_corpus::mesh_path("odedstein-meshes/spot/spot_low_resolution.obj")
        .expect("the mesh corpus ../shared/data/meshes is required (or set WFEM_MESHES)");
    let (models, _) = tobj::load_obj(
        &path,
        &tobj::LoadOptions {
            triangulate: true,
            single_index: false,
            ..Default::default()
        },
    )
    .expect("readable OBJ");
    let m = &models[0].mesh;
    let positions: Vec<[f64; 3]> = m.positions.chunks(3).map(|p| [p[0], p[1], p[2]]).collect();
    let faces: Vec<[u32; 3]> = m.indices.chunks(3).map(|f| [f[0], f[1], f[2]]).collect();
    let mesh = TriMesh::new(positions, faces).expect("valid mesh");
    Some(ops_of(&mesh))
}
