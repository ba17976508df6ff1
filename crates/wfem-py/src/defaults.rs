//! `wfem._wfem.DEFAULTS`: the library's default parameters, by group, which the Python layer's
//! signatures read instead of repeating them (`crates/wfem-py/tests/test_defaults.py` checks
//! that no signature under `python/wfem` holds a numeric literal, and that each group equals
//! what the native functions use when an argument is left out). Every value here is read from
//! the library's own `Default` or constant: this file holds no number.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use shape_retrieval::sihks::{SihksParams, TimeUnit};

/// The factor of an SI-HKS sampling's time unit (Python's `time_unit` float, in the mesh's own
/// squared length unit for [`shape_retrieval::sihks::BRONSTEIN_KOKKINOS`]).
pub fn absolute_unit(p: &SihksParams) -> f64 {
    match p.time_unit {
        TimeUnit::Absolute(c) | TimeUnit::Area(c) | TimeUnit::Edge(c) => c,
    }
}

/// One group of defaults: `{name: value}`.
fn group<'py>(py: Python<'py>, items: &[(&str, Py<PyAny>)]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (name, value) in items {
        d.set_item(*name, value)?;
    }
    Ok(d)
}

/// Adds `DEFAULTS` to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let v = |x: f64| x.into_pyobject(py).map(|o| o.into_any().unbind());
    let n = |x: usize| x.into_pyobject(py).map(|o| o.into_any().unbind());
    let s = |x: u64| x.into_pyobject(py).map(|o| o.into_any().unbind());
    let d = PyDict::new(py);

    let eigen = wfem_heat::spectral::EigenParams::default();
    d.set_item(
        "eigen",
        group(
            py,
            &[
                ("k", n(shape_retrieval::descriptor::DEFAULT_EIGENPAIRS)?),
                ("tol", v(eigen.tol)?),
                ("block_size", n(eigen.block_size)?),
                ("seed", s(eigen.seed)?),
                ("max_restarts", n(eigen.max_restarts)?),
            ],
        )?,
    )?;
    let diagonal = wfem_heat::DiagonalParams::default();
    d.set_item(
        "diagonal",
        group(
            py,
            &[
                ("tol", v(wfem_heat::diagonal::DEFAULT_PROBING_TOL)?),
                ("max_columns", n(diagonal.max_columns)?),
                ("block", n(diagonal.block)?),
            ],
        )?,
    )?;
    d.set_item(
        "distance",
        group(
            py,
            &[
                ("block", n(wfem_heat::distance::DistanceParams::default().block)?),
                ("diagonal_tol", v(wfem_heat::diagonal::DEFAULT_PROBING_TOL)?),
            ],
        )?,
    )?;
    let inverse = wfem_heat::rkhs::InverseParams::default();
    d.set_item(
        "inverse",
        group(
            py,
            &[
                ("max_amplification", v(inverse.max_amplification)?),
                ("tol", v(inverse.tol)?),
                ("max_iter", n(inverse.max_iter)?),
                ("stall_window", n(inverse.stall_window)?),
            ],
        )?,
    )?;
    let largest = wfem_heat::scale::LargestEigenParams::default();
    d.set_item(
        "largest_eigenvalue",
        group(
            py,
            &[
                ("tol", v(largest.tol)?),
                ("max_iter", n(largest.max_iter)?),
                ("seed", s(largest.seed)?),
            ],
        )?,
    )?;
    d.set_item(
        "geodesic",
        group(py, &[("refine", n(wfem_heat::geodesic::DEFAULT_REFINE as usize)?)])?,
    )?;
    let bk = shape_retrieval::sihks::BRONSTEIN_KOKKINOS;
    d.set_item(
        "sihks",
        group(
            py,
            &[
                ("alpha", v(bk.alpha)?),
                ("tau_min", v(bk.tau_min)?),
                ("tau_max", v(bk.tau_max)?),
                ("tau_step", v(bk.tau_step)?),
                ("time_unit", v(absolute_unit(&bk))?),
                ("num_frequencies", n(bk.num_frequencies)?),
            ],
        )?,
    )?;
    let descriptor = shape_retrieval::descriptor::DescriptorParams::default();
    d.set_item(
        "descriptor",
        group(
            py,
            &[
                ("k", n(descriptor.eigenpairs)?),
                ("num_times", n(shape_retrieval::hks::DEFAULT_NUM_TIMES)?),
                ("feature_time_factor", v(descriptor.feature_time_factor)?),
                ("feature_rings", n(descriptor.feature_rings)?),
                ("persistence_fraction", v(descriptor.persistence_fraction)?),
            ],
        )?,
    )?;
    let kmeans = shape_retrieval::kmeans::KmeansParams::default();
    d.set_item(
        "kmeans",
        group(py, &[("max_iter", n(kmeans.max_iter)?), ("seed", s(kmeans.seed)?)])?,
    )?;
    let vocabulary = shape_retrieval::bof::VocabularyParams::default();
    d.set_item(
        "vocabulary",
        group(
            py,
            &[
                ("size", n(vocabulary.size)?),
                ("max_iter", n(vocabulary.max_iter)?),
                ("seed", s(vocabulary.seed)?),
            ],
        )?,
    )?;
    d.set_item(
        "index",
        group(
            py,
            &[
                ("seed", s(shape_retrieval::model::TrainingParams::default().seed)?),
                ("k", n(shape_retrieval::model::DEFAULT_RESULTS)?),
                ("chunk_rows", n(retrieval_store::DEFAULT_CHUNK_ROWS)?),
            ],
        )?,
    )?;
    d.set_item(
        "global",
        group(
            py,
            &[
                ("eigenvalues", n(shape_retrieval::global::DEFAULT_EIGENVALUES)?),
                ("dimension", n(shape_retrieval::global::DEFAULT_DIMENSION)?),
            ],
        )?,
    )?;
    m.add("DEFAULTS", d)?;
    Ok(())
}
