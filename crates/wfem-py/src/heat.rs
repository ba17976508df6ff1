//! The heat kernel K_t = exp(−t M⁻¹L) (paper, Eq. (6)), its algebra and diffusion distances.

use crate::choices;
use crate::convert::{mat_in, mesh_in, sparse_arg, vec_in, SparseIn};
use crate::errors::{invalid, invalid_param};
use crate::out::{mat_out, mats_out, sparse_out, vec_out, SparseOut};
use crate::run::run;
use faer::Mat;
use mesh_fem::{assemble, AssemblyParams, Mass, TriMesh};
use numpy::{PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use shape_retrieval::sihks::{MeshLengths, TimeUnit};
use shifted_solve::backend::Backend;
use std::sync::Arc;
use wfem_base::Choice;
use wfem_heat::distance::{DiffusionDistance, DistanceKind, DistanceParams};
use wfem_heat::method::{Method, MethodOptions};
use wfem_heat::rkhs::{heat_inner_product, inverse_cg, InverseParams};
use wfem_heat::scale::{largest_eigenvalue, LargestEigenParams};
use wfem_heat::times::TimeScales;
use wfem_heat::{HeatError, HeatKernel, HeatParams, Operators};

/// The method of a name and its options (`degree`, `backend` for the rational method; `k` for
/// the spectral one); an option that does not belong to the method is refused.
pub fn method(
    py: Python<'_>,
    name: Option<&str>,
    degree: Option<usize>,
    k: Option<usize>,
    backend: Option<&str>,
) -> PyResult<Method> {
    let backend = match backend {
        None => None,
        Some(b) => Some(choices::parse::<Backend>(py, "backend", Some(b))?),
    };
    let options = MethodOptions {
        degree,
        backend,
        eigenpairs: k,
    };
    let method: Method = match name {
        None if options.names_rational() => Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
        other => choices::parse(py, "method", other)?,
    };
    if matches!(method, Method::Spectral { .. }) && k.is_none() {
        return Err(invalid_param(
            py,
            "k",
            "the spectral method needs k (number of eigenpairs)",
        ));
    }
    method.with_options(&options).map_err(|e| match e {
        HeatError::MisplacedOption { option, method, owner } => {
            let option = if option == "eigenpairs" { "k" } else { option };
            invalid_param(
                py,
                "method",
                format!("`{option}` does not apply to method {method:?} (only to {owner:?})"),
            )
        }
        other => crate::errors::heat(py, &other),
    })
}

fn check_times(py: Python<'_>, times: &[f64]) -> PyResult<()> {
    if times.is_empty() {
        return Err(invalid(py, "Empty", "t is empty: give at least one diffusion time"));
    }
    Ok(())
}

/// (HKS values (n, T), per time its source and bound).
type Sourced<'py> = (Bound<'py, PyArray2<f64>>, Vec<(String, f64)>);

/// (K_t F for each t (T, n, k), per-t error estimates).
type Series<'py> = (Bound<'py, PyArray3<f64>>, Vec<Option<f64>>);

/// Rust side of `wfem.HeatKernel`.
#[pyclass(name = "HeatKernel", module = "wfem._wfem", frozen)]
pub struct PyHeatKernel {
    pub kernel: HeatKernel,
    pub mesh: Option<Arc<TriMesh>>,
    /// Which times mean something on this kernel (built on first use; issue #25).
    pub scales: std::sync::OnceLock<Arc<TimeScales>>,
}

