//! Geodesic distances on meshes and point clouds, from vertices or points on faces (beyond the
//! paper, which uses the heat kernel for diffusion distances, Eq. (18)). Two methods
//! ([`GeodesicMethod`]), both on the robust intrinsic Delaunay triangulation of the tufted cover
//! by default (Sharp & Crane 2020; without it a mesh with obtuse triangles gets wrong
//! distances), or on the mesh's own triangles with `Laplacian::Cotan`:
//!
//! * **fast marching** (the default): the discrete eikonal equation solved by accepting vertices
//!   in order of distance ([`eikonal`] module docs), with every source's one-ring fixed at its
//!   exact edge lengths. No factorization; O(n log n) per query. Its mean relative error against
//!   exact polyhedral geodesics is 0.1–0.3 times the heat method's on the shared corpus
//!   (docs/BENCHMARKS.md).
//! * **heat** (Crane, Weischedel & Wardetzky 2013 — what potpourri3d, geometry-central and libigl
//!   compute):
//!   1. one backward-Euler step `u = (D + tL)⁻¹ δ_S` with the lumped mass D — the step the method
//!      is defined with, *not* the exact kernel K_t of the rest of wfem: K_t's far field decays
//!      like `exp(−d²/4t)` and underflows some 50 edges from the source at t = h², while the
//!      resolvent decays like `exp(−d/√t)`. `t = c·h²`, h the mean edge length of the
//!      triangulation the operators live on, c = `t_coef` (1 by default, the peers' convention);
//!   2. `X = −∇u/|∇u|` per triangle ([`mesh_fem::gradient`]) from u rescaled by its largest value
//!      on the triangle, so it stays defined where u is tiny; where u has underflowed to 0 (or
//!      is constant on a triangle) X = 0, never 0/0 (counted in [`GeodesicReport::heat_underflow`]);
//!   3. `L φ = ∇·X` (the integrated divergence `Σ|T| X·∇φᵢ`) with φ pinned to 0 on **every**
//!      source vertex (to the exact in-face distances on the corners of a source point), so that
//!      distances from many sources are right near each of them.
//!
//!   Both factorizations (`D + tL` and the grounded L) are made once and reused by every query.
//!
//! `refine` splits every triangle into four at its edge midpoints that many times first (the
//! same surface, a finer triangulation; distances are returned at the mesh's own vertices): the
//! most accurate option. Vertices of a connected component that holds no source are
//! unreachable: their distance is `f64::INFINITY` (counted in [`GeodesicReport::unreachable`]),
//! never NaN.

mod eikonal;
mod poisson;

use crate::{HeatError, Operators};
use eikonal::Eikonal;
use mesh_fem::cloud::{CloudParams, PointCloud};
use mesh_fem::gradient::ElementGradients;
use mesh_fem::graph::VertexNeighbours;
use mesh_fem::intrinsic::{robust_triangulation, IntrinsicTriangulation, ROBUST_WEIGHT};
use mesh_fem::vec3::{norm, sub};
use mesh_fem::{AssemblyParams, Laplacian, Lumping, Mass, TriMesh};
use poisson::Poisson;
use rayon::prelude::*;
use shifted_solve::SpdFactor;

/// u below this (in reached components) counts as underflowed ([`GeodesicReport::heat_underflow`]).
const UNDERFLOW: f64 = 1e-280;

/// How geodesic distances are computed (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GeodesicMethod {
    /// Fast marching on the (intrinsic Delaunay) triangles, one-rings exact.
    #[default]
    FastMarching,
    /// The heat method of Crane et al. 2013.
    Heat,
}

wfem_base::registry! {
    GeodesicMethod as "geodesic method" {
        GeodesicMethod::FastMarching = GeodesicMethod::FastMarching => "fast-marching" ["fmm", "eikonal"]:
            "fast marching on the intrinsic Delaunay triangulation, one-rings at their exact edge lengths; 3-10x the heat method's accuracy, no factorization (default)",
        GeodesicMethod::Heat = GeodesicMethod::Heat => "heat" ["heat-method"]:
            "the heat method (Crane et al. 2013; = potpourri3d, geometry-central): t = t_coef * h^2, one backward-Euler solve, one pinned Poisson solve",
    }
}
/// Most midpoint refinements (each multiplies the vertices by about 4).
pub const MAX_REFINE: u32 = 3;

