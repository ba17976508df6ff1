//! Shape descriptors (DHK1–3, SI-HKS, sparse features), vocabularies, bags of features and
//! retrieval metrics (paper, Sect. 5).

use crate::choices;
use crate::convert::{mat_in, mesh_in, vec_in};
use crate::errors::invalid_param;
use crate::heat::PyHeatKernel;
use crate::out::{mat_out, vec_out};
use crate::run::run;
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use shape_retrieval::bof::{Vocabulary, VocabularyParams};
use shape_retrieval::descriptor::{Descriptor, DescriptorOptions, DescriptorParams, FeatureDetector, ShapeDescriptors};
use shape_retrieval::hks::TimeSampling;
use shape_retrieval::kmeans::{kmeans, KmeansParams};
use shape_retrieval::retrieval::evaluate;
use shape_retrieval::sihks::SihksParams;
use shape_retrieval::RetrievalError;
use std::sync::Arc;

/// The descriptor pipeline's parameters from Python values.
fn descriptor_params(
    k: usize,
    feature_time_factor: f64,
    feature_rings: usize,
    persistence_fraction: f64,
) -> DescriptorParams {
    DescriptorParams {
        eigenpairs: k,
        feature_time_factor,
        feature_rings,
        persistence_fraction,
        ..Default::default()
    }
}

/// `descriptors`' keyword arguments as the options of one descriptor: each descriptor takes
/// those that apply to it (the times for DHK1–3 and area-HKS, `sihks` for SI-HKS), so one call
/// can ask for several.
fn options_for(
    descriptor: &Descriptor,
    times: &Option<Vec<f64>>,
    num_times: usize,
    sihks: &SihksParams,
) -> DescriptorOptions {
    let takes = descriptor.options();
    if takes.contains(&"times") {
        let sampling = match times {
            Some(t) => Some(TimeSampling::Explicit(t.clone())),
            // area-HKS has no automatic times: without times it is refused as empty.
            None if matches!(descriptor, Descriptor::AreaHks { .. }) => None,
            None => Some(TimeSampling::Auto { num_times }),
        };
        DescriptorOptions {
            times: sampling,
            ..Default::default()
        }
    } else if takes.contains(&"tau_min") {
        DescriptorOptions::sihks(sihks)
    } else {
        DescriptorOptions::default()
    }
}

fn sihks_params(py: Python<'_>, d: Option<&Bound<'_, PyDict>>) -> PyResult<Option<SihksParams>> {
    let Some(d) = d else { return Ok(None) };
    let mut p = SihksParams::default();
    for (key, value) in d.iter() {
        let key: String = key.extract()?;
        match key.as_str() {
            "alpha" => p.alpha = value.extract()?,
            "tau_min" => p.tau_min = value.extract()?,
            "tau_max" => p.tau_max = value.extract()?,
            "tau_step" => p.tau_step = value.extract()?,
            // t₀ in squared length units, or t₀ = c·area (exactly scale invariant).
            "time_unit" => p.time_unit = shape_retrieval::sihks::TimeUnit::Absolute(value.extract()?),
            "time_unit_area" => p.time_unit = shape_retrieval::sihks::TimeUnit::Area(value.extract()?),
            "num_frequencies" => p.num_frequencies = value.extract()?,
            "convention" => p.convention = choices::parse(py, "convention", Some(&value.extract::<String>()?))?,
            other => {
                return Err(invalid_param(
                    py,
                    "sihks",
                    format!(
                        "unknown option {other:?} (alpha, tau_min, tau_max, tau_step, time_unit, time_unit_area, num_frequencies, convention)"
                    ),
                ))
            }
        }
    }
    if (p.tau_max - p.tau_min) / p.tau_step > 100_000.0 {
        return Err(invalid_param(
            py,
            "sihks",
            "the τ window would have more than 100000 samples",
        ));
    }
    Ok(Some(p))
}

