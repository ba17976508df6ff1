//! Intrinsic triangulations and the robust Laplacian (Sharp & Crane, "A Laplacian for
//! Nonmanifold Triangle Meshes", SGP 2020).
//!
//! An [`IntrinsicTriangulation`] is a closed, oriented triangulation given by its
//! combinatorics and its edge lengths only (no vertex positions): the metric of a surface
//! made of flat triangles. Its faces need not be embedded, two faces may share more than one
//! edge and an edge may join a vertex to itself — everything a sequence of intrinsic edge
//! flips produces. [`IntrinsicTriangulation::flip_to_delaunay`] flips edges until every edge
//! is Delaunay (the two angles opposite it sum to at most π), which makes the cotangent L an
//! M-matrix: off-diagonal entries ≤ 0, so the lumped heat kernel is never negative.
//!
//! The robust Laplacian of a mesh ([`crate::Laplacian::Robust`]) is built in three steps:
//! 1. **mollification** ([`tufted::mollify`]): all edge lengths grow by the smallest ε ≥ 0
//!    that leaves every triangle a margin δ in its triangle inequalities;
//! 2. the **tufted cover** ([`tufted::tufted_cover`]): every face is doubled into a front and
//!    a back sheet, and around each edge the sheets are glued in the angular order of the
//!    faces, so any triangle soup becomes a closed oriented manifold;
//! 3. **intrinsic Delaunay flips** on the cover, then L, B, D on the flipped triangulation
//!    ([`assembly`]), halved because the cover has every face twice.
//!
//! Faces are implicit: triangle f owns the half-edges 3f, 3f + 1, 3f + 2 (in order around the
//! face), half-edge h runs from `tail[h]` to `tail[next(h)]` and is glued to `twin[h]`.

pub(crate) mod assembly;
pub(crate) mod tufted;

use crate::laplacian::RobustParams;
use crate::operators::{AssemblyParams, FemOperators};
use crate::{MeshError, TriMesh};
use std::collections::VecDeque;

/// The Delaunay tolerance of the flips: an edge is flipped when its cotangent weight
/// `½(cot α + cot β)` is below −1e-6 (geometry-central's `flipToDelaunay` default, so
/// near-cocircular quads are left as they are, as robust_laplacian leaves them).
pub const DELAUNAY_TOLERANCE: f64 = 1e-6;

/// A closed, oriented intrinsic triangulation: combinatorics and edge lengths (see the module
/// documentation).
#[derive(Clone, Debug)]
pub struct IntrinsicTriangulation {
    n_vertices: usize,
    /// The vertices of each triangle: half-edge 3t + k runs from corner k to corner k + 1.
    triangles: Vec<[u32; 3]>,
    /// The half-edge glued to each half-edge (an involution without fixed points).
    twin: Vec<u32>,
    /// Edge lengths of each triangle (entry k: the half-edge 3t + k; equal on both
    /// half-edges of an edge), divided by 2^`scale` so that lengths are of order one.
    lengths: Vec<[f64; 3]>,
    /// Binary exponent of the stored lengths: true length = `length · 2^scale` (exact).
    scale: i32,
}

/// The half-edge after `h` in its triangle.
#[inline]
fn next(h: usize) -> usize {
    if h % 3 == 2 {
        h - 2
    } else {
        h + 1
    }
}

/// Area of a triangle with edge lengths a, b, c (Kahan's stable form of Heron's formula);
/// 0 when the lengths violate a triangle inequality.
#[inline]
pub(crate) fn triangle_area(a: f64, b: f64, c: f64) -> f64 {
    // Sort a ≥ b ≥ c.
    let (mut a, mut b, mut c) = (a, b, c);
    if a < b {
        std::mem::swap(&mut a, &mut b);
    }
    if b < c {
        std::mem::swap(&mut b, &mut c);
    }
    if a < b {
        std::mem::swap(&mut a, &mut b);
    }
    let p = (a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c));
    if p > 0.0 {
        0.25 * p.sqrt()
    } else {
        0.0
    }
}

