//! Which diffusion times mean something on a given mesh (issue #25): a time so small that
//! `K_t f` equals f, or so large that the heat has spread to its mean, gives a blank result
//! (a uniform figure, a distance of 0 everywhere) without any error. [`TimeScales`] finds
//! both ends cheaply and says which times are sensible.
//!
//! With the eigenpairs `L xᵢ = λᵢ M xᵢ` (paper, Eq. (4)–(6)), `K_t f = Σᵢ e^{−tλᵢ} ⟨f, xᵢ⟩_M xᵢ`:
//!
//! * **time at infinity**: every non-constant mode has decayed by `e^{−tλ₂} ≤ ε` once
//!   `t ≥ ln(1/ε)/λ₂`, λ₂ the smallest non-zero eigenvalue (of the slowest component); then
//!   `K_t f` is the M-mean of f on each component to ε;
//! * **negligible time**: `‖K_t f − f‖ ≈ t‖M⁻¹L f‖`, and for an impulse `eᵢ` the Rayleigh
//!   quotient `L_ii/M_ii` is about `λ̄ = tr(L)/tr(M)` (≈ 1/h² on a mesh of edge length h); a
//!   time with `tλ̄ ≤ ε` leaves the input unchanged to ε.
//!
//! The sensible range named to users is `[1/λ̄, 4 ln10/λ₂]`: from the time heat takes to cross
//! about one edge to the time it is within 1e−4 of its mean (the top of the automatic HKS
//! times, Sun et al. 2009). ε = [`SETTLED`].
//!
//! **Cost.** λ̄ is O(n). λ₂ is needed only for a time near the top: first an upper bound, the
//! Rayleigh quotient of the vertex coordinates centred (in M) on each component — any function
//! M-orthogonal to the null space gives `λ₂ ≤ xᵀLx / xᵀMx` (min-max), and a coordinate along
//! the longest axis is close to the first non-constant mode — and only when `t` times that
//! bound reaches `ln(1/ε)` the eigenvalue itself ([`Eigenbasis::partial_of`], c + 1 pairs on c
//! components).

use crate::spectral::{EigenParams, Eigenbasis};
use crate::{HeatError, Operators};
use std::fmt;
use std::sync::OnceLock;

/// The relative size ε below which a change does not show in double-precision results (see
/// the module docs).
pub const SETTLED: f64 = 1e-12;

/// Components above which λ₂ is not computed (c + 1 eigenpairs would be needed).
const MAX_COMPONENTS: usize = 64;

/// The time scales of one kernel (its L and M) on one mesh; see the module docs.
#[derive(Debug)]
pub struct TimeScales {
    ops: Operators,
    mean: f64,
    bound: f64,
    first: OnceLock<Option<f64>>,
}

/// A diffusion time whose result carries no information, with the range that would.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeWarning {
    /// `t λ̄ ≤ ε`: `K_t f` equals f to ε.
    Negligible {
        /// The time given.
        t: f64,
        /// The sensible range `[1/λ̄, 4 ln10/λ₂]`.
        sensible: (f64, f64),
    },
    /// `t λ₂ ≥ ln(1/ε)`: `K_t f` is the mean of f to ε.
    PastInfinity {
        /// The time given.
        t: f64,
        /// The time at infinity `ln(1/ε)/λ₂`.
        infinity: f64,
        /// The sensible range `[1/λ̄, 4 ln10/λ₂]`.
        sensible: (f64, f64),
    },
}

impl TimeWarning {
    /// The same warning with every time divided by `unit` (times read in a unit of the mesh:
    /// `t = τ·unit`).
    pub fn in_unit(self, unit: f64) -> Self {
        let s = |(a, b): (f64, f64)| (a / unit, b / unit);
        match self {
            TimeWarning::Negligible { t, sensible } => TimeWarning::Negligible {
                t: t / unit,
                sensible: s(sensible),
            },
            TimeWarning::PastInfinity { t, infinity, sensible } => TimeWarning::PastInfinity {
                t: t / unit,
                infinity: infinity / unit,
                sensible: s(sensible),
            },
        }
    }

    /// The sensible range of the mesh.
    pub fn sensible(&self) -> (f64, f64) {
        match self {
            TimeWarning::Negligible { sensible, .. } | TimeWarning::PastInfinity { sensible, .. } => *sensible,
        }
    }
}

impl fmt::Display for TimeWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (lo, hi) = self.sensible();
        match self {
            TimeWarning::Negligible { t, .. } => write!(
                f,
                "t = {} is too small for this mesh: the result equals the input to {SETTLED:.0e}",
                short(*t)
            )?,
            TimeWarning::PastInfinity { t, infinity, .. } => write!(
                f,
                "t = {} is past the time at infinity of this mesh ({}): the heat has spread \
                 to its mean to {SETTLED:.0e}, so the result is constant",
                short(*t),
                short(*infinity)
            )?,
        }
        write!(
            f,
            "; sensible times for this mesh are about {} to {}",
            short(lo),
            short(hi)
        )
    }
}

/// `x` with 3 significant digits and no trailing zeros: plain from 0.001 to 9990 (`0.1`,
/// `1.75`, `100`), else in exponent form (`1.75e-5`).
fn short(x: f64) -> String {
    let text = format!("{x:.2e}");
    let Some((mantissa, exponent)) = text.split_once('e') else {
        return text;
    };
    match (exponent.parse::<i32>(), text.parse::<f64>()) {
        (Ok(e), Ok(rounded)) if (-3..=3).contains(&e) => format!("{rounded}"),
        _ => format!("{}e{exponent}", mantissa.trim_end_matches('0').trim_end_matches('.')),
    }
}

