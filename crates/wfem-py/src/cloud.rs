//! Point clouds and the choice of Laplacian (issue #27): `cloud_operators(P, …)` and
//! `read_points(path)`, and the `laplacian=` names, all taken from mesh-fem's types.

use crate::choices;
use crate::errors::{invalid_param, Error};
use crate::out::{sparse_out, SparseOut};
use crate::run::run;
use mesh_fem::cloud::{assemble_cloud, CloudParams, PointCloud};
use mesh_fem::io::load_points;
use mesh_fem::{AssemblyParams, Laplacian, Lumping, RobustParams};
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use wfem_base::Choice;

/// The Laplacian of an optional `laplacian=` name (`None`: [`Laplacian::default`]) with the
/// given mollification (robust only).
pub fn assembly_laplacian(py: Python<'_>, name: Option<&str>, mollify_factor: Option<f64>) -> PyResult<Laplacian> {
    match (choices::parse::<Laplacian>(py, "laplacian", name)?, mollify_factor) {
        (Laplacian::Robust(mut params), Some(m)) => {
            params.mollify_factor = m;
            Ok(Laplacian::Robust(params))
        }
        (l, None) => Ok(l),
        (l, Some(_)) => Err(invalid_param(
            py,
            "mollify_factor",
            format!("applies to the robust Laplacian, not to {:?}", l.name()),
        )),
    }
}

/// Refuses a `laplacian=` naming another Laplacian than the robust one (a point cloud has
/// only that one); `None` is fine.
pub fn robust_only(py: Python<'_>, laplacian: Option<&str>) -> PyResult<()> {
    if laplacian.is_some() {
        let l: Laplacian = choices::parse(py, "laplacian", laplacian)?;
        if !matches!(l, Laplacian::Robust(_)) {
            return Err(invalid_param(
                py,
                "laplacian",
                format!("a point cloud has only the robust Laplacian, not {:?}", l.name()),
            ));
        }
    }
    Ok(())
}

/// An (n, 3) array as rows.
fn rows(py: Python<'_>, a: &PyReadonlyArray2<'_, f64>, name: &str) -> PyResult<Vec<[f64; 3]>> {
    let a = a.as_array();
    if a.ncols() != 3 {
        return Err(invalid_param(
            py,
            name,
            format!("must have shape (n, 3), got {:?}", a.shape()),
        ));
    }
    Ok(a.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
}

/// A point cloud from an (n, 3) array (validated), with the assembly options of
/// `n_neighbors` (default [`mesh_fem::cloud::DEFAULT_NEIGHBOURS`]).
pub fn cloud_in(
    py: Python<'_>,
    p: &PyReadonlyArray2<'_, f64>,
    n_neighbors: Option<usize>,
) -> PyResult<(PointCloud, CloudParams)> {
    let positions = rows(py, p, "P")?;
    let cloud = PointCloud::new(positions, None).map_err(|e| Error::from(e).into_py(py))?;
    let params = CloudParams {
        n_neighbours: n_neighbors.unwrap_or(mesh_fem::cloud::DEFAULT_NEIGHBOURS),
        ..CloudParams::default()
    };
    Ok((cloud, params))
}

/// A cloud's (L, B, D) and its report as JSON.
type CloudOut<'py> = (SparseOut<'py>, SparseOut<'py>, SparseOut<'py>, String);

/// `cloud_operators(P, normals=None, lumped_mass=None, n_neighbors, mollify_factor, laplacian=None)
/// -> (L, B, D, report)`; a cloud has the robust Laplacian only (`laplacian` may name it).
#[pyfunction]
#[pyo3(signature = (p, normals=None, lumped_mass=None, n_neighbors=mesh_fem::cloud::DEFAULT_NEIGHBOURS, mollify_factor=None, laplacian=None))]
#[allow(clippy::too_many_arguments)]
pub fn cloud_operators<'py>(
    py: Python<'py>,
    p: PyReadonlyArray2<'py, f64>,
    normals: Option<PyReadonlyArray2<'py, f64>>,
    lumped_mass: Option<&str>,
    n_neighbors: usize,
    mollify_factor: Option<f64>,
    laplacian: Option<&str>,
) -> PyResult<CloudOut<'py>> {
    robust_only(py, laplacian)?;
    let positions = rows(py, &p, "P")?;
    let normals = normals.map(|n| rows(py, &n, "normals")).transpose()?;
    let lumping: Lumping = choices::parse(py, "lumped_mass", lumped_mass)?;
    let params = CloudParams {
        n_neighbours: n_neighbors,
        mollify_factor: mollify_factor.unwrap_or(RobustParams::default().mollify_factor),
        ..CloudParams::default()
    };
    let ops = run(py, move |_| {
        let cloud = PointCloud::new(positions, normals)?;
        let assembly = AssemblyParams {
            lumping,
            ..Default::default()
        };
        assemble_cloud(&cloud, &params, &assembly).map_err(Error::from)
    })?;
    let r = &ops.report;
    let report = format!(
        "{{\"n_neighbors\": {}, \"n_local_triangles\": {}, \"n_triangles\": {}, \"n_rescued_points\": {}, \"n_estimated_normals\": {}, \"n_flips\": {}}}",
        r.n_neighbours, r.n_local_triangles, r.n_triangles, r.n_rescued_points, r.n_estimated_normals, r.n_flips
    );
    let fem = &ops.operators;
    Ok((
        sparse_out(py, fem.stiffness.as_ref()),
        sparse_out(py, fem.mass.as_ref()),
        sparse_out(py, fem.lumped_mass().as_ref()),
        report,
    ))
}

/// Positions (n, 3) and normals (n, 3) or None.
type PointsOut<'py> = (Bound<'py, PyArray2<f64>>, Option<Bound<'py, PyArray2<f64>>>);

/// `read_points(path) -> (P, normals | None)`: .ply without faces, .xyz, .pts, .csv, .npy.
#[pyfunction]
pub fn read_points(py: Python<'_>, path: std::path::PathBuf) -> PyResult<PointsOut<'_>> {
    let cloud = run(py, move |_| load_points(&path).map_err(Error::from))?;
    let to_array = |v: &[[f64; 3]]| PyArray2::from_vec2(py, &v.iter().map(|r| r.to_vec()).collect::<Vec<_>>());
    let positions = to_array(cloud.positions())?;
    let normals = cloud.normals().map(to_array).transpose()?;
    Ok((positions, normals))
}

/// Which matrix of (L, B, D) is the mass of a `mass=` name — `"B"` (consistent), `"D"`
/// (lumped) or `"I"` (identity) — and the lumped mass D must be assembled with: what the
/// Python layer needs to build a kernel on a point cloud's operators.
#[pyfunction]
#[pyo3(signature = (mass=None))]
pub fn mass_matrix(py: Python<'_>, mass: Option<&str>) -> PyResult<(&'static str, &'static str)> {
    let mass: mesh_fem::Mass = choices::parse(py, "mass", mass)?;
    let matrix = match mass {
        mesh_fem::Mass::Consistent => "B",
        mesh_fem::Mass::Lumped(_) => "D",
        mesh_fem::Mass::Identity => "I",
    };
    Ok((matrix, mass.lumping().name()))
}

/// Registers the functions and constants of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("DEFAULT_NEIGHBORS", mesh_fem::cloud::DEFAULT_NEIGHBOURS)?;
    m.add_function(wrap_pyfunction!(cloud_operators, m)?)?;
    m.add_function(wrap_pyfunction!(read_points, m)?)?;
    m.add_function(wrap_pyfunction!(mass_matrix, m)?)?;
    Ok(())
}
