//! Feature points (local maxima), their repeatability, and dense-descriptor robustness (SHREC'10 feature track; paper, Sect. 5).
//!
//! **Repeatability.** Let 𝒜(X), 𝒜(Y) be the feature points detected on a null shape X and a
//! transformed shape Y, and let the ground truth map each vertex of Y to a vertex of X (and
//! vice versa) where it exists. A feature `y_k ∈ 𝒜(Y)` with ground-truth image `x'_k` is
//! *repeatable* if the geodesic ball `B_R(x'_k)` on X contains a feature of 𝒜(X). Then
//! `rep(Y, X)` = (# repeatable features of Y) / (# features of Y with a ground truth), and the
//! detection quality is `(rep(Y, X) + rep(X, Y))/2`. Features without ground truth (e.g. in a
//! hole) are ignored. The benchmark uses R = 5% of the shape's diameter. Geodesic distances
//! come from a [`DistanceOracle`]: a closure `Fn(u32, u32) -> f64` or a dense matrix.
//!
//! **Descriptor robustness.** For corresponding points (x, y(x)) the relative L2 distance
//! `‖f_X(x) − f_Y(y(x))‖₂ / ‖f_X(x)‖₂`, averaged over the correspondences. The SHREC'10 paper
//! reports "the average L2 distance between descriptors at corresponding points" without
//! stating its normalisation; dividing by the null shape's descriptor norm is **our choice**
//! (it makes the number scale-free and comparable with the paper's Table 4 magnitudes, but this
//! is unverified).

use crate::check;
use crate::RetrievalError;
use faer::MatRef;

/// Geodesic (or any) distance between two vertices of one shape.
pub trait DistanceOracle {
    /// The distance from vertex `from` to vertex `to`; must be finite and ≥ 0.
    fn distance(&self, from: u32, to: u32) -> f64;
}

impl<F: Fn(u32, u32) -> f64> DistanceOracle for F {
    fn distance(&self, from: u32, to: u32) -> f64 {
        self(from, to)
    }
}

/// A dense n × n distance matrix (precomputed, e.g. all-pairs geodesics of a small mesh).
impl DistanceOracle for MatRef<'_, f64> {
    fn distance(&self, from: u32, to: u32) -> f64 {
        self[(from as usize, to as usize)]
    }
}

/// Detected features of one shape and its ground-truth map to the other shape.
#[derive(Clone, Copy, Debug)]
pub struct FeatureSet<'a> {
    /// Feature vertices 𝒜.
    pub features: &'a [u32],
    /// Number of vertices of this shape.
    pub n_vertices: usize,
    /// For every vertex of this shape, its ground-truth image on the other shape (or `None`).
    pub correspondence: &'a [Option<u32>],
}

/// Result of [`repeatability`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RepeatabilityReport {
    /// rep(Y, X): fraction of Y's features (with ground truth) that are repeatable in X.
    pub y_in_x: f64,
    /// rep(X, Y).
    pub x_in_y: f64,
    /// (rep(Y, X) + rep(X, Y)) / 2.
    pub overall: f64,
    /// Features of Y that have a ground truth (the denominator of rep(Y, X)).
    pub y_with_ground_truth: usize,
    /// Features of X that have a ground truth.
    pub x_with_ground_truth: usize,
}

