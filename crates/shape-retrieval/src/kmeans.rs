//! Seeded k-means: k-means++ initialisation (Arthur & Vassilvitskii 2007) and Lloyd iterations.
//!
//! Minimises the inertia `Σ_x min_c ‖p(x) − m_c‖²` over k centres. Points are the rows of an
//! n × d matrix. Fully deterministic for a given seed ([`wfem_base::rng::SplitMix64`] (the `shifted_solve` one); the parallel
//! assignment step does not change the result).

use crate::{check, RetrievalError};
use faer::{Mat, MatRef};
use rayon::prelude::*;
use wfem_base::rng::SplitMix64;

/// Options of [`kmeans`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KmeansParams {
    /// Number of clusters k (default 48, the Shape Google vocabulary size).
    pub k: usize,
    /// Maximum number of Lloyd iterations (default 300).
    pub max_iter: usize,
    /// Seed of the k-means++ sampling (default 0).
    pub seed: u64,
}

impl Default for KmeansParams {
    fn default() -> Self {
        Self {
            k: 48,
            max_iter: 300,
            seed: 0,
        }
    }
}

/// Result of [`kmeans`].
#[derive(Clone, Debug)]
pub struct KmeansReport {
    /// k × d centres m_c (row c is centre c).
    pub centers: Mat<f64>,
    /// Centre index of every point.
    pub assignment: Vec<u32>,
    /// `Σ_x ‖p(x) − m_{c(x)}‖²` at the returned centres and assignment.
    pub inertia: f64,
    /// Lloyd iterations performed.
    pub iterations: usize,
    /// `true` if the assignment stopped changing before `max_iter`.
    pub converged: bool,
}

/// Clusters the rows of `points` (n × d) into `params.k` groups.
///
/// k-means++: the first centre is a uniformly random point, each next one a point drawn with
/// probability ∝ D(x)², its squared distance to the nearest chosen centre. Lloyd: assign every
/// point to its nearest centre (ties → lowest index; parallel over points), move each centre to
/// the mean of its points, until no assignment changes or `max_iter`. A cluster that becomes
/// empty is re-seeded with the point farthest from its centre (deterministic).
///
/// # Errors
/// [`RetrievalError::Empty`] for no points or d = 0, [`RetrievalError::InvalidParameter`] for
/// k = 0, [`RetrievalError::TooFewDescriptors`] for n < k, [`RetrievalError::NonFinite`].
pub fn kmeans(points: MatRef<'_, f64>, params: &KmeansParams) -> Result<KmeansReport, RetrievalError> {
    let (n, d) = (points.nrows(), points.ncols());
    check::non_empty("points", n)?;
    check::non_empty("point dimension", d)?;
    check::at_least_one("k", params.k)?;
    if n < params.k {
        return Err(RetrievalError::TooFewDescriptors {
            n_points: n,
            k: params.k,
        });
    }
    check::finite_mat("points", points)?;
    // Row-major copy: every distance evaluation walks a row.
    let data: Vec<f64> = (0..n).flat_map(|i| (0..d).map(move |j| points[(i, j)])).collect();
    let row = |i: usize| &data[i * d..(i + 1) * d];
    let k = params.k;
    let mut centers = plus_plus_seeds(&data, n, d, k, params.seed);

    let mut assignment = vec![u32::MAX; n];
    let mut iterations = 0;
    let mut converged = false;
    while iterations < params.max_iter {
        iterations += 1;
        let nearest: Vec<(u32, f64)> = (0..n)
            .into_par_iter()
            .map(|i| nearest_center(row(i), &centers, d))
            .collect();
        let changed = nearest.iter().zip(&assignment).any(|((c, _), a)| c != a);
        assignment.iter_mut().zip(&nearest).for_each(|(a, (c, _))| *a = *c);
        if !changed {
            converged = true;
            break;
        }
        // Update step (sequential sums keep the result independent of the thread count).
        let mut sums = vec![0.0; k * d];
        let mut counts = vec![0usize; k];
        for (i, &a) in assignment.iter().enumerate() {
            let c = a as usize;
            counts[c] += 1;
            sums[c * d..(c + 1) * d]
                .iter_mut()
                .zip(row(i))
                .for_each(|(s, x)| *s += x);
        }
        let mut taken = vec![false; n];
        for c in 0..k {
            if counts[c] > 0 {
                let inv = 1.0 / counts[c] as f64;
                for j in 0..d {
                    centers[c * d + j] = sums[c * d + j] * inv;
                }
            } else {
                // Empty cluster: move it to the point worst served by its current centre.
                let far = (0..n)
                    .filter(|&i| !taken[i])
                    .max_by(|&a, &b| nearest[a].1.total_cmp(&nearest[b].1).then(b.cmp(&a)))
                    .unwrap_or(0);
                taken[far] = true;
                centers[c * d..(c + 1) * d].copy_from_slice(row(far));
                // Force another iteration so the moved centre gets its points.
                assignment[far] = u32::MAX;
            }
        }
    }
    if !converged {
        // Report an assignment consistent with the final centres.
        let nearest: Vec<(u32, f64)> = (0..n)
            .into_par_iter()
            .map(|i| nearest_center(row(i), &centers, d))
            .collect();
        assignment.iter_mut().zip(&nearest).for_each(|(a, (c, _))| *a = *c);
    }
    let inertia = (0..n)
        .map(|i| {
            let c = assignment[i] as usize;
            squared_distance(row(i), &centers[c * d..(c + 1) * d])
        })
        .sum();
    Ok(KmeansReport {
        centers: Mat::from_fn(k, d, |c, j| centers[c * d + j]),
        assignment,
        inertia,
        iterations,
        converged,
    })
}

/// k-means++ seeding on row-major `data` (n × d); returns k × d row-major centres.
fn plus_plus_seeds(data: &[f64], n: usize, d: usize, k: usize, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix64::new(seed);
    let row = |i: usize| &data[i * d..(i + 1) * d];
    let mut centers = Vec::with_capacity(k * d);
    let first = ((rng.next_f64() * n as f64) as usize).min(n - 1);
    centers.extend_from_slice(row(first));
    let mut d2: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|i| squared_distance(row(i), row(first)))
        .collect();
    for _ in 1..k {
        let total: f64 = d2.iter().sum();
        let next = if total > 0.0 {
            let target = rng.next_f64() * total;
            let mut acc = 0.0;
            let mut pick = n - 1;
            for (i, v) in d2.iter().enumerate() {
                acc += v;
                if acc > target && *v > 0.0 {
                    pick = i;
                    break;
                }
            }
            // Round-off can push `target` past the running sum: fall back to the last positive D².
            if d2[pick] == 0.0 {
                pick = d2.iter().rposition(|&v| v > 0.0).unwrap_or(pick);
            }
            pick
        } else {
            // All points coincide with chosen centres (fewer distinct points than k).
            ((rng.next_f64() * n as f64) as usize).min(n - 1)
        };
        centers.extend_from_slice(row(next));
        let c = row(next);
        d2.par_iter_mut()
            .enumerate()
            .for_each(|(i, v)| *v = v.min(squared_distance(row(i), c)));
    }
    centers
}

/// Index and squared distance of the nearest centre (ties → lowest index).
pub(crate) fn nearest_center(x: &[f64], centers: &[f64], d: usize) -> (u32, f64) {
    let mut best = (0u32, f64::INFINITY);
    for (c, m) in centers.chunks_exact(d).enumerate() {
        let dist = squared_distance(x, m);
        if dist < best.1 {
            best = (c as u32, dist);
        }
    }
    best
}

pub(crate) fn squared_distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}
