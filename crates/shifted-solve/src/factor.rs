//! Thin wrappers over faer's low-level sparse Cholesky and LU that run *sequentially* inside
//! one pole: the crate parallelises across poles and right-hand sides with rayon instead.
//! (Measured at n = 10,242 on a loaded 2-core box: a 2-RHS Cholesky solve takes 5.1 ms with
//! `Par::Seq` and 26.7 ms with faer's default rayon parallelism, which the high-level
//! `Llt`/`Lu` types always use.)

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{c64, Conj, MatMut, Par, Side};

use crate::ordering::{self, FillOrdering};
use crate::trisolve::SolvePlan;
use crate::SolveError;

/// Patterns smaller than this solve sequentially (a sweep of a few hundred microseconds gains
/// less than the fork/join and the per-worker buffers cost).
const PARALLEL_SOLVE_MIN_N: usize = 8192;

/// Shared symbolic Cholesky analysis of the pattern of L and B (its ordering chosen by
/// [`analyse`]).
pub(crate) type CholeskySymbolic = Arc<SymbolicCholesky<usize>>;
/// Shared symbolic LU analysis (COLAMD) of the pattern of L and B.
pub(crate) type LuSymbolic = Arc<SymbolicLu<usize>>;

/// The one place a Cholesky ordering is chosen: faer's AMD analysis, and for large patterns
/// whose AMD factor is dense enough also our nested dissection, whose analysis is kept when
/// its predicted factor needs fewer flops and no more entries ([`ordering::choose`]).
fn analyse(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    params: CholeskySymbolicParams<'_>,
) -> Result<(CholeskySymbolic, FillOrdering), String> {
    analyse_with(pattern, params, ordering::ND_MIN_WORK_RATIO)
}

/// [`analyse`] with the threshold of [`ordering::choose_with`] (tests lower it).
pub(crate) fn analyse_with(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    params: CholeskySymbolicParams<'_>,
    min_work_ratio: f64,
) -> Result<(CholeskySymbolic, FillOrdering), String> {
    if ordering::eager(pattern) {
        if let Some(choice) = ordering::choose_eager(pattern, min_work_ratio) {
            if let Some(perm) = &choice.permutation {
                let perm_ref = PermRef::new_checked(&perm.fwd, &perm.inv, pattern.nrows());
                let symbolic =
                    factorize_symbolic_cholesky(pattern, Side::Lower, SymmetricOrdering::Custom(perm_ref), params)
                        .map_err(|e| format!("{e:?}"))?;
                return Ok((Arc::new(symbolic), choice.chosen));
            }
        }
    }
    let amd = factorize_symbolic_cholesky(pattern, Side::Lower, SymmetricOrdering::Amd, params)
        .map_err(|e| format!("{e:?}"))?;
    let choice = ordering::choose_with(pattern, &amd, min_work_ratio);
    let Some(perm) = choice.permutation else {
        return Ok((Arc::new(amd), FillOrdering::Amd));
    };
    drop(amd);
    let perm_ref = PermRef::new_checked(&perm.fwd, &perm.inv, pattern.nrows());
    let nd = factorize_symbolic_cholesky(pattern, Side::Lower, SymmetricOrdering::Custom(perm_ref), params)
        .map_err(|e| format!("{e:?}"))?;
    Ok((Arc::new(nd), FillOrdering::NestedDissection))
}

pub(crate) fn lu_symbolic(pattern: SymbolicSparseColMatRef<'_, usize>) -> Result<LuSymbolic, String> {
    factorize_symbolic_lu(pattern, Default::default())
        .map(Arc::new)
        .map_err(|e| format!("{e:?}"))
}

