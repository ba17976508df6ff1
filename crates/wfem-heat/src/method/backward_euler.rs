//! [`super::Method::BackwardEuler`]: one implicit step `(M + tL) g = M f`.

use super::{mass_columns, FactorCache, PreparedMethod};
use crate::{HeatError, Operators};
use faer::{Mat, MatRef};

/// The factor of M + tL of the last t.
#[derive(Debug, Default)]
pub(crate) struct BackwardEuler {
    cache: FactorCache,
}

impl BackwardEuler {
    pub(crate) fn prepare(ops: &Operators) -> Result<Box<dyn PreparedMethod>, HeatError> {
        ops.pair().cholesky()?;
        Ok(Box::<Self>::default())
    }
}

impl PreparedMethod for BackwardEuler {
    fn apply(&self, ops: &Operators, f: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        let g = mass_columns(ops, f);
        self.apply_kernel_matrix(ops, g.as_ref(), t)
    }

    /// `(M + tL)⁻¹ G`: no solve with M.
    fn apply_kernel_matrix(&self, ops: &Operators, g: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        let factor = self.cache.get(ops, t, "M + tL")?;
        let mut x = g.to_owned();
        factor.solve_in_place(x.as_mut());
        Ok(x)
    }
}