/// Dense descriptors of one mesh: {name: (n, d) array}, sharing one eigenbasis per mass.
#[pyfunction]
#[pyo3(signature = (v, f, kinds, k=shape_retrieval::descriptor::DEFAULT_EIGENPAIRS, times=None, num_times=shape_retrieval::hks::DEFAULT_NUM_TIMES, sihks=None))]
#[allow(clippy::too_many_arguments)]
pub fn descriptors<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray2<'py, i64>,
    kinds: Vec<String>,
    k: usize,
    times: Option<Vec<f64>>,
    num_times: usize,
    sihks: Option<Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mesh = mesh_in(py, &v, &f)?;
    let sihks = sihks_params(py, sihks.as_ref())?.unwrap_or_default();
    let which = kinds
        .iter()
        .map(|s| {
            let d = choices::parse::<Descriptor>(py, "kinds", Some(s))?;
            let options = options_for(&d, &times, num_times, &sihks);
            d.with_options(&options).map_err(|e| crate::errors::retrieval(py, &e))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let defaults = DescriptorParams::default();
    let params = descriptor_params(
        k,
        defaults.feature_time_factor,
        defaults.feature_rings,
        defaults.persistence_fraction,
    );
    let out = run(py, move |cancel| {
        let mut shape = ShapeDescriptors::new(&mesh, &params)?;
        cancel.map(which, |d| Ok(shape.dense(&d)?))
    })?;
    let d = PyDict::new(py);
    for (name, m) in kinds.iter().zip(out) {
        d.set_item(name, mat_out(py, m.as_ref()))?;
    }
    Ok(d)
}

/// Sparse feature points (SHK1 / SHK2) of a mesh and the feature time t_f.
#[pyfunction]
#[pyo3(signature = (v, f, detector=None, k=shape_retrieval::descriptor::DEFAULT_EIGENPAIRS, feature_time_factor=shape_retrieval::descriptor::DescriptorParams::default().feature_time_factor, feature_rings=shape_retrieval::descriptor::DescriptorParams::default().feature_rings, persistence_fraction=shape_retrieval::descriptor::DescriptorParams::default().persistence_fraction))]
#[allow(clippy::too_many_arguments)]
pub fn sparse_features(
    py: Python<'_>,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
    detector: Option<&str>,
    k: usize,
    feature_time_factor: f64,
    feature_rings: usize,
    persistence_fraction: f64,
) -> PyResult<(Vec<u32>, f64)> {
    let mesh = mesh_in(py, &v, &f)?;
    let detector: FeatureDetector = choices::parse(py, "detector", detector)?;
    let params = descriptor_params(k, feature_time_factor, feature_rings, persistence_fraction);
    run(py, move |_| {
        let mut shape = ShapeDescriptors::new(&mesh, &params)?;
        let (t, _) = shape.feature_function()?;
        Ok((shape.features(detector)?, t))
    })
}

/// Rust side of `wfem.Vocabulary`.
#[pyclass(name = "Vocabulary", module = "wfem._wfem", frozen)]
pub struct PyVocabulary {
    pub inner: Arc<Vocabulary>,
}

#[pymethods]
impl PyVocabulary {
    #[new]
    fn new(py: Python<'_>, words: PyReadonlyArray2<'_, f64>, sigma: f64) -> PyResult<Self> {
        let inner = Vocabulary::new(mat_in(&words), sigma).map_err(|e| crate::errors::retrieval(py, &e))?;
        Ok(Self { inner: Arc::new(inner) })
    }

    #[staticmethod]
    #[pyo3(signature = (descriptors, size=shape_retrieval::bof::VocabularyParams::default().size, max_iter=shape_retrieval::bof::VocabularyParams::default().max_iter, seed=shape_retrieval::bof::VocabularyParams::default().seed, sigma=None, max_training_points=None))]
    fn train(
        py: Python<'_>,
        descriptors: PyReadonlyArray2<'_, f64>,
        size: usize,
        max_iter: usize,
        seed: u64,
        sigma: Option<f64>,
        max_training_points: Option<usize>,
    ) -> PyResult<Self> {
        let d = mat_in(&descriptors);
        let params = VocabularyParams {
            size,
            max_iter,
            seed,
            sigma,
            max_training_points,
        };
        run(py, move |_| {
            Ok(Self {
                inner: Arc::new(Vocabulary::train(d.as_ref(), &params)?),
            })
        })
    }

    #[getter]
    fn words<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_out(py, self.inner.words())
    }

    #[getter]
    fn sigma(&self) -> f64 {
        self.inner.sigma()
    }

    #[getter]
    fn size(&self) -> usize {
        self.inner.size()
    }

    /// Θ (n, V), rows summing to 1.
    fn soft_assignment<'py>(
        &self,
        py: Python<'py>,
        descriptors: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let d = mat_in(&descriptors);
        let inner = self.inner.clone();
        let out = run(py, move |_| Ok(inner.soft_assignment(d.as_ref())?))?;
        Ok(mat_out(py, out.as_ref()))
    }

    /// Θᵀ a (V,).
    fn bag<'py>(
        &self,
        py: Python<'py>,
        descriptors: PyReadonlyArray2<'py, f64>,
        weights: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let d = mat_in(&descriptors);
        let w = vec_in(&weights);
        let inner = self.inner.clone();
        let out = run(py, move |_| Ok(inner.bag_of_features(d.as_ref(), &w)?))?;
        Ok(vec_out(py, out))
    }

    /// Θᵀ M K_t Θ (V, V) with the kernel's mass M and method.
    fn spatially_sensitive_bag<'py>(
        &self,
        py: Python<'py>,
        descriptors: PyReadonlyArray2<'py, f64>,
        kernel: PyRef<'py, PyHeatKernel>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let d = mat_in(&descriptors);
        let inner = self.inner.clone();
        let kernel = kernel.kernel.clone();
        let out = run(py, move |_| {
            Ok(inner.spatially_sensitive_bag(d.as_ref(), kernel.mass(), |theta| {
                kernel.apply_many(theta, t).map_err(RetrievalError::from)
            })?)
        })?;
        Ok(mat_out(py, out.as_ref()))
    }
}

