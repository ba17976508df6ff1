//! Geodesic distances (`wfem.GeodesicSolver`, `wfem.geodesic_distance`): fast marching on the
//! intrinsic Delaunay triangulation or the heat method (`wfem_heat::geodesic`), and all-pairs
//! matrices streamed to `.npy` for geodesic and diffusion distances.

use crate::choices;
use crate::convert::mesh_in;
use crate::out::{mat_out, vec_out};
use crate::run::{run, run_reporting};
use faer::Mat;
use mesh_fem::{Laplacian, RobustParams};
use numpy::{PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;
use wfem_heat::geodesic::{GeodesicParams, GeodesicSolver, Source};

/// The parameters from the Python arguments (potpourri3d's `t_coef`, `use_robust`).
fn params(
    py: Python<'_>,
    method: Option<&str>,
    t_coef: f64,
    use_robust: bool,
    refine: u32,
) -> PyResult<GeodesicParams> {
    Ok(GeodesicParams {
        method: choices::parse(py, "geodesic_method", method)?,
        t_coef,
        laplacian: if use_robust {
            Laplacian::Robust(RobustParams::default())
        } else {
            Laplacian::Cotan
        },
        refine,
    })
}

/// Rust side of `wfem.GeodesicSolver`.
#[pyclass(name = "GeodesicSolver", module = "wfem._wfem", frozen)]
pub struct PyGeodesicSolver {
    inner: Arc<GeodesicSolver>,
}

#[pymethods]
impl PyGeodesicSolver {
    #[staticmethod]
    #[pyo3(signature = (v, f, method=None, t_coef=wfem_heat::geodesic::DEFAULT_T_COEF, use_robust=true, refine=wfem_heat::geodesic::DEFAULT_REFINE))]
    fn from_mesh(
        py: Python<'_>,
        v: PyReadonlyArray2<'_, f64>,
        f: PyReadonlyArray2<'_, i64>,
        method: Option<&str>,
        t_coef: f64,
        use_robust: bool,
        refine: u32,
    ) -> PyResult<Self> {
        let mesh = mesh_in(py, &v, &f)?;
        let params = params(py, method, t_coef, use_robust, refine)?;
        run(py, move |_| {
            Ok(Self {
                inner: Arc::new(GeodesicSolver::new(&mesh, &params)?),
            })
        })
    }

    /// The heat method through a tetrahedral mesh (the default and only method on a volume).
    #[staticmethod]
    #[pyo3(signature = (v, t, method=None, t_coef=wfem_heat::geodesic::DEFAULT_T_COEF))]
    fn from_volume(
        py: Python<'_>,
        v: PyReadonlyArray2<'_, f64>,
        t: PyReadonlyArray2<'_, i64>,
        method: Option<&str>,
        t_coef: f64,
    ) -> PyResult<Self> {
        let volume = crate::volume::volume_in(py, &v, &t)?;
        let mut params = params(py, method, t_coef, false, 0)?;
        if method.is_none() {
            params.method = wfem_heat::geodesic::GeodesicMethod::Heat;
        }
        run(py, move |_| {
            Ok(Self {
                inner: Arc::new(GeodesicSolver::from_volume(&volume, &params)?),
            })
        })
    }

    #[staticmethod]
    #[pyo3(signature = (p, method=None, t_coef=wfem_heat::geodesic::DEFAULT_T_COEF, n_neighbors=None))]
    fn from_cloud(
        py: Python<'_>,
        p: PyReadonlyArray2<'_, f64>,
        method: Option<&str>,
        t_coef: f64,
        n_neighbors: Option<usize>,
    ) -> PyResult<Self> {
        let (cloud, cloud_params) = crate::cloud::cloud_in(py, &p, n_neighbors)?;
        let params = params(py, method, t_coef, true, 0)?;
        run(py, move |_| {
            Ok(Self {
                inner: Arc::new(GeodesicSolver::from_cloud(&cloud, &params, &cloud_params)?),
            })
        })
    }

    #[getter]
    fn n(&self) -> usize {
        self.inner.n_vertices()
    }

    #[getter]
    fn t(&self) -> Option<f64> {
        self.inner.t()
    }

    #[getter]
    fn mean_edge_length(&self) -> f64 {
        self.inner.mean_edge_length()
    }

    #[getter]
    fn memory_bytes(&self) -> usize {
        self.inner.memory_bytes()
    }

    /// Distances to the nearest of the sources: vertices and points `(face, b0, b1, b2)`;
    /// returns the distances and (unreachable, heat_underflow).
    fn distance<'py>(
        &self,
        py: Python<'py>,
        vertices: Vec<u32>,
        points: Vec<(u32, f64, f64, f64)>,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, (usize, usize))> {
        let inner = self.inner.clone();
        let mut sources: Vec<Source> = vertices.into_iter().map(Source::Vertex).collect();
        sources.extend(points.into_iter().map(|(face, a, b, c)| Source::Point {
            face,
            barycentric: [a, b, c],
        }));
        let (d, report) = run(py, move |_| Ok(inner.distance_from(&sources)?))?;
        Ok((vec_out(py, d), (report.unreachable, report.heat_underflow)))
    }

    /// One row per source vertex (|S|, n).
    fn distance_each<'py>(&self, py: Python<'py>, vertices: Vec<u32>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let inner = self.inner.clone();
        let n = inner.n_vertices();
        let m = vertices.len();
        let rows = run(py, move |cancel| {
            let mut rows = Vec::with_capacity(m);
            for chunk in vertices.chunks(64) {
                cancel.check()?;
                rows.extend(inner.distance_each(chunk)?);
            }
            Ok(rows)
        })?;
        Ok(mat_out(py, Mat::from_fn(m, n, |i, j| rows[i][j]).as_ref()))
    }

    /// The n × n matrix streamed to `out` (resumable); returns (path, resumed_from).
    #[pyo3(signature = (out, progress=None, block_rows=None))]
    fn all_pairs(
        &self,
        py: Python<'_>,
        out: PathBuf,
        progress: Option<Py<PyAny>>,
        block_rows: Option<usize>,
    ) -> PyResult<(PathBuf, usize)> {
        let inner = self.inner.clone();
        let key = format!("python|{:?}|{}", inner.params(), inner.n_vertices());
        run_reporting(py, progress, move |_, report| {
            let n = inner.n_vertices();
            let r = wfem_heat::distance::write_rows(
                &out,
                n,
                n,
                &key,
                block_rows,
                |range, block| {
                    let sources: Vec<u32> = (range.start as u32..range.end as u32).collect();
                    inner.distance_each_into(&sources, block)
                },
                &mut |done, total| {
                    // Synchronous: a callback that raises stops the call before the next block.
                    report.step(&format!("{done}/{total}"));
                    report.flush();
                },
            )?;
            Ok((r.path, r.resumed_from))
        })
    }
}

