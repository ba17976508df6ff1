//! Validation of the inputs every routine shares (times, vectors, blocks of vectors), in one
//! place.

use crate::HeatError;
use faer::MatRef;

/// t must be finite and positive.
pub(crate) fn time(t: f64) -> Result<(), HeatError> {
    if t.is_finite() && t > 0.0 {
        Ok(())
    } else {
        Err(HeatError::InvalidTime { t })
    }
}

/// A non-empty list of times, each finite and positive.
pub(crate) fn times(times: &[f64]) -> Result<(), HeatError> {
    if times.is_empty() {
        return Err(HeatError::InvalidParameter {
            name: "times",
            reason: "the list of times is empty".into(),
        });
    }
    times.iter().try_for_each(|&t| time(t))
}

/// A vector of length n with finite entries.
pub(crate) fn vector(f: &[f64], n: usize) -> Result<(), HeatError> {
    if f.len() != n {
        return Err(HeatError::LengthMismatch {
            expected: n,
            found: f.len(),
        });
    }
    if let Some((row, &value)) = f.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(HeatError::NonFiniteInput { row, column: 0, value });
    }
    Ok(())
}

/// An n × k block with finite entries.
pub(crate) fn block(f: MatRef<'_, f64>, n: usize) -> Result<(), HeatError> {
    if f.nrows() != n {
        return Err(HeatError::LengthMismatch {
            expected: n,
            found: f.nrows(),
        });
    }
    for c in 0..f.ncols() {
        for r in 0..n {
            let value = f[(r, c)];
            if !value.is_finite() {
                return Err(HeatError::NonFiniteInput {
                    row: r,
                    column: c,
                    value,
                });
            }
        }
    }
    Ok(())
}

/// Vertex indices below n.
pub(crate) fn vertices(vertices: &[usize], n: usize) -> Result<(), HeatError> {
    match vertices.iter().find(|&&i| i >= n) {
        Some(&index) => Err(HeatError::VertexOutOfRange { index, n_vertices: n }),
        None => Ok(()),
    }
}

/// The unit vectors `e_i` of the given vertices as the columns of an n × m block.
pub(crate) fn unit_columns(n: usize, vertices_: &[usize]) -> Result<faer::Mat<f64>, HeatError> {
    vertices(vertices_, n)?;
    let mut e = faer::Mat::<f64>::zeros(n, vertices_.len());
    for (c, &i) in vertices_.iter().enumerate() {
        e[(i, c)] = 1.0;
    }
    Ok(e)
}