/// Symbolic Cholesky analysis (fill-reducing ordering — AMD, or nested dissection on large
/// patterns where it gives a smaller factor —, elimination tree, supernodes) of a symmetric
/// pattern, computed once and reused for every numeric factorization on that pattern (every
/// shift `A = M + sL`, every t).
#[derive(Clone, Debug)]
pub struct CholeskyPattern {
    symbolic: CholeskySymbolic,
    /// The ordering the analysis kept.
    ordering: FillOrdering,
    /// The tree-parallel solve plan, when the factor is supernodal and the split pays.
    plan: Option<Arc<SolvePlan>>,
}

impl CholeskyPattern {
    /// Analyses the pattern of `a` (lower triangle used).
    ///
    /// # Errors
    /// [`SolveError::Factorization`] if faer's symbolic analysis fails.
    pub fn new(pattern: SymbolicSparseColMatRef<'_, usize>) -> Result<Self, SolveError> {
        let (symbolic, ordering) =
            analyse(pattern, CholeskySymbolicParams::default()).map_err(|detail| SolveError::Factorization {
                what: "symbolic Cholesky",
                detail,
            })?;
        Ok(Self::from_symbolic(symbolic, ordering))
    }

    /// Analyses the pattern with a supernodal factor forced (same ordering choice): what the
    /// complex-symmetric LDLᵀ needs, so that it and every real Cholesky share one analysis.
    ///
    /// # Errors
    /// [`SolveError::Factorization`] if faer's symbolic analysis fails.
    pub fn supernodal(pattern: SymbolicSparseColMatRef<'_, usize>) -> Result<Self, SolveError> {
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: faer::sparse::linalg::SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let (symbolic, ordering) = analyse(pattern, params).map_err(|detail| SolveError::Factorization {
            what: "symbolic Cholesky",
            detail,
        })?;
        Ok(Self::from_symbolic(symbolic, ordering))
    }

    /// The symbolic analysis.
    pub(crate) fn symbolic(&self) -> &CholeskySymbolic {
        &self.symbolic
    }

    /// The fill-reducing ordering the analysis kept.
    pub fn ordering(&self) -> FillOrdering {
        self.ordering
    }

    /// Number of stored scalars of every factor on this pattern.
    pub fn n_values(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Wraps an existing analysis (and plans its tree-parallel solve).
    pub(crate) fn from_symbolic(symbolic: CholeskySymbolic, ordering: FillOrdering) -> Self {
        let plan = match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(sn) if sn.nrows() >= PARALLEL_SOLVE_MIN_N => {
                SolvePlan::new(sn, rayon::current_num_threads()).map(Arc::new)
            }
            _ => None,
        };
        Self {
            symbolic,
            ordering,
            plan,
        }
    }

    /// Numeric factorization `A = PᵀRRᵀP` of a symmetric positive definite `a` on the analysed
    /// pattern, with faer parallelism `par` (use `Par::Seq` when parallelising over many
    /// factorizations yourself).
    ///
    /// # Errors
    /// [`SolveError::Factorization`] when `a` is not numerically positive definite.
    pub fn factor(&self, a: SparseColMatRef<'_, usize, f64>, par: Par) -> Result<SpdFactor, SolveError> {
        let mut factor = SpdFactor::with_par(&self.symbolic, a, par).map_err(|detail| SolveError::Factorization {
            what: "numeric Cholesky",
            detail,
        })?;
        factor.plan = self.plan.clone();
        Ok(factor)
    }

    /// Sequential factorization whose solves are sequential too: for the many small
    /// factorizations made inside a parallel loop (one per pole), which parallelise over poles
    /// and right-hand sides instead.
    ///
    /// # Errors
    /// As [`Self::factor`].
    pub fn factor_sequential(&self, a: SparseColMatRef<'_, usize, f64>) -> Result<SpdFactor, SolveError> {
        SpdFactor::with_par(&self.symbolic, a, Par::Seq).map_err(|detail| SolveError::Factorization {
            what: "numeric Cholesky",
            detail,
        })
    }
}

