//! Bags of features (Shape Google: Bronstein, Bronstein, Guibas, Ovsjanikov, ACM TOG 30(1), 2011).
//!
//! 1. A **vocabulary** `{p_1 … p_V}` of geometric words: k-means centres of dense descriptors
//!    p(x) (HKS at a few scales or SI-HKS) pooled over a training set; V = 48 by default.
//! 2. **Soft assignment** of each vertex x to the words,
//!    `θ_i(x) = exp(−‖p(x) − p_i‖²/(2σ²)) / Σ_j exp(−‖p(x) − p_j‖²/(2σ²))`, so `Σ_i θ_i(x) = 1`;
//!    by default σ = the median over the training descriptors of the distance to their nearest
//!    word (as in the public Shape Google code, `sigma1 = median(mind)`).
//! 3. The **bag of features** `f(X) = ∫_X θ(x) dμ(x) ≈ Θᵀ a` (Θ is n × V), with vertex areas
//!    `a = B·1` for wFEM (paper, Eq. (3)) or the lumped diagonal D (Eq. (7)); it sums to the area.
//! 4. The **spatially sensitive** bag `F(X) = ∫∫ θ(x) θ(y)ᵀ K_t(x, y) dμ(x) dμ(y) ≈ Θᵀ B K_t Θ`
//!    (V × V, symmetric because `B K_t = K_tᵀ B`), with the wFEM heat kernel `K_t = Φ D_t Φᵀ B`
//!    (Eq. (6)) applied to the V columns of Θ by a caller-supplied operator.
//! 5. Shapes are compared with the **L1 distance** between bags (or χ², see [`crate::distance`]).

use crate::kmeans::{kmeans, nearest_center, squared_distance, KmeansParams};
use crate::{check, RetrievalError};
use faer::linalg::matmul::matmul;
use faer::sparse::linalg::matmul::sparse_dense_matmul;
use faer::sparse::SparseColMatRef;
use faer::{Accum, Mat, MatRef, Par};
use rayon::prelude::*;
use wfem_base::rng::SplitMix64;

/// Options of [`Vocabulary::train`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VocabularyParams {
    /// Number of words V (default 48, Shape Google).
    pub size: usize,
    /// Lloyd iterations of k-means (default 300).
    pub max_iter: usize,
    /// Seed of k-means++ (default 0).
    pub seed: u64,
    /// Soft-assignment width σ; `None` (default) = median distance of the training descriptors
    /// to their nearest word.
    pub sigma: Option<f64>,
    /// Train on at most this many descriptors, drawn without replacement (seeded by `seed`);
    /// `None` (default) uses all. Pooled dense descriptors of a whole collection run into
    /// millions of rows, and k-means cost is linear in them.
    pub max_training_points: Option<usize>,
}

impl Default for VocabularyParams {
    fn default() -> Self {
        Self {
            size: 48,
            max_iter: 300,
            seed: 0,
            sigma: None,
            max_training_points: None,
        }
    }
}

/// A vocabulary of V geometric words (V × d) with its soft-assignment width σ.
#[derive(Clone, Debug)]
pub struct Vocabulary {
    words: Mat<f64>,
    sigma: f64,
}

impl Vocabulary {
    /// Learns the words by k-means on the rows of `descriptors` (N × d, pooled over shapes), or
    /// on a seeded random subset of `params.max_training_points` rows; σ (if not given) is the
    /// median nearest-word distance over the same rows.
    ///
    /// # Errors
    /// Those of [`kmeans`] ([`RetrievalError::TooFewDescriptors`] if N < V, NaN, empty input),
    /// and [`RetrievalError::InvalidParameter`] if σ is not positive (given, or the median
    /// distance is 0 because most descriptors coincide with words).
    pub fn train(descriptors: MatRef<'_, f64>, params: &VocabularyParams) -> Result<Self, RetrievalError> {
        let sample;
        let descriptors = match params.max_training_points {
            Some(m) if m < descriptors.nrows() => {
                let rows = sample_rows(descriptors.nrows(), m, params.seed);
                sample = Mat::from_fn(m, descriptors.ncols(), |i, j| descriptors[(rows[i], j)]);
                sample.as_ref()
            }
            _ => descriptors,
        };
        let report = kmeans(
            descriptors,
            &KmeansParams {
                k: params.size,
                max_iter: params.max_iter,
                seed: params.seed,
            },
        )?;
        let sigma = match params.sigma {
            Some(sigma) => sigma,
            None => {
                let d = descriptors.ncols();
                let words = row_major(report.centers.as_ref());
                let mut dist: Vec<f64> = (0..descriptors.nrows())
                    .into_par_iter()
                    .map(|i| {
                        let x: Vec<f64> = (0..d).map(|j| descriptors[(i, j)]).collect();
                        nearest_center(&x, &words, d).1.sqrt()
                    })
                    .collect();
                median(&mut dist)
            }
        };
        Self::new(report.centers, sigma)
    }

