//! Meshes: reading, validation, repair, statistics, generators and the FEM operators.

use crate::convert::mesh_in;
use crate::errors::{invalid_param, Error};
use crate::out::{mesh_out, sparse_out_owned, SparseOut};
use crate::run::run;
use mesh_fem::io::{load, LoadOptions};
use mesh_fem::stats::stats;
use mesh_fem::validate::{repair, validate, RepairOptions};
use mesh_fem::{assemble, generate, AssemblyParams, Lumping, TriMesh};
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use std::path::PathBuf;

type MeshArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);

/// Largest generated mesh (vertices): beyond it a typo would exhaust memory.
const MAX_GENERATED_VERTICES: usize = 20_000_000;

fn json<T: serde::Serialize>(py: Python<'_>, value: &T) -> PyResult<String> {
    serde_json::to_string(value).map_err(|e| Error::Panic(format!("report serialisation failed: {e}")).into_py(py))
}

/// `read_mesh(path, triangulate) -> (V, F, report JSON)`.
#[pyfunction]
#[pyo3(signature = (path, triangulate=false))]
pub fn read_mesh(py: Python<'_>, path: PathBuf, triangulate: bool) -> PyResult<(MeshArrays<'_>, String)> {
    let (mesh, report) = run(py, move |_| {
        load(&path, &LoadOptions::with_triangulation(triangulate)).map_err(Error::from)
    })?;
    let report = serde_json::json!({
        "format": format!("{:?}", report.format),
        "welded_vertices": report.welded_vertices,
        "triangulated_polygons": report.triangulated_polygons,
        "notes": report.notes,
    });
    Ok((mesh_out(py, &mesh), report.to_string()))
}

/// `validate(V, F) -> report JSON` (with `usable` and `summary`).
#[pyfunction]
pub fn validate_mesh(py: Python<'_>, v: PyReadonlyArray2<'_, f64>, f: PyReadonlyArray2<'_, i64>) -> PyResult<String> {
    let mesh = mesh_in(py, &v, &f)?;
    let report = run(py, move |_| Ok(validate(&mesh)))?;
    let mut value = serde_json::to_value(&report)
        .map_err(|e| Error::Panic(format!("report serialisation failed: {e}")).into_py(py))?;
    // One flat object per problem: {"kind": variant, fields…, "severity": …}.
    let problems: Vec<serde_json::Value> = report
        .problems
        .iter()
        .map(|p| {
            let mut flat = serde_json::Map::new();
            match serde_json::to_value(p) {
                Ok(serde_json::Value::Object(tagged)) => {
                    for (kind, fields) in tagged {
                        flat.insert("kind".into(), kind.into());
                        match fields {
                            serde_json::Value::Object(fields) => flat.extend(fields),
                            other => {
                                flat.insert("value".into(), other);
                            }
                        }
                    }
                }
                Ok(serde_json::Value::String(kind)) => {
                    flat.insert("kind".into(), kind.into());
                }
                _ => {}
            }
            flat.insert("severity".into(), format!("{:?}", p.severity()).into());
            serde_json::Value::Object(flat)
        })
        .collect();
    value["problems"] = problems.into();
    value["usable"] = report.is_usable().into();
    value["summary"] = report.summary().into();
    Ok(value.to_string())
}

/// `repair(V, F, options…) -> (V', F', report JSON)`.
#[pyfunction]
#[pyo3(signature = (v, f, merge_duplicate_vertices=None, drop_degenerate_faces=false, drop_duplicate_faces=false, orient_faces=false, drop_unreferenced_vertices=false))]
#[allow(clippy::too_many_arguments)]
pub fn repair_mesh<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray2<'py, i64>,
    merge_duplicate_vertices: Option<f64>,
    drop_degenerate_faces: bool,
    drop_duplicate_faces: bool,
    orient_faces: bool,
    drop_unreferenced_vertices: bool,
) -> PyResult<(MeshArrays<'py>, String)> {
    // Repairs take meshes that TriMesh::new accepts (indices in range, finite coordinates);
    // what they fix is what validate reports.
    let mesh = mesh_in(py, &v, &f)?;
    let opts = RepairOptions {
        merge_duplicate_vertices,
        drop_degenerate_faces,
        drop_duplicate_faces,
        orient_faces,
        drop_unreferenced_vertices,
    };
    let (fixed, report) = run(py, move |_| repair(&mesh, &opts).map_err(Error::from))?;
    let mut value = serde_json::to_value(&report)
        .map_err(|e| Error::Panic(format!("report serialisation failed: {e}")).into_py(py))?;
    value["unchanged"] = report.is_unchanged().into();
    value["summary"] = report.summary().into();
    Ok((mesh_out(py, &fixed), value.to_string()))
}

