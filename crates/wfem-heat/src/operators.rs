//! The one validated operator context of wfem-heat: the stiffness L, the mass M of a
//! [`Mass`] (paper, Table 1), their shared pattern and symbolic Cholesky analysis
//! ([`shifted_solve::OperatorPair`]) and the null space of L (the constants on every
//! connected component). Built once, validated once, shared (cheap clones) by
//! [`crate::HeatKernel`] and every method, [`crate::distance::DiffusionDistance`], the RKHS algebra
//! ([`crate::rkhs`]) and the eigensolver ([`crate::spectral::Eigenbasis`]).

use crate::null_space::NullSpace;
use crate::HeatError;
use faer::sparse::{SparseColMat, SparseColMatRef};
use mesh_fem::{FemOperators, Mass};
use shifted_solve::{OperatorPair, SolveError, SpdFactor};
use std::sync::{Arc, OnceLock};

/// The validated operator context: L and the kernel's mass M on one pattern with their
/// symbolic analysis and the null space of L. Cheap to clone (shared).
#[derive(Clone, Debug)]
pub struct Operators {
    pair: Arc<OperatorPair>,
    mass: Option<Mass>,
    null_space: Arc<NullSpace>,
    mass_factor: Arc<OnceLock<Option<SpdFactor>>>,
    conditioning: Arc<OnceLock<Conditioning>>,
    /// Whether L is a FEM cotangent matrix (dimensionless), as opposed to given directly.
    fem: bool,
}

/// How far rounding in the assembled operators can spoil the heat kernel
/// ([`Operators::conditioning`]).
///
/// For FEM operators (the cotangent L is dimensionless) `ratio = max_i L_ii / 4`: about 1 on
/// a well-shaped mesh (an equilateral triangulation has L_ii = √3 ≈ 1.7 for valence 6) and
/// about the largest |cot| of an angle where a needle or cap triangle sits. For operators given
/// directly, whose scale is unknown, `ratio = max_i L_ii / median_i L_ii`. The cotangent
/// weights are computed to relative rounding ε, so entries of size `ratio` carry absolute
/// errors ε·ratio, and the smooth modes of the assembled L move by up to about ε·ratio² —
/// whatever method evaluates the kernel afterwards. Measured against a 60-digit evaluation of
/// the same double-precision matrices on a lattice of flat obtuse triangles: heights 1e−4,
/// 1e−7 (ratio ≈ 1/(4·height)) gave errors 1e−9 and 3e−4 for every method, and at 1e−10 the
/// assembled L was indefinite (an eigenvalue −23) and every method was 91 % off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conditioning {
    /// See the type's documentation (≥ 1).
    pub ratio: f64,
    /// The vertex of the largest diagonal entry of L.
    pub vertex: usize,
}

impl Conditioning {
    /// The relative error rounding alone can cause in K_t f: ε·ratio².
    pub fn rounding_error(&self) -> f64 {
        f64::EPSILON * self.ratio * self.ratio
    }
}

/// Maps the validation errors of the pair to the vocabulary of this crate.
pub(crate) fn operator_error(e: SolveError) -> HeatError {
    match e {
        SolveError::NonFinite { what, row, col, value } => HeatError::InvalidOperatorEntry {
            matrix: if what == "mass" { "mass M" } else { "stiffness L" },
            row,
            col,
            value,
            requirement: "finite",
        },
        SolveError::BadDiagonal {
            which, index, value, ..
        } => HeatError::InvalidOperatorEntry {
            matrix: if which == "mass" { "mass M" } else { "stiffness L" },
            row: index,
            col: index,
            value,
            requirement: if which == "mass" {
                "> 0 on the diagonal"
            } else {
                ">= 0 on the diagonal"
            },
        },
        SolveError::NotSquare { .. } | SolveError::DimensionMismatch { .. } | SolveError::NotSymmetric { .. } => {
            HeatError::InconsistentOperators { reason: e.to_string() }
        }
        SolveError::Empty => HeatError::InconsistentOperators {
            reason: "the operators are empty (no vertices)".into(),
        },
        other => HeatError::Solve(other),
    }
}