    /// A vocabulary from given words (V × d) and σ.
    ///
    /// # Errors
    /// [`RetrievalError::Empty`], [`RetrievalError::NonFinite`], [`RetrievalError::InvalidParameter`] for σ ≤ 0.
    pub fn new(words: Mat<f64>, sigma: f64) -> Result<Self, RetrievalError> {
        check::non_empty("words", words.nrows())?;
        check::non_empty("word dimension", words.ncols())?;
        check::finite_mat("words", words.as_ref())?;
        check::positive("sigma", sigma)?;
        Ok(Self { words, sigma })
    }

    /// The words p_i (V × d).
    pub fn words(&self) -> MatRef<'_, f64> {
        self.words.as_ref()
    }

    /// The soft-assignment width σ.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Number of words V.
    pub fn size(&self) -> usize {
        self.words.nrows()
    }

    /// Soft assignment Θ (n × V) of the rows of `descriptors` (n × d); every row sums to 1.
    ///
    /// Evaluated as `exp(−(‖p − p_i‖² − min_j ‖p − p_j‖²)/(2σ²))` before normalising, so a
    /// descriptor far from every word does not underflow to 0/0.
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] if d differs from the words', [`RetrievalError::NonFinite`].
    pub fn soft_assignment(&self, descriptors: MatRef<'_, f64>) -> Result<Mat<f64>, RetrievalError> {
        self.assignment_matrix(descriptors, Assignment::Normalized)
    }

    /// The Gaussian kernel assignment `κ_i(x) = exp(−(‖p(x) − p_i‖² − m)/(2σ²))` (n × V), *not*
    /// normalised per vertex: a descriptor far from every word gets small weights on all of them.
    /// m = the smallest squared word distance over all the rows, a common factor `e^{m/2σ²}` that
    /// keeps the largest entry at 1 (no underflow to 0/0) and cancels once the bag is normalised.
    ///
    /// # Errors
    /// As [`Self::soft_assignment`].
    pub fn kernel_assignment(&self, descriptors: MatRef<'_, f64>) -> Result<Mat<f64>, RetrievalError> {
        self.assignment_matrix(descriptors, Assignment::Kernel)
    }

    fn assignment_matrix(
        &self,
        descriptors: MatRef<'_, f64>,
        assignment: Assignment,
    ) -> Result<Mat<f64>, RetrievalError> {
        let rows = AssignmentRows::new(self, descriptors, assignment)?;
        let (n, v) = (descriptors.nrows(), self.size());
        // Row-major blocks filled in parallel, one allocation; then Θ column-major.
        let mut flat = vec![0.0; n * v];
        flat.par_chunks_mut(ROW_BLOCK * v.max(1))
            .enumerate()
            .for_each(|(b, block)| {
                wfem_base::simd::clear_upper_state();
                let mut x = vec![0.0; rows.d];
                for (r, out) in block.chunks_exact_mut(v).enumerate() {
                    rows.fill(b * ROW_BLOCK + r, &mut x, out);
                }
            });
        Ok(Mat::from_fn(n, v, |i, j| flat[i * v + j]))
    }

    /// `Θᵀ w` (length V) without forming Θ (n × V): rows in blocks of [`ROW_BLOCK`], each block
    /// summed in order and the blocks added in order (the same sum whatever the threads).
    ///
    /// # Errors
    /// As [`Self::soft_assignment`]; [`RetrievalError::DimensionMismatch`] if `weights` is not
    /// one per row.
    pub fn weighted_assignment(
        &self,
        descriptors: MatRef<'_, f64>,
        weights: &[f64],
        assignment: Assignment,
    ) -> Result<Vec<f64>, RetrievalError> {
        check::same("vertex weights vs descriptors", descriptors.nrows(), weights.len())?;
        check::finite_slice("vertex weights", weights)?;
        let rows = AssignmentRows::new(self, descriptors, assignment)?;
        let v = self.size();
        let partial: Vec<Vec<f64>> = weights
            .par_chunks(ROW_BLOCK)
            .enumerate()
            .map(|(b, w)| {
                wfem_base::simd::clear_upper_state();
                let (mut x, mut theta, mut acc) = (vec![0.0; rows.d], vec![0.0; v], vec![0.0; v]);
                for (r, &a) in w.iter().enumerate() {
                    rows.fill(b * ROW_BLOCK + r, &mut x, &mut theta);
                    acc.iter_mut().zip(&theta).for_each(|(s, t)| *s += t * a);
                }
                acc
            })
            .collect();
        let mut bag = vec![0.0; v];
        for p in &partial {
            bag.iter_mut().zip(p).for_each(|(s, t)| *s += t);
        }
        Ok(bag)
    }

    /// The bag of features `Θᵀ a` (length V) with vertex areas `a` (e.g. [`vertex_areas`] of B,
    /// or the lumped diagonal), Θ the normalised [`Self::soft_assignment`]. It sums to `Σ a`
    /// (the area); divide by it for a distribution.
    ///
    /// # Errors
    /// Those of [`Self::soft_assignment`]; [`RetrievalError::DimensionMismatch`] if `a` has the
    /// wrong length; [`RetrievalError::NonFinite`].
    pub fn bag_of_features(
        &self,
        descriptors: MatRef<'_, f64>,
        vertex_weights: &[f64],
    ) -> Result<Vec<f64>, RetrievalError> {
        self.bag_with(descriptors, vertex_weights, Assignment::Normalized)
    }

    /// The bag `Θᵀ a` with the given [`Assignment`] (Θ = [`Self::soft_assignment`] or
    /// [`Self::kernel_assignment`]).
    ///
    /// # Errors
    /// As [`Self::bag_of_features`].
    pub fn bag_with(
        &self,
        descriptors: MatRef<'_, f64>,
        vertex_weights: &[f64],
        assignment: Assignment,
    ) -> Result<Vec<f64>, RetrievalError> {
        check::same(
            "vertex weights vs descriptors",
            descriptors.nrows(),
            vertex_weights.len(),
        )?;
        check::finite_slice("vertex weights", vertex_weights)?;
        self.weighted_assignment(descriptors, vertex_weights, assignment)
    }

    /// The spatially sensitive bag of features `F = Θᵀ B K_t Θ` (V × V).
    ///
    /// `apply_kernel` receives Θ (n × V) and must return `K_t Θ` (n × V), e.g. the rational
    /// wFEM kernel of `wfem-heat` or `Φ D_t Φᵀ B Θ` from a spectrum. `mass` is B (n × n).
    /// Since `Σ_i θ_i = 1`, the entries of F sum to `1ᵀ B K_t 1` = area (mass conservation).
    ///
    /// # Errors
    /// Those of [`Self::soft_assignment`], anything `apply_kernel` returns,
    /// [`RetrievalError::DimensionMismatch`] for a wrongly sized B or kernel output,
    /// [`RetrievalError::NonFinite`] if the kernel output holds NaN/∞.
    pub fn spatially_sensitive_bag(
        &self,
        descriptors: MatRef<'_, f64>,
        mass: SparseColMatRef<'_, usize, f64>,
        mut apply_kernel: impl FnMut(MatRef<'_, f64>) -> Result<Mat<f64>, RetrievalError>,
    ) -> Result<Mat<f64>, RetrievalError> {
        let n = descriptors.nrows();
        check::same("mass rows vs descriptors", n, mass.nrows())?;
        check::same("mass columns vs descriptors", n, mass.ncols())?;
        let theta = self.soft_assignment(descriptors)?;
        let k_theta = apply_kernel(theta.as_ref())?;
        check::same("kernel output rows", n, k_theta.nrows())?;
        check::same("kernel output columns", self.size(), k_theta.ncols())?;
        check::finite_mat("kernel output", k_theta.as_ref())?;
        let mut b_k_theta = Mat::<f64>::zeros(n, self.size());
        sparse_dense_matmul(
            b_k_theta.as_mut(),
            Accum::Replace,
            mass,
            k_theta.as_ref(),
            1.0,
            Par::rayon(0),
        );
        let mut f = Mat::<f64>::zeros(self.size(), self.size());
        matmul(
            f.as_mut(),
            Accum::Replace,
            theta.transpose(),
            b_k_theta.as_ref(),
            1.0,
            Par::rayon(0),
        );
        Ok(f)
    }
}

