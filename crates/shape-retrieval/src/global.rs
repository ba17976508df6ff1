//! Global spectral signatures of a shape: one vector per shape, from the same eigenpairs of
//! (L, B) as the dense descriptors (paper, Eq. (4): `L φ_i = λ_i B φ_i`, `ΦᵀBΦ = I`, L the
//! cotangent stiffness, symmetric positive semidefinite), fused with the bag of features by
//! [`crate::model::GlobalSignature`]. A shape is a surface or a solid: its [`Measure`] (area A,
//! d = 2, or volume V, d = 3) carries the dimension that scale invariance and Weyl's law need.
//! Every kind is invariant to scale (`λ → λ/β²`, `μ → β^d μ`, `φ → φ/β^{d/2}`) and to
//! isometries.
//!
//! * [`GlobalKind::LogShapeDna`]: `g_i = ln(λ_i μ^{2/d})` (on a surface `ln(λ_i A)`), i = 1 … m,
//!   compared by `(1/m) Σ|g_i − h_i|` (the first fusion; what a file without `kind` holds).
//! * [`GlobalKind::WeylShapeDna`]: Shape-DNA (Reuter et al. 2006) with Weyl's normalisation,
//!   `g_i = λ_i / λ_i^{Weyl}` ≈ 1 for every i on any shape, compared by the Euclidean distance.
//!   Weyl's law `N(λ) ≈ ω_d μ λ^{d/2}/(2π)^d` (ω_d the volume of the unit d-ball) gives
//!   `λ_i^{Weyl} = 4πi/A` on a surface and `(6π²i/V)^{2/3}` in a solid, so
//!   `g_i = λ_i A/(4πi)` and `g_i = λ_i V^{2/3}/(6π²i)^{2/3}` (the Shape-DNA of solids).
//! * [`GlobalKind::Biharmonic`]: the distribution of biharmonic distances (Lipman et al. 2010)
//!   `d(x, y)² = Σ_{i=1}^{m} (φ_i(x) − φ_i(y))² / λ_i²` between the points of the shape,
//!   in units of `μ^{(4−d)/(2d)}` (√A on a surface, V^{1/6} in a solid: d² scales like μ^{4/d−1}),
//!   as a histogram of [`BIHARMONIC_BINS`] bins over `[0, BIHARMONIC_RANGE]` units
//!   with pairs weighted by their measures `a_x a_y / μ²` (a shape distribution, Osada et al.
//!   2002, of an intrinsic distance), compared by χ². Its terms decay like `1/i²`, so a few dozen
//!   eigenpairs resolve it on any mesh, and a thin tube or a small hole moves few pairs.

use crate::{check, RetrievalError};
use faer::MatRef;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Bins of the biharmonic distance distribution.
pub const BIHARMONIC_BINS: usize = 32;
/// Range of the biharmonic distance histogram, in units of √A (μ^{(4−d)/(2d)}, see the module docs).
pub const BIHARMONIC_RANGE: f64 = 1.0;
/// Points sampled (area-proportionally) for the biharmonic distribution of a larger shape.
pub const BIHARMONIC_SAMPLES: usize = 1000;

/// Default number m of eigenvalues of a global signature (λ₁ … λ_m; λ₀ = 0 is not counted):
/// `wfem spectrum -m`, Python's `shape_dna(m=)`.
pub const DEFAULT_EIGENVALUES: usize = 50;
/// The dimension of the domain when a caller gives only a measure: a surface (Weyl's law in 2-D).
pub const DEFAULT_DIMENSION: usize = 2;

/// The measure μ of the domain a spectrum belongs to, with its dimension d: the area of a
/// surface or the volume of a solid (1ᵀB1 = 1ᵀD1 of its operators).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Measure {
    /// The area A of a surface (d = 2).
    Area(f64),
    /// The volume V of a solid (d = 3).
    Volume(f64),
}

