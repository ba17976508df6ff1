//! The heat kernel signature of a mesh, from the mesh to the values (paper, Sect. 5; Eqs. (6)–(8)):
//! the one orchestration of [`HksMethod`] (auto / exact / spectral) that the command line
//! (`wfem hks`) and the Python package (`wfem.hks`) call.
//!
//! Steps: assemble the operators of the kernel's [`Mass`]; when the method or automatic times
//! need them, the k smallest eigenpairs and the truncated sum of Eq. (8); then, per
//! [`HksMethod`], the exact diagonal of the heat kernel ([`crate::exact::signature_by_method`],
//! selected inversion by default) where the truncated sum is not accurate. The report says,
//! per time, which one was used and with what error bound.

use crate::descriptor::smallest_eigenpairs;
use crate::exact::{exact_signature, signature_by_method, truncation_bound, truncation_estimate, HksMethod, HksSource};
use crate::hks::{heat_kernel_signature, HksParams, Spectrum, SpectrumNormalization, TimeSampling};
use crate::RetrievalError;
use faer::Mat;
use mesh_fem::{assemble, AssemblyParams, FemOperators, Laplacian, Mass, TriMesh};
use wfem_base::Choice;
use wfem_heat::method::Method;
use wfem_heat::spectral::{EigenParams, Eigenbasis};
use wfem_heat::{DiagonalParams, HeatKernel, HeatParams, KernelDiagonal, Operators};

/// Options of [`mesh_hks`].
#[derive(Clone, Debug, PartialEq)]
pub struct MeshHksParams {
    /// The kernel, by its mass (default the consistent B: the wFEM kernel; a lumped mass gives
    /// the Voronoi-cot or barycentric kernel, the paper's DHK1 with the Voronoi one).
    pub mass: Mass,
    /// How the signature is evaluated (default [`HksMethod::Auto`]).
    pub method: HksMethod,
    /// The times (default [`TimeSampling::default`]: automatic, log-spaced).
    pub times: TimeSampling,
    /// Eigenpairs k of the truncated sum (default [`crate::descriptor::DEFAULT_EIGENPAIRS`], at most n).
    pub eigenpairs: usize,
    /// Eigensolver options.
    pub eigen: EigenParams,
    /// Which diagonal (default the kernel value, Sun et al.).
    pub convention: KernelDiagonal,
    /// Divide each column by the heat trace (pyFM's `scaled`); spectral only.
    pub scaled: bool,
    /// Rescaling of the spectrum for scale invariance; spectral only.
    pub normalization: SpectrumNormalization,
    /// How the exact diagonal is computed (default selected inversion).
    pub diagonal: DiagonalParams,
    /// Which Laplacian [`mesh_hks`] assembles (default the cotangent L).
    pub laplacian: Laplacian,
}

impl Default for MeshHksParams {
    fn default() -> Self {
        Self {
            mass: Mass::default(),
            method: HksMethod::default(),
            times: TimeSampling::default(),
            eigenpairs: crate::descriptor::DEFAULT_EIGENPAIRS,
            eigen: EigenParams::default(),
            convention: KernelDiagonal::default(),
            scaled: false,
            normalization: SpectrumNormalization::None,
            diagonal: DiagonalParams::default(),
            laplacian: Laplacian::default(),
        }
    }
}

/// The signature with, per time, where its values came from.
#[derive(Clone, Debug)]
pub struct MeshHks {
    /// n × T values `h(i, t_j)`.
    pub values: Mat<f64>,
    /// The times t_j (the automatic ones once chosen from the spectrum).
    pub times: Vec<f64>,
    /// Per time: the truncated sum with its error bounds, or the exact diagonal.
    pub sources: Vec<HksSource>,
    /// The eigenvalues of the truncated sum (`None` when no eigenpairs were computed: exact
    /// values at explicit times).
    pub eigenvalues: Option<Vec<f64>>,
}

/// A step of [`mesh_hks`], announced before it runs (for progress displays).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HksStep {
    /// Assembling L and M.
    Assembly,
    /// The k smallest eigenpairs.
    Eigenpairs {
        /// k.
        k: usize,
    },
    /// The truncated spectral sum.
    SpectralSum,
    /// The symbolic analysis of the heat kernel.
    Analysis,
    /// The exact diagonal where the truncated sum is not accurate.
    ExactDiagonal,
}

/// The heat kernel signature of `mesh` (see the module docs). `basis`, when given, are the
/// eigenpairs of the kernel's pencil to reuse (its size is then k). `step` is told each step
/// before it runs.
///
/// # Errors
/// [`RetrievalError::InvalidParameter`] for options that do not fit together (exact values
/// with `scaled` or a normalization, a mass without a FEM kernel); those of assembly, the
/// eigensolver, [`heat_kernel_signature`] and [`signature_by_method`].
pub fn mesh_hks(
    mesh: &TriMesh,
    params: &MeshHksParams,
    basis: Option<Eigenbasis>,
    step: &mut dyn FnMut(HksStep),
) -> Result<MeshHks, RetrievalError> {
    check_hks_params(params)?;
    check_hks_sizes(params, mesh.n_vertices())?;
    step(HksStep::Assembly);
    let assembly = AssemblyParams {
        laplacian: params.laplacian,
        ..AssemblyParams::for_mass(params.mass)
    };
    let fem = assemble(mesh, &assembly)?;
    operators_hks(&fem, params, basis, step)
}