/// `fill_holes(V, F, max_perimeter) -> (V', F', holes closed)`: the old vertices and faces
/// first, unchanged, then the patches' (`mesh_repair::holes::fill_holes`).
#[pyfunction]
#[pyo3(signature = (v, f, max_perimeter=shape_retrieval::model::DEFAULT_MAX_HOLE_PERIMETER))]
pub fn fill_holes<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray2<'py, i64>,
    max_perimeter: f64,
) -> PyResult<(MeshArrays<'py>, usize)> {
    let mesh = mesh_in(py, &v, &f)?;
    let out = run(py, move |_| {
        if !(max_perimeter.is_finite() && max_perimeter > 0.0) {
            return Err(Error::Invalid(
                "InvalidParameter",
                format!("max_perimeter must be finite and positive, got {max_perimeter}"),
            ));
        }
        mesh_repair::holes::fill_holes(&mesh, max_perimeter).map_err(Error::from)
    })?;
    Ok((mesh_out(py, &out.mesh), out.filled))
}

/// `mesh_stats(V, F) -> JSON`.
#[pyfunction]
pub fn mesh_stats(py: Python<'_>, v: PyReadonlyArray2<'_, f64>, f: PyReadonlyArray2<'_, i64>) -> PyResult<String> {
    let mesh = mesh_in(py, &v, &f)?;
    let s = run(py, move |_| Ok(stats(&mesh)))?;
    json(py, &s)
}

/// `operators(V, F, lumped_mass=None, laplacian=None, mollify_factor=None) -> (L, B, D)` as
/// CSC arrays; D is the given lumped mass (default barycentric), L the given Laplacian
/// (default the cotangent L).
#[pyfunction]
#[pyo3(signature = (v, f, lumped_mass=None, laplacian=None, mollify_factor=None))]
pub fn operators<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray2<'py, i64>,
    lumped_mass: Option<&str>,
    laplacian: Option<&str>,
    mollify_factor: Option<f64>,
) -> PyResult<(SparseOut<'py>, SparseOut<'py>, SparseOut<'py>)> {
    let mesh = mesh_in(py, &v, &f)?;
    let lumping: Lumping = crate::choices::parse(py, "lumped_mass", lumped_mass)?;
    let laplacian = crate::cloud::assembly_laplacian(py, laplacian, mollify_factor)?;
    let fem = run(py, move |_| {
        assemble(&mesh, &AssemblyParams { lumping, laplacian }).map_err(Error::from)
    })?;
    let lumped = fem.lumped_mass();
    Ok((
        sparse_out_owned(py, fem.stiffness),
        sparse_out_owned(py, fem.mass),
        sparse_out_owned(py, lumped),
    ))
}

fn check_size(py: Python<'_>, name: &'static str, vertices: Option<usize>) -> PyResult<()> {
    match vertices {
        Some(n) if n <= MAX_GENERATED_VERTICES => Ok(()),
        _ => Err(invalid_param(
            py,
            name,
            format!("the mesh would exceed {MAX_GENERATED_VERTICES} vertices"),
        )),
    }
}

fn generated(py: Python<'_>, build: impl FnOnce() -> TriMesh + Send + 'static) -> PyResult<MeshArrays<'_>> {
    let mesh = run(py, move |_| Ok(build()))?;
    Ok(mesh_out(py, &mesh))
}

