//! From a mesh to descriptors: the dense signatures DHK1–DHK3 and SI-HKS, and the sparse
//! feature points SHK1/SHK2 of the paper's Sect. 5 (Tables 3–5).
//!
//! Every descriptor is computed from the k smallest eigenpairs of a generalized problem
//! `L φ = λ M φ`, `ΦᵀMΦ = I` (paper, Eq. (4)), found by the shift-invert block Lanczos of
//! [`wfem_heat::spectral::Eigenbasis::partial`]. L is the cotangent stiffness (symmetric positive
//! semidefinite, positive diagonal); M is the mass of the kernel:
//!
//! | descriptor | kernel | mass M | HKS |
//! |---|---|---|---|
//! | [`Descriptor::Dhk1`] | Voronoi-cot, `K*_t = X D_t Xᵀ D` (Eq. (7)) | lumped D (mixed Voronoi areas) | `Σ_k e^{−λ_k t} φ_k(i)²` |
//! | [`Descriptor::Dhk2`] | wFEM, `K_t = X D_t Xᵀ B` (Eq. (6)) | consistent B | `Σ_k e^{−λ_k t} φ_k(i)²` |
//! | [`Descriptor::Dhk3`] | wFEM, eigenvalues divided by λ_max (Sect. 5) | consistent B | `Σ_k e^{−(λ_k/λ_max) t} φ_k(i)²/λ_max` |
//! | [`Descriptor::SiHks`] | wFEM | consistent B | [`crate::sihks::scale_invariant_hks`] |
//!
//! (all in the kernel-value convention `h(i, t) = K_t(x_i, x_i)` of [`crate::hks`]).
//! DHK1/DHK2 are scale-covariant (`K_t(αM) = K_{α⁻²t}(M)`), DHK3 and SI-HKS scale-invariant.
//! λ_max is the largest of the k computed eigenvalues, so DHK3 compares shapes consistently
//! only when they use the same k (λ_k ≈ 4πk/area by Weyl's law, so it is an area normalisation
//! in disguise).
//!
//! **Number of eigenpairs.** The default k = 100 (pyFM and DiffusionNet use 100–128; Sun's and
//! Aubry's codes 300). The truncation error of the HKS at time t is about e^{−λ_k t}
//! (docs/NUMERICS.md §4), so times below ≈ 4 ln10/λ_k are not resolved; the automatic time range
//! starts there.
//!
//! When n ≤ max(3k, 400) (small meshes) the eigenpairs come from the dense decomposition
//! [`wfem_heat::spectral::Eigenbasis::dense`] instead, truncated to k: it costs well under a second there,
//! and the block Lanczos can stall when its Krylov space reaches n.
//!
//! **Sparse features.** SHK1 = strict local maxima (within `rings` edge rings) of the DHK2
//! signature at one large time `t_f = feature_time_factor · 4 ln10/λ_2`; SHK2 = the maxima of
//! the same function that survive persistence simplification at `persistence_fraction` of its
//! range ([`mesh_fem::morse`], \[EMP06\]).

mod kinds;

pub use kinds::{Descriptor, DescriptorOptions, RETRIEVAL_SIHKS};

use crate::hks::{heat_kernel_signature, HksParams, Spectrum, TimeSampling};
use crate::RetrievalError;
use faer::Mat;
use mesh_fem::cloud::{assemble_cloud, CloudParams, PointCloud};
use mesh_fem::{assemble, AssemblyParams, FemOperators, Laplacian, Lumping, TriMesh};
use wfem_heat::spectral::{EigenParams, Eigenbasis};
use wfem_heat::Operators;

/// Default number k of eigenpairs (see the module docs).
pub const DEFAULT_EIGENPAIRS: usize = 100;

/// The eigensolver's relative residual tolerance in retrieval ([`crate::model::DescriptorSettings`]
/// describes every indexed and query shape with it): 10⁻⁸ instead of the general 10⁻¹⁰ of
/// [`EigenParams`]. The eigenvalues' error is about its square and a descriptor moves by about
/// the tolerance itself — measured on TOSCA non-isometric (SI-HKS, 5,000 vertices): at most
/// 2.3·10⁻⁸ relative against 10⁻¹⁰, below the single precision an index stores a bag in —
/// while the eigensolve of 100 pairs takes about a fifth less CPU time (0.19 s against
/// 0.24 s there; docs/BENCHMARKS.md, issue #42 point 2). 10⁻⁶ is hardly faster (0.18 s) and
/// moves the descriptors by 1.4·10⁻⁶.
pub const RETRIEVAL_EIGEN_TOLERANCE: f64 = 1e-8;

/// Meshes with at most this many vertices use the dense eigendecomposition.
const DENSE_BELOW: usize = 400;