/// Midpoint refinements by default: none (the mesh as given).
pub const DEFAULT_REFINE: u32 = 0;

/// How a [`GeodesicSolver`] is prepared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeodesicParams {
    /// The method (default fast marching).
    pub method: GeodesicMethod,
    /// c in t = c·h² (h the mean edge length) of the heat method. Default 1, potpourri3d's
    /// `t_coef`. Checked (finite, > 0) for every method, used by the heat method only.
    pub t_coef: f64,
    /// The triangulation (and, for the heat method, its Laplacian). Default: robust, the
    /// intrinsic Delaunay cover (potpourri3d's `use_robust=True`); cotan: the mesh's own.
    pub laplacian: Laplacian,
    /// Midpoint refinements of the mesh before anything else (default [`DEFAULT_REFINE`], at
    /// most [`MAX_REFINE`]).
    pub refine: u32,
}

impl Default for GeodesicParams {
    fn default() -> Self {
        Self {
            method: GeodesicMethod::default(),
            t_coef: DEFAULT_T_COEF,
            laplacian: Laplacian::Robust(mesh_fem::RobustParams::default()),
            refine: DEFAULT_REFINE,
        }
    }
}

/// The default `t_coef`.
pub const DEFAULT_T_COEF: f64 = 1.0;

/// A source: a vertex, or a point on a face given by its barycentric coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Source {
    /// A vertex of the mesh (or a point of the cloud).
    Vertex(u32),
    /// The point `Σ barycentric[k] · corner k` of a face of the mesh (coordinates ≥ 0 summing to
    /// 1; they are normalised).
    Point {
        /// Face index.
        face: u32,
        /// Barycentric coordinates of the face's three corners.
        barycentric: [f64; 3],
    },
}

/// What a distance computation met.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GeodesicReport {
    /// Vertices in components without a source (distance ∞).
    pub unreachable: usize,
    /// Reached vertices where the heat method's u underflowed (below 1e-280): its direction is
    /// lost there and the distances are unreliable (the heat method only; use fast marching).
    pub heat_underflow: usize,
}

/// Prepared heat-method geodesics on one mesh or cloud (see the module docs).
pub struct GeodesicSolver {
    /// Vertices the caller sees (the mesh's own; a refined mesh appends its midpoints).
    n: usize,
    /// The faces the caller's points refer to, and the refinements applied.
    user_faces: Vec<[u32; 3]>,
    refine: u32,
    /// The (refined) surface: positions for exact distances of the one-rings and face points.
    surface: TriMesh,
    ring: VertexNeighbours,
    h: f64,
    prepared: Prepared,
    params: GeodesicParams,
}

/// What each method prepares.
enum Prepared {
    FastMarching(Eikonal),
    Heat(Box<HeatMethod>),
}

/// The heat method's factorizations and gradients.
struct HeatMethod {
    t: f64,
    heat: SpdFactor,
    poisson: Poisson,
    gradients: ElementGradients,
}

impl std::fmt::Debug for GeodesicSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GeodesicSolver")
            .field("n_vertices", &self.n)
            .field("mean_edge_length", &self.h)
            .field("params", &self.params)
            .finish_non_exhaustive()
    }
}

