//! Per-dimension z-scoring of dense descriptors before quantisation.
//!
//! k-means and the Gaussian soft assignment of [`crate::bof`] measure Euclidean distances, so a
//! descriptor dimension with a large spread (e.g. the smallest HKS time, or the ω = 0 SI-HKS
//! magnitude) dominates the vocabulary while the others are ignored. Standardising every
//! dimension j to zero mean and unit variance over the training descriptors,
//!
//! `p̃_j(x) = (p_j(x) − μ_j)/s_j`, `μ_j = (1/N) Σ_x p_j(x)`, `s_j² = (1/N) Σ_x (p_j(x) − μ_j)²`,
//!
//! weighs every dimension alike. The statistics (μ, s) belong to the vocabulary: they are
//! estimated once on the training descriptors and applied unchanged to every shape that is
//! later indexed or queried. (Population variance, 1/N: N is in the tens of thousands.)

use crate::check;
use crate::RetrievalError;
use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

/// The z-score statistics of a training set: mean μ_j and standard deviation s_j per dimension.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Standardizer {
    mean: Vec<f64>,
    std: Vec<f64>,
}

impl Standardizer {
    /// Estimates μ and s over the rows of `descriptors` (N × d).
    ///
    /// Sums run in a fixed order (row by row), so the statistics do not depend on the thread
    /// count. The variance uses the two-pass formula Σ(p − μ)², which does not cancel.
    ///
    /// # Errors
    /// [`RetrievalError::Empty`] for N = 0 or d = 0, [`RetrievalError::NonFinite`],
    /// [`RetrievalError::ConstantDimension`] if some dimension has zero spread (it cannot be
    /// standardised, and carries no information for the vocabulary).
    pub fn fit(descriptors: MatRef<'_, f64>) -> Result<Self, RetrievalError> {
        let (n, d) = (descriptors.nrows(), descriptors.ncols());
        check::non_empty("training descriptors", n)?;
        check::non_empty("descriptor dimension", d)?;
        check::finite_mat("training descriptors", descriptors)?;
        let mut mean = vec![0.0; d];
        let mut std = vec![0.0; d];
        for j in 0..d {
            let col = descriptors.col(j);
            let mu = col.iter().sum::<f64>() / n as f64;
            let var = col.iter().map(|x| (x - mu) * (x - mu)).sum::<f64>() / n as f64;
            let s = var.sqrt();
            // A spread below round-off of the mean is no spread at all.
            if !(s > 0.0 && s > 1e-12 * mu.abs()) {
                return Err(RetrievalError::ConstantDimension {
                    dimension: j,
                    value: mu,
                });
            }
            mean[j] = mu;
            std[j] = s;
        }
        Self::new(mean, std)
    }

    /// Statistics given explicitly (e.g. read from a file).
    ///
    /// # Errors
    /// [`RetrievalError::Empty`], [`RetrievalError::DimensionMismatch`] if the lengths differ,
    /// [`RetrievalError::NonFinite`], [`RetrievalError::InvalidParameter`] for s_j ≤ 0.
    pub fn new(mean: Vec<f64>, std: Vec<f64>) -> Result<Self, RetrievalError> {
        check::non_empty("z-score means", mean.len())?;
        check::same("z-score deviations vs means", mean.len(), std.len())?;
        check::finite_slice("z-score means", &mean)?;
        for &s in &std {
            check::positive("z-score deviation", s)?;
        }
        Ok(Self { mean, std })
    }

    /// These statistics with dimension j weighted by `w_j` after z-scoring:
    /// `w_j (p_j − μ_j)/s_j = (p_j − μ_j)/(s_j/w_j)`, so the weights live in the deviations and
    /// an index stores them without a new field.
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] if the lengths differ,
    /// [`RetrievalError::InvalidParameter`] for a weight that is not finite and positive.
    pub fn weighted(mut self, weights: &[f64]) -> Result<Self, RetrievalError> {
        check::same(
            "dimension weights vs z-score statistics",
            self.dimension(),
            weights.len(),
        )?;
        for (s, &w) in self.std.iter_mut().zip(weights) {
            check::positive("dimension weight", w)?;
            *s /= w;
        }
        Ok(self)
    }

    /// The means μ_j.
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// The standard deviations s_j (all positive).
    pub fn std(&self) -> &[f64] {
        &self.std
    }

    /// The dimension d.
    pub fn dimension(&self) -> usize {
        self.mean.len()
    }

    /// `(p_j − μ_j)/s_j` for every row of `descriptors` (n × d).
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] if d differs, [`RetrievalError::NonFinite`] for
    /// NaN/∞ in the input (or a result that overflows).
    pub fn apply(&self, descriptors: MatRef<'_, f64>) -> Result<Mat<f64>, RetrievalError> {
        check::same(
            "descriptor dimension vs z-score statistics",
            self.dimension(),
            descriptors.ncols(),
        )?;
        check::finite_mat("descriptors", descriptors)?;
        let out = Mat::from_fn(descriptors.nrows(), descriptors.ncols(), |i, j| {
            (descriptors[(i, j)] - self.mean[j]) / self.std[j]
        });
        check::finite_mat("standardised descriptors", out.as_ref())?;
        Ok(out)
    }
}