/// How a descriptor is spread over the words.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Assignment {
    /// Shape Google's soft assignment: Gaussian weights normalised to sum 1 per vertex
    /// ([`Vocabulary::soft_assignment`]); every vertex counts with its full weight.
    #[default]
    Normalized,
    /// Unnormalised Gaussian weights ([`Vocabulary::kernel_assignment`]): a vertex whose
    /// descriptor is far from every word (a spike, a hole's rim) counts less.
    Kernel,
}

/// Vertex areas `a = B·1` (row sums of the mass matrix); for the consistent B these equal the
/// barycentric lumped areas `Σ_{T∋i}|T|/3` (paper, Eq. (7)).
pub fn vertex_areas(mass: SparseColMatRef<'_, usize, f64>) -> Vec<f64> {
    // B is symmetric, so row sums are column sums; columns are contiguous in CSC.
    (0..mass.ncols()).map(|j| mass.val_of_col(j).iter().sum()).collect()
}

/// `m` distinct indices of `0..n` (partial Fisher–Yates with SplitMix64), in increasing order.
fn sample_rows(n: usize, m: usize, seed: u64) -> Vec<usize> {
    // A different stream from the k-means++ seeding that uses the same seed.
    let mut rng = SplitMix64::new(seed ^ 0x5DEE_CE66_D1CE_5EED);
    let mut idx: Vec<usize> = (0..n).collect();
    for i in 0..m {
        let j = i + ((rng.next_f64() * (n - i) as f64) as usize).min(n - i - 1);
        idx.swap(i, j);
    }
    idx.truncate(m);
    idx.sort_unstable();
    idx
}