/// Repeatability of feature points between a null shape X and a transformed shape Y within
/// geodesic radius `radius` (see the module docs). `distance_x` measures on X, `distance_y` on Y.
///
/// Cost: O(|𝒜(X)|·|𝒜(Y)|) oracle calls.
///
/// # Errors
/// [`RetrievalError::InvalidParameter`] for a negative or non-finite radius,
/// [`RetrievalError::DimensionMismatch`] if a correspondence does not have one entry per vertex,
/// [`RetrievalError::VertexOutOfRange`] for a feature or image outside its shape,
/// [`RetrievalError::InvalidDistance`] if an oracle returns NaN or a negative value,
/// [`RetrievalError::NothingToAverage`] if one side has no feature with a ground truth.
pub fn repeatability(
    x: FeatureSet<'_>,
    y: FeatureSet<'_>,
    radius: f64,
    distance_x: &impl DistanceOracle,
    distance_y: &impl DistanceOracle,
) -> Result<RepeatabilityReport, RetrievalError> {
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(RetrievalError::InvalidParameter {
            name: "radius",
            value: radius,
            reason: "must be finite and ≥ 0",
        });
    }
    validate(&x, y.n_vertices, "features of X", "correspondence X → Y")?;
    validate(&y, x.n_vertices, "features of Y", "correspondence Y → X")?;
    let (y_hits, y_total) = one_side(&y, &x, radius, distance_x)?;
    let (x_hits, x_total) = one_side(&x, &y, radius, distance_y)?;
    if y_total == 0 {
        return Err(RetrievalError::NothingToAverage {
            what: "no feature of Y has a ground-truth image on X",
        });
    }
    if x_total == 0 {
        return Err(RetrievalError::NothingToAverage {
            what: "no feature of X has a ground-truth image on Y",
        });
    }
    let y_in_x = y_hits as f64 / y_total as f64;
    let x_in_y = x_hits as f64 / x_total as f64;
    Ok(RepeatabilityReport {
        y_in_x,
        x_in_y,
        overall: 0.5 * (y_in_x + x_in_y),
        y_with_ground_truth: y_total,
        x_with_ground_truth: x_total,
    })
}

fn validate(
    s: &FeatureSet<'_>,
    n_other: usize,
    what_features: &'static str,
    what_map: &'static str,
) -> Result<(), RetrievalError> {
    check::same(what_map, s.n_vertices, s.correspondence.len())?;
    for &f in s.features {
        if f as usize >= s.n_vertices {
            return Err(RetrievalError::VertexOutOfRange {
                what: what_features,
                index: f as usize,
                n_vertices: s.n_vertices,
            });
        }
    }
    for &image in s.correspondence.iter().flatten() {
        if image as usize >= n_other {
            return Err(RetrievalError::VertexOutOfRange {
                what: what_map,
                index: image as usize,
                n_vertices: n_other,
            });
        }
    }
    Ok(())
}

/// (# repeatable features of `from` in `to`, # features of `from` with ground truth).
fn one_side(
    from: &FeatureSet<'_>,
    to: &FeatureSet<'_>,
    radius: f64,
    distance_to: &impl DistanceOracle,
) -> Result<(usize, usize), RetrievalError> {
    let mut hits = 0;
    let mut total = 0;
    for &f in from.features {
        let Some(image) = from.correspondence[f as usize] else {
            continue;
        };
        total += 1;
        for &g in to.features {
            let d = distance_to.distance(image, g);
            if !(d.is_finite() && d >= 0.0) {
                return Err(RetrievalError::InvalidDistance {
                    from: image,
                    to: g,
                    value: d,
                });
            }
            if d <= radius {
                hits += 1;
                break;
            }
        }
    }
    Ok((hits, total))
}

