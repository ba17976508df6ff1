//! Eigenpairs L x = λ M x (paper, Eq. (4)) and the spectral descriptors built on them: HKS in
//! both conventions, SI-HKS, the truncated kernel (Eq. (8)) and the RKHS operators.

use crate::choices;
use crate::convert::{mat_in, mesh_in, sparse_arg, vec_in, SparseIn};
use crate::errors::{invalid_param, Error};
use crate::out::{mat_out, vec_out};
use crate::run::run;
use faer::Mat;
use mesh_fem::{assemble, AssemblyParams, Mass};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use shape_retrieval::global::{GlobalKind, Measure};
use shape_retrieval::hks::{heat_kernel_signature, HksParams, Spectrum, SpectrumNormalization, TimeSampling};
use shape_retrieval::sihks::{scale_invariant_hks, SihksParams};
use std::sync::Arc;
use wfem_base::Choice;
use wfem_heat::rkhs::{inverse_spectral, reproducing_kernel_apply, TruncationReport};
use wfem_heat::spectral::{EigenParams, Eigenbasis};
use wfem_heat::{KernelDiagonal, Operators};

/// Largest number of τ samples of an SI-HKS window (385 by default); beyond it a typo in
/// the step would exhaust memory.
const MAX_SIHKS_SAMPLES: f64 = 100_000.0;

/// Rust side of `wfem.Eigenbasis`: the pairs and the operators they belong to.
#[pyclass(name = "Eigenbasis", module = "wfem._wfem", frozen)]
pub struct PyEigenbasis {
    pub basis: Arc<Eigenbasis>,
    pub ops: Operators,
}

fn eigen_params(
    py: Python<'_>,
    tol: f64,
    block_size: usize,
    max_dim: Option<usize>,
    seed: u64,
    shift: Option<f64>,
    max_restarts: usize,
) -> PyResult<EigenParams> {
    if !(tol > 0.0 && tol < 1.0) {
        return Err(invalid_param(py, "tol", format!("{tol} is not in (0, 1)")));
    }
    Ok(EigenParams {
        shift,
        block_size,
        tol,
        max_dim,
        max_restarts,
        seed,
    })
}

/// The k smallest eigenpairs of `ops` (all of them, dense, for `None`) with the operators.
fn compute(ops: Operators, k: Option<usize>, params: &EigenParams) -> Result<PyEigenbasis, Error> {
    let basis = match k {
        None => Eigenbasis::dense_of(&ops)?,
        Some(k) => Eigenbasis::partial_of(&ops, k, params)?,
    };
    Ok(PyEigenbasis {
        basis: Arc::new(basis),
        ops,
    })
}

fn truncation<'py>(py: Python<'py>, r: &TruncationReport) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("k", r.k)?;
    d.set_item("lambda_k", r.lambda_k)?;
    d.set_item("amplification", r.amplification)?;
    d.set_item("dropped_norm", r.dropped_norm)?;
    d.set_item("input_norm", r.input_norm)?;
    d.set_item("relative_dropped", r.relative_dropped())?;
    Ok(d)
}

