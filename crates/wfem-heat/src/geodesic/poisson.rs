//! The Poisson step of the heat method, `L φ = b` with φ pinned on the sources.
//!
//! L is singular (the constants of each connected component). One factorization serves every
//! query: `P = L + c Σ_g e_g e_gᵀ` with one ground vertex g per component and c = L_gg. For a
//! right-hand side that sums to zero over each component, `P x = b` gives exactly `L x = b` with
//! `x_g = 0` (summing the rows of a component: `c x_g = Σ b = 0`), so the solution of the
//! Neumann problem is `x` plus a constant per component.
//!
//! * One pin in a component (a single source vertex): the constant that puts the pin at its
//!   value — pinning and the Neumann solution agree, since the equation dropped by the pin is
//!   implied by the others.
//! * Several pins in a component (many sources, a point on a face): φ is pinned on all of
//!   them, the Dirichlet problem `L_FF φ_F = b_F − L_FP τ` on the free vertices F. Its matrix is
//!   P with the pinned rows and columns replaced by the identity — the same pattern, so the
//!   symbolic analysis is reused and only a numeric factorization is made.

use faer::sparse::{SparseColMat, SparseColMatRef};
use faer::Par;
use shifted_solve::{CholeskyPattern, SpdFactor};

use crate::HeatError;

/// L with its grounded factorization.
pub(crate) struct Poisson {
    n: usize,
    stiffness: SparseColMat<usize, f64>,
    pattern: CholeskyPattern,
    grounded: SpdFactor,
    /// Per vertex its component; per component its ground vertex and its vertices.
    component: Vec<u32>,
    grounds: Vec<usize>,
    members: Vec<Vec<usize>>,
}

/// The position of the diagonal entry of column j (rows sorted, the diagonal present).
fn diagonal_index(m: SparseColMatRef<'_, usize, f64>, j: usize) -> Option<usize> {
    let ptr = m.symbolic().col_ptr();
    let rows = &m.symbolic().row_idx()[ptr[j]..ptr[j + 1]];
    rows.binary_search(&j).ok().map(|k| ptr[j] + k)
}

impl Poisson {
    /// Grounds each component (its first vertex) and factors P.
    ///
    /// # Errors
    /// [`HeatError::NotPositiveDefinite`] when P is not numerically definite (a component that
    /// is not connected through L's pattern).
    pub(crate) fn new(
        stiffness: SparseColMatRef<'_, usize, f64>,
        pattern: &CholeskyPattern,
        components: &[Vec<usize>],
    ) -> Result<Self, HeatError> {
        let n = stiffness.nrows();
        let mut component = vec![u32::MAX; n];
        for (c, vs) in components.iter().enumerate() {
            for &v in vs {
                component[v] = c as u32;
            }
        }
        let grounds: Vec<usize> = components.iter().map(|vs| vs[0]).collect();
        let mut values = stiffness.val().to_vec();
        for &g in &grounds {
            let Some(k) = diagonal_index(stiffness, g) else {
                return Err(not_definite());
            };
            // L_gg > 0 on any vertex with a neighbour; an isolated vertex gets 1.
            values[k] += if values[k] > 0.0 { values[k] } else { 1.0 };
        }
        let matrix = SparseColMat::new(stiffness.symbolic().to_owned().map_err(|_| not_definite())?, values);
        let grounded = pattern
            .factor(matrix.as_ref(), faer::get_global_parallelism())
            .map_err(|_| not_definite())?;
        Ok(Self {
            n,
            stiffness: SparseColMat::new(
                stiffness.symbolic().to_owned().map_err(|_| not_definite())?,
                stiffness.val().to_vec(),
            ),
            pattern: pattern.clone(),
            grounded,
            component,
            grounds,
            members: components.to_vec(),
        })
    }

    /// The component of vertex v.
    pub(crate) fn component_of(&self, v: usize) -> usize {
        self.component[v] as usize
    }

    /// Number of components.
    pub(crate) fn n_components(&self) -> usize {
        self.grounds.len()
    }

    /// φ with `L φ = b` and `φ_v = τ` for every pin `(v, τ)` (pins sorted by vertex, distinct),
    /// on the components that hold a pin; `None` on the others (no pin: no reference).
    ///
    /// # Errors
    /// [`HeatError::NotPositiveDefinite`] if the pinned matrix is not definite.
    pub(crate) fn solve(&self, b: &[f64], pins: &[(usize, f64)]) -> Result<Vec<Option<f64>>, HeatError> {
        let mut b = b.to_vec();
        // Make b sum to zero over each component (it does up to rounding).
        for vs in &self.members {
            let mean = vs.iter().map(|&v| b[v]).sum::<f64>() / vs.len() as f64;
            vs.iter().for_each(|&v| b[v] -= mean);
        }
        let mut per_component = vec![0usize; self.n_components()];
        for &(v, _) in pins {
            per_component[self.component_of(v)] += 1;
        }
        let x = if per_component.iter().all(|&k| k <= 1) {
            let mut x = self.grounded.solve_vec(&b);
            for &(v, tau) in pins {
                let shift = tau - x[v];
                self.members[self.component_of(v)].iter().for_each(|&w| x[w] += shift);
            }
            x
        } else {
            self.dirichlet(&b, pins)?
        };
        Ok((0..self.n)
            .map(|v| (per_component[self.component_of(v)] > 0).then_some(x[v]))
            .collect())
    }

    /// The Dirichlet problem with every pin fixed (components without a pin grounded).
    fn dirichlet(&self, b: &[f64], pins: &[(usize, f64)]) -> Result<Vec<f64>, HeatError> {
        let mut pinned = vec![None; self.n];
        for &(v, tau) in pins {
            pinned[v] = Some(tau);
        }
        let mut has_pin = vec![false; self.n_components()];
        pins.iter().for_each(|&(v, _)| has_pin[self.component_of(v)] = true);
        let l = self.stiffness.as_ref();
        let (ptr, rows, vals) = (l.symbolic().col_ptr(), l.symbolic().row_idx(), l.val());
        let mut values = vals.to_vec();
        let mut rhs = b.to_vec();
        for j in 0..self.n {
            for k in ptr[j]..ptr[j + 1] {
                let i = rows[k];
                match (pinned[i], pinned[j]) {
                    (None, None) => {}
                    (Some(_), Some(_)) => values[k] = if i == j { 1.0 } else { 0.0 },
                    (None, Some(tau)) => {
                        // Row i is free: move L_ij τ_j to the right-hand side.
                        rhs[i] -= vals[k] * tau;
                        values[k] = 0.0;
                    }
                    (Some(_), None) => values[k] = 0.0,
                }
            }
        }
        for (i, p) in pinned.iter().enumerate() {
            if let Some(tau) = p {
                rhs[i] = *tau;
            }
        }
        for (c, &g) in self.grounds.iter().enumerate() {
            if !has_pin[c] {
                if let Some(k) = diagonal_index(l, g) {
                    values[k] += if values[k] > 0.0 { values[k] } else { 1.0 };
                }
            }
        }
        let matrix = SparseColMat::new(l.symbolic().to_owned().map_err(|_| not_definite())?, values);
        let factor = self
            .pattern
            .factor(matrix.as_ref(), Par::Seq)
            .map_err(|_| not_definite())?;
        Ok(factor.solve_vec(&rhs))
    }
}

fn not_definite() -> HeatError {
    HeatError::NotPositiveDefinite {
        matrix: "the Poisson matrix L of the heat method (grounded)".into(),
    }
}
