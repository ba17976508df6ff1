//! Critical points of piecewise-linear functions on triangle meshes and their 0-dimensional
//! topological persistence.
//!
//! The paper's feature-driven approximation (Sect. 4.2, Fig. 13) selects as anchor set 𝒜 the
//! critical points of a noisy map f with the highest persistence \[Ban67; EMP06; PF09\] and
//! builds the *global component* f_glob := Σ_{i∈𝒜} f(pᵢ) K_t eᵢ from them; the sparse heat
//! kernel signature SHK2 (Sect. 5) detects features as persistent maxima. This module
//! provides the three ingredients:
//!
//! * [`critical_points`]: minima, maxima and (multiple) saddles of the piecewise-linear
//!   interpolant of per-vertex values, by Banchoff's link rule;
//! * [`persistence`]: the pairing of minima (sublevel sets) and maxima (superlevel sets) with
//!   the saddles that kill them, by a union–find sweep in O(n log n);
//! * [`persistent_extrema`] / [`persistent_extrema_relative`]: the anchor set 𝒜 that survives
//!   simplification to a persistence threshold, and [`local_maxima`] / [`local_minima`] for
//!   plain feature detection.
//!
//! ```
//! use mesh_fem::{generate, morse};
//! // A noisy height function on a sphere: many spurious extrema, two persistent ones.
//! let mesh = generate::icosphere(3);
//! let f: Vec<f64> = mesh
//!     .positions()
//!     .iter()
//!     .map(|p| p[2] + 0.02 * (40.0 * p[0]).sin() * (40.0 * p[1]).cos())
//!     .collect();
//! let diagram = morse::persistence(&mesh, &f)?;
//! // Anchor set 𝒜 of Sect. 4.2: extrema (and their saddles) with persistence ≥ 10 % of the range.
//! let anchors = morse::persistent_extrema_relative(&diagram, 0.1);
//! assert_eq!(anchors.len(), 2); // the north and south poles
//! assert!(morse::local_maxima(&mesh, &f)?.len() > 1);
//! # Ok::<(), mesh_fem::MeshError>(())
//! ```
//!
//! **Simulation of simplicity.** Ties are broken by comparing (f(v), v) lexicographically, so
//! any two distinct vertices are ordered and every neighbour of a vertex is either *lower* or
//! *higher*. The same total order is used everywhere in this module, so the critical points,
//! the local extrema and the persistence pairs are mutually consistent even on functions
//! with plateaus (which then behave like an infinitesimally tilted version of f).
//!
//! **References** (keys as in the paper). \[Ban67\] T. Banchoff, *Critical points and curvature
//! for embedded polyhedra*, J. Differential Geom. 1 (1967) — the link rule. \[EMP06\]
//! H. Edelsbrunner, D. Morozov, V. Pascucci, *Persistence-sensitive simplification of
//! functions on 2-manifolds*, SoCG 2006 — persistence pairing and simplification. \[ZC05\]
//! A. Zomorodian, G. Carlsson, *Computing persistent homology* (2005) — cited for SHK2.
//! \[PF09\] Patanè and Falcidieno (2009), cited by the paper for persistent critical points.
//! Simulation of simplicity: H. Edelsbrunner, E. Mücke, ACM TOG 9 (1990).

use crate::{MeshError, TriMesh};
use rayon::prelude::*;
use std::cmp::Ordering;

/// Type of a vertex of a piecewise-linear function, by the link rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CriticalKind {
    /// Every neighbour is higher.
    Minimum,
    /// Every neighbour is lower.
    Maximum,
    /// The link alternates between lower and higher runs more than a regular point allows;
    /// `multiplicity` is 1 for a simple saddle, 2 for a monkey saddle, and so on
    /// (the negated index of the vertex, see [`critical_points`]).
    Saddle {
        /// Number of simple saddles merged into this vertex (≥ 1).
        multiplicity: usize,
    },
    /// Not critical: one lower run and one higher run in the link.
    Regular,
}

/// A vertex of the mesh with its [`CriticalKind`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CriticalPoint {
    /// Vertex index.
    pub vertex: u32,
    /// Minimum, maximum or saddle (regular vertices are never returned).
    pub kind: CriticalKind,
    /// The function value f(vertex).
    pub value: f64,
}