/// The cotangent of the angle opposite side `c` in a triangle with sides a, b, c and area
/// `area` (law of cosines: `(a² + b² − c²) / 4|T|`).
#[inline]
pub(crate) fn cot_opposite(a: f64, b: f64, c: f64, area: f64) -> f64 {
    (a * a + b * b - c * c) / (4.0 * area)
}

impl IntrinsicTriangulation {
    /// Builds a triangulation from its half-edge arrays (crate-internal; the builders
    /// guarantee a closed oriented gluing).
    pub(crate) fn from_parts(
        n_vertices: usize,
        triangles: Vec<[u32; 3]>,
        twin: Vec<u32>,
        lengths: Vec<[f64; 3]>,
        scale: i32,
    ) -> Self {
        debug_assert_eq!(twin.len(), 3 * triangles.len());
        debug_assert_eq!(lengths.len(), triangles.len());
        debug_assert!(twin
            .iter()
            .enumerate()
            .all(|(h, &t)| t as usize != h && twin[t as usize] as usize == h));
        Self {
            n_vertices,
            triangles,
            twin,
            lengths,
            scale,
        }
    }

    /// Tail vertex of half-edge h.
    #[inline]
    fn tail(&self, h: usize) -> u32 {
        self.triangles[h / 3][h % 3]
    }

    /// Stored (scaled) length of half-edge h.
    #[inline]
    fn len(&self, h: usize) -> f64 {
        self.lengths[h / 3][h % 3]
    }

    /// The triangles (crate-internal, for assembly).
    pub(crate) fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The stored (scaled) lengths per triangle and the binary exponent of their scale.
    pub(crate) fn scaled_lengths(&self) -> (&[[f64; 3]], i32) {
        (&self.lengths, self.scale)
    }

    /// The tufted cover of a mesh with mollified edge lengths (steps 1 and 2 of the robust
    /// Laplacian), not yet flipped: 2 triangles per face.
    ///
    /// # Errors
    /// As [`assemble_robust`], except for the flips.
    pub fn tufted_cover(mesh: &TriMesh, robust: &RobustParams) -> Result<Self, MeshError> {
        robust.validate()?;
        check_no_repeated_index(mesh)?;
        tufted::tufted_cover(mesh.positions(), mesh.faces(), robust.mollify_factor)
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }

    /// Number of triangles.
    pub fn n_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// Number of edges (half the number of half-edges: the triangulation is closed).
    pub fn n_edges(&self) -> usize {
        self.twin.len() / 2
    }

    /// The vertices of triangle `t`, in its orientation (a vertex may appear more than once).
    pub fn triangle(&self, t: usize) -> [u32; 3] {
        self.triangles[t]
    }

    /// The edge lengths of triangle `t`: entry k is the length of the edge from corner k to
    /// corner k + 1.
    pub fn triangle_lengths(&self, t: usize) -> [f64; 3] {
        self.lengths[t].map(|l| crate::mesh::mul_pow2(l, self.scale))
    }

    /// The distinct vertex pairs `[a, b]` (a < b) joined by an edge, sorted: the neighbourhood
    /// graph of the triangulation (edges from a vertex to itself are left out).
    pub fn vertex_pairs(&self) -> Vec<[u32; 2]> {
        let mut pairs: Vec<[u32; 2]> = (0..self.twin.len())
            .filter_map(|h| {
                let (a, b) = (self.tail(h), self.tail(next(h)));
                (a < b).then_some([a, b])
            })
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        pairs
    }

    /// The cotangent weight `½ cot θ` of half-edge h, θ the angle opposite it in its
    /// triangle (on the stored, scaled lengths; NaN or infinite for a degenerate triangle).
    #[inline]
    fn half_cot_weight(&self, h: usize) -> f64 {
        let (h1, h2) = (next(h), next(next(h)));
        let (c, a, b) = (self.len(h), self.len(h1), self.len(h2));
        0.5 * cot_opposite(a, b, c, triangle_area(a, b, c))
    }

    /// Whether the edge of half-edge h is Delaunay: `½(cot α + cot β) ≥ −tolerance`.
    /// An edge next to a degenerate triangle counts as Delaunay (it cannot be judged).
    pub fn is_delaunay(&self, h: usize, tolerance: f64) -> bool {
        let w = self.half_cot_weight(h) + self.half_cot_weight(self.twin[h] as usize);
        // NaN (a degenerate triangle) is not judged: not flipped.
        w >= -tolerance || w.is_nan()
    }