/// Streams the n × n diffusion distances of a `DiffusionDistance` to `out` (resumable).
pub fn diffusion_all_pairs(
    py: Python<'_>,
    inner: Arc<wfem_heat::distance::DiffusionDistance>,
    out: PathBuf,
    progress: Option<Py<PyAny>>,
    block_rows: Option<usize>,
) -> PyResult<(PathBuf, usize)> {
    use wfem_base::Choice;
    let key = format!("python|{}|{:e}|{}", inner.kind().name(), inner.t(), inner.n());
    run_reporting(py, progress, move |_, report| {
        let n = inner.n();
        let r = wfem_heat::distance::write_rows(
            &out,
            n,
            n,
            &key,
            block_rows,
            |range, block| inner.rows_into(&range.collect::<Vec<usize>>(), block),
            &mut |done, total| {
                // Synchronous: a callback that raises stops the call before the next block.
                report.step(&format!("{done}/{total}"));
                report.flush();
            },
        )?;
        Ok((r.path, r.resumed_from))
    })
}

/// Registers the class.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyGeodesicSolver>()?;
    m.add("DEFAULT_T_COEF", wfem_heat::geodesic::DEFAULT_T_COEF)?;
    m.add("MAX_REFINE", wfem_heat::geodesic::MAX_REFINE)?;
    Ok(())
}