#[pymethods]
impl PyEigenbasis {
    #[staticmethod]
    #[pyo3(signature = (v, f, k=None, mass=None, tol=wfem_heat::spectral::EigenParams::default().tol, block_size=wfem_heat::spectral::EigenParams::default().block_size, max_dim=None, seed=wfem_heat::spectral::EigenParams::default().seed, shift=None, max_restarts=wfem_heat::spectral::EigenParams::default().max_restarts, laplacian=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_mesh(
        py: Python<'_>,
        v: PyReadonlyArray2<'_, f64>,
        f: PyReadonlyArray2<'_, i64>,
        k: Option<usize>,
        mass: Option<&str>,
        tol: f64,
        block_size: usize,
        max_dim: Option<usize>,
        seed: u64,
        shift: Option<f64>,
        max_restarts: usize,
        laplacian: Option<&str>,
    ) -> PyResult<Self> {
        let mesh = mesh_in(py, &v, &f)?;
        let mass: Mass = choices::parse(py, "mass", mass)?;
        let laplacian = crate::cloud::assembly_laplacian(py, laplacian, None)?;
        let params = eigen_params(py, tol, block_size, max_dim, seed, shift, max_restarts)?;
        run(py, move |_| {
            let assembly = AssemblyParams {
                laplacian,
                ..AssemblyParams::for_mass(mass)
            };
            let fem = assemble(&mesh, &assembly)?;
            compute(Operators::new(&fem, mass)?, k, &params)
        })
    }

    #[staticmethod]
    #[pyo3(signature = (l, m, k=None, tol=wfem_heat::spectral::EigenParams::default().tol, block_size=wfem_heat::spectral::EigenParams::default().block_size, max_dim=None, seed=wfem_heat::spectral::EigenParams::default().seed, shift=None, max_restarts=wfem_heat::spectral::EigenParams::default().max_restarts))]
    #[allow(clippy::too_many_arguments)]
    fn from_operators(
        py: Python<'_>,
        l: SparseIn<'_>,
        m: SparseIn<'_>,
        k: Option<usize>,
        tol: f64,
        block_size: usize,
        max_dim: Option<usize>,
        seed: u64,
        shift: Option<f64>,
        max_restarts: usize,
    ) -> PyResult<Self> {
        let l = sparse_arg(py, "L", &l)?;
        let m = sparse_arg(py, "M", &m)?;
        let params = eigen_params(py, tol, block_size, max_dim, seed, shift, max_restarts)?;
        run(py, move |_| {
            compute(Operators::from_matrices(l.as_ref(), m.as_ref())?, k, &params)
        })
    }

    #[getter]
    fn values<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_out(py, self.basis.values.clone())
    }

    #[getter]
    fn vectors<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_out(py, self.basis.vectors.as_ref())
    }

    #[getter]
    fn n(&self) -> usize {
        self.basis.vectors.nrows()
    }

    #[getter]
    fn k(&self) -> usize {
        self.basis.values.len()
    }

    /// Coefficients Xᵀ M F (k, m).
    fn project<'py>(&self, py: Python<'py>, f: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let f = mat_in(&f);
        let (basis, ops) = (self.basis.clone(), self.ops.clone());
        let out = run(py, move |_| {
            let n = basis.vectors.nrows();
            if f.nrows() != n {
                return Err(wfem_heat::HeatError::LengthMismatch {
                    expected: n,
                    found: f.nrows(),
                }
                .into());
            }
            check_finite(&f)?;
            let mut mf = Mat::<f64>::zeros(n, f.ncols());
            for j in 0..f.ncols() {
                let col: Vec<f64> = f.col(j).iter().copied().collect();
                let m = ops.mass_mul(&col);
                mf.col_mut(j).iter_mut().zip(m).for_each(|(o, x)| *o = x);
            }
            Ok(basis.vectors.transpose() * &mf)
        })?;
        Ok(mat_out(py, out.as_ref()))
    }

    /// X C (n, m) for coefficients C (k, m).
    fn reconstruct<'py>(&self, py: Python<'py>, c: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let c = mat_in(&c);
        let basis = self.basis.clone();
        let out = run(py, move |_| {
            let k = basis.values.len();
            if c.nrows() != k {
                return Err(Error::Invalid(
                    "LengthMismatch",
                    format!("coefficients have {} rows, the basis has {k} eigenpairs", c.nrows()),
                ));
            }
            check_finite(&c)?;
            Ok(&basis.vectors * &c)
        })?;
        Ok(mat_out(py, out.as_ref()))
    }

    /// Truncated K_t f = X e^{−tΛ} Xᵀ M f (Eq. (8)).
    fn heat<'py>(&self, py: Python<'py>, f: PyReadonlyArray1<'py, f64>, t: f64) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let f = vec_in(&f);
        let (basis, ops) = (self.basis.clone(), self.ops.clone());
        let out = run(py, move |_| Ok(basis.apply_heat(ops.mass(), &f, t)?))?;
        Ok(vec_out(py, out))
    }

    /// Truncated K_{−t} f: (g, report).
    fn inverse_heat<'py>(
        &self,
        py: Python<'py>,
        f: PyReadonlyArray1<'py, f64>,
        t: f64,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyDict>)> {
        self.truncated(py, &f, t, inverse_spectral)
    }

    /// Truncated reproducing kernel H_t v = X e^{+tΛ} Xᵀ v (Prop. 3.1 B): (g, report).
    fn reproducing_kernel<'py>(
        &self,
        py: Python<'py>,
        v: PyReadonlyArray1<'py, f64>,
        t: f64,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyDict>)> {
        self.truncated(py, &v, t, reproducing_kernel_apply)
    }

    /// The heat kernel signature (n, T) and its times.
    #[pyo3(signature = (times=None, num_times=shape_retrieval::hks::DEFAULT_NUM_TIMES, convention=None, scaled=false, normalization=None))]
    fn hks<'py>(
        &self,
        py: Python<'py>,
        times: Option<Vec<f64>>,
        num_times: usize,
        convention: Option<&str>,
        scaled: bool,
        normalization: Option<&str>,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, Vec<f64>)> {
        let convention: KernelDiagonal = choices::parse(py, "convention", convention)?;
        let normalization = match choices::parse(py, "normalization", normalization)? {
            SpectrumNormalization::UnitArea { .. } => SpectrumNormalization::UnitArea {
                area: self.ops.total_mass(),
            },
            other => other,
        };
        let params = HksParams {
            convention,
            times: match times {
                Some(t) => TimeSampling::Explicit(t),
                None => TimeSampling::Auto { num_times },
            },
            scaled,
            normalization,
        };
        let sig = self.on_spectrum(py, move |spectrum| heat_kernel_signature(spectrum, &params))?;
        Ok((mat_out(py, sig.values.as_ref()), sig.times))
    }

    /// The wave kernel signature (n, N) at pyFM's energies, the energies and σ.
    #[pyo3(signature = (num_energies=shape_retrieval::wks::DEFAULT_ENERGIES))]
    fn wks<'py>(&self, py: Python<'py>, num_energies: usize) -> PyResult<(Bound<'py, PyArray2<f64>>, Vec<f64>, f64)> {
        let sig = self.on_spectrum(py, move |spectrum| {
            shape_retrieval::wks::wave_kernel_signature(spectrum, num_energies)
        })?;
        Ok((
            mat_out(py, sig.values.as_ref()),
            sig.energies.energies,
            sig.energies.sigma,
        ))
    }

    /// The global signature (the Weyl-normalised Shape-DNA by default) of the first m nonzero eigenvalues, with the
    /// shape's measure (`None`: 1ᵀM1, the area or volume for B and D) and its dimension (2 for a
    /// surface, 3 for a solid: Weyl's law in that dimension).
    #[pyo3(signature = (eigenvalues, kind=None, measure=None, dimension=shape_retrieval::global::DEFAULT_DIMENSION))]
    fn global_signature(
        &self,
        py: Python<'_>,
        eigenvalues: usize,
        kind: Option<&str>,
        measure: Option<f64>,
        dimension: usize,
    ) -> PyResult<Vec<f64>> {
        // The Weyl-normalised Shape-DNA unless told otherwise (the registry's default is the
        // retrieval fusion's).
        let kind = match kind {
            None => GlobalKind::WeylShapeDna,
            text => choices::parse::<GlobalKind>(py, "kind", text)?,
        };
        let value = match measure {
            Some(v) => v,
            None if self.ops.mass_kind() == Some(Mass::Identity) => {
                return Err(invalid_param(
                    py,
                    "measure",
                    "the identity mass does not measure the shape: give its area or volume",
                ))
            }
            None => self.ops.total_mass(),
        };
        let measure = match dimension {
            2 => Measure::Area(value),
            3 => Measure::Volume(value),
            d => {
                return Err(invalid_param(
                    py,
                    "dimension",
                    format!("{d}: 2 for a surface, 3 for a solid"),
                ))
            }
        };
        if eigenvalues == 0 || eigenvalues >= self.basis.values.len() {
            return Err(invalid_param(
                py,
                "m",
                format!(
                    "{eigenvalues}: the basis has {} pairs, so 1 ..= {} nonzero eigenvalues",
                    self.basis.values.len(),
                    self.basis.values.len().saturating_sub(1)
                ),
            ));
        }
        let (basis, ops) = (self.basis.clone(), self.ops.clone());
        run(py, move |_| {
            let weights = ops.vertex_areas();
            Ok(kind.compute(&basis.values, basis.vectors.as_ref(), &weights, measure, eigenvalues)?)
        })
    }

    /// The scale-invariant HKS (n, K) of Bronstein & Kokkinos.
    #[pyo3(signature = (alpha=shape_retrieval::sihks::BRONSTEIN_KOKKINOS.alpha, tau_min=shape_retrieval::sihks::BRONSTEIN_KOKKINOS.tau_min, tau_max=shape_retrieval::sihks::BRONSTEIN_KOKKINOS.tau_max, tau_step=shape_retrieval::sihks::BRONSTEIN_KOKKINOS.tau_step, time_unit=crate::defaults::absolute_unit(&shape_retrieval::sihks::BRONSTEIN_KOKKINOS), num_frequencies=shape_retrieval::sihks::BRONSTEIN_KOKKINOS.num_frequencies, convention=None))]
    #[allow(clippy::too_many_arguments)]
    fn sihks<'py>(
        &self,
        py: Python<'py>,
        alpha: f64,
        tau_min: f64,
        tau_max: f64,
        tau_step: f64,
        time_unit: f64,
        num_frequencies: usize,
        convention: Option<&str>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let convention: KernelDiagonal = choices::parse(py, "convention", convention)?;
        let samples = (tau_max - tau_min) / tau_step;
        if samples.is_finite() && samples > MAX_SIHKS_SAMPLES {
            return Err(invalid_param(
                py,
                "tau_step",
                format!("the window would have {samples:.0} samples (limit {MAX_SIHKS_SAMPLES})"),
            ));
        }
        let params = SihksParams {
            alpha,
            tau_min,
            tau_max,
            tau_step,
            time_unit: shape_retrieval::sihks::TimeUnit::Absolute(time_unit),
            num_frequencies,
            convention,
        };
        let out = self.on_spectrum(py, move |spectrum| scale_invariant_hks(spectrum, &params))?;
        Ok(mat_out(py, out.as_ref()))
    }
}