impl TimeScales {
    /// The scales of `ops` (a shared copy is kept) on a mesh with these vertex positions (one
    /// per row of L). Without positions (operators given directly) there is no bound of λ₂:
    /// [`Self::check`] then warns about negligible times only (λ₂ would cost a factorization
    /// on every such kernel), and [`Self::first_nonzero`] still computes it on demand.
    ///
    /// # Errors
    /// [`HeatError::LengthMismatch`] if `positions` does not have one row per vertex.
    pub fn new(ops: &Operators, positions: Option<&[[f64; 3]]>) -> Result<Self, HeatError> {
        let n = ops.n();
        let bound = match positions {
            Some(p) if p.len() != n => {
                return Err(HeatError::LengthMismatch {
                    expected: n,
                    found: p.len(),
                })
            }
            Some(p) => coordinate_bound(ops, p),
            None => f64::INFINITY,
        };
        Ok(Self {
            ops: ops.clone(),
            mean: ops.mean_rayleigh_quotient(),
            bound,
            first: OnceLock::new(),
        })
    }

    /// `λ̄ = tr(L)/tr(M)`.
    pub fn mean_eigenvalue(&self) -> f64 {
        self.mean
    }

    /// An upper bound of λ₂: the smallest Rayleigh quotient of the centred coordinates
    /// (∞ when every coordinate is constant on its component).
    pub fn first_nonzero_bound(&self) -> f64 {
        self.bound
    }

    /// λ₂, the smallest non-zero eigenvalue over the components (computed once, on first
    /// use); `None` above 64 components or when no component has a non-constant mode.
    ///
    /// # Errors
    /// Those of [`Eigenbasis::partial_of`].
    pub fn first_nonzero(&self) -> Result<Option<f64>, HeatError> {
        if let Some(first) = self.first.get() {
            return Ok(*first);
        }
        let first = self.compute_first()?;
        Ok(*self.first.get_or_init(|| first))
    }

    fn compute_first(&self) -> Result<Option<f64>, HeatError> {
        let c = self.ops.components().len();
        let n = self.ops.n();
        if c > MAX_COMPONENTS || c >= n {
            return Ok(None);
        }
        let params = EigenParams {
            tol: 1e-6,
            block_size: 4,
            ..EigenParams::default()
        };
        let basis = Eigenbasis::partial_of(&self.ops, c + 1, &params)?;
        let floor = 1e-8 * self.mean;
        Ok(basis.values.iter().copied().find(|&l| l > floor))
    }

    /// `[1/λ̄, 4 ln10/λ₂]` (λ₂ replaced by its upper bound when it is not known).
    ///
    /// # Errors
    /// As [`Self::first_nonzero`].
    pub fn sensible(&self) -> Result<(f64, f64), HeatError> {
        let first = self.first_nonzero()?.unwrap_or(self.bound);
        let first = if first.is_finite() { first } else { self.mean };
        Ok((1.0 / self.mean, 4.0 * std::f64::consts::LN_10 / first))
    }

    /// The warning for the time `t`, if its result carries no information (see the module
    /// docs); λ₂ is computed only when `t` is within reach of the time at infinity. `None` for
    /// a value that is not a time (≤ 0, NaN, ∞), which the kernel refuses.
    ///
    /// # Errors
    /// As [`Self::first_nonzero`].
    pub fn check(&self, t: f64) -> Result<Option<TimeWarning>, HeatError> {
        if !(t.is_finite() && t > 0.0) {
            // Not a time: the kernel refuses it (HeatError::InvalidTime).
            return Ok(None);
        }
        let settled = (1.0 / SETTLED).ln();
        if t * self.mean <= SETTLED {
            return Ok(Some(TimeWarning::Negligible {
                t,
                sensible: self.sensible()?,
            }));
        }
        if t * self.bound < settled || !self.bound.is_finite() {
            return Ok(None);
        }
        match self.first_nonzero()? {
            Some(first) if t * first >= settled => Ok(Some(TimeWarning::PastInfinity {
                t,
                infinity: settled / first,
                sensible: self.sensible()?,
            })),
            _ => Ok(None),
        }
    }
}

/// `min_c xᵀLx / xᵀMx` over the coordinates x, each centred in M on every component: an upper
/// bound of λ₂ (module docs); ∞ if every coordinate is constant on its components.
fn coordinate_bound(ops: &Operators, positions: &[[f64; 3]]) -> f64 {
    let weights = ops.vertex_areas();
    let components = ops.components();
    let mut best = f64::INFINITY;
    for axis in 0..3 {
        let mut x: Vec<f64> = positions.iter().map(|p| p[axis]).collect();
        for vertices in components {
            let w: f64 = vertices.iter().map(|&v| weights[v]).sum();
            let m: f64 = vertices.iter().map(|&v| weights[v] * x[v]).sum();
            if w > 0.0 {
                let mean = m / w;
                for &v in vertices {
                    x[v] -= mean;
                }
            }
        }
        let lx = ops.stiffness_mul(&x);
        let mx = ops.mass_mul(&x);
        let num: f64 = x.iter().zip(&lx).map(|(a, b)| a * b).sum();
        let den: f64 = x.iter().zip(&mx).map(|(a, b)| a * b).sum();
        if den > 0.0 && num.is_finite() && num > 0.0 {
            best = best.min(num / den);
        }
    }
    best
}