impl Operators {
    /// The context of the kernel of `mass` on assembled FEM operators: L with B (the wFEM
    /// kernel), the lumped D, or I (the linear FEM kernel).
    ///
    /// # Errors
    /// [`HeatError::InvalidParameter`] for a lumped mass the operators were not assembled with
    /// (assemble with [`mesh_fem::AssemblyParams::for_mass`]); as [`Self::from_matrices`].
    pub fn new(fem: &FemOperators, mass: Mass) -> Result<Self, HeatError> {
        let diagonal;
        let matrix = match mass {
            Mass::Consistent => &fem.mass,
            Mass::Lumped(lumping) => {
                if lumping != fem.lumping {
                    return Err(HeatError::InvalidParameter {
                        name: "mass",
                        reason: format!(
                            "the {lumping:?} lumped mass was asked for, but the operators were assembled with the \
                             {:?} one (assemble with AssemblyParams::for_mass)",
                            fem.lumping
                        ),
                    });
                }
                diagonal = fem.lumped_mass();
                &diagonal
            }
            Mass::Identity => {
                diagonal = fem.identity_mass();
                &diagonal
            }
        };
        // Assembled here: symmetric by construction, so the entry-wise checks of given
        // matrices are skipped.
        let mut ops = Self::from_pair(fem.stiffness.as_ref(), matrix.as_ref())?;
        ops.mass = Some(mass);
        ops.fem = true;
        Ok(ops)
    }

    /// The context of any stiffness L (symmetric positive semidefinite, non-negative diagonal;
    /// −libigl's `cotmatrix`) and mass M (symmetric positive definite), e.g. a robust or
    /// intrinsic Laplacian computed elsewhere. The patterns may differ (they are merged).
    ///
    /// # Errors
    /// [`HeatError::InvalidOperatorEntry`] for a NaN/∞ entry, a non-positive diagonal entry of
    /// M or a negative one of L, an entry that differs from its transpose (relative 1e−12), or
    /// one with `|a_ij| > √(a_ii a_jj)` (an indefinite matrix; strict for M), naming the row and
    /// column; [`HeatError::InconsistentOperators`] for sizes or emptiness.
    pub fn from_matrices(
        stiffness: SparseColMatRef<'_, usize, f64>,
        mass: SparseColMatRef<'_, usize, f64>,
    ) -> Result<Self, HeatError> {
        if stiffness.nrows() == stiffness.ncols() && stiffness.nrows() == mass.nrows() && mass.nrows() == mass.ncols() {
            check_symmetric("stiffness L", stiffness, false)?;
            check_symmetric("mass M", mass, true)?;
        }
        Self::from_pair(stiffness, mass)
    }

    /// [`Self::from_matrices`] without the entry-wise symmetry checks (for operators assembled
    /// by mesh-fem).
    fn from_pair(
        stiffness: SparseColMatRef<'_, usize, f64>,
        mass: SparseColMatRef<'_, usize, f64>,
    ) -> Result<Self, HeatError> {
        let pair = OperatorPair::new(stiffness, mass).map_err(operator_error)?;
        let null_space = NullSpace::new(&pair);
        Ok(Self {
            pair: Arc::new(pair),
            mass: None,
            null_space: Arc::new(null_space),
            mass_factor: Arc::new(OnceLock::new()),
            conditioning: Arc::new(OnceLock::new()),
            fem: false,
        })
    }

    /// Number of vertices n.
    pub fn n(&self) -> usize {
        self.pair.n()
    }

    /// The mass of this context's kernel; `None` for matrices given directly.
    pub fn mass_kind(&self) -> Option<Mass> {
        self.mass
    }

    /// The validated pair (L, M) of shifted-solve.
    pub fn pair(&self) -> &Arc<OperatorPair> {
        &self.pair
    }

