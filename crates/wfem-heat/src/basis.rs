//! The canonical basis `{K_t eᵢ}` of F(M) (paper, Sect. 4.1, Eq. (21)) and its t → ∞ limit.

use crate::check;
use crate::{HeatError, HeatKernel};
use faer::Mat;

pub(crate) fn check_anchors(anchors: &[u32], n: usize) -> Result<(), HeatError> {
    if let Some(&a) = anchors.iter().find(|&&a| a as usize >= n) {
        return Err(HeatError::InvalidParameter {
            name: "anchors",
            reason: format!("vertex {a} does not exist (the mesh has {n} vertices)"),
        });
    }
    Ok(())
}

/// The canonical basis functions `K_t eᵢ` for every anchor i (paper, Sect. 4.1: the image of
/// the standard basis under the operator K_t of Eq. (21)), as the columns of an n × |A|
/// matrix, column j = `K_t e_{anchors[j]}`.
///
/// All anchors are computed together: one [`HeatKernel::apply_many`] on the n × |A| block
/// of unit vectors, so the t-dependent factorizations are done once for all anchors.
///
/// # Errors
/// [`HeatError::InvalidParameter`] for an anchor that is not a vertex; the errors of
/// [`HeatKernel::apply_many`] (e.g. [`HeatError::InvalidTime`]).
pub fn canonical_basis(kernel: &HeatKernel, anchors: &[u32], t: f64) -> Result<Mat<f64>, HeatError> {
    let n = kernel.n();
    check_anchors(anchors, n)?;
    check::time(t)?;
    let e = Mat::<f64>::from_fn(
        n,
        anchors.len(),
        |i, j| if anchors[j] as usize == i { 1.0 } else { 0.0 },
    );
    kernel.apply_many(e.as_ref(), t)
}

/// The constant limits `lim_{t→∞} K_t eᵢ = cᵢ·1` of the canonical basis functions of the
/// anchors, `cᵢ = 1ᵀM eᵢ / 1ᵀM1` (M the mass of the kernel: B, D or I).
///
/// **Correction of the paper.** Sect. 4.1 writes `K_t eᵢ → (eᵢᵀB1)·1`. On a connected mesh
/// the eigenvector of λ₁ = 0 is the B-normalised constant `x₁ = 1/√(1ᵀB1)` (not 1), so
/// `K_t eᵢ → ⟨eᵢ, x₁⟩_B x₁ = (eᵢᵀB1 / 1ᵀB1)·1`: the paper's limit misses the factor
/// 1/area(M) (1ᵀB1 is the surface area). The limit preserves the B-mean,
/// `1ᵀB K_t eᵢ = 1ᵀB eᵢ` for every t. (On a mesh with several connected components the
/// limit is piecewise constant instead.)
///
/// # Errors
/// [`HeatError::InvalidParameter`] for an anchor that is not a vertex.
pub fn canonical_limit(kernel: &HeatKernel, anchors: &[u32]) -> Result<Vec<f64>, HeatError> {
    let n = kernel.n();
    check_anchors(anchors, n)?;
    let row_sums = kernel.operators().vertex_areas();
    let total: f64 = row_sums.iter().sum();
    Ok(anchors.iter().map(|&a| row_sums[a as usize] / total).collect())
}