impl Measure {
    /// μ.
    pub fn value(self) -> f64 {
        match self {
            Measure::Area(a) => a,
            Measure::Volume(v) => v,
        }
    }

    /// What μ is: "area" or "volume".
    pub fn quantity(self) -> &'static str {
        match self {
            Measure::Area(_) => "area",
            Measure::Volume(_) => "volume",
        }
    }

    /// The dimension d of the domain.
    pub fn dimension(self) -> usize {
        match self {
            Measure::Area(_) => 2,
            Measure::Volume(_) => 3,
        }
    }

    /// `μ^{2/d}`: λ·μ^{2/d} is invariant to scale (λ → λ/β², μ → β^d μ).
    pub fn eigenvalue_unit(self) -> f64 {
        match self {
            Measure::Area(a) => a,
            Measure::Volume(v) => v.cbrt() * v.cbrt(),
        }
    }

    /// Weyl's asymptotic i-th eigenvalue `λ_i^{Weyl}`: 4πi/A on a surface, (6π²i/V)^{2/3} in a
    /// solid (from `N(λ) ≈ ω_d μ λ^{d/2}/(2π)^d`).
    pub fn weyl_eigenvalue(self, i: usize) -> f64 {
        1.0 / self.weyl_ratio(1.0, i)
    }

    /// `λ / λ_i^{Weyl}` (the Weyl-normalised Shape-DNA entry; ≈ 1 for large i): `λA/(4πi)` on a
    /// surface, `λV^{2/3}/(6π²i)^{2/3}` in a solid.
    pub fn weyl_ratio(self, lambda: f64, i: usize) -> f64 {
        use std::f64::consts::PI;
        match self {
            Measure::Area(a) => lambda * a / (4.0 * PI * i as f64),
            Measure::Volume(_) => {
                let c = (6.0 * PI * PI * i as f64).cbrt();
                lambda * self.eigenvalue_unit() / (c * c)
            }
        }
    }

    /// The unit of a biharmonic distance, `μ^{(4−d)/(2d)}`: √A, V^{1/6}.
    fn biharmonic_unit(self) -> f64 {
        match self {
            Measure::Area(a) => a.sqrt(),
            Measure::Volume(v) => v.sqrt().cbrt(),
        }
    }
}

/// Which global signature (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GlobalKind {
    /// `ln(λ_i A)`, mean absolute difference.
    #[default]
    LogShapeDna,
    /// `λ_i A/(4π i)`, Euclidean distance.
    WeylShapeDna,
    /// Histogram of biharmonic distances / √A, χ².
    Biharmonic,
}

wfem_base::registry! {
    GlobalKind as "global signature" {
        GlobalKind::LogShapeDna = GlobalKind::LogShapeDna => "log-shape-dna":
            "ln(λ_i·A), i = 1…m, mean absolute difference",
        GlobalKind::WeylShapeDna = GlobalKind::WeylShapeDna => "weyl-shape-dna" ["shape-dna"]:
            "Shape-DNA λ_i·A/(4πi), i = 1…m, Euclidean distance",
        GlobalKind::Biharmonic = GlobalKind::Biharmonic => "biharmonic":
            "histogram of biharmonic distances / √A (m eigenpairs), χ²",
    }
}

impl GlobalKind {
    /// The signature length for m eigenvalues.
    pub fn len(&self, eigenvalues: usize) -> usize {
        match self {
            GlobalKind::LogShapeDna | GlobalKind::WeylShapeDna => eigenvalues,
            GlobalKind::Biharmonic => BIHARMONIC_BINS,
        }
    }

