//! [`super::Method::Taylor`]: the first-order explicit step `M g = (M − tL) f` (Eq. (9)).

use super::PreparedMethod;
use crate::{HeatError, Operators};
use faer::{Mat, MatRef};

/// Nothing beyond the context: the factor of M is the context's own (cached there).
#[derive(Debug)]
pub(crate) struct Taylor;

impl Taylor {
    pub(crate) fn prepare(ops: &Operators) -> Result<Box<dyn PreparedMethod>, HeatError> {
        ops.mass_factor()?;
        Ok(Box::new(Taylor))
    }
}

impl PreparedMethod for Taylor {
    fn apply(&self, ops: &Operators, f: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        // g = f − t M⁻¹L f.
        let (n, k) = (f.nrows(), f.ncols());
        let mut step = Mat::<f64>::zeros(n, k);
        for j in 0..k {
            let col: Vec<f64> = f.col(j).iter().copied().collect();
            step.col_as_slice_mut(j).copy_from_slice(&ops.stiffness_mul(&col));
        }
        ops.mass_factor()?.solve_in_place(step.as_mut());
        Ok(Mat::from_fn(n, k, |i, j| f[(i, j)] - t * step[(i, j)]))
    }
}