    /// The stiffness L on the shared pattern.
    pub fn stiffness(&self) -> SparseColMatRef<'_, usize, f64> {
        self.pair.stiffness()
    }

    /// The mass M of the kernel on the shared pattern.
    pub fn mass(&self) -> SparseColMatRef<'_, usize, f64> {
        self.pair.mass()
    }

    /// An owned copy of M (for APIs that keep a matrix).
    pub fn mass_matrix(&self) -> SparseColMat<usize, f64> {
        self.pair.combination(0.0, 1.0)
    }

    /// `M x` (rows in parallel).
    pub fn mass_mul(&self, x: &[f64]) -> Vec<f64> {
        self.pair.mass_mul_par(x)
    }

    /// `L x` (rows in parallel).
    pub fn stiffness_mul(&self, x: &[f64]) -> Vec<f64> {
        self.pair.stiffness_mul_par(x)
    }

    /// The vertex weights `M·1` (the vertex areas for B and D).
    pub fn vertex_areas(&self) -> Vec<f64> {
        self.pair.mass_row_sums()
    }

    /// The total mass `1ᵀM1` (the surface area for B and D).
    pub fn total_mass(&self) -> f64 {
        self.pair.mass_values().iter().sum()
    }

    /// The time from which `K_t = P` (the projector onto the null space of L) to double
    /// precision: `10¹⁴/λ̄` with `λ̄ = tr(L)/tr(M)` the mean Rayleigh quotient of the vertex
    /// hat functions, about 1/h² on a mesh of edge length h. Since λ₂ ≥ λ̄/n² on any connected
    /// mesh of n ≤ 10⁶ vertices (and far more in practice: λ̄/λ₂ ≈ (diameter/h)² ≈ n for a
    /// surface), every non-constant mode has decayed by e^{−tλ₂} ≤ e^{−100} there. Methods need
    /// not (and cannot: M + γtL overflows at t = 1e300) evaluate beyond it.
    pub fn time_at_infinity(&self) -> f64 {
        let mean = self.mean_rayleigh_quotient();
        if mean > 0.0 && mean.is_finite() {
            1e14 / mean
        } else {
            f64::INFINITY
        }
    }

    /// The connected components of the operators' pattern (vertex lists, increasing).
    pub fn components(&self) -> &[Vec<usize>] {
        self.null_space.components()
    }

    /// The context restricted to a set of vertices (sorted, distinct — e.g. a connected
    /// component): the principal submatrices of L and M.
    ///
    /// # Errors
    /// As [`Self::from_matrices`] (e.g. an empty set).
    pub fn restrict(&self, vertices: &[usize]) -> Result<Self, HeatError> {
        let n = self.n();
        let mut local = vec![usize::MAX; n];
        for (k, &v) in vertices.iter().enumerate() {
            if v < n {
                local[v] = k;
            }
        }
        let pattern = self.pair.pattern();
        let (l, m) = (self.pair.stiffness_values(), self.pair.mass_values());
        let mut lt = Vec::new();
        let mut mt = Vec::new();
        for &j in vertices {
            for p in pattern.col_range(j) {
                let i = pattern.row_idx()[p];
                if local[i] != usize::MAX {
                    lt.push(faer::sparse::Triplet::new(local[i], local[j], l[p]));
                    mt.push(faer::sparse::Triplet::new(local[i], local[j], m[p]));
                }
            }
        }
        let k = vertices.len();
        let build = |t: &[faer::sparse::Triplet<usize, usize, f64>]| {
            SparseColMat::try_new_from_triplets(k, k, t).map_err(|e| HeatError::InconsistentOperators {
                reason: format!("restriction to {k} vertices: {e:?}"),
            })
        };
        let mut ops = Self::from_pair(build(&lt)?.as_ref(), build(&mt)?.as_ref())?;
        ops.mass = self.mass;
        ops.fem = self.fem;
        Ok(ops)
    }

    /// `λ̄ = tr(L)/tr(M)`: the mean Rayleigh quotient of the vertex hat functions, the scale of
    /// the spectrum (about 1/h² on a mesh of edge length h).
    pub fn mean_rayleigh_quotient(&self) -> f64 {
        let diag_l: f64 = self.pair.diagonal(1.0, 0.0).iter().sum();
        let diag_m: f64 = self.pair.diagonal(0.0, 1.0).iter().sum();
        diag_l / diag_m
    }

    /// Whether every vertex lies in a component whose constants are in the null space of L
    /// (true for FEM stiffness matrices; false e.g. with Dirichlet rows).
    pub(crate) fn null_space_is_deflated(&self) -> bool {
        self.null_space.all_deflated()
    }

    /// How far rounding in L and M can spoil the kernel (see [`Conditioning`]); computed once.
    pub fn conditioning(&self) -> Conditioning {
        *self.conditioning.get_or_init(|| {
            let diag = self.pair.diagonal(1.0, 0.0);
            let (vertex, largest) = diag
                .iter()
                .enumerate()
                .fold((0, 0.0f64), |(bi, bv), (i, &v)| if v > bv { (i, v) } else { (bi, bv) });
            let reference = if self.fem {
                4.0
            } else {
                let mut sorted: Vec<f64> = diag.iter().copied().filter(|v| *v > 0.0).collect();
                sorted.sort_by(f64::total_cmp);
                sorted.get(sorted.len() / 2).copied().unwrap_or(1.0)
            };
            Conditioning {
                ratio: (largest / reference).max(1.0),
                vertex,
            }
        })
    }

    /// The null space of L that every method deflates exactly.
    pub(crate) fn null_space(&self) -> &NullSpace {
        &self.null_space
    }

    /// The Cholesky factor of M, computed on first use (for M⁻¹ in K̃_t = K_t M⁻¹).
    ///
    /// # Errors
    /// [`HeatError::NotPositiveDefinite`] if M cannot be factored.
    pub fn mass_factor(&self) -> Result<&SpdFactor, HeatError> {
        self.mass_factor
            .get_or_init(|| {
                self.pair
                    .factor_spd(0.0, 1.0, || SolveError::MassNotPositiveDefinite {
                        detail: "Cholesky of M".into(),
                    })
                    .ok()
            })
            .as_ref()
            .ok_or_else(|| HeatError::NotPositiveDefinite {
                matrix: "mass matrix M".into(),
            })
    }

    /// Factors the SPD matrix `M + s·L`.
    ///
    /// # Errors
    /// [`HeatError::NotPositiveDefinite`] naming `what` if it is not numerically positive
    /// definite.
    pub(crate) fn factor_shifted(&self, s: f64, what: impl FnOnce() -> String) -> Result<SpdFactor, HeatError> {
        self.factor_combination(s, 1.0, what)
    }

    /// Factors the SPD matrix `a·L + b·M` on the shared analysis.
    ///
    /// # Errors
    /// [`HeatError::NotPositiveDefinite`] naming `what` if it is not numerically positive
    /// definite; [`HeatError::Solve`] if the symbolic analysis fails.
    pub(crate) fn factor_combination(
        &self,
        a: f64,
        b: f64,
        what: impl FnOnce() -> String,
    ) -> Result<SpdFactor, HeatError> {
        let pattern = self.pair.cholesky()?;
        let matrix = self.pair.combination(a, b);
        pattern
            .factor(matrix.as_ref(), faer::get_global_parallelism())
            .map_err(|_| HeatError::NotPositiveDefinite { matrix: what() })
    }

    /// `M X` for an n × k block.
    pub(crate) fn mass_mul_block(&self, x: faer::MatRef<'_, f64>) -> faer::Mat<f64> {
        let mut out = faer::Mat::<f64>::zeros(x.nrows(), x.ncols());
        faer::sparse::linalg::matmul::sparse_dense_matmul(
            out.as_mut(),
            faer::Accum::Replace,
            self.mass(),
            x,
            1.0,
            faer::get_global_parallelism(),
        );
        out
    }

    /// The mass scalar product `⟨f, g⟩_M = fᵀ M g` (paper, Eq. (4); B, D or I).
    ///
    /// # Errors
    /// [`HeatError::LengthMismatch`], [`HeatError::NonFiniteInput`].
    pub fn mass_inner_product(&self, f: &[f64], g: &[f64]) -> Result<f64, HeatError> {
        crate::check::vector(f, self.n())?;
        crate::check::vector(g, self.n())?;
        Ok(dot(f, &self.mass_mul(g)))
    }

    /// The mass norm `‖f‖_M = √(fᵀ M f)` (paper, Eq. (4)).
    ///
    /// # Errors
    /// As [`Self::mass_inner_product`].
    pub fn mass_norm(&self, f: &[f64]) -> Result<f64, HeatError> {
        Ok(self.mass_inner_product(f, f)?.max(0.0).sqrt())
    }
}

