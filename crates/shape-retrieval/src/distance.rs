//! Distances between bags of features (and between any non-negative histograms).
//!
//! Bags are compared as normalised histograms `a, b ∈ ℝ^V`, `a_i, b_i ≥ 0`, `Σ a_i = Σ b_i = 1`
//! (the area-weighted bag `Θᵀ a` of [`crate::bof`] divided by the area):
//!
//! * **L1** (Shape Google's choice): `d₁(a, b) = Σ_i |a_i − b_i|`, in [0, 2] for histograms;
//! * **χ²**: `χ²(a, b) = ½ Σ_i (a_i − b_i)²/(a_i + b_i)` over the bins with `a_i + b_i > 0`, in
//!   [0, 1] for histograms. It divides each bin's difference by the bin's mass, so a difference
//!   in a rare word counts more than the same difference in a frequent one (the usual choice for
//!   visual-word histograms).
//!
//! Both are symmetric, zero only for equal histograms, and invariant under a common permutation
//! of the bins.

use crate::check;
use crate::RetrievalError;
use faer::Mat;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which distance compares two bags.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BagDistance {
    /// `Σ |a_i − b_i|` (Shape Google).
    L1,
    /// `½ Σ (a_i − b_i)²/(a_i + b_i)` (default: measured best on TOSCA, docs/SHREC-RESULTS.md).
    #[default]
    ChiSquared,
}

wfem_base::registry! {
    BagDistance as "bag distance" {
        BagDistance::L1 = BagDistance::L1 => "l1" ["manhattan"]:
            "Σ |a_i − b_i| (Shape Google)",
        BagDistance::ChiSquared = BagDistance::ChiSquared => "chi-squared" ["chi2", "chi-square"]:
            "½ Σ (a_i − b_i)²/(a_i + b_i) (default)",
    }
}

impl BagDistance {
    /// Both distances.
    pub const ALL: [BagDistance; 2] = [BagDistance::L1, BagDistance::ChiSquared];

    /// The distance between two bags.
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`], [`RetrievalError::NonFinite`], and for χ²
    /// [`RetrievalError::NegativeBin`] (the formula assumes histograms).
    pub fn between(self, a: &[f64], b: &[f64]) -> Result<f64, RetrievalError> {
        check::same("bag lengths", a.len(), b.len())?;
        check::finite_slice("first bag", a)?;
        check::finite_slice("second bag", b)?;
        if self == BagDistance::ChiSquared {
            non_negative("first bag", a)?;
            non_negative("second bag", b)?;
        }
        Ok(self.unchecked(a, b))
    }

    /// The formula without checks (inputs validated by the caller).
    pub(crate) fn unchecked(self, a: &[f64], b: &[f64]) -> f64 {
        self.of_pairs(a.iter().copied().zip(b.iter().copied()))
    }

    /// The formula on pairs of bins `(a_i, b_i)`, without checks: the one definition, also
    /// used by retrieval-store's scan of f32 rows.
    #[inline]
    pub fn of_pairs(self, pairs: impl Iterator<Item = (f64, f64)>) -> f64 {
        match self {
            BagDistance::L1 => pairs.map(|(x, y)| (x - y).abs()).sum(),
            BagDistance::ChiSquared => {
                0.5 * pairs
                    .map(|(x, y)| {
                        let s = x + y;
                        if s > 0.0 {
                            (x - y) * (x - y) / s
                        } else {
                            0.0
                        }
                    })
                    .sum::<f64>()
            }
        }
    }
}

fn non_negative(what: &'static str, v: &[f64]) -> Result<(), RetrievalError> {
    match v.iter().position(|&x| x < 0.0) {
        Some(index) => Err(RetrievalError::NegativeBin {
            what,
            index,
            value: v[index],
        }),
        None => Ok(()),
    }
}

/// L1 distance `Σ_i |a_i − b_i|` between two bags (vectors, or V × V matrices flattened).
///
/// # Errors
/// [`RetrievalError::DimensionMismatch`], [`RetrievalError::NonFinite`].
pub fn l1_distance(a: &[f64], b: &[f64]) -> Result<f64, RetrievalError> {
    BagDistance::L1.between(a, b)
}

/// χ² distance `½ Σ_i (a_i − b_i)²/(a_i + b_i)` between two histograms.
///
/// # Errors
/// [`RetrievalError::DimensionMismatch`], [`RetrievalError::NonFinite`],
/// [`RetrievalError::NegativeBin`].
pub fn chi_squared_distance(a: &[f64], b: &[f64]) -> Result<f64, RetrievalError> {
    BagDistance::ChiSquared.between(a, b)
}

/// The symmetric matrix of distances between all pairs of bags (for [`crate::retrieval`]).
///
/// # Errors
/// [`RetrievalError::Empty`], and those of [`BagDistance::between`].
pub fn pairwise_distances(bags: &[Vec<f64>], distance: BagDistance) -> Result<Mat<f64>, RetrievalError> {
    check::non_empty("bags", bags.len())?;
    for bag in bags {
        // One full check per bag; the pairs then use the unchecked formula.
        distance.between(&bags[0], bag)?;
    }
    let m = bags.len();
    let rows: Vec<Vec<f64>> = (0..m)
        .into_par_iter()
        .map(|i| (0..m).map(|j| distance.unchecked(&bags[i], &bags[j])).collect())
        .collect();
    Ok(Mat::from_fn(m, m, |i, j| rows[i][j]))
}

/// The symmetric matrix of L1 distances between all pairs of bags.
///
/// # Errors
/// Those of [`pairwise_distances`].
pub fn pairwise_l1(bags: &[Vec<f64>]) -> Result<Mat<f64>, RetrievalError> {
    pairwise_distances(bags, BagDistance::L1)
}