/// A spectrally truncated amplifying operator (K_{−t}, H_t) of the rkhs module.
type Truncated = fn(&Eigenbasis, &Operators, &[f64], f64) -> Result<(Vec<f64>, TruncationReport), wfem_heat::HeatError>;

impl PyEigenbasis {
    fn truncated<'py>(
        &self,
        py: Python<'py>,
        v: &PyReadonlyArray1<'py, f64>,
        t: f64,
        op: Truncated,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyDict>)> {
        let v = vec_in(v);
        let (basis, ops) = (self.basis.clone(), self.ops.clone());
        let (g, r) = run(py, move |_| Ok(op(&basis, &ops, &v, t)?))?;
        Ok((vec_out(py, g), truncation(py, &r)?))
    }

    /// `descriptor` of the spectrum of these pairs with their mass, without the GIL.
    fn on_spectrum<T: Send + 'static>(
        &self,
        py: Python<'_>,
        descriptor: impl FnOnce(&Spectrum<'_>) -> Result<T, shape_retrieval::RetrievalError> + Send + 'static,
    ) -> PyResult<T> {
        let (basis, ops) = (self.basis.clone(), self.ops.clone());
        run(py, move |_| {
            let spectrum = Spectrum::new(&basis.values, basis.vectors.as_ref())?.with_mass(ops.mass())?;
            Ok(descriptor(&spectrum)?)
        })
    }
}

