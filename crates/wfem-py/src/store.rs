//! The SQLite retrieval store (crate retrieval-store): create/open, append, exact top-k scan.

use crate::convert::{mat_in, vec_in};
use crate::errors::{invalid_param, Error};
use crate::run::run;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use retrieval_store::check::CheckReport;
use retrieval_store::metric::StandardMetric;
use retrieval_store::{Entry, Store, StoreParams};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// (id, name, info, distance).
type HitTuple = (u64, String, String, f64);

/// A [`CheckReport`] for Python: (version, checksums, metadata, shapes, chunks,
/// [(record, reason)], text).
pub type CheckTuple = (u32, bool, usize, usize, usize, Vec<(String, String)>, String);

/// The tuple form of a check report (`wfem.CheckReport` in the Python layer).
pub fn check_tuple(r: CheckReport) -> CheckTuple {
    let text = r.to_text();
    (
        r.version,
        r.checksums,
        r.metadata,
        r.shapes,
        r.chunks,
        r.damage.into_iter().map(|d| (d.record, d.reason)).collect(),
        text,
    )
}

/// Rust side of `wfem.VectorStore`: one connection, used by one call at a time.
#[pyclass(name = "VectorStore", module = "wfem._wfem", frozen)]
pub struct PyVectorStore {
    store: Arc<Mutex<Store>>,
    path: PathBuf,
    dimension: usize,
}

impl PyVectorStore {
    fn wrap(store: Store) -> Self {
        Self {
            path: store.path().to_path_buf(),
            dimension: store.dimension(),
            store: Arc::new(Mutex::new(store)),
        }
    }

    /// Runs `f` on the store in a worker thread.
    fn with<T, F>(&self, py: Python<'_>, f: F) -> PyResult<T>
    where
        T: Send + 'static,
        F: FnOnce(&mut Store) -> Result<T, Error> + Send + 'static,
    {
        let store = self.store.clone();
        run(py, move |_| {
            let mut guard = store
                .lock()
                .map_err(|_| Error::Panic("the store's lock is poisoned by an earlier panic".into()))?;
            f(&mut guard)
        })
    }
}

#[pymethods]
impl PyVectorStore {
    #[staticmethod]
    #[pyo3(signature = (path, dimension, chunk_rows=retrieval_store::DEFAULT_CHUNK_ROWS, overwrite=false))]
    fn create(py: Python<'_>, path: PathBuf, dimension: usize, chunk_rows: usize, overwrite: bool) -> PyResult<Self> {
        let params = StoreParams { dimension, chunk_rows };
        run(py, move |_| Ok(Self::wrap(Store::create(&path, &params, overwrite)?)))
    }

    #[staticmethod]
    #[pyo3(signature = (path, readonly=false))]
    fn open(py: Python<'_>, path: PathBuf, readonly: bool) -> PyResult<Self> {
        run(py, move |_| {
            let store = if readonly {
                Store::open_readonly(&path)?
            } else {
                Store::open(&path)?
            };
            Ok(Self::wrap(store))
        })
    }

    /// Verifies every record of the store at `path` and reports all damage.
    #[staticmethod]
    fn check(py: Python<'_>, path: PathBuf) -> PyResult<CheckTuple> {
        run(py, move |_| Ok(check_tuple(Store::check(&path)?)))
    }

    /// Adds checksums to a store of format version 1 in place; returns the check after.
    #[staticmethod]
    fn upgrade(py: Python<'_>, path: PathBuf) -> PyResult<CheckTuple> {
        run(py, move |_| Ok(check_tuple(Store::upgrade(&path)?)))
    }

    /// Whether every record carries a checksum (format version 2).
    #[getter]
    fn checksummed(&self, py: Python<'_>) -> PyResult<bool> {
        self.with(py, |s| Ok(s.checksummed()))
    }

    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    #[getter]
    fn dimension(&self) -> usize {
        self.dimension
    }

    fn __len__(&self, py: Python<'_>) -> PyResult<usize> {
        self.with(py, |s| Ok(s.len()?))
    }

    fn meta<'py>(&self, py: Python<'py>, key: String) -> PyResult<Option<Bound<'py, PyBytes>>> {
        let v = self.with(py, move |s| Ok(s.meta(&key)?))?;
        Ok(v.map(|b| PyBytes::new(py, &b)))
    }

    fn set_meta(&self, py: Python<'_>, key: String, value: Vec<u8>) -> PyResult<()> {
        self.with(py, move |s| Ok(s.set_meta(&key, &value)?))
    }

    /// Appends shapes (one transaction); returns their ids.
    fn add(
        &self,
        py: Python<'_>,
        names: Vec<String>,
        infos: Vec<String>,
        vectors: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<Vec<u64>> {
        let v = mat_in(&vectors);
        if names.len() != v.nrows() || infos.len() != names.len() {
            return Err(invalid_param(
                py,
                "vectors",
                format!(
                    "{} names, {} infos and {} vectors: one of each per shape",
                    names.len(),
                    infos.len(),
                    v.nrows()
                ),
            ));
        }
        self.with(py, move |s| {
            let rows: Vec<Vec<f64>> = (0..v.nrows()).map(|i| v.row(i).iter().copied().collect()).collect();
            let entries: Vec<Entry<'_>> = names
                .iter()
                .zip(&infos)
                .zip(&rows)
                .map(|((n, i), r)| Entry::new(n, i, r))
                .collect();
            Ok(s.add(&entries)?)
        })
    }

    /// The k nearest shapes: [(id, name, info, distance)].
    #[pyo3(signature = (query, k=shape_retrieval::model::DEFAULT_RESULTS, metric=None))]
    fn search(
        &self,
        py: Python<'_>,
        query: PyReadonlyArray1<'_, f64>,
        k: usize,
        metric: Option<&str>,
    ) -> PyResult<Vec<HitTuple>> {
        let q = vec_in(&query);
        let metric: StandardMetric = crate::choices::parse(py, "metric", metric)?;
        self.with(py, move |s| {
            Ok(s.search_metric(&q, k, &metric)?
                .into_iter()
                .map(|h| (h.id, h.name, h.info, h.distance))
                .collect())
        })
    }

    /// Every shape: [(id, name, info)].
    fn shapes(&self, py: Python<'_>) -> PyResult<Vec<(u64, String, String)>> {
        self.with(py, |s| {
            Ok(s.shapes()?.into_iter().map(|r| (r.id, r.name, r.info)).collect())
        })
    }

    /// The shape named `name`: (id, info), or None.
    fn find(&self, py: Python<'_>, name: String) -> PyResult<Option<(u64, String)>> {
        self.with(py, move |s| Ok(s.find(&name)?.map(|r| (r.id, r.info))))
    }

    /// Every vector (n, d) float32, by id.
    fn vectors<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let d = self.dimension;
        let flat = self.with(py, |s| Ok(s.vectors()?))?;
        let n = flat.len() / d;
        Array2::from_shape_vec((n, d), flat)
            .map(|a| a.into_pyarray(py))
            .map_err(|e| Error::Panic(format!("vector table shape: {e}")).into_py(py))
    }

    /// The vector of shape `id` (d,) float32, or None.
    fn vector<'py>(&self, py: Python<'py>, id: u64) -> PyResult<Option<Bound<'py, PyArray1<f32>>>> {
        let v = self.with(py, move |s| Ok(s.vector(id)?))?;
        Ok(v.map(|v| v.into_pyarray(py)))
    }
}

/// Registers the class of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyVectorStore>()?;
    Ok(())
}