/// One pair of the 0-dimensional persistence diagram.
///
/// For the sublevel-set filtration `birth` is a minimum and `death` the saddle at which its
/// component merges into the component of an older (lower) minimum; for the superlevel-set
/// filtration `birth` is a maximum and `death` the saddle at which it merges into a
/// component of a higher maximum (elder rule).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PersistencePair {
    /// The extremum that creates the component (a minimum or a maximum).
    pub birth: u32,
    /// The saddle that kills it, or `None` for an essential class (the oldest extremum of a
    /// connected component of the mesh, which never dies).
    pub death: Option<u32>,
    /// f(birth).
    pub birth_value: f64,
    /// f(death), or `None` for an essential class.
    pub death_value: Option<f64>,
    /// |f(death) − f(birth)| ≥ 0. For an essential class, the range of f over its connected
    /// component (max − min), i.e. the pairing of the global minimum with the global maximum
    /// of extended persistence, so that essential extrema rank first.
    pub persistence: f64,
}

impl PersistencePair {
    /// True for an essential class (no death).
    pub fn is_essential(&self) -> bool {
        self.death.is_none()
    }
}

/// The 0-dimensional persistence diagrams of f: minima (sublevel sets) and maxima
/// (superlevel sets), each sorted by decreasing persistence (ties by birth vertex).
#[derive(Clone, Debug, PartialEq)]
pub struct PersistenceDiagram {
    /// Pairs (minimum, saddle) of the sublevel-set filtration f⁻¹(−∞, a].
    pub minima: Vec<PersistencePair>,
    /// Pairs (maximum, saddle) of the superlevel-set filtration f⁻¹[a, +∞).
    pub maxima: Vec<PersistencePair>,
    /// max f − min f over the whole mesh (≥ 0), the scale of relative thresholds.
    pub value_range: f64,
}

/// Classifies every vertex of the piecewise-linear interpolant of `f` by Banchoff's link rule
/// and returns the critical ones (minima, maxima, saddles), sorted by vertex index.
///
/// This is the critical-point set from which the paper's anchor set 𝒜 is drawn (Sect. 4.2,
/// Fig. 13(b)).
///
/// **Link rule.** Let v be a vertex and Lk(v) its link: the edges (a, b) opposite to v in
/// the triangles (v, a, b) around it. Every link vertex w is *lower* or *higher* than v in the
/// order (f(w), w) vs (f(v), v). Let s be the number of link edges whose two ends are on
/// different sides, i.e. the number of sign changes of f(w) − f(v) walking along the link.
///
/// * Interior vertex (link = one cycle, s even): s = 0 → minimum or maximum; s = 2 →
///   regular; s = 2k ≥ 4 → saddle of multiplicity k − 1. The index 1 − s/2 sums to the Euler
///   characteristic: #max + #min − Σ multiplicities = χ(M) on a closed surface.
/// * Boundary vertex (link = one path): the vertex is classified as in the *doubled*
///   surface M ∪_∂ M (M glued to its mirror image along the boundary), where its link is the
///   path followed by its mirror and has 2s sign changes: s = 0 → minimum or maximum (so a
///   maximum on the boundary is reported as a maximum, as feature detection wants);
///   s = 1 → regular; s ≥ 2 → saddle of multiplicity s − 1. Since χ(M ∪_∂ M) = 2χ(M), the
///   identity becomes 2·Σ_interior ind(v) + Σ_boundary ind(v) = 2χ(M) with ind = +1 for
///   extrema and −multiplicity for saddles. This convention is symmetric under f ↦ −f,
///   unlike counting lower-link components only.
/// * A mesh with any other link (a non-manifold vertex: an edge shared by three or more
///   triangles, several fans pinched at one vertex — the neighbourhood mesh of a point
///   cloud, a non-manifold scan) is not a surface, and the rules above do not apply: all its
///   vertices are classified on the edge graph, as [`persistence`] sees it. No lower
///   neighbour → minimum, no upper neighbour → maximum, otherwise a saddle of multiplicity m
///   when m sublevel (or superlevel) components die at v by the elder rule (the larger of
///   the two counts), and regular when none does. Every death vertex of [`persistence`] is a
///   saddle, as on a surface; saddles that only create 1-cycles are not counted.
///
/// Runs in O(F + Σ_v deg(v) log deg(v)), in parallel over vertices.
///
/// # Errors
/// [`MeshError::ScalarFieldLength`] if `f.len() != mesh.n_vertices()`,
/// [`MeshError::NonFiniteScalarField`] for a NaN or infinite value,
/// [`MeshError::UnreferencedVertex`] for a vertex in no triangle (its link is empty),
/// and [`MeshError::RepeatedIndex`] for a triangle that repeats a vertex.
pub fn critical_points(mesh: &TriMesh, f: &[f64]) -> Result<Vec<CriticalPoint>, MeshError> {
    check_field(mesh, f)?;
    let rank = ranks(f);
    let incidence = crate::graph::VertexFaces::new(mesh.faces(), mesh.n_vertices());
    let faces = mesh.faces();
    let kinds: Vec<Option<CriticalKind>> = (0..mesh.n_vertices())
        .into_par_iter()
        .map_init(LinkScratch::default, |scratch, v| {
            classify_vertex(v as u32, &incidence, faces, &rank, scratch)
        })
        .collect::<Result<_, _>>()?;
    let kinds: Vec<CriticalKind> = if kinds.iter().all(Option::is_some) {
        kinds.into_iter().flatten().collect()
    } else {
        classify_on_the_graph(mesh, f, &rank)?
    };
    Ok(kinds
        .into_iter()
        .enumerate()
        .filter(|(_, kind)| *kind != CriticalKind::Regular)
        .map(|(v, kind)| CriticalPoint {
            vertex: v as u32,
            kind,
            value: f[v],
        })
        .collect())
}

