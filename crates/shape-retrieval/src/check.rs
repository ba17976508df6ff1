//! Input validation shared by the modules (crate-private).

use crate::RetrievalError;
use faer::MatRef;

/// Errors with [`RetrievalError::NonFinite`] on the first NaN/∞ of `values`.
pub(crate) fn finite_slice(what: &'static str, values: &[f64]) -> Result<(), RetrievalError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(RetrievalError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// Errors with [`RetrievalError::NonFinite`] on the first NaN/∞ of `m` (row-major index).
pub(crate) fn finite_mat(what: &'static str, m: MatRef<'_, f64>) -> Result<(), RetrievalError> {
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            if !m[(i, j)].is_finite() {
                return Err(RetrievalError::NonFinite {
                    what,
                    index: i * m.ncols() + j,
                });
            }
        }
    }
    Ok(())
}

/// Errors with [`RetrievalError::DimensionMismatch`] unless `expected == actual`.
pub(crate) fn same(what: &'static str, expected: usize, actual: usize) -> Result<(), RetrievalError> {
    if expected == actual {
        Ok(())
    } else {
        Err(RetrievalError::DimensionMismatch { what, expected, actual })
    }
}

/// Errors with [`RetrievalError::Empty`] if `len == 0`.
pub(crate) fn non_empty(what: &'static str, len: usize) -> Result<(), RetrievalError> {
    if len == 0 {
        Err(RetrievalError::Empty { what })
    } else {
        Ok(())
    }
}

/// Errors with [`RetrievalError::InvalidParameter`] unless `value` is finite and `> 0`.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<(), RetrievalError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(RetrievalError::InvalidParameter {
            name,
            value,
            reason: "must be finite and positive",
        })
    }
}

/// Errors with [`RetrievalError::InvalidParameter`] if the count `value` is 0.
pub(crate) fn at_least_one(name: &'static str, value: usize) -> Result<(), RetrievalError> {
    if value == 0 {
        Err(RetrievalError::InvalidParameter {
            name,
            value: 0.0,
            reason: "must be at least 1",
        })
    } else {
        Ok(())
    }
}

/// `values` divided by their sum; [`RetrievalError::InvalidModel`] (`what`, "`sums` to …")
/// unless the sum is finite and positive.
pub(crate) fn unit_sum(what: &'static str, sums: &str, mut values: Vec<f64>) -> Result<Vec<f64>, RetrievalError> {
    let total: f64 = values.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(RetrievalError::InvalidModel {
            what,
            reason: format!("{sums} to {total}"),
        });
    }
    values.iter_mut().for_each(|x| *x /= total);
    Ok(values)
}