/// The elements a method works on: an intrinsic cover, the mesh's own triangles, or the
/// tetrahedra of a volume (the heat method only).
enum Triangles<'a> {
    Intrinsic(&'a IntrinsicTriangulation),
    Mesh(&'a TriMesh),
    Volume(&'a mesh_fem::volume::TetMesh),
}

impl Triangles<'_> {
    fn n_vertices(&self) -> usize {
        match self {
            Triangles::Intrinsic(t) => t.n_vertices(),
            Triangles::Mesh(m) => m.n_vertices(),
            Triangles::Volume(v) => v.n_vertices(),
        }
    }

    /// The mean edge length h.
    fn mean_edge_length(&self) -> f64 {
        match self {
            Triangles::Intrinsic(t) => mean_intrinsic_length(t),
            Triangles::Mesh(m) => mesh_fem::stats::mean_edge_length(m),
            Triangles::Volume(v) => {
                let mut edges: Vec<[u32; 2]> = v
                    .tets()
                    .iter()
                    .flat_map(|t| (0..4).flat_map(move |a| (a + 1..4).map(move |b| [t[a].min(t[b]), t[a].max(t[b])])))
                    .collect();
                edges.sort_unstable();
                edges.dedup();
                let p = v.positions();
                let total: f64 = edges
                    .iter()
                    .map(|&[a, b]| norm(sub(p[a as usize], p[b as usize])))
                    .sum();
                total / edges.len().max(1) as f64
            }
        }
    }

    fn eikonal(&self) -> Result<Eikonal, HeatError> {
        Ok(match self {
            Triangles::Intrinsic(tri) => {
                let (t, l) = distinct_triangles(tri);
                Eikonal::new(tri.n_vertices(), &t, |k| l[k])
            }
            Triangles::Mesh(m) => {
                let l = mesh_lengths(m);
                Eikonal::new(m.n_vertices(), m.faces(), |k| l[k])
            }
            Triangles::Volume(_) => {
                return Err(HeatError::InvalidParameter {
                    name: "method",
                    reason: "fast marching is implemented on triangles; use the heat method on a volume".into(),
                })
            }
        })
    }

    /// L and the lumped barycentric D, and the gradients of the same triangles.
    fn operators(&self) -> Result<(mesh_fem::FemOperators, ElementGradients), HeatError> {
        Ok(match self {
            Triangles::Intrinsic(tri) => (
                tri.operators(ROBUST_WEIGHT, &lumped())?,
                ElementGradients::of_intrinsic(tri, ROBUST_WEIGHT)?,
            ),
            Triangles::Mesh(m) => (
                mesh_fem::assemble(
                    m,
                    &AssemblyParams {
                        laplacian: Laplacian::Cotan,
                        ..lumped()
                    },
                )?,
                ElementGradients::of_mesh(m),
            ),
            Triangles::Volume(v) => (
                mesh_fem::volume::assemble_volume(
                    v,
                    &AssemblyParams {
                        laplacian: Laplacian::Cotan,
                        ..lumped()
                    },
                )?,
                ElementGradients::of_volume(v)?,
            ),
        })
    }
}

fn check_params(params: &GeodesicParams) -> Result<(), HeatError> {
    if !(params.t_coef.is_finite() && params.t_coef > 0.0) {
        return Err(HeatError::InvalidParameter {
            name: "t_coef",
            reason: format!("{} must be finite and > 0", params.t_coef),
        });
    }
    if params.refine > MAX_REFINE {
        return Err(HeatError::InvalidParameter {
            name: "refine",
            reason: format!(
                "{} refinements asked for, at most {MAX_REFINE} are allowed",
                params.refine
            ),
        });
    }
    if let Laplacian::Robust(r) = params.laplacian {
        r.validate()?;
    }
    Ok(())
}

/// Mean length over the half-edges of an intrinsic triangulation (each edge twice).
fn mean_intrinsic_length(tri: &IntrinsicTriangulation) -> f64 {
    let m = tri.n_triangles();
    let total: f64 = (0..m).map(|t| tri.triangle_lengths(t).iter().sum::<f64>()).sum();
    if m == 0 {
        0.0
    } else {
        total / (3 * m) as f64
    }
}

/// The triangles of an intrinsic triangulation, each once: a tufted cover holds the faces of a
/// manifold part twice (its two sheets), which would double the work of fast marching.
fn distinct_triangles(tri: &IntrinsicTriangulation) -> (Vec<[u32; 3]>, Vec<[f64; 3]>) {
    let mut keyed: Vec<([u32; 3], [u64; 3], usize)> = (0..tri.n_triangles())
        .map(|t| {
            let mut v = tri.triangle(t);
            v.sort_unstable();
            let mut l = tri.triangle_lengths(t).map(f64::to_bits);
            l.sort_unstable();
            (v, l, t)
        })
        .collect();
    keyed.sort_unstable();
    keyed.dedup_by(|a, b| a.0 == b.0 && a.1 == b.1);
    keyed.sort_unstable_by_key(|k| k.2);
    (
        keyed.iter().map(|k| tri.triangle(k.2)).collect(),
        keyed.iter().map(|k| tri.triangle_lengths(k.2)).collect(),
    )
}

fn mesh_lengths(mesh: &TriMesh) -> Vec<[f64; 3]> {
    let p = mesh.positions();
    mesh.faces()
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|v| p[v as usize]);
            [norm(sub(b, a)), norm(sub(c, b)), norm(sub(a, c))]
        })
        .collect()
}

fn lumped() -> AssemblyParams {
    AssemblyParams::for_mass(Mass::Lumped(Lumping::Barycentric))
}

