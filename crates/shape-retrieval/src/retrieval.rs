//! Retrieval metrics: ranking by distance, average precision, mAP, precision/recall.
//!
//! For a query q, the other shapes are ranked by increasing distance (the query itself is
//! excluded; ties go to the lower index, so results are deterministic). With `rel_q(k) = 1` if
//! the k-th ranked shape has the query's class, `P_q(k) = (Σ_{j≤k} rel_q(j))/k` and
//! `R_q = Σ_k rel_q(k)`, the average precision is
//!
//! `AP(q) = (1/R_q) Σ_k P_q(k) · rel_q(k)`,
//!
//! and mAP is the mean of AP over the queries (paper, Sect. 5; SHREC'10 uses every
//! transformation of the same null shape as relevant). A query whose class has no other
//! member has no AP and is left out of the means.

use crate::check;
use crate::RetrievalError;
use faer::MatRef;

/// The indices of all items except `query`, by increasing `distances[i]` (ties → lower index).
///
/// # Errors
/// [`RetrievalError::VertexOutOfRange`] if `query` ≥ len (the "vertex" is an item here),
/// [`RetrievalError::NonFinite`] for NaN distances.
pub fn rank(distances: &[f64], query: usize) -> Result<Vec<usize>, RetrievalError> {
    if query >= distances.len() {
        return Err(RetrievalError::VertexOutOfRange {
            what: "query",
            index: query,
            n_vertices: distances.len(),
        });
    }
    check::finite_slice("distances", distances)?;
    let mut order: Vec<usize> = (0..distances.len()).filter(|&i| i != query).collect();
    // Stable sort keeps the index order among equal distances.
    order.sort_by(|&a, &b| distances[a].total_cmp(&distances[b]));
    Ok(order)
}

/// `AP = (1/R) Σ_k P(k)·rel(k)` of one ranked relevance list (`relevance[k]` for rank k+1);
/// `None` if nothing is relevant (R = 0).
pub fn average_precision(relevance: &[bool]) -> Option<f64> {
    let mut hits = 0usize;
    let mut sum = 0.0;
    for (k, &rel) in relevance.iter().enumerate() {
        if rel {
            hits += 1;
            sum += hits as f64 / (k + 1) as f64;
        }
    }
    (hits > 0).then(|| sum / hits as f64)
}

/// Precision `P(k)` and recall `(Σ_{j≤k} rel(j))/R` at every cutoff k = 1 … len.
#[derive(Clone, Debug, PartialEq)]
pub struct PrecisionRecall {
    /// `precision[k−1] = P(k)`.
    pub precision: Vec<f64>,
    /// `recall[k−1]` = fraction of the relevant items within the top k.
    pub recall: Vec<f64>,
}

/// Precision and recall at every cutoff of a ranked relevance list.
///
/// # Errors
/// [`RetrievalError::NothingToAverage`] if nothing is relevant (recall undefined).
pub fn precision_recall(relevance: &[bool]) -> Result<PrecisionRecall, RetrievalError> {
    let total = relevance.iter().filter(|&&r| r).count();
    if total == 0 {
        return Err(RetrievalError::NothingToAverage {
            what: "recall of a list without relevant items",
        });
    }
    let mut hits = 0usize;
    let (mut precision, mut recall) = (Vec::with_capacity(relevance.len()), Vec::with_capacity(relevance.len()));
    for (k, &rel) in relevance.iter().enumerate() {
        hits += rel as usize;
        precision.push(hits as f64 / (k + 1) as f64);
        recall.push(hits as f64 / total as f64);
    }
    Ok(PrecisionRecall { precision, recall })
}

/// mAP of the queries of one class.
#[derive(Clone, Debug, PartialEq)]
pub struct ClassPrecision {
    /// The class label.
    pub label: u32,
    /// Mean AP over this class's queries that have an AP.
    pub mean_average_precision: f64,
    /// Number of such queries.
    pub n_queries: usize,
}

/// Result of [`evaluate`].
#[derive(Clone, Debug, PartialEq)]
pub struct RetrievalReport {
    /// AP of every item used as a query (`None` if its class has no other member). Averages over
    /// any subset of queries (e.g. SHREC'10's per transformation and strength) come from here.
    pub average_precision: Vec<Option<f64>>,
    /// Mean of the defined APs.
    pub mean_average_precision: f64,
    /// Per class, in increasing label order (classes without any defined AP are omitted).
    pub per_class: Vec<ClassPrecision>,
}

/// Leave-one-out retrieval on a square distance matrix (m × m; row q = distances from query q)
/// with class labels: every item is a query against all the others.
///
/// # Errors
/// [`RetrievalError::DimensionMismatch`] for a non-square matrix or wrong label count,
/// [`RetrievalError::NonFinite`] for NaN distances, [`RetrievalError::NothingToAverage`] if no
/// query has a relevant item.
pub fn evaluate(distances: MatRef<'_, f64>, labels: &[u32]) -> Result<RetrievalReport, RetrievalError> {
    let m = distances.nrows();
    check::non_empty("distance matrix", m)?;
    check::same("distance matrix columns vs rows", m, distances.ncols())?;
    check::same("labels vs distance matrix", m, labels.len())?;
    check::finite_mat("distances", distances)?;
    let mut per_query = Vec::with_capacity(m);
    let mut row = vec![0.0; m];
    for q in 0..m {
        row.iter_mut().enumerate().for_each(|(j, v)| *v = distances[(q, j)]);
        let relevance: Vec<bool> = rank(&row, q)?.into_iter().map(|j| labels[j] == labels[q]).collect();
        per_query.push(average_precision(&relevance));
    }
    let defined: Vec<f64> = per_query.iter().flatten().copied().collect();
    if defined.is_empty() {
        return Err(RetrievalError::NothingToAverage {
            what: "no query has another item of its class",
        });
    }
    let mean_average_precision = defined.iter().sum::<f64>() / defined.len() as f64;
    let mut classes: Vec<u32> = labels.to_vec();
    classes.sort_unstable();
    classes.dedup();
    let per_class = classes
        .into_iter()
        .filter_map(|label| {
            let aps: Vec<f64> = (0..m)
                .filter(|&q| labels[q] == label)
                .filter_map(|q| per_query[q])
                .collect();
            (!aps.is_empty()).then(|| ClassPrecision {
                label,
                mean_average_precision: aps.iter().sum::<f64>() / aps.len() as f64,
                n_queries: aps.len(),
            })
        })
        .collect();
    Ok(RetrievalReport {
        average_precision: per_query,
        mean_average_precision,
        per_class,
    })
}