/// Sparse feature detectors of the paper's Sect. 5 (Table 4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FeatureDetector {
    /// Local maxima of the HKS at a large time.
    #[default]
    Shk1,
    /// Maxima of the same function after persistence simplification.
    Shk2,
}

wfem_base::registry! {
    FeatureDetector as "feature detector" {
        FeatureDetector::Shk1 = FeatureDetector::Shk1 => "shk1":
            "local maxima of the wFEM HKS at a large time (default)",
        FeatureDetector::Shk2 = FeatureDetector::Shk2 => "shk2":
            "the maxima of the same function that survive persistence simplification",
    }
}

/// Options of the descriptor pipeline.
#[derive(Clone, Debug, PartialEq)]
pub struct DescriptorParams {
    /// Number k of eigenpairs (default [`DEFAULT_EIGENPAIRS`]); clamped to the vertex count.
    pub eigenpairs: usize,
    /// The Lanczos options.
    pub eigen: EigenParams,
    /// Feature time `t_f = feature_time_factor · 4 ln10/λ_2` of SHK1/SHK2 (default 0.1).
    pub feature_time_factor: f64,
    /// Edge rings within which an SHK1 feature must be the maximum (default 1: the local maxima
    /// of the piecewise-linear function, so that SHK2 ⊆ SHK1).
    pub feature_rings: usize,
    /// SHK2 keeps maxima whose persistence is at least this fraction of the range (default 0.05).
    pub persistence_fraction: f64,
}

impl DescriptorParams {
    /// The size limits of the eigenpair count on a shape of `n` vertices, checked before
    /// anything is assembled or allocated.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for k = 0, [`RetrievalError::Heat`] beyond the limits.
    fn check_size(&self, n: usize) -> Result<(), RetrievalError> {
        crate::check::at_least_one("eigenpairs", self.eigenpairs)?;
        let n = n.max(1);
        wfem_heat::limits::eigenpairs("eigenpairs", self.eigenpairs.min(n), n)?;
        Ok(())
    }
}

impl Default for DescriptorParams {
    fn default() -> Self {
        Self {
            eigenpairs: DEFAULT_EIGENPAIRS,
            eigen: EigenParams::default(),
            feature_time_factor: 0.1,
            feature_rings: 1,
            persistence_fraction: 0.05,
        }
    }
}

/// One shape with its operators and lazily computed eigenbases, serving many descriptors.
#[derive(Clone, Debug)]
pub struct ShapeDescriptors {
    mesh: TriMesh,
    operators: FemOperators,
    pub(crate) params: DescriptorParams,
    wfem: Option<Eigenbasis>,
    lumped: Option<Eigenbasis>,
    described: usize,
}

impl ShapeDescriptors {
    /// Assembles L, B and the Voronoi lumped mass D of `mesh` with the cotangent Laplacian.
    ///
    /// # Errors
    /// [`RetrievalError::Mesh`] if assembly fails, [`RetrievalError::InvalidParameter`] for
    /// k = 0 or bad feature parameters.
    pub fn new(mesh: &TriMesh, params: &DescriptorParams) -> Result<Self, RetrievalError> {
        Self::with_laplacian(mesh, Laplacian::default(), params)
    }

    /// The parameters it was made with (the eigensolver's among them).
    pub fn params(&self) -> &DescriptorParams {
        &self.params
    }

    /// As [`Self::new`] with the given Laplacian ([`mesh_fem::Laplacian`]: the cotangent L or
    /// the robust one of the mesh's tufted cover; L symmetric positive semidefinite either way).
    ///
    /// # Errors
    /// As [`Self::new`].
    pub fn with_laplacian(
        mesh: &TriMesh,
        laplacian: Laplacian,
        params: &DescriptorParams,
    ) -> Result<Self, RetrievalError> {
        // Sizes first (a huge k must not cost an assembly, let alone an allocation).
        params.check_size(mesh.n_vertices())?;
        let operators = assemble(
            mesh,
            &AssemblyParams {
                lumping: Lumping::Voronoi,
                laplacian,
            },
        )?;
        Self::from_operators(mesh, operators, params)
    }

    /// The operators of a point cloud ([`mesh_fem::cloud::assemble_cloud`] with its default
    /// neighbourhood size: the robust Laplacian from local triangulations of the 30 nearest
    /// neighbours, B and the Voronoi lumped D on its intrinsic triangulation); the shape's mesh
    /// is the cloud's neighbourhood mesh (the merged local triangles on the points), which gives
    /// the adjacency that feature points and vertex weights need.
    ///
    /// # Errors
    /// [`RetrievalError::Mesh`] if assembly fails (duplicate points, degenerate
    /// neighbourhoods), and those of [`Self::from_operators`].
    pub fn from_cloud(cloud: &PointCloud, params: &DescriptorParams) -> Result<Self, RetrievalError> {
        params.check_size(cloud.n_points())?;
        let ops = assemble_cloud(
            cloud,
            &CloudParams::default(),
            &AssemblyParams {
                lumping: Lumping::Voronoi,
                ..Default::default()
            },
        )?;
        Self::from_operators(&ops.neighbourhood, ops.operators, params)
    }

