//! Spatially sensitive bags of features (Bronstein et al., "Shape Google", ACM TOG 30(1) 2011,
//! Sect. 4.2): which words lie near which, at one diffusion scale.
//!
//! With the soft assignment Θ (n × V, rows summing to 1) of a shape's described vertices,
//! their weights W = diag(w) (the bag's [`crate::model::VertexWeights`]) and the heat kernel
//! matrix of the wFEM kernel (paper, Eq. (6): `K_t = H_t B`, `H_t = Φ e^{−tΛ} Φᵀ`, from the k
//! smallest eigenpairs `L φ_i = λ_i B φ_i`, L symmetric positive semidefinite), the spatial
//! bag is the V × V matrix
//!
//! `F = Θᵀ W H_t W Θ = Pᵀ e^{−tΛ} P`,  `P = Φᵀ W Θ` (k × V),
//!
//! `F_ab ≈ ∫∫ θ_a(x) k_t(x, y) θ_b(y) dx dy`: how much heat flows in time t between the parts
//! of the surface described by words a and b. It is symmetric, so its upper triangle (the
//! off-diagonal entries counted twice) is kept and normalised to sum 1: a histogram of
//! V(V+1)/2 bins. The time is `t = c·A` (A = 1ᵀB1), so F is scale invariant.
//!
//! The signature's bag is then the concatenation `[½ f, ½ F]` of the plain bag f and the
//! spatial histogram, a histogram of V + V(V+1)/2 bins that sums to 1 and is compared by the
//! same χ² or L1: since both are homogeneous of degree one, the distance is the mean of the two
//! parts' distances — a fusion without a weight to tune. A query still costs one description
//! (the eigenpairs are those of the descriptor) and an O(N) scan.
//!
//! **Groups of words** ([`SpatialBag::groups`]): V(V+1)/2 bins grow fast (131,328 for 512
//! words). With G groups — the k-means clusters of the word centres ([`word_groups`]) — the
//! flow is measured between groups: `F_G = Mᵀ F M` (M the V × G membership matrix), computed as
//! the flow of the grouped assignment `Θ M` ([`grouped`]), G(G+1)/2 bins. Measured on the dev
//! sets (docs/RETRIEVAL-RESULTS.md): 512 words with 48 groups tie with plain bags of 512 words
//! (the default), so spatial bags are an option, not the default.

use crate::check;
use crate::RetrievalError;
use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

/// Default time c of [`SpatialBag`]: `t = A/256`, a diffusion length `√(4t) ≈ √A/8`, a part's
/// neighbourhood. SHREC'11 is flat around it (mAP 0.9856 / 0.9858 / 0.9854 at c = 2⁻¹⁰, 2⁻⁸,
/// 2⁻⁶ with 96 words; docs/RETRIEVAL-RESULTS.md).
pub const DEFAULT_SPATIAL_TIME: f64 = 1.0 / 256.0;

/// The spatial part of the bags (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpatialBag {
    /// c in `t = c·A` (> 0).
    pub time: f64,
    /// Measure the heat flow between G groups of words instead of between the words
    /// themselves ([`word_groups`]): G(G+1)/2 bins instead of V(V+1)/2, so a large vocabulary
    /// keeps a small spatial histogram. `None` (what files written before the option existed
    /// hold) or G ≥ V: the words.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub groups: Option<usize>,
}

impl Default for SpatialBag {
    fn default() -> Self {
        Self {
            time: DEFAULT_SPATIAL_TIME,
            groups: None,
        }
    }
}

impl SpatialBag {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for c ≤ 0.
    pub fn validate(&self) -> Result<(), RetrievalError> {
        if let Some(g) = self.groups {
            check::at_least_one("spatial bag groups", g)?;
        }
        check::positive("spatial bag time", self.time)
    }

    /// The number of bins of the spatial histogram for G classes of assignment: G(G+1)/2.
    pub fn bins(classes: usize) -> usize {
        classes * (classes + 1) / 2
    }

    /// The number of classes the heat flow is measured between, for V words: min(G, V), or V
    /// without groups.
    pub fn classes(&self, words: usize) -> usize {
        self.groups.map_or(words, |g| g.min(words))
    }