    /// Flips edges until every edge is Delaunay (up to `tolerance`, see
    /// [`DELAUNAY_TOLERANCE`]), with a queue seeded by all edges (Sharp & Crane 2020,
    /// Sect. 4.2; the flip lays the two triangles out in the plane, as geometry-central's
    /// Euclidean flip). Returns the number of flips.
    ///
    /// # Errors
    /// [`MeshError::FlipLimit`] after 1000 flips per edge (a safety net: flips towards
    /// Delaunay always terminate in exact arithmetic, and the tolerance keeps rounding from
    /// cycling).
    pub fn flip_to_delaunay(&mut self, tolerance: f64) -> Result<usize, MeshError> {
        let n_half = self.twin.len();
        let n_edges = n_half / 2;
        // queued[h]: an entry for half-edge h is pending. Every edge that may need a check has
        // a pending entry on one of its half-edges; a flip only permutes the contents of the
        // four half-edges around it, and all four are (re)queued.
        let mut queued = vec![false; n_half];
        let mut queue: VecDeque<u32> = VecDeque::with_capacity(n_edges);
        for (h, (&t, q)) in self.twin.iter().zip(queued.iter_mut()).enumerate() {
            if h < t as usize {
                *q = true;
                queue.push_back(h as u32);
            }
        }
        let limit = n_edges.saturating_mul(1000).max(1000);
        let mut flips = 0usize;
        while let Some(h) = queue.pop_front() {
            let h = h as usize;
            queued[h] = false;
            if self.is_delaunay(h, tolerance) || !self.flip(h) {
                continue;
            }
            flips += 1;
            if flips > limit {
                return Err(MeshError::FlipLimit { flips, n_edges });
            }
            let t = self.twin[h] as usize;
            for s in [next(h), next(next(h)), next(t), next(next(t))] {
                if !queued[s] && !queued[self.twin[s] as usize] {
                    queued[s] = true;
                    queue.push_back(s as u32);
                }
            }
        }
        Ok(flips)
    }

    /// Flips the edge of half-edge h (u→v in triangle (u, v, c), its twin v→u in (v, u, d))
    /// into the edge c–d. Returns `false` (and changes nothing) when the edge cannot be
    /// flipped: both half-edges in one triangle, or a new length that is not a positive
    /// finite number.
    fn flip(&mut self, h: usize) -> bool {
        let t = self.twin[h] as usize;
        if h / 3 == t / 3 {
            return false;
        }
        let (a1, a2, b1, b2) = (next(h), next(next(h)), next(t), next(next(t)));
        let (l_uv, l_vc, l_cu, l_ud, l_dv) = (self.len(h), self.len(a1), self.len(a2), self.len(b1), self.len(b2));
        // Lay the quad out with u at the origin and v on the positive x axis: c above, d below.
        let area_a = triangle_area(l_uv, l_vc, l_cu);
        let area_b = triangle_area(l_uv, l_ud, l_dv);
        let cx = (l_uv * l_uv + l_cu * l_cu - l_vc * l_vc) / (2.0 * l_uv);
        let dx = (l_uv * l_uv + l_ud * l_ud - l_dv * l_dv) / (2.0 * l_uv);
        let cy = 2.0 * area_a / l_uv;
        let dy = -2.0 * area_b / l_uv;
        let new_length = (cx - dx).hypot(cy - dy);
        if !(new_length.is_finite() && new_length > 0.0) {
            return false;
        }
        let (c, d) = (self.tail(a2), self.tail(b2));
        // New triangles: (d, c, u) in slots (h, a1, a2) = (new, old a2, old b1) and
        // (c, d, v) in slots (t, b1, b2) = (new, old b2, old a1).
        let moves = [(a2, a1), (b1, a2), (b2, b1), (a1, b2)];
        let old = moves.map(|(from, _)| (self.tail(from), self.twin[from], self.len(from)));
        let relocate = |x: usize| moves.iter().find(|&&(from, _)| from == x).map_or(x, |&(_, to)| to);
        for (&(_, to), &(tail, twin, length)) in moves.iter().zip(&old) {
            let twin = relocate(twin as usize);
            self.triangles[to / 3][to % 3] = tail;
            self.lengths[to / 3][to % 3] = length;
            self.twin[to] = twin as u32;
            self.twin[twin] = to as u32;
        }
        self.triangles[h / 3][h % 3] = d;
        self.triangles[t / 3][t % 3] = c;
        self.lengths[h / 3][h % 3] = new_length;
        self.lengths[t / 3][t % 3] = new_length;
        true
    }

