//! Feature points: the extrema of a field or of the first Laplacian eigenfunctions, and the
//! anchor set A of the feature-driven approximation ranked by persistence (paper, Sect. 4.2).

use crate::spectral::Eigenbasis;
use crate::HeatError;
use mesh_fem::morse::{self, PersistenceDiagram};
use mesh_fem::TriMesh;

/// Extrema of a field: all strict local maxima and minima (`persistence = None`), or only the
/// extrema whose persistence is at least `fraction · (max f − min f)` (`Some(fraction)`,
/// [`morse::persistent_extrema_relative`], saddles dropped). Sorted, without repetition.
///
/// # Errors
/// [`HeatError::Mesh`] for a field of the wrong length or with non-finite values.
pub fn extrema(mesh: &TriMesh, f: &[f64], persistence: Option<f64>) -> Result<Vec<u32>, HeatError> {
    let maxima = morse::local_maxima(mesh, f)?;
    let minima = morse::local_minima(mesh, f)?;
    let mut all: Vec<u32> = maxima.into_iter().chain(minima).collect();
    all.sort_unstable();
    all.dedup();
    if let Some(fraction) = persistence {
        let diagram = morse::persistence(mesh, f)?;
        let keep = morse::persistent_extrema_relative(&diagram, fraction);
        all.retain(|v| keep.binary_search(v).is_ok());
    }
    Ok(all)
}

/// Feature points from the first Laplacian eigenfunctions (paper, Sect. 4.2, \[RPSS10\]): the
/// union of the [`extrema`] of the eigenvectors x₂, …, x_{count+1} of `basis` (x₁, the
/// constant of λ₁ = 0, is skipped). Sorted, without repetition. Eigenvectors are defined up
/// to sign, and the union of maxima and minima does not depend on it.
///
/// # Errors
/// [`HeatError::InvalidParameter`] if `basis` has fewer than `count + 1` pairs;
/// [`HeatError::Mesh`] if the mesh and the basis disagree in size.
pub fn eigenfunction_features(
    mesh: &TriMesh,
    basis: &Eigenbasis,
    count: usize,
    persistence: Option<f64>,
) -> Result<Vec<u32>, HeatError> {
    if basis.values.len() < count + 1 {
        return Err(HeatError::InvalidParameter {
            name: "count",
            reason: format!(
                "{count} eigenfunctions after the constant need {} eigenpairs, the basis has {}",
                count + 1,
                basis.values.len()
            ),
        });
    }
    let mut all = Vec::new();
    for k in 1..=count {
        let x: Vec<f64> = basis.vectors.col(k).iter().copied().collect();
        all.extend(extrema(mesh, &x, persistence)?);
    }
    all.sort_unstable();
    all.dedup();
    Ok(all)
}

/// The anchor set A of a persistence threshold, most persistent first.
#[derive(Clone, Debug, PartialEq)]
pub struct RankedAnchors {
    /// The critical points of [`morse::persistent_extrema`] at the threshold (the extrema of
    /// every pair with persistence ≥ the threshold, their saddles and the essential extrema),
    /// ordered by decreasing persistence of their pair; an extremum comes before its saddle.
    pub vertices: Vec<u32>,
    /// The persistence of each vertex's pair, in units of f (an essential extremum: the range
    /// of f on its connected component).
    pub persistence: Vec<f64>,
}

/// [`morse::persistent_extrema`] at the absolute `threshold`, as a priority list: the same
/// set of vertices, ordered by decreasing persistence (ties by vertex index; a vertex in two
/// pairs, a saddle that kills both a minimum and a maximum, ranks by the stronger one). The
/// order decides which of two anchors closer than the kernel's reach is kept at a scale t
/// ([`super::Coefficients::Anchored`]).
pub fn ranked_anchors(diagram: &PersistenceDiagram, threshold: f64) -> RankedAnchors {
    // (persistence, is-saddle, vertex): sorted by decreasing persistence, extrema first.
    let mut entries: Vec<(f64, bool, u32)> = diagram
        .minima
        .iter()
        .chain(&diagram.maxima)
        .filter(|pair| pair.is_essential() || pair.persistence >= threshold)
        .flat_map(|pair| {
            std::iter::once((pair.persistence, false, pair.birth))
                .chain(pair.death.map(|s| (pair.persistence, true, s)))
        })
        .collect();
    entries.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut seen = std::collections::HashSet::new();
    entries.retain(|e| seen.insert(e.2));
    RankedAnchors {
        vertices: entries.iter().map(|e| e.2).collect(),
        persistence: entries.iter().map(|e| e.0).collect(),
    }
}

/// Number of extrema of a persistence diagram with persistence ≥ `threshold` (essential ones
/// included): the extrema that survive simplification to the threshold \[EMP06\]. Compared
/// between f and f_glob, it shows whether f_glob has spurious extrema above the threshold.
pub fn persistent_extremum_count(diagram: &PersistenceDiagram, threshold: f64) -> usize {
    diagram
        .minima
        .iter()
        .chain(&diagram.maxima)
        .filter(|pair| pair.is_essential() || pair.persistence >= threshold)
        .count()
}