/// The heat method's factorizations on a triangulation.
fn prepare_heat(triangles: &Triangles<'_>, t_coef: f64) -> Result<HeatMethod, HeatError> {
    let (fem, gradients) = triangles.operators()?;
    let ops = Operators::new(&fem, Mass::Lumped(Lumping::Barycentric))?;
    let h = triangles.mean_edge_length();
    let t = t_coef * h * h;
    if !(t > 0.0 && t.is_finite()) {
        return Err(HeatError::InvalidParameter {
            name: "t_coef",
            reason: format!("t = t_coef·h² = {t} (mean edge length {h}) is not a usable time"),
        });
    }
    let pair = ops.pair();
    let heat = pair
        .factor_spd(t, 1.0, || shifted_solve::SolveError::MassNotPositiveDefinite {
            detail: "D + tL of the heat method".into(),
        })
        .map_err(|_| HeatError::NotPositiveDefinite {
            matrix: "D + tL of the heat method".into(),
        })?;
    let poisson = Poisson::new(pair.stiffness(), pair.cholesky()?, ops.components())?;
    Ok(HeatMethod {
        t,
        heat,
        poisson,
        gradients,
    })
}

/// The method's preparation on a triangulation, and the mean edge length.
fn prepare(triangles: &Triangles<'_>, params: &GeodesicParams) -> Result<(f64, Prepared), HeatError> {
    let h = triangles.mean_edge_length();
    if !(h > 0.0 && h.is_finite()) || triangles.n_vertices() == 0 {
        return Err(HeatError::InvalidParameter {
            name: "mesh",
            reason: format!("its mean edge length is {h}: no distances can be measured"),
        });
    }
    let prepared = match params.method {
        GeodesicMethod::FastMarching => {
            if let Triangles::Mesh(m) = triangles {
                // The cotangent path refuses what assembly refuses (e.g. degenerate faces).
                mesh_fem::assemble(
                    m,
                    &AssemblyParams {
                        laplacian: Laplacian::Cotan,
                        ..lumped()
                    },
                )?;
            }
            Prepared::FastMarching(triangles.eikonal()?)
        }
        GeodesicMethod::Heat => Prepared::Heat(Box::new(prepare_heat(triangles, params.t_coef)?)),
    };
    Ok((h, prepared))
}

impl GeodesicSolver {
    /// Prepares the solver on a mesh: the triangulation, and for the heat method both
    /// factorizations and the gradients.
    ///
    /// # Errors
    /// [`HeatError::InvalidParameter`] for a bad `t_coef` or `refine`; [`HeatError::Mesh`] from
    /// the triangulation (e.g. a degenerate face with the cotangent Laplacian);
    /// [`HeatError::NotPositiveDefinite`] if a factorization fails.
    pub fn new(mesh: &TriMesh, params: &GeodesicParams) -> Result<Self, HeatError> {
        check_params(params)?;
        let mut surface = mesh.clone();
        for _ in 0..params.refine {
            surface = mesh_fem::refine::split_faces(&surface);
        }
        let cover;
        let triangles = match params.laplacian {
            Laplacian::Robust(robust) => {
                cover = robust_triangulation(&surface, &robust)?.0;
                Triangles::Intrinsic(&cover)
            }
            Laplacian::Cotan => Triangles::Mesh(&surface),
        };
        let (h, prepared) = prepare(&triangles, params)?;
        Ok(Self::finish(
            mesh.n_vertices(),
            mesh.faces().to_vec(),
            surface,
            h,
            prepared,
            *params,
        ))
    }

    /// Prepares the solver on a point cloud: the intrinsic Delaunay cover of its local
    /// triangulations ([`mesh_fem::cloud::cloud_triangulation`]), as potpourri3d's
    /// `PointCloudHeatSolver`. Sources are points (`Source::Vertex`); the Laplacian of `params`
    /// is ignored (a cloud has only the robust one) and `refine` must be 0.
    ///
    /// # Errors
    /// As [`Self::new`], and the cloud's ([`mesh_fem::cloud::assemble_cloud`]).
    pub fn from_cloud(
        cloud: &PointCloud,
        params: &GeodesicParams,
        cloud_params: &CloudParams,
    ) -> Result<Self, HeatError> {
        check_params(params)?;
        if params.refine != 0 {
            return Err(HeatError::InvalidParameter {
                name: "refine",
                reason: "a point cloud cannot be refined; use refine = 0".into(),
            });
        }
        let built = mesh_fem::cloud::cloud_triangulation(cloud, cloud_params)?;
        let (h, prepared) = prepare(&Triangles::Intrinsic(&built.triangulation), params)?;
        Ok(Self::finish(
            cloud.n_points(),
            Vec::new(),
            built.neighbourhood,
            h,
            prepared,
            *params,
        ))
    }