/// [`mesh_hks`] on operators already assembled (of a mesh with any Laplacian, or of a point
/// cloud, [`mesh_fem::cloud::assemble_cloud`]); they must hold the lumped mass of `params.mass`.
/// `params.laplacian` is not used.
///
/// # Errors
/// As [`mesh_hks`], and [`RetrievalError::Heat`] if the operators lack the lumping of the mass.
pub fn operators_hks(
    fem: &FemOperators,
    params: &MeshHksParams,
    basis: Option<Eigenbasis>,
    step: &mut dyn FnMut(HksStep),
) -> Result<MeshHks, RetrievalError> {
    check_hks_params(params)?;
    check_hks_sizes(params, fem.n())?;
    let spectral_only = params.scaled || params.normalization != SpectrumNormalization::None;
    let ops = Operators::new(fem, params.mass)?;
    let explicit = matches!(params.times, TimeSampling::Explicit(_));
    // The eigenpairs serve the spectral sum and the automatic times; exact values at given
    // times need none.
    if params.method == HksMethod::Exact && explicit {
        let TimeSampling::Explicit(times) = &params.times else {
            return Err(RetrievalError::Empty { what: "times" });
        };
        step(HksStep::Analysis);
        let kernel = heat_kernel(fem, params.mass)?;
        step(HksStep::ExactDiagonal);
        let series = exact_signature(&kernel, times, params.convention, &params.diagonal)?;
        let sources = vec![
            HksSource::Exact {
                relative_tail: series.info.relative_tail
            };
            times.len()
        ];
        return Ok(MeshHks {
            values: series.values,
            times: times.clone(),
            sources,
            eigenvalues: None,
        });
    }
    let basis = match basis {
        Some(basis) => {
            crate::check::same("eigenvector rows vs vertices", fem.n(), basis.vectors.nrows())?;
            basis
        }
        None => {
            let k = params.eigenpairs.min(fem.n());
            step(HksStep::Eigenpairs { k });
            smallest_eigenpairs(&ops, k, &params.eigen)?
        }
    };
    step(HksStep::SpectralSum);
    let mut spectrum = Spectrum::new(&basis.values, basis.vectors.as_ref())?;
    if params.convention == KernelDiagonal::OperatorDiagonal {
        spectrum = spectrum.with_mass(ops.mass())?;
    }
    let normalization = match params.normalization {
        SpectrumNormalization::UnitArea { .. } => SpectrumNormalization::UnitArea { area: fem.area() },
        other => other,
    };
    let spectral = heat_kernel_signature(
        &spectrum,
        &HksParams {
            convention: params.convention,
            times: params.times.clone(),
            scaled: params.scaled,
            normalization,
        },
    )?;
    let n = fem.n();
    let (values, sources) = if params.method == HksMethod::Spectral || spectral_only {
        let sources = spectral
            .times
            .iter()
            .map(|&t| HksSource::Spectral {
                bound: truncation_bound(&basis.values, n, t),
                estimate: truncation_estimate(&basis.values, n, t),
            })
            .collect();
        (spectral.values, sources)
    } else {
        step(HksStep::Analysis);
        let kernel = heat_kernel(fem, params.mass)?;
        step(HksStep::ExactDiagonal);
        signature_by_method(
            &kernel,
            &basis.values,
            spectral.values,
            &spectral.times,
            params.convention,
            params.method,
            &params.diagonal,
        )?
    };
    Ok(MeshHks {
        values,
        times: spectral.times,
        sources,
        eigenvalues: Some(basis.values),
    })
}

/// The heat kernel of the mass, on the fast exact path (its diagonal needs no method: selected
/// inversion works on the operators).
fn heat_kernel(fem: &FemOperators, mass: Mass) -> Result<HeatKernel, RetrievalError> {
    Ok(HeatKernel::new(
        fem,
        HeatParams {
            mass,
            method: Method::fast(),
        },
    )?)
}

impl MeshHks {
    /// How many times used the exact diagonal.
    pub fn exact_count(&self) -> usize {
        self.sources
            .iter()
            .filter(|s| matches!(s, HksSource::Exact { .. }))
            .count()
    }

    /// The largest Weyl-law estimate of the truncation error over the spectral columns (0 when
    /// every column is exact).
    pub fn worst_estimate(&self) -> f64 {
        self.sources.iter().fold(0.0f64, |m, s| match s {
            HksSource::Spectral { estimate, .. } => m.max(*estimate),
            HksSource::Exact { .. } => m,
        })
    }

    /// The name of the method of column j ([`HksSource::method`]).
    pub fn source_name(&self, j: usize) -> &'static str {
        self.sources.get(j).map_or("", |s| s.method().name())
    }
}

/// The options of [`mesh_hks`] that do not fit together, refused before any work.
fn check_hks_params(params: &MeshHksParams) -> Result<(), RetrievalError> {
    let spectral_only = params.scaled || params.normalization != SpectrumNormalization::None;
    if spectral_only && params.method == HksMethod::Exact {
        return Err(RetrievalError::InvalidParameter {
            name: "method",
            value: 0.0,
            reason: "the exact diagonal has no scaled or normalized form: use the spectral method",
        });
    }
    crate::check::at_least_one("eigenpairs", params.eigenpairs)?;
    Ok(())
}

/// The sizes of [`mesh_hks`] on n vertices within the shared limits (the n × T output, the
/// eigenpairs), checked before anything is allocated.
fn check_hks_sizes(params: &MeshHksParams, n: usize) -> Result<(), RetrievalError> {
    params.times.check_size(n)?;
    let n = n.max(1);
    wfem_heat::limits::eigenpairs("eigenpairs", params.eigenpairs.min(n), n)?;
    Ok(())
}
