//! [`GlobalSignature`]: the global spectral signature fused with the bag.

use crate::descriptor::ShapeDescriptors;
use crate::global::{GlobalKind, Measure};
use crate::RetrievalError;
use serde::{Deserialize, Serialize};

/// The global spectral signature fused with the bag ([`crate::global`]): by default the
/// Shape-DNA of the wFEM spectrum in logarithms, `g_i = ln(λ_i A)`, i = 1 … m (λ₀ = 0
/// skipped; what files written before `kind` existed hold), scale invariant since λ → λ/β² and
/// A → β²A; its distance, weighted by `weight`, is added to the bag's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlobalSignature {
    /// Which signature (a missing field reads as [`GlobalKind::LogShapeDna`]).
    #[serde(default)]
    pub kind: GlobalKind,
    /// Number m of eigenvalues (≤ eigenpairs − 1).
    pub eigenvalues: usize,
    /// Weight w_g of its distance in the fused distance.
    pub weight: f64,
}

impl GlobalSignature {
    /// Checks the parameters against the number of eigenpairs k.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for m = 0, m ≥ k, or a weight not finite and ≥ 0.
    pub fn validate(&self, eigenpairs: usize) -> Result<(), RetrievalError> {
        if self.eigenvalues == 0 || self.eigenvalues >= eigenpairs {
            return Err(RetrievalError::InvalidParameter {
                name: "global eigenvalues",
                value: self.eigenvalues as f64,
                reason: "must be in 1 ..= eigenpairs − 1",
            });
        }
        if !(self.weight.is_finite() && self.weight >= 0.0) {
            return Err(RetrievalError::InvalidParameter {
                name: "global weight",
                value: self.weight,
                reason: "must be finite and ≥ 0",
            });
        }
        Ok(())
    }

    /// The length of the signature.
    pub fn len(&self) -> usize {
        self.kind.len(self.eigenvalues)
    }

    /// Whether the signature is empty (never, for valid settings).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The signature of one shape ([`GlobalKind::compute`] on its wFEM eigenpairs and the areas
    /// of its own vertices).
    ///
    /// # Errors
    /// Those of the eigensolver and of [`GlobalKind::compute`].
    pub fn compute(&self, shape: &mut ShapeDescriptors) -> Result<Vec<f64>, RetrievalError> {
        let area = shape.area();
        let mut weights = shape.vertex_areas();
        weights.truncate(shape.described_vertices());
        let basis = shape.eigenbasis(false)?;
        self.kind.compute(
            &basis.values,
            basis.vectors.as_ref(),
            &weights,
            Measure::Area(area),
            self.eigenvalues,
        )
    }

    /// The distance of two signatures of this kind (inputs validated by the caller).
    pub(crate) fn distance(&self, g: &[f64], h: &[f64]) -> f64 {
        self.kind.distance(g, h)
    }
}