#[pymethods]
impl PyHeatKernel {
    #[staticmethod]
    #[pyo3(signature = (v, f, mass=None, method_name=None, degree=None, k=None, backend=None, laplacian=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_mesh(
        py: Python<'_>,
        v: PyReadonlyArray2<'_, f64>,
        f: PyReadonlyArray2<'_, i64>,
        mass: Option<&str>,
        method_name: Option<&str>,
        degree: Option<usize>,
        k: Option<usize>,
        backend: Option<&str>,
        laplacian: Option<&str>,
    ) -> PyResult<Self> {
        let mesh = mesh_in(py, &v, &f)?;
        let mass: Mass = choices::parse(py, "mass", mass)?;
        let method = method(py, method_name, degree, k, backend)?;
        let laplacian = crate::cloud::assembly_laplacian(py, laplacian, None)?;
        run(py, move |_| {
            let assembly = AssemblyParams {
                laplacian,
                ..AssemblyParams::for_mass(mass)
            };
            let fem = assemble(&mesh, &assembly)?;
            let kernel = HeatKernel::new(&fem, HeatParams { mass, method })?;
            Ok(Self {
                kernel,
                mesh: Some(Arc::new(mesh)),
                scales: Default::default(),
            })
        })
    }

    /// The kernel of a tetrahedral mesh V (n, 3), T (m, 4): the linear FEM operators of its
    /// tetrahedra (issue #39); no mesh is kept (the feature-driven approximation needs a surface).
    #[staticmethod]
    #[pyo3(signature = (v, t, mass=None, method_name=None, degree=None, k=None, backend=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_volume(
        py: Python<'_>,
        v: PyReadonlyArray2<'_, f64>,
        t: PyReadonlyArray2<'_, i64>,
        mass: Option<&str>,
        method_name: Option<&str>,
        degree: Option<usize>,
        k: Option<usize>,
        backend: Option<&str>,
    ) -> PyResult<Self> {
        let volume = crate::volume::volume_in(py, &v, &t)?;
        let mass: Mass = choices::parse(py, "mass", mass)?;
        let method = method(py, method_name, degree, k, backend)?;
        run(py, move |_| {
            let fem = mesh_fem::volume::assemble_volume(&volume, &AssemblyParams::for_mass(mass))?;
            let kernel = HeatKernel::new(&fem, HeatParams { mass, method })?;
            Ok(Self {
                kernel,
                mesh: None,
                scales: Default::default(),
            })
        })
    }

    /// The kernel of a point cloud: its robust operators (`laplacian` may only name the robust
    /// Laplacian) and its neighbourhood mesh, which the feature-driven approximation and the
    /// edge time unit use as a mesh's edges.
    #[staticmethod]
    #[pyo3(signature = (p, mass=None, method_name=None, degree=None, k=None, backend=None, laplacian=None, n_neighbors=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_cloud(
        py: Python<'_>,
        p: PyReadonlyArray2<'_, f64>,
        mass: Option<&str>,
        method_name: Option<&str>,
        degree: Option<usize>,
        k: Option<usize>,
        backend: Option<&str>,
        laplacian: Option<&str>,
        n_neighbors: Option<usize>,
    ) -> PyResult<Self> {
        crate::cloud::robust_only(py, laplacian)?;
        let (cloud, params) = crate::cloud::cloud_in(py, &p, n_neighbors)?;
        let mass: Mass = choices::parse(py, "mass", mass)?;
        let method = method(py, method_name, degree, k, backend)?;
        run(py, move |_| {
            let built = mesh_fem::cloud::assemble_cloud(&cloud, &params, &AssemblyParams::for_mass(mass))?;
            let kernel = HeatKernel::new(&built.operators, HeatParams { mass, method })?;
            Ok(Self {
                kernel,
                mesh: Some(Arc::new(built.neighbourhood)),
                scales: Default::default(),
            })
        })
    }

    #[staticmethod]
    #[pyo3(signature = (l, m, method_name=None, degree=None, k=None, backend=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_operators(
        py: Python<'_>,
        l: SparseIn<'_>,
        m: SparseIn<'_>,
        method_name: Option<&str>,
        degree: Option<usize>,
        k: Option<usize>,
        backend: Option<&str>,
    ) -> PyResult<Self> {
        let l = sparse_arg(py, "L", &l)?;
        let m = sparse_arg(py, "M", &m)?;
        let method = method(py, method_name, degree, k, backend)?;
        run(py, move |_| {
            let ops = Operators::from_matrices(l.as_ref(), m.as_ref())?;
            Ok(Self {
                kernel: HeatKernel::with_operators(&ops, method)?,
                mesh: None,
                scales: Default::default(),
            })
        })
    }

    /// Number of vertices n.
    #[getter]
    fn n(&self) -> usize {
        self.kernel.n()
    }

    /// The value on this kernel's mesh of one unit of time (`time_unit=`): 1, the area
    /// A = 1ᵀM1 or the mean edge length squared (needs the mesh).
    #[pyo3(signature = (name=None))]
    fn time_unit_value(&self, py: Python<'_>, name: Option<&str>) -> PyResult<f64> {
        let unit: TimeUnit = choices::parse(py, "time_unit", name)?;
        let lengths = match (unit, &self.mesh) {
            (TimeUnit::Absolute(_), _) => return Ok(1.0),
            (TimeUnit::Edge(_), Some(mesh)) => MeshLengths::of(mesh),
            (TimeUnit::Edge(_), None) => {
                return Err(invalid_param(
                    py,
                    "time_unit",
                    format!(
                        "{:?} needs the mesh (a kernel of given operators has no edges)",
                        unit.name()
                    ),
                ))
            }
            (_, _) => MeshLengths {
                area: self.kernel.operators().total_mass(),
                mean_edge_length: 0.0,
            },
        };
        unit.on(&lengths).map_err(|e| invalid_param(py, "time_unit", e))
    }

    /// The warnings (texts) for the times (in the mesh's units) whose result carries no
    /// information: of `K_t f`, or of the diffusion distance of `distance_kind` (the diffusion
    /// distance is made of kernel values at 2t); the texts give the times divided by `unit`
    /// and name `unit_name`.
    #[pyo3(signature = (times, unit, unit_name, distance_kind=None))]
    fn time_warnings(
        &self,
        py: Python<'_>,
        times: Vec<f64>,
        unit: f64,
        unit_name: &str,
        distance_kind: Option<&str>,
    ) -> PyResult<Vec<String>> {
        let doubling = match distance_kind {
            None => 1.0,
            Some(kind) => match choices::parse::<DistanceKind>(py, "kind", Some(kind))? {
                DistanceKind::Diffusion => 2.0,
                _ => 1.0,
            },
        };
        let scales = match self.scales.get() {
            Some(s) => s,
            None => {
                let positions = self.mesh.as_ref().map(|m| m.positions());
                let built =
                    TimeScales::new(self.kernel.operators(), positions).map_err(|e| crate::errors::heat(py, &e))?;
                self.scales.get_or_init(|| Arc::new(built))
            }
        };
        let suffix = if unit_name == TimeUnit::default_name() {
            String::new()
        } else {
            format!(" (time_unit='{unit_name}')")
        };
        let mut out: Vec<String> = Vec::new();
        let mut said = [false; 2];
        for t in times {
            let found = py
                .detach(|| scales.check(doubling * t))
                .map_err(|e| crate::errors::heat(py, &e))?;
            if let Some(w) = found.map(|w| w.in_unit(doubling * unit)) {
                let kind = matches!(w, wfem_heat::times::TimeWarning::PastInfinity { .. }) as usize;
                if !said[kind] {
                    said[kind] = true;
                    out.push(format!("{w}{suffix}"));
                }
            }
        }
        Ok(out)
    }

    /// The method's short name.
    #[getter]
    fn method(&self) -> &'static str {
        self.kernel.method().name()
    }

    /// The mass's name (the registry's), or None for operators given directly.
    #[getter]
    fn mass_name(&self) -> Option<&'static str> {
        self.kernel.operators().mass_kind().map(|m| m.name())
    }

    fn stiffness<'py>(&self, py: Python<'py>) -> SparseOut<'py> {
        sparse_out(py, self.kernel.operators().stiffness())
    }

    fn mass<'py>(&self, py: Python<'py>) -> SparseOut<'py> {
        sparse_out(py, self.kernel.mass())
    }

    fn vertex_areas<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_out(py, self.kernel.operators().vertex_areas())
    }

    /// K_t F for every t (T, n, k): one factorization per t serves all k columns.
    fn apply<'py>(
        &self,
        py: Python<'py>,
        f: PyReadonlyArray2<'py, f64>,
        times: Vec<f64>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        check_times(py, &times)?;
        let f = mat_in(&f);
        let (n, k) = (f.nrows(), f.ncols());
        let kernel = self.kernel.clone();
        // Each t has its own factorization, shared by every column, so every t gets the
        // method's full accuracy; `apply_times` trades some of it for one factorization.
        let out = run(py, move |cancel| {
            cancel.map(times, |t| Ok(kernel.apply_many(f.as_ref(), t)?))
        })?;
        Ok(mats_out(py, &out, n, k))
    }

    /// K_t F for every t with the per-t error estimates: ((T, n, k), [estimate or None]).
    fn apply_times<'py>(
        &self,
        py: Python<'py>,
        f: PyReadonlyArray2<'py, f64>,
        times: Vec<f64>,
    ) -> PyResult<Series<'py>> {
        check_times(py, &times)?;
        let f = mat_in(&f);
        let (n, k) = (f.nrows(), f.ncols());
        let kernel = self.kernel.clone();
        let series = run(py, move |_| Ok(kernel.apply_times(f.as_ref(), &times)?))?;
        Ok((mats_out(py, &series.values, n, k), series.error_estimates))
    }

    /// The exact diagonal of the heat kernel at every t (n, T), without eigenpairs, by
    /// `method` ([`diagonal_method`]).
    #[pyo3(signature = (times, convention=None, method=None, tol=wfem_heat::diagonal::DEFAULT_PROBING_TOL, max_columns=wfem_heat::DiagonalParams::default().max_columns, block=wfem_heat::DiagonalParams::default().block))]
    #[allow(clippy::too_many_arguments)]
    fn diagonal<'py>(
        &self,
        py: Python<'py>,
        times: Vec<f64>,
        convention: Option<&str>,
        method: Option<&str>,
        tol: f64,
        max_columns: usize,
        block: usize,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyDict>)> {
        use wfem_heat::{DiagonalParams, KernelDiagonal};
        check_times(py, &times)?;
        let which: KernelDiagonal = choices::parse(py, "convention", convention)?;
        let params = DiagonalParams {
            method: diagonal_method(py, method, tol)?,
            max_columns,
            block,
        };
        let kernel = self.kernel.clone();
        let series = run(py, move |_| Ok(kernel.diagonal(&times, which, &params)?))?;
        let info = PyDict::new(py);
        info.set_item("method", series.info.method.name())?;
        info.set_item("probe_columns", series.info.columns)?;
        info.set_item("hops", series.info.hops)?;
        info.set_item("relative_tail", series.info.relative_tail)?;
        info.set_item("error_estimates", series.error_estimates)?;
        Ok((mat_out(py, series.values.as_ref()), info))
    }

    /// The HKS by method (`shape_retrieval::exact::signature_by_method`): `spectral` (n, T) is the
    /// truncated sum from `eigenvalues` at `times`; "auto" replaces the columns whose truncation
    /// bound is above `tol` by the exact diagonal (selected inversion, as the CLI), "exact"
    /// replaces every column.
    /// Returns (values, [(source, bound)]).
    #[pyo3(signature = (eigenvalues, spectral, times, convention=None, method=None, tol=shape_retrieval::exact::DEFAULT_TRUNCATION_TOL))]
    #[allow(clippy::too_many_arguments)]
    fn hks_by_method<'py>(
        &self,
        py: Python<'py>,
        eigenvalues: Vec<f64>,
        spectral: PyReadonlyArray2<'py, f64>,
        times: Vec<f64>,
        convention: Option<&str>,
        method: Option<&str>,
        tol: f64,
    ) -> PyResult<Sourced<'py>> {
        use shape_retrieval::exact::{HksMethod, HksSource};
        use wfem_heat::DiagonalParams;
        check_times(py, &times)?;
        let convention = choices::parse(py, "convention", convention)?;
        let method = match choices::parse::<HksMethod>(py, "method", method)? {
            HksMethod::Auto { .. } => HksMethod::Auto { tol },
            other => other,
        };
        let params = DiagonalParams::default();
        let spectral = mat_in(&spectral);
        let kernel = self.kernel.clone();
        let (values, sources) = run(py, move |_| {
            Ok(shape_retrieval::exact::signature_by_method(
                &kernel,
                &eigenvalues,
                spectral,
                &times,
                convention,
                method,
                &params,
            )?)
        })?;
        let sources = sources
            .iter()
            .map(|s| match *s {
                HksSource::Spectral { estimate, .. } => (HksMethod::Spectral.name().to_string(), estimate),
                HksSource::Exact { relative_tail } => (HksMethod::Exact.name().to_string(), relative_tail),
            })
            .collect();
        Ok((mat_out(py, values.as_ref()), sources))
    }

    /// H_t G = K_t M⁻¹ G (n, k).
    fn apply_kernel_matrix<'py>(
        &self,
        py: Python<'py>,
        g: PyReadonlyArray2<'py, f64>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let g = mat_in(&g);
        let kernel = self.kernel.clone();
        let out = run(py, move |_| Ok(kernel.apply_kernel_matrix(g.as_ref(), t)?))?;
        Ok(mat_out(py, out.as_ref()))
    }

    /// Columns K_t e_i for the anchors (n, |A|).
    fn canonical_basis<'py>(&self, py: Python<'py>, anchors: Vec<u32>, t: f64) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let kernel = self.kernel.clone();
        let out = run(py, move |_| {
            Ok(wfem_heat::basis::canonical_basis(&kernel, &anchors, t)?)
        })?;
        Ok(mat_out(py, out.as_ref()))
    }

    /// lim_{t→∞} K_t e_i = c_i·1: the constants c_i.
    fn canonical_limit<'py>(&self, py: Python<'py>, anchors: Vec<u32>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let out = wfem_heat::basis::canonical_limit(&self.kernel, &anchors).map_err(|e| crate::errors::heat(py, &e))?;
        Ok(vec_out(py, out))
    }

    /// ⟨f, g⟩_M = fᵀMg.
    fn mass_inner_product(
        &self,
        py: Python<'_>,
        f: PyReadonlyArray1<'_, f64>,
        g: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<f64> {
        self.kernel
            .operators()
            .mass_inner_product(&vec_in(&f), &vec_in(&g))
            .map_err(|e| crate::errors::heat(py, &e))
    }

    /// ⟨f, g⟩_t = fᵀ M K_t g (Eq. (16)).
    fn heat_inner_product(
        &self,
        py: Python<'_>,
        f: PyReadonlyArray1<'_, f64>,
        g: PyReadonlyArray1<'_, f64>,
        t: f64,
    ) -> PyResult<f64> {
        let (f, g) = (vec_in(&f), vec_in(&g));
        let kernel = self.kernel.clone();
        run(py, move |_| Ok(heat_inner_product(&kernel, &f, &g, t)?))
    }

    /// [h_i] = K_{t/2}[e_i] (Eq. (18b)), (n, m).
    fn diffusion_embeddings<'py>(
        &self,
        py: Python<'py>,
        vertices: Vec<usize>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let kernel = self.kernel.clone();
        let out = run(py, move |_| {
            Ok(wfem_heat::rkhs::diffusion_embeddings(&kernel, &vertices, t)?)
        })?;
        Ok(mat_out(py, out.as_ref()))
    }

    /// K_{−t} f by conjugate gradients (refused when ill-conditioned): (g, report dict).
    #[pyo3(signature = (f, t, max_amplification=wfem_heat::rkhs::InverseParams::default().max_amplification, tol=wfem_heat::rkhs::InverseParams::default().tol, max_iter=wfem_heat::rkhs::InverseParams::default().max_iter, stall_window=wfem_heat::rkhs::InverseParams::default().stall_window))]
    #[allow(clippy::too_many_arguments)]
    fn inverse<'py>(
        &self,
        py: Python<'py>,
        f: PyReadonlyArray1<'py, f64>,
        t: f64,
        max_amplification: f64,
        tol: f64,
        max_iter: usize,
        stall_window: usize,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyDict>)> {
        let f = vec_in(&f);
        let kernel = self.kernel.clone();
        let params = InverseParams {
            max_amplification,
            tol,
            max_iter,
            stall_window,
        };
        let (g, report) = run(py, move |_| Ok(inverse_cg(&kernel, &f, t, &params)?))?;
        let d = PyDict::new(py);
        d.set_item("iterations", report.iterations)?;
        d.set_item("relative_residual", report.relative_residual)?;
        d.set_item("amplification", report.amplification)?;
        Ok((vec_out(py, g), d))
    }

    /// λ_max of L x = λ M x (Lanczos).
    #[pyo3(signature = (tol=wfem_heat::scale::LargestEigenParams::default().tol, max_iter=wfem_heat::scale::LargestEigenParams::default().max_iter, seed=wfem_heat::scale::LargestEigenParams::default().seed))]
    fn largest_eigenvalue(&self, py: Python<'_>, tol: f64, max_iter: usize, seed: u64) -> PyResult<f64> {
        let kernel = self.kernel.clone();
        let params = LargestEigenParams { tol, max_iter, seed };
        run(py, move |_| Ok(largest_eigenvalue(kernel.operators(), &params)?))
    }

    /// The feature-driven approximation (Sect. 4.2) of f on the kernel's mesh; `None` takes the
    /// library's default ([`wfem_heat::approx::ApproxParams`]).
    #[pyo3(signature = (f, k=None, num_times=None, persistence=None, absolute=false, coefficients=None, sampling=None, noise=None))]
    #[allow(clippy::too_many_arguments)]
    fn feature_approximation<'py>(
        &self,
        py: Python<'py>,
        f: PyReadonlyArray1<'py, f64>,
        k: Option<usize>,
        num_times: Option<usize>,
        persistence: Option<f64>,
        absolute: bool,
        coefficients: Option<&str>,
        sampling: Option<&str>,
        noise: Option<&str>,
    ) -> PyResult<Bound<'py, PyDict>> {
        use wfem_heat::approx::{
            feature_approximation, ApproxParams, Coefficients, NoiseRule, Persistence, ScaleSampling,
        };
        let mesh = self.mesh.clone().ok_or_else(|| {
            invalid(
                py,
                "NoMesh",
                "the feature-driven approximation needs the mesh (build the kernel from V, F, not from operators)",
            )
        })?;
        let defaults = ApproxParams::default();
        let persistence = match (persistence, absolute) {
            (Some(x), true) => Persistence::Absolute(x),
            (Some(x), false) => Persistence::Relative(x),
            (None, true) => return Err(invalid_param(py, "absolute", "absolute=True needs a persistence")),
            (None, false) => defaults.persistence,
        };
        let coefficients: Coefficients = choices::parse(py, "coefficients", coefficients)?;
        let sampling: ScaleSampling = choices::parse(py, "sampling", sampling)?;
        let noise: NoiseRule = choices::parse(py, "noise", noise)?;
        let f = vec_in(&f);
        let kernel = self.kernel.clone();
        let params = ApproxParams {
            k: k.unwrap_or(defaults.k),
            scales: num_times.unwrap_or(defaults.scales),
            persistence,
            coefficients,
            sampling,
            noise,
            ..defaults
        };
        let result = run(py, move |_| Ok(feature_approximation(&mesh, &kernel, &f, &params)?))?;
        let d = PyDict::new(py);
        d.set_item("coefficients", result.coefficients.name())?;
        d.set_item("formula", result.coefficients.formula())?;
        d.set_item("sampling", result.sampling.name())?;
        d.set_item("anchors", result.anchors.clone())?;
        d.set_item("anchor_values", vec_out(py, result.anchor_values.clone()))?;
        d.set_item("anchor_persistence", result.anchor_persistence.clone())?;
        d.set_item("noise_rule", result.noise_rule.name())?;
        d.set_item("chosen", result.chosen)?;
        let estimate = match &result.noise {
            None => None,
            Some(c) => {
                let e = PyDict::new(py);
                e.set_item("sigma", c.noise)?;
                e.set_item("gcv_sigma", c.gcv_noise)?;
                e.set_item("t", c.t)?;
                e.set_item("smoothing_helps", c.smoothing_helps())?;
                e.set_item("scores", vec_out(py, c.scores.clone()))?;
                e.set_item("trace_fraction", vec_out(py, c.trace_fraction.clone()))?;
                Some(e)
            }
        };
        d.set_item("noise", estimate)?;
        d.set_item("threshold", result.threshold)?;
        d.set_item("range", result.range)?;
        d.set_item("lambda_k", result.lambda_k)?;
        d.set_item("lambda_max", result.lambda_max)?;
        d.set_item("input_critical_points", result.input_critical_points)?;
        d.set_item("persistent_extrema", result.persistent_extrema)?;
        let warning = result
            .warning()
            .map(|w| w.message(&|p, v| v.map_or_else(|| format!("{p}=…"), |v| format!("{p}={v:?}"))));
        d.set_item("warning", warning)?;
        let scales = pyo3::types::PyList::empty(py);
        for s in result.scales {
            let e = PyDict::new(py);
            e.set_item("t", s.t)?;
            e.set_item("global_", vec_out(py, s.global))?;
            e.set_item("local", vec_out(py, s.local))?;
            e.set_item("anchors", s.anchors)?;
            e.set_item("coefficients", vec_out(py, s.coefficients))?;
            e.set_item("linf_error", s.linf_error)?;
            e.set_item("relative_linf_error", s.relative_linf_error)?;
            e.set_item("anchor_error", s.anchor_error)?;
            e.set_item("critical_points", s.critical_points)?;
            e.set_item("significant_critical_points", s.significant_critical_points)?;
            e.set_item("persistent_extrema", s.persistent_extrema)?;
            scales.append(e)?;
        }
        d.set_item("scales", scales)?;
        Ok(d)
    }

    /// Diffusion distances of `kind` at time t on this kernel.
    #[pyo3(signature = (t, kind=None, block=wfem_heat::distance::DistanceParams::default().block, diagonal=None, diagonal_tol=wfem_heat::diagonal::DEFAULT_PROBING_TOL))]
    fn distance(
        &self,
        py: Python<'_>,
        t: f64,
        kind: Option<&str>,
        block: usize,
        diagonal: Option<&str>,
        diagonal_tol: f64,
    ) -> PyResult<PyDiffusionDistance> {
        let kind: DistanceKind = choices::parse(py, "kind", kind)?;
        let params = DistanceParams {
            block,
            diagonal: diagonal_method(py, diagonal, diagonal_tol)?,
        };
        let inner = DiffusionDistance::new(&self.kernel, kind, t, &params).map_err(|e| crate::errors::heat(py, &e))?;
        Ok(PyDiffusionDistance { inner: Arc::new(inner) })
    }
}

