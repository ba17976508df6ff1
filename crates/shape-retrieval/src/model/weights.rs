//! [`VertexWeights`]: the weight of each vertex in a bag, and the breadth-first hop sweeps
//! that damp vertices near a boundary or a repair.

use crate::check;
use crate::descriptor::ShapeDescriptors;
use crate::RetrievalError;
use mesh_fem::TriMesh;
use serde::{Deserialize, Serialize};

/// Default cap of [`VertexWeights::CappedArea`], in medians of the vertex areas: the default
/// weights. On the TOSCA shapes (regular meshes) only a few vertices reach it (around
/// single-vertex tips); with hole filling on, it adds +0.3 / +0.6 / +1.0 points to the
/// synthetic SHREC'10 cumulative mAP at ≤ 3 / ≤ 4 / ≤ 5 (outside vocabulary,
/// docs/SHREC-RESULTS.md).
pub const DEFAULT_AREA_CAP: f64 = 3.0;

/// The weight `w_i` of each vertex in the bag `f = Θᵀ w / Σ w` (default: capped areas).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum VertexWeights {
    /// `w = B·1`: the vertex areas (barycentric lumped areas, Eq. (7)), i.e. `f ≈ ∫ θ dμ / A`.
    Area,
    /// `w_i = min(a_i, c · median(a))`: the areas, capped. A spike (shot noise) or a sliver
    /// fan inflates a few vertex areas by one or two orders of magnitude; the cap keeps those
    /// vertices from dominating the bag, while a regular mesh (a_i within a few times the
    /// median) keeps its plain area weights.
    CappedArea {
        /// The cap c, in medians (> 0).
        factor: f64,
    },
    /// `w_i = a_i · s(h_i / H)` with `h_i` the edge hops from vertex i to the nearest boundary
    /// vertex, s the smoothstep, H = `hops`: vertices at a hole's rim, whose heat kernel sees
    /// the reflecting boundary, count less. Closed meshes keep their area weights.
    BoundaryDamped {
        /// Hops H over which the weight rises from 0 to the area (≥ 1).
        hops: u32,
    },
    /// `w_i = min(a_i, c · median(a)) · s(h_i / H)` with `h_i` the edge hops from vertex i to
    /// the nearest vertex the cleaning added (hole patches, copies, the rims of removed
    /// handles), s the smoothstep: vertices whose small-scale heat kernel sees a repair count
    /// less. Shapes without repairs keep their capped areas.
    RepairDamped {
        /// The cap c, in medians (> 0).
        factor: f64,
        /// Hops H over which the weight rises from 0 (≥ 1).
        hops: u32,
    },
}

impl VertexWeights {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for a non-positive factor or zero hops.
    pub fn validate(&self) -> Result<(), RetrievalError> {
        match *self {
            VertexWeights::Area => Ok(()),
            VertexWeights::CappedArea { factor } => check::positive("capped-area factor", factor),
            VertexWeights::RepairDamped { factor, hops } => {
                check::positive("capped-area factor", factor)?;
                check::at_least_one("repair hops", hops as usize)
            }
            VertexWeights::BoundaryDamped { hops } => check::at_least_one("boundary hops", hops as usize),
        }
    }