/// Real sparse Cholesky factor `A = PᵀRRᵀP` of a symmetric positive definite matrix.
#[derive(Debug)]
pub struct SpdFactor {
    symbolic: CholeskySymbolic,
    values: Vec<f64>,
    /// Tree-parallel solve plan (factors made through [`CholeskyPattern::factor`] only; the
    /// per-pole factors inside parallel loops solve sequentially).
    plan: Option<Arc<SolvePlan>>,
}

impl SpdFactor {
    fn with_par(symbolic: &CholeskySymbolic, a: SparseColMatRef<'_, usize, f64>, par: Par) -> Result<Self, String> {
        let mut values = vec![0.0; symbolic.len_val()];
        let mut buf = MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
            .map_err(|e| format!("{e:?}"))?;
        symbolic
            .factorize_numeric_llt(
                &mut values,
                a,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut buf),
                Default::default(),
            )
            .map_err(|e| format!("{e:?}"))?;
        Ok(Self {
            symbolic: symbolic.clone(),
            values,
            plan: None,
        })
    }

    /// Overwrites `rhs` (n × k) with `A⁻¹ rhs`. Factors from [`CholeskyPattern::factor`] on a
    /// large enough pattern sweep disjoint subtrees of the elimination tree in parallel (see
    /// `trisolve.rs`); the others run sequentially (parallelise over right-hand sides or poles
    /// instead).
    pub fn solve_in_place(&self, mut rhs: MatMut<'_, f64>) {
        if let (Some(plan), SymbolicCholeskyRaw::Supernodal(sn), Some(perm), true) =
            (&self.plan, self.symbolic.raw(), self.symbolic.perm(), true)
        {
            let (fwd, inv) = perm.arrays();
            let mut x = faer::Mat::<f64>::from_fn(rhs.nrows(), rhs.ncols(), |i, j| rhs[(fwd[i], j)]);
            plan.solve_in_place(SupernodalLltRef::new(sn, &self.values), x.as_mut());
            for j in 0..rhs.ncols() {
                for (i, &p) in inv.iter().enumerate() {
                    rhs[(i, j)] = x[(p, j)];
                }
            }
            return;
        }
        let par = Par::Seq;
        let mut buf = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(rhs.ncols(), par));
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(Conj::No, rhs, par, MemStack::new(&mut buf));
    }

    /// Number of stored scalars of the factor (its memory is 8 bytes each).
    pub fn n_values(&self) -> usize {
        self.values.len()
    }

    /// `A⁻¹ b` for one vector.
    pub fn solve_vec(&self, b: &[f64]) -> Vec<f64> {
        let mut m = faer::Mat::<f64>::from_fn(b.len(), 1, |i, _| b[i]);
        self.solve_in_place(m.as_mut());
        (0..b.len()).map(|i| m[(i, 0)]).collect()
    }
}

/// Complex sparse LU factor (partial pivoting) of one tL − zB.
#[derive(Debug)]
pub(crate) struct SeqLu {
    symbolic: LuSymbolic,
    numeric: NumericLu<usize, c64>,
}

impl SeqLu {
    pub fn new(symbolic: &LuSymbolic, a: SparseColMatRef<'_, usize, c64>) -> Result<Self, String> {
        let par = Par::Seq;
        let mut numeric = NumericLu::new();
        let mut buf = MemBuffer::try_new(symbolic.factorize_numeric_lu_scratch::<c64>(par, Default::default()))
            .map_err(|e| format!("{e:?}"))?;
        symbolic
            .factorize_numeric_lu(&mut numeric, a, par, MemStack::new(&mut buf), Default::default())
            .map_err(|e| format!("{e:?}"))?;
        Ok(Self {
            symbolic: symbolic.clone(),
            numeric,
        })
    }

    pub fn solve_in_place(&self, rhs: MatMut<'_, c64>) {
        let par = Par::Seq;
        let mut buf = MemBuffer::new(self.symbolic.solve_in_place_scratch::<c64>(rhs.ncols(), par));
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            rhs,
            par,
            MemStack::new(&mut buf),
        );
    }
}