    /// The signature of one shape from its ascending eigenpairs (`values`, `vectors` n × k,
    /// B-orthonormal), its vertex weights (areas or volumes, one per described vertex: the first
    /// rows of `vectors`) and its [`Measure`] (area A or volume V); m = `eigenvalues` (≤ k − 1).
    ///
    /// # Errors
    /// [`RetrievalError::NoNonzeroEigenvalue`] if some λ_i, 1 ≤ i ≤ m, is not positive (a
    /// disconnected mesh has several zero eigenvalues), [`RetrievalError::DimensionMismatch`]
    /// if there are fewer than m + 1 eigenpairs or the weights do not fit,
    /// [`RetrievalError::InvalidParameter`] for a measure that is not finite and positive.
    pub fn compute(
        &self,
        values: &[f64],
        vectors: MatRef<'_, f64>,
        weights: &[f64],
        measure: Measure,
        eigenvalues: usize,
    ) -> Result<Vec<f64>, RetrievalError> {
        if values.len() < eigenvalues + 1 {
            return Err(RetrievalError::DimensionMismatch {
                what: "eigenpairs vs global eigenvalues + 1",
                expected: eigenvalues + 1,
                actual: values.len(),
            });
        }
        check::positive(measure.quantity(), measure.value())?;
        let scale = values.iter().fold(0.0f64, |m, &v| m.max(v));
        let lambda = |i: usize| -> Result<f64, RetrievalError> {
            let l = values[i];
            if l > 1e-8 * scale && l.is_finite() {
                Ok(l)
            } else {
                Err(RetrievalError::NoNonzeroEigenvalue)
            }
        };
        match self {
            GlobalKind::LogShapeDna => {
                let unit = measure.eigenvalue_unit();
                (1..=eigenvalues).map(|i| Ok((lambda(i)? * unit).ln())).collect()
            }
            GlobalKind::WeylShapeDna => (1..=eigenvalues)
                .map(|i| Ok(measure.weyl_ratio(lambda(i)?, i)))
                .collect(),
            GlobalKind::Biharmonic => {
                let inv: Vec<f64> = (1..=eigenvalues)
                    .map(|i| lambda(i).map(|l| 1.0 / l))
                    .collect::<Result<_, _>>()?;
                check::same(
                    "eigenvector rows vs weights",
                    weights.len().max(vectors.nrows()),
                    vectors.nrows(),
                )?;
                Ok(biharmonic_histogram(vectors, &inv, weights, measure))
            }
        }
    }

    /// The distance between two signatures of this kind (validated by the caller).
    pub fn distance(&self, g: &[f64], h: &[f64]) -> f64 {
        match self {
            GlobalKind::LogShapeDna => g.iter().zip(h).map(|(a, b)| (a - b).abs()).sum::<f64>() / g.len().max(1) as f64,
            GlobalKind::WeylShapeDna => g.iter().zip(h).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt(),
            GlobalKind::Biharmonic => {
                crate::distance::BagDistance::ChiSquared.of_pairs(g.iter().copied().zip(h.iter().copied()))
            }
        }
    }
}

/// A global signature of one shape with the eigenvalues it was computed from.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectrumSignature {
    /// λ₀ … λ_m of (L, M), ascending (λ₀ = 0 on a connected shape).
    pub eigenvalues: Vec<f64>,
    /// The signature ([`GlobalKind::len`] values).
    pub signature: Vec<f64>,
    /// The measure it was normalised with.
    pub measure: Measure,
}

/// The global signature `kind` of a surface or a solid from its operators (the one
/// orchestration the CLI's `wfem spectrum` and Python's `shape_dna` call): the m + 1 smallest
/// eigenpairs of `L φ = λ M φ` (paper, Eq. (4); [`crate::descriptor::smallest_eigenpairs`]:
/// dense on small meshes, shift-invert block Lanczos otherwise), the vertex weights `M·1`, and
/// [`GlobalKind::compute`] with `measure` (the area or volume 1ᵀD1 of the geometry, which
/// [`Operators`](wfem_heat::Operators) cannot tell apart from a mass of another scale).
///
/// # Errors
/// Those of the eigensolver and of [`GlobalKind::compute`]; [`RetrievalError::InvalidParameter`]
/// for m = 0 or m ≥ n.
pub fn operators_signature(
    ops: &wfem_heat::Operators,
    kind: GlobalKind,
    eigenvalues: usize,
    measure: Measure,
) -> Result<SpectrumSignature, RetrievalError> {
    if eigenvalues == 0 || eigenvalues >= ops.n() {
        return Err(RetrievalError::InvalidParameter {
            name: "eigenvalues",
            value: eigenvalues as f64,
            reason: "must be in 1 ..= n − 1 (the first, zero eigenvalue is not counted)",
        });
    }
    let basis = crate::descriptor::smallest_eigenpairs(ops, eigenvalues + 1, &Default::default())?;
    let weights = ops.vertex_areas();
    let signature = kind.compute(&basis.values, basis.vectors.as_ref(), &weights, measure, eigenvalues)?;
    Ok(SpectrumSignature {
        eigenvalues: basis.values,
        signature,
        measure,
    })
}