    /// Prepares the heat method on a tetrahedral mesh (fast marching is implemented on
    /// triangles: `params.method` must be `Heat`; `laplacian` and `refine` are not used):
    /// geodesic distances through the solid, with the gradients of the tetrahedra.
    ///
    /// # Errors
    /// [`HeatError::InvalidParameter`] for fast marching or a bad `t_coef`; [`HeatError::Mesh`]
    /// from the assembly ([`mesh_fem::volume::assemble_volume`]).
    pub fn from_volume(mesh: &mesh_fem::volume::TetMesh, params: &GeodesicParams) -> Result<Self, HeatError> {
        check_params(params)?;
        let (h, prepared) = prepare(&Triangles::Volume(mesh), params)?;
        let surface = mesh.boundary_mesh()?;
        Ok(Self::finish(
            mesh.n_vertices(),
            surface.faces().to_vec(),
            surface,
            h,
            prepared,
            *params,
        ))
    }

    fn finish(
        n: usize,
        user_faces: Vec<[u32; 3]>,
        surface: TriMesh,
        h: f64,
        prepared: Prepared,
        params: GeodesicParams,
    ) -> Self {
        let ring = VertexNeighbours::new(surface.n_vertices(), surface.faces());
        Self {
            n,
            user_faces,
            refine: params.refine,
            surface,
            ring,
            h,
            prepared,
            params,
        }
    }

    /// Number of vertices (points) distances are returned for.
    pub fn n_vertices(&self) -> usize {
        self.n
    }

    /// The time t = c·h² of the heat method's step (`None` for fast marching).
    pub fn t(&self) -> Option<f64> {
        match &self.prepared {
            Prepared::Heat(h) => Some(h.t),
            Prepared::FastMarching(_) => None,
        }
    }

    /// The mean edge length h of the triangulation (the unit of t).
    pub fn mean_edge_length(&self) -> f64 {
        self.h
    }

    /// The parameters the solver was prepared with.
    pub fn params(&self) -> &GeodesicParams {
        &self.params
    }

    /// Approximate memory of the prepared solver in bytes: the surface and its one-rings, the
    /// wedges of fast marching with one kept query state, or the heat method's two Cholesky
    /// factors and gradients.
    pub fn memory_bytes(&self) -> usize {
        let n = self.surface.n_vertices();
        let base =
            n * (24 + 8) + self.surface.n_faces() * 12 + self.ring.indices().len() * 4 + self.user_faces.len() * 12;
        base + match &self.prepared {
            Prepared::FastMarching(e) => e.memory_bytes(),
            Prepared::Heat(h) => 8 * 2 * h.heat.n_values() + h.gradients.n_elements() * (12 + 72 + 8) + n * 16,
        }
    }

    /// Geodesic distances from a set of source vertices to every vertex (a vertex's distance is
    /// to the nearest source).
    ///
    /// # Errors
    /// [`HeatError::VertexOutOfRange`] for a source out of range, [`HeatError::InvalidParameter`]
    /// for an empty set; as [`Self::distance_from`].
    pub fn distance(&self, vertices: &[u32]) -> Result<Vec<f64>, HeatError> {
        let sources: Vec<Source> = vertices.iter().map(|&v| Source::Vertex(v)).collect();
        Ok(self.distance_from(&sources)?.0)
    }

    /// Distances from each source vertex separately: row i is the distance from `vertices[i]`
    /// (an |S| × n result, computed in parallel).
    ///
    /// # Errors
    /// As [`Self::distance`].
    pub fn distance_each(&self, vertices: &[u32]) -> Result<Vec<Vec<f64>>, HeatError> {
        if vertices.is_empty() {
            return Err(empty_sources());
        }
        vertices.par_iter().map(|&v| self.distance(&[v])).collect()
    }