    /// L, B and D on this triangulation, each multiplied by `weight` (½ for a tufted cover,
    /// where every face is there twice): see [`assembly`].
    ///
    /// # Errors
    /// [`MeshError::DegenerateIntrinsicTriangle`] for a triangle of zero or non-finite area,
    /// [`MeshError::UnreferencedVertex`] for a vertex in no triangle.
    pub fn operators(&self, weight: f64, params: &AssemblyParams) -> Result<FemOperators, MeshError> {
        assembly::assemble(self, weight, params.lumping)
    }
}

/// The robust Laplacian of a mesh ([`crate::Laplacian::Robust`]): mollification, tufted
/// cover, intrinsic Delaunay flips, then L, B, D on the flipped cover, halved (every face of
/// the cover is there twice). Returns the operators and the number of flips.
///
/// On a closed manifold mesh whose triangulation is already (intrinsically) Delaunay and
/// whose triangles are not within δ of degenerate, the cover is two copies of the mesh,
/// nothing is flipped and L, B, D are the cotangent operators of [`crate::assemble`].
///
/// # Errors
/// * [`MeshError::InvalidParameter`] for a bad mollification factor;
/// * [`MeshError::RepeatedIndex`] for a face that repeats a vertex (not a triangle; drop such
///   faces with [`crate::validate::repair`]'s `degenerate` option);
/// * [`MeshError::UnreferencedVertex`] for a vertex that belongs to no face;
/// * [`MeshError::DegenerateIntrinsicTriangle`] for a flat face when mollification is off;
/// * [`MeshError::DegenerateMesh`] for a mesh whose edges are all of length zero or whose
///   area overflows;
/// * [`MeshError::Invalid`] for a mesh of more than 2³² / 6 faces.
pub fn assemble_robust(
    mesh: &TriMesh,
    robust: &RobustParams,
    params: &AssemblyParams,
) -> Result<(FemOperators, usize), MeshError> {
    let (cover, flips) = robust_triangulation(mesh, robust)?;
    let ops = cover.operators(ROBUST_WEIGHT, params)?;
    Ok((ops, flips))
}

/// The weight of every triangle of a tufted cover in its operators (each face is there twice).
pub const ROBUST_WEIGHT: f64 = 0.5;

/// The triangulation the robust Laplacian is assembled on: the mollified tufted cover of the
/// mesh flipped to intrinsic Delaunay, and the number of flips. Its operators with
/// [`ROBUST_WEIGHT`] are those of [`assemble_robust`]; what needs more than L, B and D (the
/// gradients of [`crate::gradient`], the triangles of a distance computation) starts here.
///
/// # Errors
/// As [`assemble_robust`].
pub fn robust_triangulation(
    mesh: &TriMesh,
    robust: &RobustParams,
) -> Result<(IntrinsicTriangulation, usize), MeshError> {
    let mut cover = IntrinsicTriangulation::tufted_cover(mesh, robust)?;
    let flips = cover.flip_to_delaunay(DELAUNAY_TOLERANCE)?;
    Ok((cover, flips))
}

/// [`MeshError::RepeatedIndex`] for the first face that repeats a vertex.
fn check_no_repeated_index(mesh: &TriMesh) -> Result<(), MeshError> {
    match mesh
        .faces()
        .iter()
        .enumerate()
        .find(|(_, f)| f[0] == f[1] || f[1] == f[2] || f[2] == f[0])
    {
        Some((face, f)) => Err(MeshError::RepeatedIndex {
            face,
            vertices: f.to_vec(),
        }),
        None => Ok(()),
    }
}
