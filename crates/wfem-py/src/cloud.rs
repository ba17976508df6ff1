//! Point clouds and the choice of Laplacian (issue #27): `cloud_operators(P, …)` and
//! `read_points(path)`, and the `laplacian=` names, all taken from mesh-fem's types.

use crate::convert::{sparse_out, SparseOut};
use crate::errors::{invalid_param, Error};
use crate::mesh::lumped_kind;
use crate::run::run;
use mesh_fem::io::load_points;
use mesh_fem::{assemble_cloud, AssemblyParams, CloudParams, Laplacian, PointCloud, RobustParams};
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;

/// The Laplacian of a `laplacian=` name ([`Laplacian::NAMES`]) with the given mollification.
pub fn laplacian_of(py: Python<'_>, name: &str, mollify_factor: Option<f64>) -> PyResult<Laplacian> {
    match Laplacian::from_name(name) {
        Some(Laplacian::Robust(mut params)) => {
            if let Some(m) = mollify_factor {
                params.mollify_factor = m;
            }
            Ok(Laplacian::Robust(params))
        }
        Some(l) if mollify_factor.is_none() => Ok(l),
        Some(l) => Err(invalid_param(
            py,
            "mollify_factor",
            format!("applies to the robust Laplacian, not to {:?}", l.name()),
        )),
        None => Err(invalid_param(
            py,
            "laplacian",
            format!("{name:?} is not one of {:?}", Laplacian::NAMES),
        )),
    }
}

/// The Laplacian of an optional `laplacian=` name (`None`: [`Laplacian::default`]).
pub fn assembly_laplacian(py: Python<'_>, name: Option<&str>, mollify_factor: Option<f64>) -> PyResult<Laplacian> {
    match name {
        Some(name) => laplacian_of(py, name, mollify_factor),
        None => laplacian_of(py, Laplacian::default().name(), mollify_factor),
    }
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

/// A cloud's (L, B, D) and its report as JSON.
type CloudOut<'py> = (SparseOut<'py>, SparseOut<'py>, SparseOut<'py>, String);

/// `cloud_operators(P, normals=None, lumped, n_neighbors, mollify_factor) -> (L, B, D, report)`.
#[pyfunction]
#[pyo3(signature = (p, normals=None, lumped="barycentric", n_neighbors=mesh_fem::cloud::DEFAULT_NEIGHBOURS, mollify_factor=None))]
pub fn cloud_operators<'py>(
    py: Python<'py>,
    p: PyReadonlyArray2<'py, f64>,
    normals: Option<PyReadonlyArray2<'py, f64>>,
    lumped: &str,
    n_neighbors: usize,
    mollify_factor: Option<f64>,
) -> PyResult<CloudOut<'py>> {
    let positions = rows(py, &p, "P")?;
    let normals = normals.map(|n| rows(py, &n, "normals")).transpose()?;
    let lumped = lumped_kind(py, lumped)?;
    let params = CloudParams {
        n_neighbours: n_neighbors,
        mollify_factor: mollify_factor.unwrap_or(RobustParams::default().mollify_factor),
        ..CloudParams::default()
    };
    let ops = run(py, move |_| {
        let cloud = PointCloud::new(positions, normals)?;
        let assembly = AssemblyParams {
            lumped,
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

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("LAPLACIANS", Laplacian::NAMES.to_vec())?;
    m.add(
        "LAPLACIAN_HELP",
        Laplacian::NAMES
            .iter()
            .filter_map(|n| Laplacian::from_name(n).map(|l| (*n, l.help())))
            .collect::<Vec<_>>(),
    )?;
    m.add("DEFAULT_NEIGHBORS", mesh_fem::cloud::DEFAULT_NEIGHBOURS)?;
    m.add_function(wrap_pyfunction!(cloud_operators, m)?)?;
    m.add_function(wrap_pyfunction!(read_points, m)?)?;
    Ok(())
}