    /// [`Self::distance_each`] written into `out` (`|vertices| × n`, row-major) instead of new
    /// vectors: what [`crate::distance::write_rows`] streams an all-pairs matrix with.
    ///
    /// # Errors
    /// As [`Self::distance`]; [`HeatError::LengthMismatch`] if `out` is not `|vertices| × n`.
    pub fn distance_each_into(&self, vertices: &[u32], out: &mut [f64]) -> Result<(), HeatError> {
        if vertices.is_empty() {
            return Err(empty_sources());
        }
        let n = self.n;
        if out.len() != vertices.len() * n {
            return Err(HeatError::LengthMismatch {
                expected: vertices.len() * n,
                found: out.len(),
            });
        }
        out.par_chunks_mut(n)
            .zip(vertices.par_iter())
            .try_for_each(|(row, &v)| {
                row.copy_from_slice(&self.distance(&[v])?);
                Ok(())
            })
    }

    /// Geodesic distances from sources (vertices and points on faces) to every vertex, and what
    /// was met.
    ///
    /// # Errors
    /// [`HeatError::InvalidParameter`] for an empty set, a face out of range or barycentric
    /// coordinates that are not finite, negative or do not sum to 1, a point on a face of zero
    /// area; [`HeatError::VertexOutOfRange`]; [`HeatError::NonFiniteResult`] if a value came out
    /// NaN (never expected); [`HeatError::NotPositiveDefinite`] if the pinned Poisson matrix of a
    /// query with several sources per component fails.
    pub fn distance_from(&self, sources: &[Source]) -> Result<(Vec<f64>, GeodesicReport), HeatError> {
        let seeds = self.seeds(sources)?;
        let mut report = GeodesicReport::default();
        let mut d = match &self.prepared {
            Prepared::FastMarching(eikonal) => {
                let mut d = vec![f64::INFINITY; self.surface.n_vertices()];
                eikonal.march(&seeds.fixed, &mut d);
                d
            }
            Prepared::Heat(heat) => heat.distance(&seeds, self.n, &mut report)?,
        };
        d.truncate(self.n);
        report.unreachable = d.iter().filter(|x| x.is_infinite()).count();
        if let Some(row) = d.iter().position(|x| x.is_nan()) {
            return Err(HeatError::NonFiniteResult {
                method: "geodesic",
                row,
                column: 0,
            });
        }
        Ok((d, report))
    }

    /// The heat step's right-hand side, the Poisson pins and the eikonal step's fixed values.
    fn seeds(&self, sources: &[Source]) -> Result<Seeds, HeatError> {
        if sources.is_empty() {
            return Err(empty_sources());
        }
        let p = self.surface.positions();
        let mut rhs: Vec<(usize, f64)> = Vec::new();
        let mut pins: Vec<(usize, f64)> = Vec::new();
        let mut ring: Vec<(usize, f64)> = Vec::new();
        for source in sources {
            match *source {
                Source::Vertex(v) => {
                    if v as usize >= self.n {
                        return Err(HeatError::VertexOutOfRange {
                            index: v as usize,
                            n_vertices: self.n,
                        });
                    }
                    rhs.push((v as usize, 1.0));
                    pins.push((v as usize, 0.0));
                    for &w in self.ring.of(v) {
                        ring.push((w as usize, norm(sub(p[w as usize], p[v as usize]))));
                    }
                }
                Source::Point { face, barycentric } => {
                    let (corners, w) = self.point_on_face(face, barycentric)?;
                    let x = (0..3).fold([0.0; 3], |acc, k| {
                        let c = p[corners[k] as usize];
                        [acc[0] + w[k] * c[0], acc[1] + w[k] * c[1], acc[2] + w[k] * c[2]]
                    });
                    for k in 0..3 {
                        rhs.push((corners[k] as usize, w[k]));
                        pins.push((corners[k] as usize, norm(sub(p[corners[k] as usize], x))));
                    }
                }
            }
        }
        let pins = merge_min(pins);
        let mut fixed = pins.clone();
        fixed.extend(
            merge_min(ring)
                .into_iter()
                .filter(|(v, _)| pins.binary_search_by(|q| q.0.cmp(v)).is_err()),
        );
        fixed.sort_unstable_by_key(|x| x.0);
        Ok(Seeds { rhs, pins, fixed })
    }