fn check_finite(m: &Mat<f64>) -> Result<(), Error> {
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            let value = m[(i, j)];
            if !value.is_finite() {
                return Err(wfem_heat::HeatError::NonFiniteInput {
                    row: i,
                    column: j,
                    value,
                }
                .into());
            }
        }
    }
    Ok(())
}

/// The wave kernel signature of given eigenpairs (values (k,), vectors (n, k), M-orthonormal):
/// (values (n, N), energies, σ).
#[pyfunction]
#[pyo3(signature = (values, vectors, num_energies=shape_retrieval::wks::DEFAULT_ENERGIES))]
pub fn eigenpairs_wks<'py>(
    py: Python<'py>,
    values: Vec<f64>,
    vectors: numpy::PyReadonlyArray2<'py, f64>,
    num_energies: usize,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Vec<f64>, f64)> {
    let vectors = crate::convert::mat_in(&vectors);
    let sig = run(py, move |_| {
        let spectrum = Spectrum::new(&values, vectors.as_ref())?;
        Ok(shape_retrieval::wks::wave_kernel_signature(&spectrum, num_energies)?)
    })?;
    Ok((
        mat_out(py, sig.values.as_ref()),
        sig.energies.energies,
        sig.energies.sigma,
    ))
}

/// Registers the classes of this module.
/// `(values (n, T), times, [(method name, bound)], eigenvalues or None)` of [`mesh_hks`].
type MeshHksOut<'py> = (
    Bound<'py, PyArray2<f64>>,
    Vec<f64>,
    Vec<(&'static str, f64)>,
    Option<Vec<f64>>,
);

