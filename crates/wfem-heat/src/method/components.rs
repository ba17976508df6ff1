//! Any method on a mesh of several connected components: one prepared method per component.
//!
//! L and M do not couple components, so `K_t = ⊕_c K_t^{(c)}` and each component can be
//! solved on its own. It matters when components differ in scale: a stray tetrahedron of size
//! 1e−12 next to a unit shape has eigenvalues ~1e24 times larger, and the joint matrices
//! `tL + |z|M` (real pole) or `M + tL` lose its constant direction below rounding (the
//! factorization then fails, or a dense eigendecomposition scaled for the big part is off by
//! tens of per cent). Each component's own matrices are well scaled.

use super::{spread_times, PreparedMethod, TimesResult};
use crate::method::Method;
use crate::{HeatError, Operators};
use faer::{Mat, MatRef};

/// Components beyond this count are solved jointly (debris of thousands of pieces would
/// otherwise cost one preparation each).
pub(crate) const MAX_PARTS: usize = 256;

#[derive(Debug)]
struct Part {
    vertices: Vec<usize>,
    ops: Operators,
    prepared: Box<dyn PreparedMethod>,
}

impl Part {
    /// `K_t F` (or `K̃_t F`) of this component at every t; from the component's own
    /// [`Operators::time_at_infinity`] on the (deflated) result is 0 without a solve — a tiny
    /// component reaches it at once, and its shifted matrices, whose constant direction is
    /// below rounding, are never factored.
    fn times(&self, f: MatRef<'_, f64>, times: &[f64], kernel_matrix: bool) -> TimesResult {
        let t_inf = self.ops.time_at_infinity();
        let finite: Vec<f64> = times.iter().copied().filter(|&t| t < t_inf).collect();
        let (computed, estimates) = match finite.len() {
            0 => (Vec::new(), Vec::new()),
            1 => {
                let t = finite[0];
                let v = if kernel_matrix {
                    self.prepared.apply_kernel_matrix(&self.ops, f, t)?
                } else {
                    self.prepared.apply(&self.ops, f, t)?
                };
                (vec![v], vec![None])
            }
            _ => self.prepared.apply_times(&self.ops, f, &finite, kernel_matrix)?,
        };
        Ok(spread_times(
            times,
            t_inf,
            (computed, estimates),
            (f.nrows(), f.ncols()),
        ))
    }
}

/// The method prepared on every component.
#[derive(Debug)]
pub(crate) struct Components {
    parts: Vec<Part>,
}

impl Components {
    pub(crate) fn prepare(ops: &Operators, method: &Method) -> Result<Box<dyn PreparedMethod>, HeatError> {
        let parts = ops
            .components()
            .iter()
            .map(|vertices| {
                let sub = ops.restrict(vertices)?;
                let prepared = method.prepare_connected(&sub)?;
                Ok(Part {
                    vertices: vertices.clone(),
                    ops: sub,
                    prepared,
                })
            })
            .collect::<Result<_, HeatError>>()?;
        Ok(Box::new(Self { parts }))
    }

    /// Applies `each` to the rows of every part and scatters the results.
    fn per_part(
        &self,
        f: MatRef<'_, f64>,
        count: usize,
        each: &dyn Fn(&Part, MatRef<'_, f64>) -> TimesResult,
    ) -> TimesResult {
        let mut out = vec![Mat::<f64>::zeros(f.nrows(), f.ncols()); count];
        let mut estimates: Vec<Option<f64>> = vec![None; count];
        for part in &self.parts {
            let sub = Mat::<f64>::from_fn(part.vertices.len(), f.ncols(), |i, j| f[(part.vertices[i], j)]);
            let (values, est) = each(part, sub.as_ref())?;
            for ((o, v), (e, pe)) in out.iter_mut().zip(values).zip(estimates.iter_mut().zip(est)) {
                for j in 0..f.ncols() {
                    for (i, &row) in part.vertices.iter().enumerate() {
                        o[(row, j)] = v[(i, j)];
                    }
                }
                *e = match (*e, pe) {
                    (Some(a), Some(b)) => Some(a.max(b)),
                    (a, b) => a.or(b),
                };
            }
        }
        Ok((out, estimates))
    }
}

impl PreparedMethod for Components {
    fn apply(&self, _ops: &Operators, f: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        let (mut v, _) = self.per_part(f, 1, &|p, sub| p.times(sub, &[t], false))?;
        Ok(v.remove(0))
    }

    fn apply_kernel_matrix(&self, _ops: &Operators, g: MatRef<'_, f64>, t: f64) -> Result<Mat<f64>, HeatError> {
        let (mut v, _) = self.per_part(g, 1, &|p, sub| p.times(sub, &[t], true))?;
        Ok(v.remove(0))
    }

    fn apply_times(&self, _ops: &Operators, f: MatRef<'_, f64>, times: &[f64], kernel_matrix: bool) -> TimesResult {
        self.per_part(f, times.len(), &|p, sub| p.times(sub, times, kernel_matrix))
    }
}