/// (centers (k, d), assignment, inertia, iterations, converged).
type Clusters<'py> = (Bound<'py, PyArray2<f64>>, Vec<u32>, f64, usize, bool);

/// k-means.
#[pyfunction]
#[pyo3(signature = (points, k, max_iter=shape_retrieval::kmeans::KmeansParams::default().max_iter, seed=shape_retrieval::kmeans::KmeansParams::default().seed))]
pub fn kmeans_clusters<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    k: usize,
    max_iter: usize,
    seed: u64,
) -> PyResult<Clusters<'py>> {
    let p = mat_in(&points);
    let report = run(py, move |_| {
        Ok(kmeans(p.as_ref(), &KmeansParams { k, max_iter, seed })?)
    })?;
    Ok((
        mat_out(py, report.centers.as_ref()),
        report.assignment,
        report.inertia,
        report.iterations,
        report.converged,
    ))
}

/// (AP per query (None if undefined), mAP, per class [(label, mAP, queries)]).
type Evaluation = (Vec<Option<f64>>, f64, Vec<(u32, f64, usize)>);

/// Leave-one-out retrieval on a distance matrix.
#[pyfunction]
pub fn evaluate_retrieval(
    py: Python<'_>,
    distances: PyReadonlyArray2<'_, f64>,
    labels: Vec<u32>,
) -> PyResult<Evaluation> {
    let d = mat_in(&distances);
    let report = run(py, move |_| Ok(evaluate(d.as_ref(), &labels)?))?;
    Ok((
        report.average_precision,
        report.mean_average_precision,
        report
            .per_class
            .iter()
            .map(|c| (c.label, c.mean_average_precision, c.n_queries))
            .collect(),
    ))
}

/// Pairwise L1 distances between bags (m, m).
#[pyfunction]
pub fn pairwise_l1<'py>(py: Python<'py>, bags: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let b = mat_in(&bags);
    let rows: Vec<Vec<f64>> = (0..b.nrows()).map(|i| b.row(i).iter().copied().collect()).collect();
    let out = run(py, move |_| Ok(shape_retrieval::distance::pairwise_l1(&rows)?))?;
    Ok(mat_out(py, out.as_ref()))
}

/// Registers the functions and classes of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(descriptors, m)?)?;
    m.add_function(wrap_pyfunction!(sparse_features, m)?)?;
    m.add_function(wrap_pyfunction!(kmeans_clusters, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate_retrieval, m)?)?;
    m.add_function(wrap_pyfunction!(pairwise_l1, m)?)?;
    m.add_class::<PyVocabulary>()?;
    Ok(())
}