    /// Uses given operators (their `lumped_mass` is the D of DHK1, whatever its kind).
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] if the operators do not match the mesh,
    /// [`RetrievalError::InvalidParameter`] for bad parameters.
    pub fn from_operators(
        mesh: &TriMesh,
        operators: FemOperators,
        params: &DescriptorParams,
    ) -> Result<Self, RetrievalError> {
        crate::check::same("operator size vs mesh vertices", mesh.n_vertices(), operators.n())?;
        params.check_size(mesh.n_vertices())?;
        crate::check::positive("feature_time_factor", params.feature_time_factor)?;
        crate::check::at_least_one("feature_rings", params.feature_rings)?;
        if !(params.persistence_fraction.is_finite() && (0.0..=1.0).contains(&params.persistence_fraction)) {
            return Err(RetrievalError::InvalidParameter {
                name: "persistence_fraction",
                value: params.persistence_fraction,
                reason: "must be in [0, 1]",
            });
        }
        Ok(Self {
            mesh: mesh.clone(),
            operators,
            params: params.clone(),
            wfem: None,
            lumped: None,
            described: mesh.n_vertices(),
        })
    }

    /// Marks the vertices from `m` on as added (e.g. the patches of filled holes): they take
    /// part in the operators but are not described ([`Self::described_vertices`]).
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] if `m` is zero or more than the vertex count.
    pub fn described_only(mut self, m: usize) -> Result<Self, RetrievalError> {
        if m == 0 || m > self.mesh.n_vertices() {
            return Err(RetrievalError::DimensionMismatch {
                what: "described vertices vs vertices",
                expected: self.mesh.n_vertices(),
                actual: m,
            });
        }
        self.described = m;
        Ok(self)
    }

    /// The number of vertices that are the shape's own (the first ones); the rest were added
    /// by hole filling. Equal to the vertex count unless [`Self::described_only`] said otherwise.
    pub fn described_vertices(&self) -> usize {
        self.described
    }

    /// The mesh.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// The operators (L, B, D).
    pub fn operators(&self) -> &FemOperators {
        &self.operators
    }

    /// The vertex areas `a = B·1` (row sums of the consistent mass, = barycentric lumped areas).
    pub fn vertex_areas(&self) -> Vec<f64> {
        crate::bof::vertex_areas(self.operators.mass.as_ref())
    }

    /// The surface area `A = 1ᵀB1` (paper, Eq. (3)).
    pub fn area(&self) -> f64 {
        self.vertex_areas().iter().sum()
    }

    /// Supplies a precomputed eigenbasis (e.g. from a cache) of (L, D) if `lumped`, else of
    /// (L, B), with k columns for the k smallest eigenvalues (ascending).
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] if it does not have n rows and
    /// `min(eigenpairs, n)` columns.
    pub fn set_eigenbasis(&mut self, lumped: bool, basis: Eigenbasis) -> Result<(), RetrievalError> {
        let k = self.params.eigenpairs.min(self.operators.n());
        crate::check::same("eigenbasis rows vs vertices", self.operators.n(), basis.vectors.nrows())?;
        crate::check::same("eigenbasis columns vs eigenpairs", k, basis.vectors.ncols())?;
        crate::check::same("eigenvalues vs eigenpairs", k, basis.values.len())?;
        if lumped {
            self.lumped = Some(basis);
        } else {
            self.wfem = Some(basis);
        }
        Ok(())
    }

    /// The k smallest eigenpairs of (L, D) if `lumped`, else of (L, B), computed once.
    ///
    /// # Errors
    /// [`RetrievalError::Heat`] if the eigensolver fails.
    pub fn eigenbasis(&mut self, lumped: bool) -> Result<&Eigenbasis, RetrievalError> {
        let k = self.params.eigenpairs.min(self.operators.n());
        let ops = &self.operators;
        let lumped_mass;
        let (slot, mass) = if lumped {
            lumped_mass = ops.lumped_mass();
            (&mut self.lumped, &lumped_mass)
        } else {
            (&mut self.wfem, &ops.mass)
        };
        let basis = match slot.take() {
            Some(basis) => basis,
            None => smallest_eigenpairs(
                &Operators::from_matrices(ops.stiffness.as_ref(), mass.as_ref())?,
                k,
                &self.params.eigen,
            )?,
        };
        Ok(slot.insert(basis))
    }

    /// The feature function of SHK1/SHK2: the wFEM HKS at `t_f = feature_time_factor · 4 ln10/λ_2`.
    /// Returns (t_f, values).
    ///
    /// # Errors
    /// As [`Self::dense`]; [`RetrievalError::NoNonzeroEigenvalue`] if k = 1.
    pub fn feature_function(&mut self) -> Result<(f64, Vec<f64>), RetrievalError> {
        let factor = self.params.feature_time_factor;
        let basis = self.eigenbasis(false)?;
        let spectrum = Spectrum::new(&basis.values, basis.vectors.as_ref())?;
        let lambda_max = spectrum.max_eigenvalue();
        let lambda_2 = basis
            .values
            .iter()
            .copied()
            .filter(|&v| v > 1e-8 * lambda_max)
            .fold(f64::INFINITY, f64::min);
        if !lambda_2.is_finite() {
            return Err(RetrievalError::NoNonzeroEigenvalue);
        }
        let t = factor * 4.0 * std::f64::consts::LN_10 / lambda_2;
        let hks = heat_kernel_signature(
            &spectrum,
            &HksParams {
                times: TimeSampling::Explicit(vec![t]),
                ..Default::default()
            },
        )?;
        Ok((t, hks.values.col(0).iter().copied().collect()))
    }

    /// Sparse feature points (vertex indices, increasing).
    ///
    /// # Errors
    /// As [`Self::feature_function`]; [`RetrievalError::Mesh`] from the persistence computation.
    pub fn features(&mut self, detector: FeatureDetector) -> Result<Vec<u32>, RetrievalError> {
        let (_, f) = self.feature_function()?;
        match detector {
            FeatureDetector::Shk1 => crate::features::local_maxima(self.mesh.faces(), &f, self.params.feature_rings),
            FeatureDetector::Shk2 => {
                let diagram = mesh_fem::morse::persistence(&self.mesh, &f)?;
                let threshold = self.params.persistence_fraction * diagram.value_range;
                let mut out: Vec<u32> = diagram
                    .maxima
                    .iter()
                    .filter(|p| p.is_essential() || p.persistence >= threshold)
                    .map(|p| p.birth)
                    .collect();
                out.sort_unstable();
                out.dedup();
                Ok(out)
            }
        }
    }
}

