//! The global component `f_glob` at one scale t for every [`Coefficients`] rule (paper,
//! Sect. 4.2).

use super::Coefficients;
use crate::basis::{canonical_basis, check_anchors};
use crate::{check, HeatError, HeatKernel};
use faer::linalg::solvers::Solve;
use faer::Mat;

/// At a scale t, an anchor is *resolved* when, at every kept anchor p_i, the other kept
/// basis functions sum to at most this fraction of its own value:
/// `Σ_{j≠i} |K_t e_j(p_i)| ≤ RESOLVED_OVERLAP · K_t e_i(p_i)` (see
/// [`Coefficients::Anchored`]).
///
/// The interpolation matrix `G = [K_t e_j(p_i)]` of the kept anchors is then strictly
/// diagonally dominant by rows, so `‖G⁻¹‖∞ ≤ 1 / ((1 − ½) min_i G_ii)` (Varah's bound): the
/// coefficients are at most twice the residuals over the basis peaks, and the correction
/// cannot swing. With ½ the correction stays within the range of the residuals it
/// interpolates on every benchmark case (docs/APPROX-RESULTS.md); a weaker margin keeps more
/// anchors at the coarse scales and lets the interpolant overshoot between close ones.
pub const RESOLVED_OVERLAP: f64 = 0.5;

/// The global component at one scale with what defines it: `values = base + Σ_j
/// coefficients[j] · K_t e_{anchors[j]}` (base = K_t f for [`Coefficients::Anchored`], 0
/// otherwise; for [`Coefficients::Normalized`] the basis is normalised, see there).
#[derive(Clone, Debug, PartialEq)]
pub struct GlobalComponent {
    /// f_glob, one value per vertex.
    pub values: Vec<f64>,
    /// The anchors whose basis functions carry a coefficient, in the order of `coefficients`
    /// (with [`Coefficients::Anchored`], the anchors resolved at this t).
    pub anchors: Vec<u32>,
    /// The coefficients c_j of the basis functions `K_t e_{anchors[j]}`.
    pub coefficients: Vec<f64>,
}

/// The global component `f_glob` of f on the anchors at time t (paper, Sect. 4.2), with the
/// coefficients of `coefficients`; only the values (see [`fit_global_component`]).
///
/// # Errors
/// As [`fit_global_component`].
pub fn global_component(
    kernel: &HeatKernel,
    anchors: &[u32],
    f: &[f64],
    t: f64,
    coefficients: Coefficients,
) -> Result<Vec<f64>, HeatError> {
    Ok(fit_global_component(kernel, anchors, f, t, coefficients)?.values)
}

/// The global component `f_glob` of f on the anchors at time t (paper, Sect. 4.2), with the
/// coefficients of `coefficients`, its anchors and coefficients. `anchors` is a priority
/// list for [`Coefficients::Anchored`] (most important first, as
/// [`super::ranked_anchors`] orders them). The anchors' values are f's own
/// ([`fit_to_values`] with `f(aⱼ)`).
///
/// # Errors
/// [`HeatError::LengthMismatch`], [`HeatError::NonFiniteInput`], [`HeatError::InvalidTime`],
/// [`HeatError::InvalidParameter`] for a bad or repeated anchor, a singular anchor matrix or
/// an unstable interpolation ([`Coefficients::Interpolate`]).
pub fn fit_global_component(
    kernel: &HeatKernel,
    anchors: &[u32],
    f: &[f64],
    t: f64,
    coefficients: Coefficients,
) -> Result<GlobalComponent, HeatError> {
    check::vector(f, kernel.n())?;
    check_anchors(anchors, kernel.n())?;
    let values: Vec<f64> = anchors.iter().map(|&a| f[a as usize]).collect();
    fit_to_values(kernel, anchors, &values, f, t, coefficients)
}

