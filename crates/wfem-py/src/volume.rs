//! Tetrahedral meshes (issue #39): `read_volume(path) -> (V, T)`, their validation and their
//! linear FEM operators; `HeatKernel.from_volume` and `GeodesicSolver.from_volume` build on
//! [`volume_in`].

use crate::convert::{elements_in, Elements};
use crate::errors::Error;
use crate::out::{sparse_out_owned, SparseOut};
use crate::run::run;
use mesh_fem::io::volume::read_volume as read_volume_file;
use mesh_fem::volume::{assemble_volume, validate_volume as validate_tets, TetMesh};
use mesh_fem::{AssemblyParams, Lumping};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use std::path::PathBuf;
use wfem_base::Choice;

type VolumeArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);

/// A tetrahedral mesh from V (n, 3) float64 and T (m, 4) int64, validated by `TetMesh::new`.
pub fn volume_in(py: Python<'_>, v: &PyReadonlyArray2<'_, f64>, t: &PyReadonlyArray2<'_, i64>) -> PyResult<TetMesh> {
    let elements = Elements {
        array: "T",
        shape_kind: "TetsShape",
        shape: "(m, 4) (tetrahedra)",
        element: "tetrahedron",
        key: "tet",
        index_kind: "TetIndexOutOfRange",
    };
    let (positions, tets) = elements_in::<4>(py, v, t, &elements)?;
    TetMesh::new(positions, tets).map_err(|e| crate::errors::mesh(py, &e))
}

fn volume_out<'py>(py: Python<'py>, mesh: &TetMesh) -> VolumeArrays<'py> {
    let (p, t) = (mesh.positions(), mesh.tets());
    let v = Array2::from_shape_fn((p.len(), 3), |(i, j)| p[i][j]).into_pyarray(py);
    let t = Array2::from_shape_fn((t.len(), 4), |(i, j)| i64::from(t[i][j])).into_pyarray(py);
    (v, t)
}

/// `read_volume(path) -> ((V, T), report JSON)`: MEDIT, Gmsh, VTK legacy, TetGen by extension.
#[pyfunction]
pub fn read_volume(py: Python<'_>, path: PathBuf) -> PyResult<(VolumeArrays<'_>, String)> {
    let read = run(py, move |_| read_volume_file(&path).map_err(Error::from))?;
    let report = serde_json::json!({
        "format": read.format.name(),
        "ignored": read.ignored,
    });
    Ok((volume_out(py, &read.mesh), report.to_string()))
}

/// `validate_volume(V, T) -> report JSON`.
#[pyfunction]
pub fn validate_volume(py: Python<'_>, v: PyReadonlyArray2<'_, f64>, t: PyReadonlyArray2<'_, i64>) -> PyResult<String> {
    let mesh = volume_in(py, &v, &t)?;
    let r = run(py, move |_| Ok(validate_tets(&mesh)))?;
    let problems: Vec<serde_json::Value> = r
        .problems
        .iter()
        .map(|p| serde_json::json!({"severity": if p.is_fatal() { "Error" } else { "Warning" }, "message": p.to_string()}))
        .collect();
    Ok(serde_json::json!({
        "n_vertices": r.n_vertices,
        "n_tets": r.n_tets,
        "volume": r.volume,
        "n_boundary_faces": r.n_boundary_faces,
        "n_boundary_vertices": r.n_boundary_vertices,
        "boundary_euler": r.boundary_euler,
        "n_boundary_components": r.n_boundary_components,
        "boundary_genus": r.boundary_genus,
        "n_components": r.n_components,
        "quality": [r.quality.0, r.quality.1],
        "worst_tet": r.worst_tet,
        "usable": !r.problems.iter().any(|p| p.is_fatal()),
        "problems": problems,
    })
    .to_string())
}

/// `volume_operators(V, T, lumped_mass=None) -> (L, B, D)` of the linear tetrahedral elements.
#[pyfunction]
#[pyo3(signature = (v, t, lumped_mass=None))]
pub fn volume_operators<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'py, f64>,
    t: PyReadonlyArray2<'py, i64>,
    lumped_mass: Option<&str>,
) -> PyResult<(SparseOut<'py>, SparseOut<'py>, SparseOut<'py>)> {
    let mesh = volume_in(py, &v, &t)?;
    let lumping: Lumping = crate::choices::parse(py, "lumped_mass", lumped_mass)?;
    let fem = run(py, move |_| {
        assemble_volume(
            &mesh,
            &AssemblyParams {
                lumping,
                ..AssemblyParams::default()
            },
        )
        .map_err(Error::from)
    })?;
    let lumped = fem.lumped_mass();
    Ok((
        sparse_out_owned(py, fem.stiffness),
        sparse_out_owned(py, fem.mass),
        sparse_out_owned(py, lumped),
    ))
}

/// `repair_volume(V, T, orient, degenerate, unreferenced) -> ((V, T), report JSON)`.
#[pyfunction]
#[pyo3(signature = (v, t, orient=true, degenerate=true, unreferenced=true))]
pub fn repair_volume<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'py, f64>,
    t: PyReadonlyArray2<'py, i64>,
    orient: bool,
    degenerate: bool,
    unreferenced: bool,
) -> PyResult<(VolumeArrays<'py>, String)> {
    let mesh = volume_in(py, &v, &t)?;
    let (repaired, report) = run(py, move |_| {
        mesh_fem::volume::repair_volume(&mesh, orient, degenerate, unreferenced).map_err(Error::from)
    })?;
    let map: Vec<i64> = report.vertex_map.iter().map(|m| m.map_or(-1, i64::from)).collect();
    let json = serde_json::json!({
        "flipped": report.flipped,
        "dropped_tets": report.dropped_tets,
        "dropped_vertices": report.dropped_vertices,
        "vertex_map": map,
    });
    Ok((volume_out(py, &repaired), json.to_string()))
}

/// Registers the functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_volume, m)?)?;
    m.add_function(wrap_pyfunction!(validate_volume, m)?)?;
    m.add_function(wrap_pyfunction!(volume_operators, m)?)?;
    m.add_function(wrap_pyfunction!(repair_volume, m)?)?;
    Ok(())
}