/// Average relative descriptor distance over corresponding points,
/// `(1/|C|) Σ_{(x,y)∈C} ‖f_X(x) − f_Y(y)‖₂ / ‖f_X(x)‖₂` (normalisation: our choice, see module docs).
///
/// `descriptors_x` is n_X × d (row = vertex), `descriptors_y` n_Y × d, `pairs` the ground-truth
/// correspondences (x, y).
///
/// # Errors
/// [`RetrievalError::Empty`] for no pairs, [`RetrievalError::DimensionMismatch`] for different d,
/// [`RetrievalError::VertexOutOfRange`], [`RetrievalError::NonFinite`],
/// [`RetrievalError::ZeroDescriptor`] if some `f_X(x) = 0`.
pub fn descriptor_distance(
    descriptors_x: MatRef<'_, f64>,
    descriptors_y: MatRef<'_, f64>,
    pairs: &[(u32, u32)],
) -> Result<f64, RetrievalError> {
    check::non_empty("correspondence pairs", pairs.len())?;
    check::same(
        "descriptor dimension of Y vs X",
        descriptors_x.ncols(),
        descriptors_y.ncols(),
    )?;
    let mut sum = 0.0;
    for &(x, y) in pairs {
        let (x, y) = (x as usize, y as usize);
        if x >= descriptors_x.nrows() {
            return Err(RetrievalError::VertexOutOfRange {
                what: "pairs (X)",
                index: x,
                n_vertices: descriptors_x.nrows(),
            });
        }
        if y >= descriptors_y.nrows() {
            return Err(RetrievalError::VertexOutOfRange {
                what: "pairs (Y)",
                index: y,
                n_vertices: descriptors_y.nrows(),
            });
        }
        let (mut diff2, mut norm2) = (0.0, 0.0);
        for j in 0..descriptors_x.ncols() {
            let (a, b) = (descriptors_x[(x, j)], descriptors_y[(y, j)]);
            if !a.is_finite() {
                return Err(RetrievalError::NonFinite {
                    what: "descriptors of X",
                    index: x * descriptors_x.ncols() + j,
                });
            }
            if !b.is_finite() {
                return Err(RetrievalError::NonFinite {
                    what: "descriptors of Y",
                    index: y * descriptors_y.ncols() + j,
                });
            }
            diff2 += (a - b) * (a - b);
            norm2 += a * a;
        }
        if norm2 == 0.0 {
            return Err(RetrievalError::ZeroDescriptor { vertex: x });
        }
        sum += (diff2 / norm2).sqrt();
    }
    Ok(sum / pairs.len() as f64)
}

/// Feature detection by local maxima of a vertex function (e.g. the HKS at a large t, as in
/// Sun et al. 2009 and the paper's SHK1): vertex v is a feature if `f(v)` beats every vertex
/// within `rings` edges of it. Vertices are compared by `(f(v), v)` lexicographically (ties go
/// to the higher index), the simulation-of-simplicity order of `mesh_fem::morse`, so `rings = 1`
/// gives the same set as `mesh_fem::morse::local_maxima`; larger rings suppress maxima that are
/// close to a higher one. Returns the features in increasing order.
///
/// `faces` define the edge graph on `values.len()` vertices. Cost O(n · |k-ring|).
///
/// # Errors
/// [`RetrievalError::Empty`] for no values, [`RetrievalError::InvalidParameter`] for `rings = 0`,
/// [`RetrievalError::VertexOutOfRange`] for a face index ≥ n, [`RetrievalError::NonFinite`].
pub fn local_maxima(faces: &[[u32; 3]], values: &[f64], rings: usize) -> Result<Vec<u32>, RetrievalError> {
    let n = values.len();
    check::non_empty("values", n)?;
    check::finite_slice("values", values)?;
    check::at_least_one("rings", rings)?;
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n];
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            for v in [a, b] {
                if v as usize >= n {
                    return Err(RetrievalError::VertexOutOfRange {
                        what: "faces",
                        index: v as usize,
                        n_vertices: n,
                    });
                }
            }
            neighbours[a as usize].push(b);
            neighbours[b as usize].push(a);
        }
    }
    neighbours.iter_mut().for_each(|nb| {
        nb.sort_unstable();
        nb.dedup();
    });
    // (f(v), v) lexicographic order: larger value wins, equal values go to the higher index.
    let beats = |v: usize, u: usize| values[v] > values[u] || (values[v] == values[u] && v > u);
    use rayon::prelude::*;
    let is_max: Vec<bool> = (0..n)
        .into_par_iter()
        .map(|v| {
            // Breadth-first search over the k-ring, stopping at the first vertex that wins.
            let mut seen = vec![v as u32];
            let mut frontier = vec![v as u32];
            for _ in 0..rings {
                let mut next = Vec::new();
                for &u in &frontier {
                    for &w in &neighbours[u as usize] {
                        if !seen.contains(&w) {
                            if !beats(v, w as usize) {
                                return false;
                            }
                            seen.push(w);
                            next.push(w);
                        }
                    }
                }
                frontier = next;
            }
            true
        })
        .collect();
    Ok((0..n as u32).filter(|&v| is_max[v as usize]).collect())
}