/// Area-proportional sample of at most [`BIHARMONIC_SAMPLES`] vertices (systematic sampling of
/// the cumulative areas: deterministic, every region represented by its area) with their
/// weights; all vertices with their areas when there are fewer.
fn sample_vertices(weights: &[f64]) -> (Vec<usize>, Vec<f64>) {
    let n = weights.len();
    if n <= BIHARMONIC_SAMPLES {
        return ((0..n).collect(), weights.to_vec());
    }
    let total: f64 = weights.iter().sum();
    let step = total / BIHARMONIC_SAMPLES as f64;
    let mut picked = Vec::with_capacity(BIHARMONIC_SAMPLES);
    let mut next = 0.5 * step;
    let mut acc = 0.0;
    for (i, &w) in weights.iter().enumerate() {
        acc += w;
        let mut hits = 0usize;
        while next < acc && picked.len() + hits < BIHARMONIC_SAMPLES {
            hits += 1;
            next += step;
        }
        if hits > 0 {
            picked.push((i, hits as f64));
        }
    }
    picked.into_iter().unzip()
}

/// The biharmonic distance histogram of the module docs: `vectors` rows = vertices (the first
/// `weights.len()` described), columns 0 … k−1 (column 0 the constant mode, skipped), `inv[i−1]
/// = 1/λ_i`.
fn biharmonic_histogram(vectors: MatRef<'_, f64>, inv: &[f64], weights: &[f64], measure: Measure) -> Vec<f64> {
    let (idx, w) = sample_vertices(weights);
    let m = inv.len();
    let embed: Vec<Vec<f64>> = idx
        .iter()
        .map(|&v| (0..m).map(|i| vectors[(v, i + 1)] * inv[i]).collect())
        .collect();
    let unit = measure.biharmonic_unit() * BIHARMONIC_RANGE / BIHARMONIC_BINS as f64;
    let hist = (0..idx.len())
        .into_par_iter()
        .map(|a| {
            let mut h = vec![0.0; BIHARMONIC_BINS];
            for b in 0..idx.len() {
                if a == b {
                    continue;
                }
                let d2: f64 = embed[a].iter().zip(&embed[b]).map(|(x, y)| (x - y) * (x - y)).sum();
                // Linear interpolation between the two nearest bin centres (a smooth histogram).
                let x = (d2.sqrt() / unit - 0.5).clamp(0.0, (BIHARMONIC_BINS - 1) as f64);
                let lo = x.floor() as usize;
                let f = x - lo as f64;
                let ww = w[a] * w[b];
                h[lo] += ww * (1.0 - f);
                if lo + 1 < BIHARMONIC_BINS {
                    h[lo + 1] += ww * f;
                }
            }
            h
        })
        .reduce(
            || vec![0.0; BIHARMONIC_BINS],
            |mut x, y| {
                x.iter_mut().zip(&y).for_each(|(a, b)| *a += b);
                x
            },
        );
    let total: f64 = hist.iter().sum();
    if total > 0.0 {
        hist.into_iter().map(|x| x / total).collect()
    } else {
        hist
    }
}