/// The heat kernel signature of a mesh: shape_retrieval's one orchestration (auto / exact /
/// spectral), as `wfem hks` runs it.
#[pyfunction]
#[pyo3(signature = (v, f, times=None, num_times=None, k=shape_retrieval::descriptor::DEFAULT_EIGENPAIRS, mass=None, method=None, convention=None, scaled=false, normalization=None, basis=None, tol=shape_retrieval::exact::DEFAULT_TRUNCATION_TOL, laplacian=None, n_neighbors=None, cloud_time_unit=None))]
#[allow(clippy::too_many_arguments)]
pub fn mesh_hks<'py>(
    py: Python<'py>,
    v: PyReadonlyArray2<'py, f64>,
    f: Option<PyReadonlyArray2<'py, i64>>,
    times: Option<Vec<f64>>,
    num_times: Option<usize>,
    k: usize,
    mass: Option<&str>,
    method: Option<&str>,
    convention: Option<&str>,
    scaled: bool,
    normalization: Option<&str>,
    basis: Option<PyRef<'py, PyEigenbasis>>,
    tol: f64,
    laplacian: Option<&str>,
    n_neighbors: Option<usize>,
    cloud_time_unit: Option<&str>,
) -> PyResult<MeshHksOut<'py>> {
    use shape_retrieval::exact::{HksMethod, HksSource};
    use shape_retrieval::mesh_hks::MeshHksParams;
    // A mesh, or (no F) a point cloud with its neighbourhood size.
    let shape = match &f {
        Some(f) => Ok(mesh_in(py, &v, f)?),
        None => Err(crate::cloud::cloud_in(py, &v, n_neighbors)?),
    };
    let laplacian = crate::cloud::assembly_laplacian(py, laplacian, None)?;
    // A cloud's given times in a unit (`time_unit=`): the unit is measured on its neighbourhood
    // mesh once the operators are built, as `wfem hks CLOUD --time-unit …` does.
    let cloud_unit: shape_retrieval::sihks::TimeUnit = choices::parse(py, "time_unit", cloud_time_unit)?;
    let method = match choices::parse::<HksMethod>(py, "method", method)? {
        HksMethod::Auto { .. } => HksMethod::Auto { tol },
        other => other,
    };
    let params = MeshHksParams {
        mass: choices::parse(py, "mass", mass)?,
        method,
        times: match times {
            Some(t) => TimeSampling::Explicit(t),
            None => TimeSampling::Auto {
                num_times: num_times.unwrap_or(shape_retrieval::hks::DEFAULT_NUM_TIMES),
            },
        },
        eigenpairs: k,
        convention: choices::parse(py, "convention", convention)?,
        scaled,
        normalization: choices::parse(py, "normalization", normalization)?,
        laplacian,
        ..Default::default()
    };
    if let Some(b) = &basis {
        if let Some(own) = b.ops.mass_kind().filter(|own| *own != params.mass) {
            return Err(invalid_param(
                py,
                "basis",
                format!(
                    "the basis holds eigenpairs of the {} mass, not of the {} one",
                    own.name(),
                    params.mass.name()
                ),
            ));
        }
    }
    let basis = basis.map(|b| (*b.basis).clone());
    let hks = run(py, move |_| match shape {
        Ok(mesh) => Ok(shape_retrieval::mesh_hks::mesh_hks(&mesh, &params, basis, &mut |_| {})?),
        Err((cloud, cloud_params)) => {
            let assembly = mesh_fem::AssemblyParams::for_mass(params.mass);
            let built = mesh_fem::cloud::assemble_cloud(&cloud, &cloud_params, &assembly)?;
            let mut params = params;
            if let TimeSampling::Explicit(times) = &mut params.times {
                let lengths = shape_retrieval::sihks::MeshLengths::of(&built.neighbourhood);
                let unit = cloud_unit
                    .on(&lengths)
                    .map_err(|e| Error::Invalid("InvalidParameter", format!("time_unit: {e}")))?;
                times.iter_mut().for_each(|t| *t *= unit);
            }
            Ok(shape_retrieval::mesh_hks::operators_hks(
                &built.operators,
                &params,
                basis,
                &mut |_| {},
            )?)
        }
    })?;
    let sources = hks
        .sources
        .iter()
        .map(|s| match *s {
            HksSource::Spectral { estimate, .. } => (s.method().name(), estimate),
            HksSource::Exact { relative_tail } => (s.method().name(), relative_tail),
        })
        .collect();
    Ok((mat_out(py, hks.values.as_ref()), hks.times, sources, hks.eigenvalues))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(eigenpairs_wks, m)?)?;
    m.add("DEFAULT_ENERGIES", shape_retrieval::wks::DEFAULT_ENERGIES)?;
    m.add_class::<PyEigenbasis>()?;
    m.add_function(wrap_pyfunction!(mesh_hks, m)?)?;
    Ok(())
}