/// The k smallest eigenpairs of (L, M), ascending: by the shift-invert block Lanczos, or by
/// the dense decomposition truncated to k when k is a large fraction of n (the Krylov space
/// then fills the whole space, where a dense decomposition is both cheaper and exact, and block
/// Lanczos can stall).
///
/// # Errors
/// [`RetrievalError::Heat`] if the eigensolver fails.
pub fn smallest_eigenpairs(ops: &Operators, k: usize, eigen: &EigenParams) -> Result<Eigenbasis, RetrievalError> {
    let n = ops.n();
    let k = k.min(n);
    if n <= (3 * k).max(DENSE_BELOW) && n <= wfem_heat::spectral::DENSE_MAX_VERTICES {
        let mut full = Eigenbasis::dense_of(ops)?;
        full.values.truncate(k);
        full.vectors = full.vectors.subcols(0, k).to_owned();
        Ok(full)
    } else {
        Ok(Eigenbasis::partial_of(ops, k, eigen)?)
    }
}

/// One-shot dense descriptor of a mesh (see [`ShapeDescriptors`]); for several descriptors of
/// one shape, use [`ShapeDescriptors`] to share the eigenbases.
///
/// ```
/// use shape_retrieval::descriptor::{dense_descriptor, Descriptor, DescriptorParams};
/// use wfem_base::Choice;
/// let mesh = mesh_fem::generate::icosphere(2);
/// let params = DescriptorParams { eigenpairs: 20, ..Default::default() };
/// let dhk2 = Descriptor::parse("dhk2").expect("a registered name");
/// let d = dense_descriptor(&mesh, &dhk2, &params)?;
/// assert_eq!((d.nrows(), d.ncols()), (mesh.n_vertices(), 16));
/// # Ok::<(), shape_retrieval::RetrievalError>(())
/// ```
///
/// # Errors
/// Those of [`ShapeDescriptors::new`] and [`ShapeDescriptors::dense`].
pub fn dense_descriptor(
    mesh: &TriMesh,
    descriptor: &Descriptor,
    params: &DescriptorParams,
) -> Result<Mat<f64>, RetrievalError> {
    ShapeDescriptors::new(mesh, params)?.dense(descriptor)
}

/// One-shot sparse features of a mesh (see [`ShapeDescriptors::features`]).
///
/// # Errors
/// Those of [`ShapeDescriptors::new`] and [`ShapeDescriptors::features`].
pub fn sparse_features(
    mesh: &TriMesh,
    detector: FeatureDetector,
    params: &DescriptorParams,
) -> Result<Vec<u32>, RetrievalError> {
    ShapeDescriptors::new(mesh, params)?.features(detector)
}