    /// The face of the (refined) surface holding a point of a user face, with its corners and
    /// barycentric coordinates there.
    fn point_on_face(&self, face: u32, barycentric: [f64; 3]) -> Result<([u32; 3], [f64; 3]), HeatError> {
        let faces = if self.user_faces.is_empty() {
            self.surface.faces()
        } else {
            &self.user_faces
        };
        if face as usize >= faces.len() {
            return Err(HeatError::InvalidParameter {
                name: "sources",
                reason: format!("face {face} is out of range: the mesh has {} faces", faces.len()),
            });
        }
        let sum: f64 = barycentric.iter().sum();
        if barycentric.iter().any(|w| !w.is_finite() || *w < -1e-12) || (sum - 1.0).abs() > 1e-6 {
            return Err(HeatError::InvalidParameter {
                name: "sources",
                reason: format!("barycentric coordinates {barycentric:?} of face {face} must be ≥ 0 and sum to 1"),
            });
        }
        let mut w = barycentric.map(|x| x.max(0.0) / sum);
        let mut f = face as usize;
        for _ in 0..self.refine {
            // split_faces: face f becomes [a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca].
            let [wa, wb, wc] = w;
            let (child, nw) = if wa >= 0.5 {
                (0, [2.0 * wa - 1.0, 2.0 * wb, 2.0 * wc])
            } else if wb >= 0.5 {
                (1, [2.0 * wb - 1.0, 2.0 * wc, 2.0 * wa])
            } else if wc >= 0.5 {
                (2, [2.0 * wc - 1.0, 2.0 * wa, 2.0 * wb])
            } else {
                (3, [1.0 - 2.0 * wc, 1.0 - 2.0 * wa, 1.0 - 2.0 * wb])
            };
            f = 4 * f + child;
            w = nw;
        }
        let corners = self.surface.faces()[f];
        let [a, b, c] = corners.map(|v| self.surface.positions()[v as usize]);
        let area = 0.5 * norm(mesh_fem::vec3::cross(sub(b, a), sub(c, a)));
        if !(area > 0.0) {
            return Err(HeatError::InvalidParameter {
                name: "sources",
                reason: format!("face {face} has zero area: a point on it has no distances"),
            });
        }
        Ok((corners, w))
    }
}

impl HeatMethod {
    /// Steps 1–3 of the heat method (module docs).
    fn distance(&self, seeds: &Seeds, n: usize, report: &mut GeodesicReport) -> Result<Vec<f64>, HeatError> {
        let mut rhs = vec![0.0; self.gradients.n_vertices()];
        for &(v, w) in &seeds.rhs {
            rhs[v] += w;
        }
        let u = self.heat.solve_vec(&rhs);
        let g = &self.gradients;
        let field: Vec<[f64; 3]> = (0..g.n_elements())
            .into_par_iter()
            .map(|e| {
                let top = g.corners(e).iter().map(|&v| u[v as usize]).fold(0.0, f64::max);
                if !(top > 0.0 && top.is_finite()) {
                    return [0.0; 3];
                }
                let grad = g.gradient_on(e, |v| u[v as usize] / top);
                let len = norm(grad);
                if len > 0.0 && len.is_finite() {
                    grad.map(|x| -x / len)
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        let b = g.divergence(&field)?;
        let phi = self.poisson.solve(&b, &seeds.pins)?;
        report.heat_underflow = (0..n.min(phi.len()))
            .filter(|&v| phi[v].is_some() && !(u[v] > UNDERFLOW))
            .count();
        Ok(phi.iter().map(|x| x.unwrap_or(f64::INFINITY)).collect())
    }
}

struct Seeds {
    /// The heat step's right-hand side δ_S as (vertex, weight), a vertex possibly repeated.
    rhs: Vec<(usize, f64)>,
    pins: Vec<(usize, f64)>,
    fixed: Vec<(usize, f64)>,
}

/// Sorted by vertex, one entry per vertex with its least value.
fn merge_min(mut list: Vec<(usize, f64)>) -> Vec<(usize, f64)> {
    list.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    list.dedup_by_key(|x| x.0);
    list
}

fn empty_sources() -> HeatError {
    HeatError::InvalidParameter {
        name: "sources",
        reason: "no source given; give at least one vertex".into(),
    }
}

/// Geodesic distances from source vertices on a mesh, with a solver prepared for this one
/// query (prepare a [`GeodesicSolver`] once for several).
///
/// # Errors
/// As [`GeodesicSolver::new`] and [`GeodesicSolver::distance`].
pub fn geodesic_distance(mesh: &TriMesh, sources: &[u32], params: &GeodesicParams) -> Result<Vec<f64>, HeatError> {
    GeodesicSolver::new(mesh, params)?.distance(sources)
}
