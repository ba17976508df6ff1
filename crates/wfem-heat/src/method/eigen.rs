//! [`super::Method::Dense`] and [`super::Method::Spectral`]: `K_t F = X e^{−tΛ} XᵀM F` with all
//! (Eq. (6)) or the k smallest (Eq. (8)) eigenpairs of `L x = λ M x`.

use super::{mass_columns, PreparedMethod};
use crate::spectral::{EigenParams, Eigenbasis};
use crate::{HeatError, Operators};
use faer::{Mat, MatRef};

/// The eigenpairs of the kernel's pair.
#[derive(Debug)]
pub(crate) struct EigenMethod {
    basis: Eigenbasis,
}

impl EigenMethod {
    pub(crate) fn dense(ops: &Operators) -> Result<Box<dyn PreparedMethod>, HeatError> {
        Ok(Box::new(Self {
            basis: Eigenbasis::dense_of(ops)?,
        }))
    }

    pub(crate) fn partial(
        ops: &Operators,
        k: usize,
        params: &EigenParams,
    ) -> Result<Box<dyn PreparedMethod>, HeatError> {
        Ok(Box::new(Self {
            basis: Eigenbasis::partial_of(ops, k, params)?,
        }))
    }
}

impl PreparedMethod for EigenMethod {
    fn apply(&self, ops: &Operators, f: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        let mf = mass_columns(ops, f);
        Ok(self.basis.heat_scaled(mf.as_ref(), t))
    }

    fn apply_kernel_matrix(&self, _ops: &Operators, g: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        Ok(self.basis.heat_scaled(g, t))
    }

    fn eigenbasis(&self) -> Option<&Eigenbasis> {
        Some(&self.basis)
    }
}