/// 0-dimensional persistence of the sublevel-set filtration (minima paired with saddles) and
/// of the superlevel-set filtration (maxima paired with saddles) of `f` \[EMP06\], as used to
/// rank critical points in the paper's Sect. 4.2.
///
/// **Algorithm.** Vertices are swept in increasing order of (f(v), v) (decreasing for
/// superlevel sets). When v is reached, the components of the already swept vertices that
/// contain a mesh-graph neighbour of v are merged with v by union–find: with none, v starts a
/// new component (v is a minimum); with several, all but the one with the oldest minimum die
/// at v (elder rule), giving pairs (minimum, v) with persistence f(v) − f(minimum). The
/// 0-homology of a sublevel set of the piecewise-linear interpolant only depends on the edges
/// of its lower-star filtration, so the mesh graph suffices and the result equals the
/// persistence of the PL function; every death vertex is a saddle of [`critical_points`].
/// Components that never die are essential; their persistence is the range of f on the
/// component. Cost: O(n log n) for the sort, O(F + Σ_v deg(v) log deg(v)) for the adjacency
/// and α(n) per union–find step; the sublevel and superlevel sweeps run in parallel.
///
/// The counts match the critical points: there is one minima pair per minimum and one
/// maxima pair per maximum, and on a closed surface of genus g the finite pairs account for
/// all saddles but 2g: #finite pairs = Σ multiplicities − 2g.
///
/// # Errors
/// [`MeshError::ScalarFieldLength`] and [`MeshError::NonFiniteScalarField`].
pub fn persistence(mesh: &TriMesh, f: &[f64]) -> Result<PersistenceDiagram, MeshError> {
    check_field(mesh, f)?;
    let order = sorted_order(f);
    let adjacency = crate::graph::VertexNeighbours::new(mesh.n_vertices(), mesh.faces());
    let n = f.len();
    let mut rank = vec![0u32; n];
    for (r, &v) in order.iter().enumerate() {
        rank[v as usize] = r as u32;
    }
    let top = (n - 1) as u32;
    let reversed_rank: Vec<u32> = rank.iter().map(|&r| top - r).collect();
    let (minima, maxima) = rayon::join(
        || sweep(order.iter().copied(), &rank, &adjacency, f, Direction::Sublevel),
        || {
            sweep(
                order.iter().rev().copied(),
                &reversed_rank,
                &adjacency,
                f,
                Direction::Superlevel,
            )
        },
    );
    let value_range = f[order[n - 1] as usize] - f[order[0] as usize];
    Ok(PersistenceDiagram {
        minima,
        maxima,
        value_range,
    })
}