/// The value of one unit of time (`time_unit=`) on the mesh (V, F): 1, A or ℓ̄².
#[pyfunction]
#[pyo3(signature = (v, f, name=None))]
pub fn mesh_time_unit(
    py: Python<'_>,
    v: PyReadonlyArray2<'_, f64>,
    f: PyReadonlyArray2<'_, i64>,
    name: Option<&str>,
) -> PyResult<f64> {
    let unit: TimeUnit = choices::parse(py, "time_unit", name)?;
    if matches!(unit, TimeUnit::Absolute(_)) {
        return Ok(1.0);
    }
    let mesh = mesh_in(py, &v, &f)?;
    unit.on(&MeshLengths::of(&mesh))
        .map_err(|e| invalid_param(py, "time_unit", e))
}

/// Rust side of `wfem.DiffusionDistance`.
#[pyclass(name = "DiffusionDistance", module = "wfem._wfem", frozen)]
pub struct PyDiffusionDistance {
    inner: Arc<DiffusionDistance>,
}

#[pymethods]
impl PyDiffusionDistance {
    #[getter]
    fn t(&self) -> f64 {
        self.inner.t()
    }

    #[getter]
    fn kind(&self) -> &'static str {
        self.inner.kind().name()
    }

    #[getter]
    fn n(&self) -> usize {
        self.inner.n()
    }

    /// d(i, ·) for each source (m, n).
    fn rows<'py>(&self, py: Python<'py>, sources: Vec<usize>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let inner = self.inner.clone();
        let n = inner.n();
        let m = sources.len();
        let rows = run(py, move |cancel| cancel.map(sources, |i| Ok(inner.row(i)?)))?;
        let out = Mat::from_fn(m, n, |i, j| rows[i][j]);
        Ok(mat_out(py, out.as_ref()))
    }

    /// d(i, j) for each pair.
    fn pairs<'py>(&self, py: Python<'py>, pairs: Vec<(usize, usize)>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let inner = self.inner.clone();
        let out = run(py, move |_| Ok(inner.pairs(&pairs)?))?;
        Ok(vec_out(py, out))
    }

    /// The n × n matrix streamed to `out` (resumable); returns (path, resumed_from).
    #[pyo3(signature = (out, progress=None, block_rows=None))]
    fn all_pairs(
        &self,
        py: Python<'_>,
        out: std::path::PathBuf,
        progress: Option<Py<PyAny>>,
        block_rows: Option<usize>,
    ) -> PyResult<(std::path::PathBuf, usize)> {
        crate::geodesic::diffusion_all_pairs(py, self.inner.clone(), out, progress, block_rows)
    }

    /// The diagonal A_ii of the distance's Gram matrix.
    fn diagonal<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let inner = self.inner.clone();
        let out = run(py, move |_| Ok(inner.diagonal()?.to_vec()))?;
        Ok(vec_out(py, out))
    }
}

/// The diagonal method of a name (the registry's; default selected inversion), probing with
/// relative tail `tol`.
fn diagonal_method(py: Python<'_>, name: Option<&str>, tol: f64) -> PyResult<wfem_heat::diagonal::DiagonalMethod> {
    use wfem_heat::diagonal::DiagonalMethod;
    Ok(match choices::parse(py, "method", name)? {
        DiagonalMethod::Probing { .. } => DiagonalMethod::Probing { tol },
        other => other,
    })
}

/// Registers the classes of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyHeatKernel>()?;
    m.add_class::<PyDiffusionDistance>()?;
    m.add_function(wrap_pyfunction!(mesh_time_unit, m)?)?;
    Ok(())
}