/// Unit icosphere of subdivision `level` (10·4^level + 2 vertices).
#[pyfunction]
pub fn icosphere(py: Python<'_>, level: u32) -> PyResult<MeshArrays<'_>> {
    check_size(py, "level", 4usize.checked_pow(level).and_then(|p| p.checked_mul(10)))?;
    generated(py, move || generate::icosphere(level))
}

/// Unit UV sphere with `rings` ≥ 2 and `segments` ≥ 3.
#[pyfunction]
pub fn uv_sphere(py: Python<'_>, rings: usize, segments: usize) -> PyResult<MeshArrays<'_>> {
    if rings < 2 || segments < 3 {
        return Err(invalid_param(
            py,
            "rings",
            "a UV sphere needs rings >= 2 and segments >= 3",
        ));
    }
    check_size(py, "rings", rings.checked_mul(segments))?;
    generated(py, move || generate::uv_sphere(rings, segments))
}

/// Grid on the unit square with nx × ny ≥ 2 × 2 vertices.
#[pyfunction]
pub fn grid(py: Python<'_>, nx: usize, ny: usize) -> PyResult<MeshArrays<'_>> {
    if nx < 2 || ny < 2 {
        return Err(invalid_param(py, "nx", "a grid needs at least 2 × 2 vertices"));
    }
    check_size(py, "nx", nx.checked_mul(ny))?;
    generated(py, move || generate::grid(nx, ny))
}

/// Torus with radii 0 < minor < major and nu, nv ≥ 3 samples.
#[pyfunction]
pub fn torus(py: Python<'_>, major: f64, minor: f64, nu: usize, nv: usize) -> PyResult<MeshArrays<'_>> {
    if nu < 3 || nv < 3 {
        return Err(invalid_param(py, "nu", "a torus needs nu >= 3 and nv >= 3"));
    }
    if !(minor.is_finite() && major.is_finite() && minor > 0.0 && minor < major) {
        return Err(invalid_param(
            py,
            "minor",
            format!("the radii must satisfy 0 < minor < major (got minor = {minor}, major = {major})"),
        ));
    }
    check_size(py, "nu", nu.checked_mul(nv))?;
    generated(py, move || generate::torus(major, minor, nu, nv))
}

/// Unit sphere with face areas varying by ≈ s⁴.
#[pyfunction]
pub fn irregular_sphere(py: Python<'_>, level: u32, s: f64) -> PyResult<MeshArrays<'_>> {
    if !(s.is_finite() && s > 0.0) {
        return Err(invalid_param(py, "s", format!("{s} must be finite and > 0")));
    }
    check_size(py, "level", 4usize.checked_pow(level).and_then(|p| p.checked_mul(10)))?;
    generated(py, move || generate::irregular_sphere(level, s))
}

/// The demo's bumpy irregular sphere.
#[pyfunction]
pub fn bumpy(py: Python<'_>, level: u32) -> PyResult<MeshArrays<'_>> {
    check_size(py, "level", 4usize.checked_pow(level).and_then(|p| p.checked_mul(10)))?;
    generated(py, move || generate::bumpy(level))
}

/// Persistent extrema of a field (sorted vertex indices).
#[pyfunction]
#[pyo3(signature = (v, f, field, persistence=None))]
pub fn extrema(
    py: Python<'_>,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
    field: numpy::PyReadonlyArray1<'_, f64>,
    persistence: Option<f64>,
) -> PyResult<Vec<u32>> {
    let mesh = mesh_in(py, &v, &f)?;
    let field = crate::convert::vec_in(&field);
    run(py, move |_| {
        wfem_heat::approx::extrema(&mesh, &field, persistence).map_err(Error::from)
    })
}

/// Registers the functions of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(validate_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(repair_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(fill_holes, m)?)?;
    m.add_function(wrap_pyfunction!(mesh_stats, m)?)?;
    m.add_function(wrap_pyfunction!(operators, m)?)?;
    m.add_function(wrap_pyfunction!(icosphere, m)?)?;
    m.add_function(wrap_pyfunction!(uv_sphere, m)?)?;
    m.add_function(wrap_pyfunction!(grid, m)?)?;
    m.add_function(wrap_pyfunction!(torus, m)?)?;
    m.add_function(wrap_pyfunction!(irregular_sphere, m)?)?;
    m.add_function(wrap_pyfunction!(bumpy, m)?)?;
    m.add_function(wrap_pyfunction!(extrema, m)?)?;
    Ok(())
}