    /// The weights of one shape: one per own vertex (`shape.described_vertices()`; the areas
    /// of rim vertices include their share of a filled hole's patch), non-negative, positive
    /// sum.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidModel`] if every weight is zero (a mesh that is all boundary).
    pub fn compute(&self, shape: &ShapeDescriptors) -> Result<Vec<f64>, RetrievalError> {
        // The shape's own vertices only (not the patches of filled holes), so that the cap's
        // median is that of the shape.
        let mut areas = shape.vertex_areas();
        areas.truncate(shape.described_vertices());
        let weights = match *self {
            VertexWeights::Area => areas,
            VertexWeights::CappedArea { factor } => {
                let mut sorted = areas.clone();
                let cap = factor * crate::bof::median(&mut sorted);
                areas.into_iter().map(|a| a.min(cap)).collect()
            }
            VertexWeights::RepairDamped { factor, hops } => {
                let mut sorted = areas.clone();
                let cap = factor * crate::bof::median(&mut sorted);
                let h = added_hops(shape.mesh(), shape.described_vertices(), hops);
                areas
                    .iter()
                    .zip(&h)
                    .map(|(a, &d)| {
                        let x = (d as f64 / hops as f64).min(1.0);
                        a.min(cap) * x * x * (3.0 - 2.0 * x)
                    })
                    .collect()
            }
            VertexWeights::BoundaryDamped { hops } => {
                let h = boundary_hops(shape.mesh(), hops);
                areas
                    .iter()
                    .zip(&h)
                    .map(|(a, &d)| {
                        let x = (d as f64 / hops as f64).min(1.0);
                        a * x * x * (3.0 - 2.0 * x)
                    })
                    .collect()
            }
        };
        if weights.iter().sum::<f64>() > 0.0 {
            Ok(weights)
        } else {
            Err(RetrievalError::InvalidModel {
                what: "vertex weights",
                reason: "every vertex weight is zero".into(),
            })
        }
    }
}

/// Edge hops from every own vertex (the first `own`) to the nearest added vertex (index ≥
/// `own`), capped at `cap`.
fn added_hops(mesh: &TriMesh, own: usize, cap: u32) -> Vec<u32> {
    let n = mesh.n_vertices();
    let mut neighbors: Vec<Vec<u32>> = vec![Vec::new(); n];
    for f in mesh.faces() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            neighbors[a as usize].push(b);
            neighbors[b as usize].push(a);
        }
    }
    let mut hops = vec![cap; n];
    let frontier: Vec<u32> = (own as u32..n as u32).collect();
    frontier.iter().for_each(|&v| hops[v as usize] = 0);
    sweep_hops(&neighbors, &mut hops, frontier, cap);
    hops.truncate(own);
    hops
}

/// Breadth-first sweep from `frontier` (its vertices at 0 hops), one ring per round:
/// `hops[w]` becomes the edge hops from the frontier, where below `cap`.
fn sweep_hops(neighbors: &[Vec<u32>], hops: &mut [u32], mut frontier: Vec<u32>, cap: u32) {
    let mut depth = 0;
    while !frontier.is_empty() && depth + 1 < cap {
        depth += 1;
        let mut next = Vec::new();
        for v in frontier {
            for &w in &neighbors[v as usize] {
                if hops[w as usize] > depth {
                    hops[w as usize] = depth;
                    next.push(w);
                }
            }
        }
        frontier = next;
    }
}

/// Edge hops from every vertex to the nearest boundary vertex, capped at `cap` (closed meshes:
/// `cap` everywhere). A boundary vertex lies on an edge used by exactly one face.
fn boundary_hops(mesh: &TriMesh, cap: u32) -> Vec<u32> {
    let n = mesh.n_vertices();
    let mut edges: Vec<(u32, u32)> = Vec::with_capacity(3 * mesh.n_faces());
    for f in mesh.faces() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            edges.push((a.min(b), a.max(b)));
        }
    }
    edges.sort_unstable();
    let mut hops = vec![cap; n];
    let mut frontier = Vec::new();
    let mut neighbors: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut i = 0;
    while i < edges.len() {
        let mut j = i;
        while j < edges.len() && edges[j] == edges[i] {
            j += 1;
        }
        let (a, b) = edges[i];
        neighbors[a as usize].push(b);
        neighbors[b as usize].push(a);
        if j - i == 1 {
            for v in [a, b] {
                if hops[v as usize] != 0 {
                    hops[v as usize] = 0;
                    frontier.push(v);
                }
            }
        }
        i = j;
    }
    // Breadth-first sweep from the boundary, one ring per round.
    sweep_hops(&neighbors, &mut hops, frontier, cap);
    hops
}
