//! Python strings to the library's registries ([`wfem_base::Choice`]): the one module where
//! the bindings parse a choice (a mass, a method, a backend, a descriptor, …). The names,
//! aliases, help and defaults come from the library types; `wfem._wfem.choices()` hands them
//! to the Python layer, which keeps no copy either.

use crate::errors::invalid_param;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use wfem_base::Choice;

/// The value of `text` in the registry `T`, or its default for `None`; an unknown name is an
/// `InvalidInputError` naming the parameter and listing the valid names.
pub fn parse<T: Choice + Default>(py: Python<'_>, param: &'static str, text: Option<&str>) -> PyResult<T> {
    match text {
        None => Ok(T::default()),
        Some(text) => T::parse(text).map_err(|e| invalid_param(py, param, e.to_string())),
    }
}

/// `{name: (help, aliases)}` of a registry, in order, and its default name.
fn table<T: Choice + Default>(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    let names = PyDict::new(py);
    for e in T::entries() {
        names.set_item(e.name, (e.help, e.aliases.to_vec()))?;
    }
    d.set_item("what", T::WHAT)?;
    d.set_item("names", names)?;
    d.set_item("default", T::default_name())?;
    Ok(d)
}

/// The registries the Python API takes, each by the keyword argument that takes it: one line
/// per registry generates `choices()` and `canonical()`.
macro_rules! registries {
    ($($key:literal => $ty:ty),+ $(,)?) => {
        /// Every registry: `{argument: {"what", "names": {name: (help, aliases)}, "default"}}`,
        /// plus `"lumped_masses"`, the masses that are diagonal.
        #[pyfunction]
        pub fn choices(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
            let d = PyDict::new(py);
            $( d.set_item($key, table::<$ty>(py)?)?; )+
            let lumped: Vec<&str> = mesh_fem::Mass::entries()
                .iter()
                .filter(|e| matches!(mesh_fem::Mass::from_canonical(e.name), Some(mesh_fem::Mass::Lumped(_))))
                .map(|e| e.name)
                .collect();
            d.set_item("lumped_masses", lumped)?;
            Ok(d)
        }

        /// The canonical name of `text` in the registry of `argument` (aliases, any case, `_`
        /// for `-`); an unknown name is an `InvalidInputError` listing the valid ones.
        #[pyfunction]
        pub fn canonical(py: Python<'_>, argument: &str, text: &str) -> PyResult<&'static str> {
            match argument {
                $( $key => Ok(parse::<$ty>(py, $key, Some(text))?.name()), )+
                other => Err(invalid_param(py, "argument", format!("no registry is called {other:?}"))),
            }
        }
    };
}

registries! {
    "mass" => mesh_fem::Mass,
    "lumped_mass" => mesh_fem::Lumping,
    "laplacian" => mesh_fem::Laplacian,
    "method" => wfem_heat::method::Method,
    "backend" => shifted_solve::backend::Backend,
    "convention" => wfem_heat::KernelDiagonal,
    "diagonal" => wfem_heat::diagonal::DiagonalMethod,
    "distance" => wfem_heat::distance::DistanceKind,
    "geodesic_method" => wfem_heat::geodesic::GeodesicMethod,
    "coefficients" => wfem_heat::approx::Coefficients,
    "sampling" => wfem_heat::approx::ScaleSampling,
    "noise" => wfem_heat::approx::NoiseRule,
    "hks_method" => shape_retrieval::exact::HksMethod,
    "normalization" => shape_retrieval::hks::SpectrumNormalization,
    "descriptor" => shape_retrieval::descriptor::Descriptor,
    "detector" => shape_retrieval::descriptor::FeatureDetector,
    "bag_distance" => shape_retrieval::distance::BagDistance,
    "global_kind" => shape_retrieval::global::GlobalKind,
    "metric" => retrieval_store::metric::StandardMetric,
    "time_unit" => shape_retrieval::sihks::TimeUnit,
    "class_from" => shape_retrieval::eval::ClassRule,
}

/// Registers `choices` and `canonical`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(choices, m)?)?;
    m.add_function(wrap_pyfunction!(canonical, m)?)?;
    Ok(())
}