/// [`fit_global_component`] with given anchor values vⱼ in place of f(aⱼ): the value f_glob
/// keeps at a resolved anchor ([`Coefficients::Anchored`]: `f_glob(aⱼ) = vⱼ`) and the
/// feature value of the other rules (`Σ vⱼ K_t e_(aⱼ)`, …); f itself enters through the
/// smooth part K_t f ([`Coefficients::Anchored`], [`Coefficients::Smooth`]) and the
/// projection ([`Coefficients::LeastSquares`]). On a noisy f the values are a smoothed
/// estimate of the clean map at the anchors rather than the noisy samples (issue #40,
/// [`super::NoiseRule`]).
///
/// # Errors
/// As [`fit_global_component`]; [`HeatError::LengthMismatch`] when `values` and `anchors`
/// differ in length, [`HeatError::NonFiniteInput`] for a non-finite value.
pub fn fit_to_values(
    kernel: &HeatKernel,
    anchors: &[u32],
    values: &[f64],
    f: &[f64],
    t: f64,
    coefficients: Coefficients,
) -> Result<GlobalComponent, HeatError> {
    let n = kernel.n();
    check::vector(f, n)?;
    check_anchors(anchors, n)?;
    check::vector(values, anchors.len())?;
    check::time(t)?;
    let mut sorted = anchors.to_vec();
    sorted.sort_unstable();
    if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
        return Err(HeatError::InvalidParameter {
            name: "anchors",
            reason: format!("vertex {} is repeated", w[0]),
        });
    }
    // Every rule is homogeneous of degree 1 in (f, values): work on both over 2ᵉ with 2ᵉ ≈
    // their largest magnitude (exact), so that the M-products of a field of 1e308 do not
    // overflow, and scale back.
    let (down, up) = shifted_solve::lanczos::pow2_scale(linf(f).max(linf(values)));
    if down != 1.0 {
        let scaled: Vec<f64> = f.iter().map(|x| x * down).collect();
        let scaled_values: Vec<f64> = values.iter().map(|x| x * down).collect();
        let fit = Fit {
            kernel,
            anchors,
            values: &scaled_values,
            t,
            coefficients,
        };
        let mut g = fit.unit(&scaled)?;
        g.values
            .iter_mut()
            .chain(g.coefficients.iter_mut())
            .for_each(|x| *x *= up);
        return Ok(g);
    }
    let fit = Fit {
        kernel,
        anchors,
        values,
        t,
        coefficients,
    };
    fit.unit(f)
}

/// The validated inputs of [`fit_to_values`] but the field.
#[derive(Clone, Copy)]
struct Fit<'a> {
    kernel: &'a HeatKernel,
    anchors: &'a [u32],
    /// The anchors' values, one per anchor.
    values: &'a [f64],
    t: f64,
    coefficients: Coefficients,
}

impl Fit<'_> {
    /// [`fit_global_component`] of a validated field `f` of moderate size.
    fn unit(self, f: &[f64]) -> Result<GlobalComponent, HeatError> {
        let Fit {
            kernel,
            anchors,
            values,
            t,
            coefficients,
        } = self;
        let n = kernel.n();
        match coefficients {
            Coefficients::Smooth => Ok(GlobalComponent {
                values: kernel.apply(f, t)?,
                anchors: Vec::new(),
                coefficients: Vec::new(),
            }),
            Coefficients::Anchored => anchored(kernel, anchors, values, f, t),
            _ if anchors.is_empty() => Ok(GlobalComponent {
                values: vec![0.0; n],
                anchors: Vec::new(),
                coefficients: Vec::new(),
            }),
            Coefficients::FeatureValues => {
                // Σ f(pᵢ) K_t eᵢ = K_t (Σ f(pᵢ) eᵢ): one application (linearity of Eq. (21)).
                let mut masked = vec![0.0; n];
                for (&a, &v) in anchors.iter().zip(values) {
                    masked[a as usize] = v;
                }
                Ok(GlobalComponent {
                    values: kernel.apply(&masked, t)?,
                    anchors: anchors.to_vec(),
                    coefficients: values.to_vec(),
                })
            }
            Coefficients::Interpolate => interpolate(kernel, anchors, values, f, t),
            Coefficients::Normalized => Ok(GlobalComponent {
                values: normalized(kernel, anchors, values, f, t)?,
                anchors: anchors.to_vec(),
                coefficients: values.to_vec(),
            }),
            Coefficients::LeastSquares => least_squares(kernel, anchors, f, t),
        }
    }
}