/// The critical points that survive simplification of f to persistence `threshold`
/// (absolute, in units of f): the extrema of all pairs with persistence ≥ `threshold`, the
/// saddles they are paired with, and all essential extrema (which always survive).
/// Sorted by vertex index, without repetition.
///
/// By the persistence simplification theorem \[EMP06\] (for 2-manifolds), f can be perturbed by
/// at most `threshold` in L∞ so that exactly these extrema and paired saddles remain; they are
/// the paper's anchor set 𝒜 for the global component f_glob = Σ_{i∈𝒜} f(pᵢ) K_t eᵢ
/// (Sect. 4.2, Fig. 13). Saddles that create 1-cycles (2g of them on a closed genus-g
/// surface) are not paired by 0-dimensional persistence and are not returned. A NaN
/// threshold keeps only the essential extrema.
pub fn persistent_extrema(diagram: &PersistenceDiagram, threshold: f64) -> Vec<u32> {
    let mut out: Vec<u32> = diagram
        .minima
        .iter()
        .chain(&diagram.maxima)
        .filter(|pair| pair.is_essential() || pair.persistence >= threshold)
        .flat_map(|pair| std::iter::once(pair.birth).chain(pair.death))
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// [`persistent_extrema`] with a threshold relative to the range of f: persistence ≥
/// `fraction` · (max f − min f), e.g. `fraction = 0.1` keeps the extrema whose persistence
/// is at least 10 % of the range (the paper simplifies "from 40 % to 10 %" in Fig. 13).
pub fn persistent_extrema_relative(diagram: &PersistenceDiagram, fraction: f64) -> Vec<u32> {
    persistent_extrema(diagram, fraction * diagram.value_range)
}

/// Strict local maxima of f over the mesh graph: vertices whose every edge neighbour is lower
/// in the order (f, vertex index) — the feature points of SHK1 (paper, Sect. 5). On a
/// manifold mesh these are exactly the [`CriticalKind::Maximum`] vertices of
/// [`critical_points`]. A vertex without neighbours (in no triangle) is vacuously a local
/// maximum. Sorted by vertex index.
///
/// # Errors
/// [`MeshError::ScalarFieldLength`] and [`MeshError::NonFiniteScalarField`].
pub fn local_maxima(mesh: &TriMesh, f: &[f64]) -> Result<Vec<u32>, MeshError> {
    local_extrema(mesh, f, Ordering::Less)
}

/// Strict local minima of f over the mesh graph: vertices whose every edge neighbour is higher
/// in the order (f, vertex index). See [`local_maxima`].
///
/// # Errors
/// [`MeshError::ScalarFieldLength`] and [`MeshError::NonFiniteScalarField`].
pub fn local_minima(mesh: &TriMesh, f: &[f64]) -> Result<Vec<u32>, MeshError> {
    local_extrema(mesh, f, Ordering::Greater)
}

/// Vertices v whose every neighbour w satisfies key(w) `neighbour` key(v), by one scan over
/// the triangle edges in O(F): each edge disqualifies the end that has a neighbour on the
/// wrong side.
fn local_extrema(mesh: &TriMesh, f: &[f64], neighbour: Ordering) -> Result<Vec<u32>, MeshError> {
    check_field(mesh, f)?;
    let mut candidate = vec![true; mesh.n_vertices()];
    for &[a, b, c] in mesh.faces() {
        for (x, y) in [(a, b), (b, c), (c, a)] {
            if x == y {
                continue;
            }
            // y is on the `neighbour` side of x, so x may still qualify and y does not.
            if compare(f, y, x) == neighbour {
                candidate[y as usize] = false;
            } else {
                candidate[x as usize] = false;
            }
        }
    }
    Ok((0..mesh.n_vertices() as u32)
        .filter(|&v| candidate[v as usize])
        .collect())
}

// ---------------------------------------------------------------------------------------------
// Input checks and the simulation-of-simplicity order.

fn check_field(mesh: &TriMesh, f: &[f64]) -> Result<(), MeshError> {
    if f.len() != mesh.n_vertices() {
        return Err(MeshError::ScalarFieldLength {
            len: f.len(),
            n_vertices: mesh.n_vertices(),
        });
    }
    if let Some((vertex, &value)) = f.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(MeshError::NonFiniteScalarField { vertex, value });
    }
    Ok(())
}

/// Lexicographic order of (f(a), a) and (f(b), b). Values are finite (checked), and
/// `partial_cmp` treats −0.0 and +0.0 as equal so that the index decides, as documented.
fn compare(f: &[f64], a: u32, b: u32) -> Ordering {
    f[a as usize]
        .partial_cmp(&f[b as usize])
        .unwrap_or(Ordering::Equal)
        .then(a.cmp(&b))
}

/// Vertices sorted by (f, index).
fn sorted_order(f: &[f64]) -> Vec<u32> {
    let mut order: Vec<u32> = (0..f.len() as u32).collect();
    order.par_sort_unstable_by(|&a, &b| compare(f, a, b));
    order
}