/// Anything that views as a sparse CSC matrix of f64 (owned, borrowed, or a reference), so
/// that the convenience constructors accept `&fem.stiffness` and `kernel.mass()` alike.
pub trait AsSparse {
    /// The borrowed view.
    fn as_sparse(&self) -> SparseColMatRef<'_, usize, f64>;
}

impl AsSparse for SparseColMat<usize, f64> {
    fn as_sparse(&self) -> SparseColMatRef<'_, usize, f64> {
        self.as_ref()
    }
}

impl AsSparse for SparseColMatRef<'_, usize, f64> {
    fn as_sparse(&self) -> SparseColMatRef<'_, usize, f64> {
        *self
    }
}

impl<T: AsSparse + ?Sized> AsSparse for &T {
    fn as_sparse(&self) -> SparseColMatRef<'_, usize, f64> {
        (**self).as_sparse()
    }
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A given matrix must be symmetric (`a_ij = a_ji` up to 1e−12 relative) and pass the 2 × 2
/// principal-minor test of a positive (semi)definite matrix, `|a_ij| ≤ √(a_ii a_jj)` (strict
/// for the mass): necessary conditions, cheap (one pass over the entries), and enough to refuse
/// the usual mistakes — an unsymmetric matrix (whose lower triangle alone would otherwise be
/// used) or an indefinite one such as `[[1, 2], [2, 1]]`. L is symmetric positive
/// semidefinite throughout wfem.
fn check_symmetric(matrix: &'static str, a: SparseColMatRef<'_, usize, f64>, strict: bool) -> Result<(), HeatError> {
    let n = a.ncols();
    let mut entries: std::collections::HashMap<(usize, usize), f64> =
        std::collections::HashMap::with_capacity(a.compute_nnz());
    for j in 0..n {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            if !v.is_finite() {
                return Err(HeatError::InvalidOperatorEntry {
                    matrix,
                    row: i,
                    col: j,
                    value: v,
                    requirement: "finite",
                });
            }
            *entries.entry((i, j)).or_insert(0.0) += v;
        }
    }
    let diagonal = |i: usize| entries.get(&(i, i)).copied().unwrap_or(0.0).max(0.0);
    let mut culprits: Vec<(&(usize, usize), &f64)> = entries.iter().filter(|((i, j), _)| i != j).collect();
    // The first culprit in (column, row) order, whatever the hash order.
    culprits.sort_by_key(|((i, j), _)| (*j, *i));
    for (&(i, j), &v) in culprits {
        let w = entries.get(&(j, i)).copied().unwrap_or(0.0);
        if (v - w).abs() > 1e-12 * v.abs().max(w.abs()) {
            return Err(HeatError::InvalidOperatorEntry {
                matrix,
                row: i,
                col: j,
                value: v,
                requirement: "symmetric: equal to the entry at (col, row)",
            });
        }
        // √a_ii·√a_jj, not √(a_ii a_jj): no underflow at 1e−200 entries.
        let bound = diagonal(i).sqrt() * diagonal(j).sqrt();
        let singular = strict && v != 0.0 && v.abs() >= bound * (1.0 - 1e-12);
        if v.abs() > bound * (1.0 + 1e-12) || singular {
            return Err(HeatError::InvalidOperatorEntry {
                matrix,
                row: i,
                col: j,
                value: v,
                requirement: "|a_ij| ≤ √(a_ii a_jj), as in a positive (semi)definite matrix (this one is indefinite)",
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    fn matrix(entries: &[(usize, usize, f64)]) -> SparseColMat<usize, f64> {
        let t: Vec<Triplet<usize, usize, f64>> = entries.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
        SparseColMat::try_new_from_triplets(2, 2, &t).unwrap()
    }

    #[test]
    fn given_matrices_must_be_symmetric_and_pass_the_minor_test() {
        let identity = matrix(&[(0, 0, 1.0), (1, 1, 1.0)]);
        let laplacian = matrix(&[(0, 0, 1.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 1.0)]);
        assert!(Operators::from_matrices(laplacian.as_ref(), identity.as_ref()).is_ok());
        let unsymmetric = matrix(&[(0, 0, 1.0), (0, 1, -1.0), (1, 0, -0.5), (1, 1, 1.0)]);
        let e = Operators::from_matrices(unsymmetric.as_ref(), identity.as_ref()).unwrap_err();
        assert!(
            matches!(
                e,
                HeatError::InvalidOperatorEntry {
                    matrix: "stiffness L",
                    row: 1,
                    col: 0,
                    ..
                }
            ),
            "{e}"
        );
        let indefinite = matrix(&[(0, 0, 1.0), (0, 1, 2.0), (1, 0, 2.0), (1, 1, 1.0)]);
        let e = Operators::from_matrices(indefinite.as_ref(), identity.as_ref()).unwrap_err();
        assert!(e.to_string().contains("indefinite"), "{e}");
        // A singular mass (|m_01| = √(m_00 m_11)) is refused; tiny entries do not underflow.
        let singular = matrix(&[(0, 0, 1.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, 1.0)]);
        let e = Operators::from_matrices(laplacian.as_ref(), singular.as_ref()).unwrap_err();
        assert!(
            matches!(e, HeatError::InvalidOperatorEntry { matrix: "mass M", .. }),
            "{e}"
        );
        let tiny = matrix(&[(0, 0, 1e-200), (0, 1, -1e-200), (1, 0, -1e-200), (1, 1, 1e-200)]);
        assert!(Operators::from_matrices(tiny.as_ref(), identity.as_ref()).is_ok());
    }
}