/// Rows per parallel task of the assignments.
const ROW_BLOCK: usize = 256;

/// One row of an assignment at a time: the words row-major, the scale and, for the kernel
/// assignment, the common shift m.
struct AssignmentRows<'a> {
    descriptors: MatRef<'a, f64>,
    words: Vec<f64>,
    d: usize,
    inv_two_sigma2: f64,
    /// `None`: normalised per row (shift = the row's own minimum).
    shift: Option<f64>,
}

impl<'a> AssignmentRows<'a> {
    fn new(
        vocabulary: &Vocabulary,
        descriptors: MatRef<'a, f64>,
        assignment: Assignment,
    ) -> Result<Self, RetrievalError> {
        let d = vocabulary.words.ncols();
        check::same("descriptor dimension vs vocabulary", d, descriptors.ncols())?;
        check::finite_mat("descriptors", descriptors)?;
        let mut rows = Self {
            descriptors,
            words: row_major(vocabulary.words.as_ref()),
            d,
            inv_two_sigma2: 1.0 / (2.0 * vocabulary.sigma * vocabulary.sigma),
            shift: None,
        };
        if assignment == Assignment::Kernel {
            let min = (0..descriptors.nrows())
                .into_par_iter()
                .map_init(
                    || {
                        wfem_base::simd::clear_upper_state();
                        (vec![0.0; d], Vec::new())
                    },
                    |(x, d2), i| {
                        rows.distances(i, x, d2);
                        d2.iter().copied().fold(f64::INFINITY, f64::min)
                    },
                )
                .reduce(|| f64::INFINITY, f64::min);
            rows.shift = Some(min);
        }
        Ok(rows)
    }

    /// The squared distances of row i to every word, into `d2` (`x`: scratch of length d).
    fn distances(&self, i: usize, x: &mut [f64], d2: &mut Vec<f64>) {
        x.iter_mut()
            .enumerate()
            .for_each(|(j, v)| *v = self.descriptors[(i, j)]);
        d2.clear();
        d2.extend(self.words.chunks_exact(self.d).map(|w| squared_distance(x, w)));
    }

    /// Row i of Θ into `out` (length V).
    fn fill(&self, i: usize, x: &mut [f64], out: &mut [f64]) {
        x.iter_mut()
            .enumerate()
            .for_each(|(j, v)| *v = self.descriptors[(i, j)]);
        for (o, w) in out.iter_mut().zip(self.words.chunks_exact(self.d)) {
            *o = squared_distance(x, w);
        }
        let shift = self
            .shift
            .unwrap_or_else(|| out.iter().copied().fold(f64::INFINITY, f64::min));
        out.iter_mut()
            .for_each(|q| *q = (-(*q - shift) * self.inv_two_sigma2).exp());
        if self.shift.is_none() {
            let sum: f64 = out.iter().sum();
            out.iter_mut().for_each(|t| *t /= sum);
        }
    }
}

fn row_major(m: MatRef<'_, f64>) -> Vec<f64> {
    (0..m.nrows())
        .flat_map(|i| (0..m.ncols()).map(move |j| m[(i, j)]))
        .collect()
}

/// Median (mean of the two middle values for even length) of a non-empty slice (sorts it).
pub(crate) fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}
