//! The distance of a scan: [`Metric`], any function of a query (f64) and a stored row (f32),
//! and the [`StandardMetric`]s a store offers without any model.

/// A distance between a query and a stored vector, for [`Store::search_metric`](crate::Store::search_metric).
///
/// Implement it for a model's own distance (the `index` feature implements it for
/// shape-retrieval's bag distances); [`StandardMetric`] covers the plain cases.
pub trait Metric: Sync {
    /// The distance between `query` and a stored `row` (both of the store's dimension).
    fn eval(&self, query: &[f64], row: &[f32]) -> f64;

    /// Whether [`Metric::refuse`] can refuse a value (when false, values are not inspected).
    fn checks_values(&self) -> bool {
        false
    }

    /// Why a value cannot be compared under this metric (`Some("is negative; …")`), or `None`.
    fn refuse(&self, _value: f64) -> Option<&'static str> {
        None
    }
}

/// Built-in distances of [`Store::search_metric`](crate::Store::search_metric), on vectors read
/// as `f32` and accumulated in `f64`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StandardMetric {
    /// `Σ |a_i − b_i|`.
    #[default]
    L1,
    /// `½ Σ (a_i − b_i)²/(a_i + b_i)` over the bins with `a_i + b_i > 0` (histograms).
    ChiSquared,
    /// `(Σ (a_i − b_i)²)^½`.
    Euclidean,
}

wfem_base::registry! {
    StandardMetric as "metric" {
        StandardMetric::L1 = StandardMetric::L1 => "l1" ["manhattan"]: "Σ |a_i − b_i| (default)",
        StandardMetric::ChiSquared = StandardMetric::ChiSquared => "chi-squared" ["chi2", "chi-square"]:
            "½ Σ (a_i − b_i)²/(a_i + b_i), for histograms",
        StandardMetric::Euclidean = StandardMetric::Euclidean => "euclidean" ["l2"]: "(Σ (a_i − b_i)²)^½",
    }
}

impl Metric for StandardMetric {
    #[inline]
    fn eval(&self, query: &[f64], row: &[f32]) -> f64 {
        let pairs = query.iter().zip(row).map(|(&a, &b)| (a, f64::from(b)));
        match self {
            StandardMetric::L1 => pairs.map(|(a, b)| (a - b).abs()).sum(),
            StandardMetric::ChiSquared => {
                0.5 * pairs
                    .map(|(a, b)| {
                        let s = a + b;
                        if s > 0.0 {
                            (a - b) * (a - b) / s
                        } else {
                            0.0
                        }
                    })
                    .sum::<f64>()
            }
            StandardMetric::Euclidean => pairs.map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt(),
        }
    }

    fn checks_values(&self) -> bool {
        *self == StandardMetric::ChiSquared
    }

    fn refuse(&self, value: f64) -> Option<&'static str> {
        (*self == StandardMetric::ChiSquared && value < 0.0).then_some("is negative; chi-squared compares histograms")
    }
}