    /// The normalised spatial histogram of one shape (see the module docs): `theta` is Θ
    /// (m × V) of its m described vertices, `weights` their weights, `spectrum` its
    /// eigenpairs restricted to them.
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] for sizes that disagree,
    /// [`RetrievalError::InvalidModel`] if the histogram sums to zero.
    pub fn histogram(
        &self,
        theta: MatRef<'_, f64>,
        weights: &[f64],
        spectrum: &ShapeSpectrum,
    ) -> Result<Vec<f64>, RetrievalError> {
        self.validate()?;
        let (m, v) = (theta.nrows(), theta.ncols());
        check::same("spatial bag: weights vs assignment rows", m, weights.len())?;
        check::same(
            "spatial bag: eigenvector rows vs assignment rows",
            m,
            spectrum.vectors.nrows(),
        )?;
        let k = spectrum.values.len();
        check::same(
            "spatial bag: eigenvector columns vs eigenvalues",
            k,
            spectrum.vectors.ncols(),
        )?;
        // W Θ, then P = Φᵀ (W Θ) (k × V).
        let w_theta = Mat::from_fn(m, v, |i, a| weights[i] * theta[(i, a)]);
        let p = spectrum.vectors.transpose() * &w_theta;
        let t = self.time * spectrum.area;
        let decay: Vec<f64> = spectrum.values.iter().map(|&l| (-l.max(0.0) * t).exp()).collect();
        let scaled = Mat::from_fn(k, v, |i, a| decay[i] * p[(i, a)]);
        let f = p.transpose() * &scaled;
        let mut out = Vec::with_capacity(Self::bins(v));
        for a in 0..v {
            for b in a..v {
                // A truncated kernel can dip below zero by rounding; a heat flow cannot.
                let x = f[(a, b)].max(0.0);
                out.push(if a == b { x } else { 2.0 * x });
            }
        }
        check::unit_sum("spatial bag", "the heat flow between words sums", out)
    }
}

/// The groups of [`SpatialBag::groups`]: k-means (seed 0, up to 300 iterations) of the V
/// words' centres (V × d, the space they were trained in) into G clusters; entry a is the
/// group of word a. A pure function of the words, so a stored vocabulary gives the same groups
/// at every query. G ≥ V gives every word its own group.
///
/// # Errors
/// Those of [`crate::kmeans::kmeans`] (non-finite words), and
/// [`RetrievalError::InvalidParameter`] for G = 0.
pub fn word_groups(words: MatRef<'_, f64>, groups: usize) -> Result<Vec<u32>, RetrievalError> {
    check::at_least_one("spatial bag groups", groups)?;
    if groups >= words.nrows() {
        return Ok((0..words.nrows() as u32).collect());
    }
    let report = crate::kmeans::kmeans(
        words,
        &crate::kmeans::KmeansParams {
            k: groups,
            max_iter: 300,
            seed: 0,
        },
    )?;
    Ok(report.assignment)
}

/// The assignment to groups: `Θ_g[i, c] = Σ_{a: group(a) = c} Θ[i, a]` (rows still sum to 1).
///
/// # Errors
/// [`RetrievalError::DimensionMismatch`] if `group` does not have one entry per column of Θ.
pub fn grouped(theta: MatRef<'_, f64>, group: &[u32], classes: usize) -> Result<Mat<f64>, RetrievalError> {
    check::same(
        "spatial bag: word groups vs assignment columns",
        theta.ncols(),
        group.len(),
    )?;
    let mut out = Mat::<f64>::zeros(theta.nrows(), classes);
    for (a, &c) in group.iter().enumerate() {
        let c = c as usize;
        for i in 0..theta.nrows() {
            out[(i, c)] += theta[(i, a)];
        }
    }
    Ok(out)
}

/// The eigenpairs a spatial bag needs: the k smallest of (L, B), the eigenvectors' rows of the
/// described vertices only, and the surface area A.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeSpectrum {
    /// λ_0 … λ_{k−1}.
    pub values: Vec<f64>,
    /// m × k: the rows of the described vertices.
    pub vectors: Mat<f64>,
    /// A = 1ᵀB1 of the whole (prepared) mesh.
    pub area: f64,
}