/// rank[v] = position of v in the order (f, index); comparing ranks is comparing (f, index).
fn ranks(f: &[f64]) -> Vec<u32> {
    let order = sorted_order(f);
    let mut rank = vec![0u32; f.len()];
    for (r, &v) in order.iter().enumerate() {
        rank[v as usize] = r as u32;
    }
    rank
}

// ---------------------------------------------------------------------------------------------
// Connectivity: vertex → triangles and vertex → neighbours, both in CSR form.

// ---------------------------------------------------------------------------------------------
// Link rule.

/// Reusable per-thread buffers for [`classify_vertex`].
#[derive(Default)]
struct LinkScratch {
    edges: Vec<(u32, u32)>,
    vertices: Vec<u32>,
    links: crate::graph::UnionFind,
}

/// Classifies v by the number of sign changes along its link (see [`critical_points`]).
///
/// The link is checked to be one cycle or one path without ordering it: every link vertex
/// must lie on at most two link edges, and the link graph must be connected (local
/// union–find). The sign changes along the ordered link are then simply the link edges
/// whose two ends lie on different sides of v.
fn classify_vertex(
    v: u32,
    incidence: &crate::graph::VertexFaces,
    faces: &[[u32; 3]],
    rank: &[u32],
    scratch: &mut LinkScratch,
) -> Result<Option<CriticalKind>, MeshError> {
    let incident = incidence.of(v);
    if incident.is_empty() {
        return Err(MeshError::UnreferencedVertex { vertex: v as usize });
    }
    scratch.edges.clear();
    for &fi in incident {
        let [a, b, c] = faces[fi as usize];
        if a == b || b == c || a == c {
            return Err(MeshError::RepeatedIndex {
                face: fi as usize,
                vertices: vec![a, b, c],
            });
        }
        let edge = if a == v {
            (b, c)
        } else if b == v {
            (c, a)
        } else {
            (a, b)
        };
        scratch.edges.push(edge);
    }

    // Link vertices with their number of link edges (= triangles on the edge v–w).
    scratch.vertices.clear();
    scratch.vertices.extend(scratch.edges.iter().flat_map(|&(a, b)| [a, b]));
    scratch.vertices.sort_unstable();
    let mut n_ends = 0usize;
    let mut manifold = true;
    let mut i = 0;
    while i < scratch.vertices.len() {
        let w = scratch.vertices[i];
        let mut j = i;
        while j < scratch.vertices.len() && scratch.vertices[j] == w {
            j += 1;
        }
        match j - i {
            1 => n_ends += 1,
            2 => {}
            _ => manifold = false,
        }
        i = j;
    }
    scratch.vertices.dedup();

    // Connectivity of the link graph by union–find on local indices.
    let m = scratch.vertices.len();
    scratch.links.reset(m);
    let mut components = m;
    for &(a, b) in &scratch.edges {
        // Both ends are in `vertices` by construction.
        let ia = scratch.vertices.binary_search(&a).unwrap_or(0);
        let ib = scratch.vertices.binary_search(&b).unwrap_or(0);
        if scratch.links.union(ia as u32, ib as u32) {
            components -= 1;
        }
    }
    let rv = rank[v as usize];
    let lower = |w: u32| rank[w as usize] < rv;
    if !manifold || components != 1 {
        return Ok(None);
    }
    // Connected with all degrees ≤ 2: a cycle (no ends) or a path (two ends).
    let closed = n_ends == 0;

    let changes = scratch.edges.iter().filter(|&&(a, b)| lower(a) != lower(b)).count();
    let extremum = || {
        if lower(scratch.edges[0].0) {
            CriticalKind::Maximum
        } else {
            CriticalKind::Minimum
        }
    };
    Ok(Some(match (closed, changes) {
        (_, 0) => extremum(),
        (true, 2) | (false, 1) => CriticalKind::Regular,
        (true, s) => CriticalKind::Saddle {
            multiplicity: s / 2 - 1,
        },
        (false, s) => CriticalKind::Saddle { multiplicity: s - 1 },
    }))
}