/// `f_glob = K_t f + Σ_{i∈S} cᵢ K_t eᵢ` with `f_glob(pⱼ) = vⱼ` for the anchors S ⊆ A resolved
/// at t ([`RESOLVED_OVERLAP`], greedily in the priority order of `anchors`): one block
/// application `K_t [f, e_A]`, an |S| × |S| LU solve.
fn anchored(
    kernel: &HeatKernel,
    anchors: &[u32],
    values: &[f64],
    f: &[f64],
    t: f64,
) -> Result<GlobalComponent, HeatError> {
    let n = kernel.n();
    let m = anchors.len();
    let block = Mat::<f64>::from_fn(n, m + 1, |i, j| match j {
        0 => f[i],
        _ if anchors[j - 1] as usize == i => 1.0,
        _ => 0.0,
    });
    let smoothed = kernel.apply_many(block.as_ref(), t)?;
    // g(r, c): the basis function of anchor c at anchor r.
    let g = |r: usize, c: usize| smoothed[(anchors[r] as usize, c + 1)];
    let kept = resolved(m, &g);
    let s = kept.len();
    let matrix = Mat::<f64>::from_fn(s, s, |r, c| g(kept[r], kept[c]));
    let residual = Mat::<f64>::from_fn(s, 1, |r, _| values[kept[r]] - smoothed[(anchors[kept[r]] as usize, 0)]);
    let c = if s == 0 {
        Mat::<f64>::zeros(0, 1)
    } else {
        matrix.partial_piv_lu().solve(&residual)
    };
    if let Some(r) = c.col(0).iter().position(|x| !x.is_finite()) {
        return Err(HeatError::InvalidParameter {
            name: "anchors",
            reason: format!(
                "the anchor matrix K_t[A,A] is singular at t = {t:e} (anchor {})",
                anchors[kept[r]]
            ),
        });
    }
    let mut values: Vec<f64> = smoothed.col(0).iter().copied().collect();
    for (j, &k) in kept.iter().enumerate() {
        let cj = c[(j, 0)];
        for (i, v) in values.iter_mut().enumerate() {
            *v += cj * smoothed[(i, k + 1)];
        }
    }
    Ok(GlobalComponent {
        values,
        anchors: kept.iter().map(|&k| anchors[k]).collect(),
        coefficients: c.col(0).iter().copied().collect(),
    })
}

/// The anchors resolved at one scale, greedily in priority order: anchor a joins the kept set
/// S when `Σ_{j∈S∪{a}, j≠i} |g(i, j)| ≤ RESOLVED_OVERLAP · g(i, i)` for every i ∈ S ∪ {a}
/// (`g(i, j)`: basis function j at anchor i). Returns indices into the anchor list.
fn resolved(m: usize, g: &dyn Fn(usize, usize) -> f64) -> Vec<usize> {
    let mut kept: Vec<usize> = Vec::new();
    // off[k]: Σ_{j∈S, j≠kept[k]} |g(kept[k], j)|.
    let mut off: Vec<f64> = Vec::new();
    for a in 0..m {
        let diagonal = g(a, a);
        if diagonal.is_nan() || diagonal <= 0.0 {
            continue;
        }
        let own: f64 = kept.iter().map(|&j| g(a, j).abs()).sum();
        if own > RESOLVED_OVERLAP * diagonal {
            continue;
        }
        let fits = kept
            .iter()
            .zip(&off)
            .all(|(&i, &o)| o + g(i, a).abs() <= RESOLVED_OVERLAP * g(i, i));
        if fits {
            for (k, o) in off.iter_mut().enumerate() {
                *o += g(kept[k], a).abs();
            }
            kept.push(a);
            off.push(own);
        }
    }
    kept
}

/// The M-orthogonal projection of f onto span{K_t eᵢ : i ∈ A}.
fn least_squares(kernel: &HeatKernel, anchors: &[u32], f: &[f64], t: f64) -> Result<GlobalComponent, HeatError> {
    let m = anchors.len();
    // Φ = [K_t e_i]_{i∈A}; minimise ‖f − Φc‖_M: (ΦᵀMΦ) c = ΦᵀM f, solved through the
    // eigendecomposition of the Gram matrix with the directions below 1e−12 of its largest
    // eigenvalue dropped (nearly dependent basis functions at large t).
    let basis = canonical_basis(kernel, anchors, t)?;
    let ops = kernel.operators();
    let m_basis = ops.mass_mul_block(basis.as_ref());
    let gram = basis.transpose() * &m_basis;
    let gram = Mat::<f64>::from_fn(m, m, |r, c| 0.5 * (gram[(r, c)] + gram[(c, r)]));
    let mf = ops.mass_mul(f);
    let rhs = basis.transpose() * faer::ColRef::from_slice(&mf);
    let evd = gram
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|_| HeatError::DenseEigen)?;
    let top = evd.S().column_vector().iter().fold(0.0f64, |a, &b| a.max(b));
    let mut y = evd.U().transpose() * &rhs;
    for (k, yk) in y.iter_mut().enumerate() {
        let s = evd.S()[k];
        *yk = if s > 1e-12 * top { *yk / s } else { 0.0 };
    }
    let c = evd.U() * &y;
    let out = &basis * &c;
    Ok(GlobalComponent {
        values: out.iter().copied().collect(),
        anchors: anchors.to_vec(),
        coefficients: c.iter().copied().collect(),
    })
}

