//! `wfem._wfem`: the compiled part of the Python package `wfem` (see `python/wfem`, which
//! converts and checks arguments, builds `scipy.sparse` matrices and carries the docstrings).
//!
//! Every long call runs without the GIL and can be interrupted with Ctrl-C (`run.rs`); every
//! Rust error becomes an exception of `wfem._errors` keeping the culprit (`errors.rs`).

/// mimalloc as the extension's allocator (see Cargo.toml): freed memory is reused by the next
/// call instead of being unmapped and faulted in again.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod choices;
mod cloud;
mod convert;
mod defaults;
mod errors;
mod geodesic;
mod heat;
mod index;
mod mesh;
mod out;
mod retrieval;
mod run;
mod spectral;
mod store;
mod volume;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _wfem(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("DENSE_MAX_VERTICES", wfem_heat::spectral::DENSE_MAX_VERTICES)?;
    m.add("DEFAULT_DEGREE", shifted_solve::poles::DEFAULT_DEGREE)?;
    m.add(
        "DEFAULT_SPIKE_THRESHOLD",
        shape_retrieval::model::DEFAULT_SPIKE_THRESHOLD,
    )?;
    m.add(
        "DEFAULT_MAX_HOLE_PERIMETER",
        shape_retrieval::model::DEFAULT_MAX_HOLE_PERIMETER,
    )?;
    m.add(
        "DEFAULT_TARGET_ROUGHNESS",
        shape_retrieval::model::DEFAULT_TARGET_ROUGHNESS,
    )?;
    m.add(
        "DEFAULT_VERTICES_PER_EIGENPAIR",
        shape_retrieval::model::DEFAULT_VERTICES_PER_EIGENPAIR,
    )?;
    m.add("DEFAULT_SPATIAL_TIME", shape_retrieval::spatial::DEFAULT_SPATIAL_TIME)?;
    // The library's default bags: the spatial time when they are on by default, else None.
    m.add(
        "DEFAULT_SPATIAL",
        shape_retrieval::model::BagSettings::default().spatial.map(|s| s.time),
    )?;
    m.add("DEFAULT_WORDS", shape_retrieval::model::DEFAULT_WORDS)?;
    m.add("SHIPPED_DEGREES", shifted_solve::poles::SHIPPED_DEGREES.to_vec())?;
    m.add(
        "PAPER_DESCRIPTORS",
        shape_retrieval::descriptor::Descriptor::paper()
            .map(|d| wfem_base::Choice::name(&d))
            .to_vec(),
    )?;
    m.add("DEFAULT_NUM_TIMES", shape_retrieval::hks::DEFAULT_NUM_TIMES)?;
    choices::register(m)?;
    defaults::register(m)?;
    mesh::register(m)?;
    cloud::register(m)?;
    heat::register(m)?;
    geodesic::register(m)?;
    spectral::register(m)?;
    retrieval::register(m)?;
    store::register(m)?;
    index::register(m)?;
    volume::register(m)?;
    m.add_function(wrap_pyfunction!(run::_live_workers, m)?)?;
    Ok(())
}