/// The kinds of all vertices of a mesh that is not a surface, on its edge graph (see
/// [`critical_points`]): extrema by their neighbours, saddles by the components that die at
/// them in the persistence sweeps.
fn classify_on_the_graph(mesh: &TriMesh, f: &[f64], rank: &[u32]) -> Result<Vec<CriticalKind>, MeshError> {
    let adjacency = crate::graph::VertexNeighbours::new(mesh.n_vertices(), mesh.faces());
    let diagram = persistence(mesh, f)?;
    let mut deaths = [vec![0usize; f.len()], vec![0usize; f.len()]];
    for (counts, pairs) in deaths.iter_mut().zip([&diagram.minima, &diagram.maxima]) {
        for death in pairs.iter().filter_map(|p| p.death) {
            counts[death as usize] += 1;
        }
    }
    Ok((0..f.len())
        .map(|v| {
            let rv = rank[v];
            let neighbours = adjacency.of(v as u32);
            if neighbours.iter().all(|&w| rank[w as usize] > rv) {
                CriticalKind::Minimum
            } else if neighbours.iter().all(|&w| rank[w as usize] < rv) {
                CriticalKind::Maximum
            } else {
                match deaths[0][v].max(deaths[1][v]) {
                    0 => CriticalKind::Regular,
                    multiplicity => CriticalKind::Saddle { multiplicity },
                }
            }
        })
        .collect())
}

// ---------------------------------------------------------------------------------------------
// Persistence sweep.

#[derive(Clone, Copy)]
enum Direction {
    Sublevel,
    Superlevel,
}

/// Union–find sweep over `order`; `rank[v]` is the position of v in `order`.
fn sweep(
    order: impl Iterator<Item = u32>,
    rank: &[u32],
    adjacency: &crate::graph::VertexNeighbours,
    f: &[f64],
    direction: Direction,
) -> Vec<PersistencePair> {
    const UNSEEN: u32 = u32::MAX;
    let n = f.len();
    // parent[v] = UNSEEN until v is swept. For a root r: oldest[r] is the extremum that created
    // the component and newest[r] its last swept vertex (the opposite extremum so far).
    let mut parent = vec![UNSEEN; n];
    let mut size = vec![1u32; n];
    let mut oldest = vec![0u32; n];
    let mut newest = vec![0u32; n];
    let mut pairs = Vec::new();
    let mut roots: Vec<u32> = Vec::new();
    let persistence = |birth: u32, death: u32| match direction {
        Direction::Sublevel => f[death as usize] - f[birth as usize],
        Direction::Superlevel => f[birth as usize] - f[death as usize],
    };

    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            let p = parent[v as usize];
            parent[v as usize] = parent[p as usize];
            v = p;
        }
        v
    }

    for v in order {
        roots.clear();
        for &w in adjacency.of(v) {
            if parent[w as usize] != UNSEEN {
                roots.push(root(&mut parent, w));
            }
        }
        roots.sort_unstable();
        roots.dedup();
        parent[v as usize] = v;
        oldest[v as usize] = v;
        newest[v as usize] = v;
        let Some(&elder) = roots.iter().min_by_key(|&&r| rank[oldest[r as usize] as usize]) else {
            continue; // v is an extremum and starts a component.
        };
        let mut merged = elder;
        for &r in &roots {
            if r != elder {
                let birth = oldest[r as usize];
                pairs.push(PersistencePair {
                    birth,
                    death: Some(v),
                    birth_value: f[birth as usize],
                    death_value: Some(f[v as usize]),
                    persistence: persistence(birth, v),
                });
            }
        }
        // Union by size; the merged root keeps the elder extremum.
        for &r in roots.iter().chain([v].iter()) {
            if r == merged {
                continue;
            }
            let (big, small) = if size[merged as usize] >= size[r as usize] {
                (merged, r)
            } else {
                (r, merged)
            };
            parent[small as usize] = big;
            size[big as usize] += size[small as usize];
            merged = big;
        }
        oldest[merged as usize] = oldest[elder as usize];
        newest[merged as usize] = v;
    }
    for v in 0..n as u32 {
        if parent[v as usize] == v {
            let (birth, top) = (oldest[v as usize], newest[v as usize]);
            pairs.push(PersistencePair {
                birth,
                death: None,
                birth_value: f[birth as usize],
                death_value: None,
                persistence: persistence(birth, top),
            });
        }
    }
    pairs.sort_by(|a, b| {
        b.persistence
            .total_cmp(&a.persistence)
            .then(a.death.is_some().cmp(&b.death.is_some()))
            .then(a.birth.cmp(&b.birth))
    });
    pairs
}