/// `Σ_{i∈A} f(pᵢ) wᵢ / Σ_{i∈A} wᵢ` with the weights `wᵢ = max(K_t eᵢ, 0)` (the exact weights are
/// positive; the computed ones carry rounding of ≈1e−12 of their maximum). Where every weight
/// is below the accuracy of the kernel (1e−9 of the largest total weight: far from all anchors
/// at a small t) the ratio would be noise over noise, and the value of the nearest anchor in
/// edge hops is used instead — the limit of the weighted average as t → 0.
fn normalized(kernel: &HeatKernel, anchors: &[u32], values: &[f64], f: &[f64], t: f64) -> Result<Vec<f64>, HeatError> {
    let n = kernel.n();
    let basis = canonical_basis(kernel, anchors, t)?;
    let mut num = vec![0.0; n];
    let mut den = vec![0.0; n];
    for (c, &fa) in values.iter().enumerate() {
        for i in 0..n {
            let w = basis[(i, c)].max(0.0);
            num[i] += fa * w;
            den[i] += w;
        }
    }
    let top = den.iter().fold(0.0f64, |a, &b| a.max(b));
    let floor = 1e-9 * top;
    let mut out: Vec<f64> = (0..n)
        .map(|i| if den[i] > floor { num[i] / den[i] } else { f64::NAN })
        .collect();
    // The value of each anchor by vertex (for the nearest-anchor fallback).
    let mut value_at = vec![f64::NAN; n];
    for (&a, &v) in anchors.iter().zip(values) {
        value_at[a as usize] = v;
    }
    if out.iter().any(|v| v.is_nan()) {
        // Multi-source breadth-first search from the anchors over the mesh graph.
        let pattern = kernel.operators().pair().pattern();
        let mut nearest = vec![usize::MAX; n];
        let mut queue = std::collections::VecDeque::new();
        for &a in anchors {
            let a = a as usize;
            if nearest[a] == usize::MAX {
                nearest[a] = a;
                queue.push_back(a);
            }
        }
        while let Some(v) = queue.pop_front() {
            for &w in &pattern.row_idx()[pattern.col_range(v)] {
                if nearest[w] == usize::MAX {
                    nearest[w] = nearest[v];
                    queue.push_back(w);
                }
            }
        }
        for (i, o) in out.iter_mut().enumerate() {
            if o.is_nan() {
                // A vertex in a component without anchors keeps f's own value (no feature there).
                *o = if nearest[i] == usize::MAX {
                    f[i]
                } else {
                    value_at[nearest[i]]
                };
            }
        }
    }
    Ok(out)
}

/// `Σ_{i∈A} cᵢ K_t eᵢ` with `K_t[A,A] c = v` (its value at every anchor is the anchor's value).
fn interpolate(
    kernel: &HeatKernel,
    anchors: &[u32],
    values: &[f64],
    f: &[f64],
    t: f64,
) -> Result<GlobalComponent, HeatError> {
    let m = anchors.len();
    let basis = canonical_basis(kernel, anchors, t)?;
    let g = Mat::<f64>::from_fn(m, m, |r, c| basis[(anchors[r] as usize, c)]);
    let rhs = Mat::<f64>::from_fn(m, 1, |r, _| values[r]);
    let c = g.partial_piv_lu().solve(&rhs);
    if c.col(0).iter().any(|x| !x.is_finite()) {
        return Err(HeatError::InvalidParameter {
            name: "anchors",
            reason: format!("the anchor matrix K_t[A,A] is singular at t = {t:e}"),
        });
    }
    let out: Vec<f64> = (&basis * &c).col(0).iter().copied().collect();
    // Overlapping basis functions make K_t[A,A] nearly singular: the interpolant then swings
    // far beyond the data (measured up to 5e4 × the range of f) instead of approximating it.
    let data = linf(f).max(linf(values));
    let swing = linf(&out);
    if swing > 1e3 * data.max(f64::MIN_POSITIVE) {
        return Err(HeatError::InvalidParameter {
            name: "anchors",
            reason: format!(
                "interpolating {m} anchors at t = {t:e} is unstable (values up to {swing:.1e} for data up to \
                 {data:.1e}: the basis functions overlap); use the anchored or least-squares coefficients"
            ),
        });
    }
    Ok(GlobalComponent {
        values: out,
        anchors: anchors.to_vec(),
        coefficients: c.col(0).iter().copied().collect(),
    })
}

pub(super) fn linf(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, &x| m.max(x.abs()))
}
