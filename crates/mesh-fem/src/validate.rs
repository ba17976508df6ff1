//! Mesh validation and explicit repair.
//!
//! [`validate`] lists every problem of a mesh with a [`Severity`]:
//!
//! | problem | severity | why |
//! |---|---|---|
//! | [`Problem::RepeatedIndex`] | error | the face has zero area; its cotangents are undefined |
//! | [`Problem::ZeroAreaFace`] | error | same (see [`is_degenerate_triangle`] for the threshold) |
//! | [`Problem::UnreferencedVertex`] | error | its row of the mass matrix B is zero, so B is singular |
//! | [`Problem::NonManifoldEdge`] | warning | assembly is per face, so L, B, D still assemble |
//! | [`Problem::NonManifoldVertex`] | warning | same |
//! | [`Problem::DuplicateFace`] | warning | assembles, but the face's area counts twice |
//! | [`Problem::InconsistentOrientation`] | warning | L and B do not depend on orientation; normals do |
//! | [`Problem::NonOrientable`] | warning | same (a Möbius strip still has a Laplacian) |
//! | [`Problem::SeveralComponents`] | warning | L has one zero eigenvalue per component |
//! | [`Problem::Boundary`] | warning | the operators carry natural (Neumann) boundary conditions |
//!
//! The errors are exactly what [`crate::assemble`] rejects, so a mesh is
//! [`ValidationReport::is_usable`] if and only if it assembles.
//!
//! [`repair`] applies only the repairs the caller turns on in [`RepairOptions`] and returns a
//! [`RepairReport`] that says exactly what changed (index maps for vertices and faces).

use crate::mesh::{cross, dot, mul_pow2, neg, norm, scaled_edges, sub, ScaledTriangle};
use crate::topology::{Topology, NONE};
use crate::vec3::bbox_diagonal;
use crate::{MeshError, Remedy, TriMesh};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashMap;
use std::fmt;

/// "1 face", "2 faces".
fn counted(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// Relative area threshold below which a triangle counts as degenerate:
/// a face is degenerate when `|T| ≤ DEGENERATE_AREA_RATIO · ℓ_max²`, with ℓ_max its longest
/// edge (or when its area is not finite).
///
/// The cross product of edge vectors of length ℓ carries a rounding error of about
/// 1e-16·ℓ², so below 1e-14·ℓ² the computed area has no correct digit to speak of and the
/// cotangents (up to ~1e14) would be round-off. The ratio is scale invariant, so a mesh
/// scaled by 1e-6 or 1e6 has exactly the same degenerate faces. An exactly flat face (three
/// collinear or coincident corners) is always degenerate.
pub const DEGENERATE_AREA_RATIO: f64 = 1e-14;

/// Whether a triangle with the given corners is degenerate (zero or numerically zero area):
/// `|T| ≤ DEGENERATE_AREA_RATIO · ℓ_max²`, an area that underflows (below the smallest
/// normal double, ~2.2e−308, where B and D would hold zeros), or an edge that is not finite.
/// (An area that overflows is not degenerate; [`validate`] reports it as
/// [`Problem::AreaOverflow`].)
///
/// The test is computed on the edges scaled by an exact power of two, so it is exactly
/// scale invariant: a triangle with edges of 1e100 or 1e−160 is judged like the same
/// triangle with unit edges (an unscaled cross product would overflow or underflow there).
///
/// This is the one test used by both [`validate`] and [`crate::assemble`], so the two agree.
#[inline]
pub fn is_degenerate_triangle(corners: [[f64; 3]; 3]) -> bool {
    // None: coincident corners, or an edge that is not finite.
    ScaledTriangle::new(corners).is_none_or(|t| is_degenerate_scaled(&t))
}

/// [`is_degenerate_triangle`] on an already measured triangle (assembly measures each face
/// once for this test, its area and its cotangents).
#[inline]
pub(crate) fn is_degenerate_scaled(t: &ScaledTriangle) -> bool {
    let [e0, e1, e2] = t.edges;
    let longest_sq = dot(e0, e0).max(dot(e1, e1)).max(dot(e2, e2));
    let area = 0.5 * t.double_area;
    let true_area = mul_pow2(area, 2 * t.k);
    !(area > DEGENERATE_AREA_RATIO * longest_sq && true_area >= f64::MIN_POSITIVE)
}

/// A face with an angle closer than this (radians) to 0 or π is reported as a
/// [`Problem::NeedleFace`] (|cot| > 10⁴).
pub const NEEDLE_ANGLE: f64 = 1e-4;

/// The largest |cot| of the three angles of a triangle (scale invariant; ∞ for a degenerate
/// one).
fn max_abs_cotangent(corners: [[f64; 3]; 3]) -> f64 {
    let Some(([d01, d12, d20], _)) = scaled_edges(corners) else {
        return f64::INFINITY;
    };
    let double_area = norm(cross(d01, neg(d20)));
    [(d01, neg(d20)), (d12, neg(d01)), (d20, neg(d12))]
        .iter()
        .map(|&(e1, e2)| (dot(e1, e2) / double_area).abs())
        .fold(0.0, f64::max)
}

/// How serious a [`Problem`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub enum Severity {
    /// The FEM operators cannot be assembled (B singular or cotangents undefined).
    Error,
    /// The operators assemble, but the result may not be what the user expects.
    Warning,
}

/// One problem found by [`validate`], naming its culprit. Indices are 0-based.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub enum Problem {
    /// A face uses the same vertex twice (or three times).
    RepeatedIndex {
        /// Face index.
        face: usize,
        /// Its vertex indices.
        vertices: [u32; 3],
    },
    /// A face with (numerically) zero area, see [`is_degenerate_triangle`].
    ZeroAreaFace {
        /// Face index.
        face: usize,
        /// Its vertex indices.
        vertices: [u32; 3],
    },
    /// A vertex that belongs to no face.
    UnreferencedVertex {
        /// Vertex index.
        vertex: usize,
    },
    /// The total area Σ|T| is not a finite double (coordinates beyond ~1e154), so the mass
    /// matrices B and D cannot be stored; scale the mesh down ([`TriMesh::scaled`]).
    AreaOverflow {
        /// The total area computed (+∞).
        area: f64,
    },
    /// An edge shared by more than two faces.
    NonManifoldEdge {
        /// The edge's vertices, ascending.
        edge: [u32; 2],
        /// How many face sides lie on it (a face that repeats an index can count twice).
        n_faces: usize,
    },
    /// A vertex whose incident faces form more than one fan (e.g. two cones touching at a tip).
    NonManifoldVertex {
        /// Vertex index.
        vertex: usize,
    },
    /// A later copy of a face (same three vertices in any order).
    DuplicateFace {
        /// The later copy.
        face: usize,
        /// The first face with the same vertices.
        first: usize,
    },
    /// Two faces traverse this edge in the same direction (their normals disagree).
    InconsistentOrientation {
        /// The edge's vertices, ascending.
        edge: [u32; 2],
    },
    /// The connected component containing this edge cannot be oriented consistently
    /// (Möbius-like); the edge closes an orientation conflict.
    NonOrientable {
        /// The edge's vertices, ascending.
        edge: [u32; 2],
    },
    /// A needle or cap triangle: one of its angles is below [`NEEDLE_ANGLE`] from 0 or π, so
    /// a cotangent weight of L exceeds 1/NEEDLE_ANGLE in magnitude. The operators still
    /// assemble, but rounding errors in L grow with these weights: the heat kernel solvers
    /// measure the resulting loss of accuracy (`wfem_heat::Operators::conditioning`) and refuse
    /// when it is too large. Fix: drop or collapse such faces, or use an intrinsic Delaunay
    /// Laplacian.
    NeedleFace {
        /// Face index.
        face: usize,
        /// Its vertex indices.
        vertices: [u32; 3],
        /// The largest |cot| of its angles.
        cotangent: f64,
    },
    /// The mesh has several connected components.
    SeveralComponents {
        /// Number of components (of referenced vertices).
        count: usize,
    },
    /// The mesh is open.
    Boundary {
        /// Number of boundary loops.
        loops: usize,
        /// Number of boundary edges.
        edges: usize,
    },
}

impl Problem {
    /// What fixes it, when a repair does.
    pub fn remedy(&self) -> Option<Remedy> {
        match self {
            Problem::RepeatedIndex { .. } | Problem::ZeroAreaFace { .. } => Some(Remedy::DropDegenerateFaces),
            Problem::UnreferencedVertex { .. } => Some(Remedy::DropUnreferencedVertices),
            Problem::AreaOverflow { .. } => Some(Remedy::ScaleDown),
            Problem::DuplicateFace { .. } => Some(Remedy::DropDuplicateFaces),
            Problem::InconsistentOrientation { .. } => Some(Remedy::OrientFaces),
            _ => None,
        }
    }

    /// What it means for the operators, in a few words (`None` where nothing needs saying).
    pub fn note(&self) -> Option<&'static str> {
        Some(match self {
            Problem::NonManifoldEdge { .. } | Problem::NonManifoldVertex { .. } => {
                "FEM assembly is per face, so the operators still assemble"
            }
            Problem::DuplicateFace { .. } => "assembles but counts the face twice",
            Problem::InconsistentOrientation { .. } => "L and B do not depend on it",
            Problem::NonOrientable { .. } => "L and B do not depend on it, but no consistent normals exist",
            Problem::NeedleFace { .. } => {
                "rounding in L grows with |cot|: drop or collapse such faces if the heat kernel refuses them"
            }
            Problem::SeveralComponents { .. } => "L has one zero eigenvalue per component",
            Problem::Boundary { .. } => "natural (Neumann) boundary conditions apply",
            _ => return None,
        })
    }

    /// Severity of this kind of problem.
    pub fn severity(&self) -> Severity {
        match self {
            Problem::RepeatedIndex { .. }
            | Problem::ZeroAreaFace { .. }
            | Problem::UnreferencedVertex { .. }
            | Problem::AreaOverflow { .. } => Severity::Error,
            _ => Severity::Warning,
        }
    }

    /// The error that names this problem's culprit (errors only).
    fn to_error(&self) -> Option<MeshError> {
        match *self {
            Problem::RepeatedIndex { face, vertices } => Some(MeshError::RepeatedIndex {
                face,
                vertices: vertices.to_vec(),
            }),
            Problem::ZeroAreaFace { face, vertices } => Some(MeshError::DegenerateFace { face, vertices }),
            Problem::UnreferencedVertex { vertex } => Some(MeshError::UnreferencedVertex { vertex }),
            Problem::AreaOverflow { area } => Some(MeshError::DegenerateMesh { area }),
            _ => None,
        }
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Problem::RepeatedIndex { face, vertices } => {
                write!(f, "face {face} repeats a vertex {vertices:?}")
            }
            Problem::ZeroAreaFace { face, vertices } => {
                write!(f, "face {face} {vertices:?} has zero area")
            }
            Problem::UnreferencedVertex { vertex } => {
                write!(f, "vertex {vertex} belongs to no face")
            }
            Problem::AreaOverflow { area } => {
                write!(
                    f,
                    "the total area {area} is not a finite number (coordinates too large)"
                )
            }
            Problem::NonManifoldEdge { edge, n_faces } => {
                write!(f, "edge {edge:?} is shared by {n_faces} faces")
            }
            Problem::NonManifoldVertex { vertex } => {
                write!(f, "vertex {vertex} joins several fans of faces")
            }
            Problem::DuplicateFace { face, first } => {
                write!(f, "face {face} duplicates face {first}")
            }
            Problem::InconsistentOrientation { edge } => {
                write!(f, "both faces of edge {edge:?} traverse it in the same direction")
            }
            Problem::NonOrientable { edge } => {
                write!(f, "the component containing edge {edge:?} is not orientable")
            }
            Problem::NeedleFace {
                face,
                vertices,
                cotangent,
            } => write!(
                f,
                "face {face} {vertices:?} is a needle or cap (|cot| of an angle = {cotangent:.1e})"
            ),
            Problem::SeveralComponents { count } => write!(f, "{count} connected components"),
            Problem::Boundary { loops, edges } => {
                write!(
                    f,
                    "open mesh: {}, {}",
                    counted(*loops, "boundary loop", "boundary loops"),
                    counted(*edges, "boundary edge", "boundary edges")
                )
            }
        }
    }
}

/// Number of problems of each kind found by [`validate`].
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ProblemCounts {
    /// Faces repeating a vertex index (error).
    pub repeated_index: usize,
    /// Faces with zero area (error).
    pub zero_area_faces: usize,
    /// Vertices in no face (error).
    pub unreferenced_vertices: usize,
    /// Edges with more than two faces.
    pub non_manifold_edges: usize,
    /// Vertices with more than one fan.
    pub non_manifold_vertices: usize,
    /// Later copies of faces.
    pub duplicate_faces: usize,
    /// Edges whose two faces traverse them in the same direction.
    pub inconsistently_oriented_edges: usize,
    /// Components that cannot be oriented.
    pub non_orientable_components: usize,
    /// Needle or cap faces (an angle within [`NEEDLE_ANGLE`] of 0 or π).
    pub needle_faces: usize,
    /// Connected components (1 for a connected mesh; not a problem by itself).
    pub components: usize,
    /// Boundary loops (0 for a closed mesh).
    pub boundary_loops: usize,
}

/// The outcome of [`validate`]: every problem found, errors first (faces in index order,
/// then vertices), then warnings.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ValidationReport {
    /// Number of vertices of the mesh validated.
    pub n_vertices: usize,
    /// Number of faces of the mesh validated.
    pub n_faces: usize,
    /// Every problem found, each naming its culprit.
    pub problems: Vec<Problem>,
    /// Number of problems of each kind.
    pub counts: ProblemCounts,
}

impl ValidationReport {
    /// `true` if there is no [`Severity::Error`]: the FEM operators can be assembled.
    pub fn is_usable(&self) -> bool {
        self.errors().next().is_none()
    }

    /// The problems of severity [`Severity::Error`].
    pub fn errors(&self) -> impl Iterator<Item = &Problem> {
        self.problems.iter().filter(|p| p.severity() == Severity::Error)
    }

    /// The problems of severity [`Severity::Warning`].
    pub fn warnings(&self) -> impl Iterator<Item = &Problem> {
        self.problems.iter().filter(|p| p.severity() == Severity::Warning)
    }

    /// `Ok(self)` if the mesh is usable, else the error naming the first fatal culprit:
    /// [`MeshError::RepeatedIndex`], [`MeshError::DegenerateFace`] (the lowest such face,
    /// as [`crate::assemble`] reports it) or [`MeshError::UnreferencedVertex`].
    ///
    /// # Errors
    /// As above.
    pub fn into_result(self) -> Result<ValidationReport, MeshError> {
        let first = self.errors().find_map(Problem::to_error);
        match first {
            Some(e) => Err(e),
            None => Ok(self),
        }
    }

    /// A few human-readable lines: the verdict, then one line per kind of problem with its
    /// count and first culprit, what it means and its remedy in this crate's terms.
    pub fn summary(&self) -> String {
        self.summary_with(&|r| r.in_library().to_string())
    }

    /// [`Self::summary`] with each remedy named by `fix` (a front end's words for [`Remedy`]).
    pub fn summary_with(&self, fix: &dyn Fn(Remedy) -> String) -> String {
        let n_errors = self.errors().count();
        let mut s = format!(
            "mesh with {} vertices and {} faces: {}",
            self.n_vertices,
            self.n_faces,
            if n_errors == 0 {
                "usable".to_string()
            } else {
                format!("NOT usable ({})", counted(n_errors, "fatal problem", "fatal problems"))
            }
        );
        // One line per kind: count and first culprit.
        let mut seen: Vec<std::mem::Discriminant<Problem>> = Vec::new();
        for p in &self.problems {
            let d = std::mem::discriminant(p);
            if seen.contains(&d) {
                continue;
            }
            seen.push(d);
            let count = self.problems.iter().filter(|q| std::mem::discriminant(*q) == d).count();
            let tag = match p.severity() {
                Severity::Error => "error",
                Severity::Warning => "warning",
            };
            let more = if count > 1 {
                format!(" (and {} more like it)", count - 1)
            } else {
                String::new()
            };
            let mut hint = p.note().map(|n| format!("; {n}")).unwrap_or_default();
            if let Some(r) = p.remedy() {
                hint.push_str(&format!("; fix: {}", fix(r)));
            }
            s.push_str(&format!("\n  {tag}: {p}{more}{hint}"));
        }
        s
    }
}

/// Validates `mesh` for FEM assembly and reports every problem with its culprit.
///
/// Runs in O(F log F). See the [module documentation](self) for what each problem means.
///
/// ```
/// use mesh_fem::validate::{Problem, validate};
/// use mesh_fem::{MeshError, TriMesh};
/// // Two triangles; vertex 4 belongs to no face.
/// let p = vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [1., 1., 0.], [5., 5., 5.]];
/// let mesh = TriMesh::new(p, vec![[0, 1, 2], [2, 1, 3]])?;
/// let report = validate(&mesh);
/// assert!(!report.is_usable());
/// assert!(report.problems.contains(&Problem::Boundary { loops: 1, edges: 4 }));
/// assert!(matches!(report.into_result(), Err(MeshError::UnreferencedVertex { vertex: 4 })));
/// # Ok::<(), MeshError>(())
/// ```
pub fn validate(mesh: &TriMesh) -> ValidationReport {
    let faces = mesh.faces();
    let topo = Topology::new(mesh.n_vertices(), faces);
    let mut problems = Vec::new();
    let mut counts = ProblemCounts::default();

    // Errors on faces, in face order (as assemble reports the lowest degenerate face).
    let degenerate: Vec<bool> = (0..faces.len())
        .into_par_iter()
        .map(|f| is_degenerate_triangle(mesh.corners(f)))
        .collect();
    for (face, &vertices) in faces.iter().enumerate() {
        let [a, b, c] = vertices;
        if a == b || b == c || a == c {
            counts.repeated_index += 1;
            problems.push(Problem::RepeatedIndex { face, vertices });
        } else if degenerate[face] {
            counts.zero_area_faces += 1;
            problems.push(Problem::ZeroAreaFace { face, vertices });
        }
    }
    for (vertex, &d) in topo.vertex_valence.iter().enumerate() {
        if d == 0 {
            counts.unreferenced_vertices += 1;
            problems.push(Problem::UnreferencedVertex { vertex });
        }
    }
    let total_area = mesh.area();
    if !total_area.is_finite() {
        problems.push(Problem::AreaOverflow { area: total_area });
    }

    // Warnings.
    for &e in &topo.non_manifold_edges {
        counts.non_manifold_edges += 1;
        problems.push(Problem::NonManifoldEdge {
            edge: topo.edges[e as usize],
            n_faces: topo.edge_face_count(e as usize),
        });
    }
    for &v in &topo.non_manifold_vertices {
        counts.non_manifold_vertices += 1;
        problems.push(Problem::NonManifoldVertex { vertex: v as usize });
    }
    let needles: Vec<(usize, f64)> = (0..faces.len())
        .into_par_iter()
        .filter(|&f| !degenerate[f])
        .filter_map(|f| {
            let c = max_abs_cotangent(mesh.corners(f));
            (c > 1.0 / NEEDLE_ANGLE).then_some((f, c))
        })
        .collect();
    for (face, cotangent) in needles {
        counts.needle_faces += 1;
        problems.push(Problem::NeedleFace {
            face,
            vertices: faces[face],
            cotangent,
        });
    }
    for (face, first) in duplicate_faces(faces) {
        counts.duplicate_faces += 1;
        problems.push(Problem::DuplicateFace { face, first });
    }
    for &e in &topo.inconsistent_edges {
        counts.inconsistently_oriented_edges += 1;
        problems.push(Problem::InconsistentOrientation {
            edge: topo.edges[e as usize],
        });
    }
    for &e in &topo.non_orientable_edges {
        counts.non_orientable_components += 1;
        problems.push(Problem::NonOrientable {
            edge: topo.edges[e as usize],
        });
    }
    counts.components = topo.n_components;
    if topo.n_components > 1 {
        problems.push(Problem::SeveralComponents {
            count: topo.n_components,
        });
    }
    counts.boundary_loops = topo.n_boundary_loops;
    if topo.n_boundary_edges > 0 {
        problems.push(Problem::Boundary {
            loops: topo.n_boundary_loops,
            edges: topo.n_boundary_edges,
        });
    }

    ValidationReport {
        n_vertices: mesh.n_vertices(),
        n_faces: faces.len(),
        problems,
        counts,
    }
}

/// Pairs `(later copy, first face)` of faces with the same vertex set, later copy ascending.
fn duplicate_faces(faces: &[[u32; 3]]) -> Vec<(usize, usize)> {
    let mut keyed: Vec<([u32; 3], u32)> = faces
        .iter()
        .enumerate()
        .map(|(f, face)| {
            let mut k = *face;
            k.sort_unstable();
            (k, f as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    let mut out = Vec::new();
    let mut i = 0;
    while i < keyed.len() {
        let mut j = i + 1;
        while j < keyed.len() && keyed[j].0 == keyed[i].0 {
            out.push((keyed[j].1 as usize, keyed[i].1 as usize));
            j += 1;
        }
        i = j;
    }
    out.sort_unstable();
    out
}

/// The merge tolerance of the `duplicate-vertices` repair unless told otherwise: identical
/// coordinates only (see [`RepairOptions::merge_duplicate_vertices`]).
pub const DEFAULT_WELD_TOLERANCE: f64 = 0.0;

/// Which repairs [`repair`] applies. Everything is off by default; the repairs run in the
/// order of the fields below.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RepairOptions {
    /// Merge vertices closer than `tol · d`, where d is the bounding-box diagonal (so the
    /// tolerance is relative and scale invariant); `Some(0.0)` merges only vertices with
    /// identical coordinates. Vertices are visited in index order; each one merges into the
    /// nearest earlier *kept* vertex within the tolerance (which keeps its position), or is
    /// kept itself. Every merged vertex is thus within `tol · d` of the vertex it became.
    pub merge_duplicate_vertices: Option<f64>,
    /// Drop faces that repeat an index (including those created by merging) or have zero area
    /// ([`is_degenerate_triangle`]).
    pub drop_degenerate_faces: bool,
    /// Drop later copies of faces with the same three vertices (the first copy stays).
    pub drop_duplicate_faces: bool,
    /// Flip faces so that every orientable component is consistently oriented, keeping the
    /// orientation of the majority of its faces. Non-orientable components are left as they
    /// are and counted in [`RepairReport::non_orientable_components`].
    pub orient_faces: bool,
    /// Drop vertices that belong to no (remaining) face and renumber the rest in order.
    pub drop_unreferenced_vertices: bool,
}

/// One repair of [`repair`], as users name it (`--repair unreferenced,orient`); the registry of
/// repair steps. [`RepairStep::options`] turns a list into [`RepairOptions`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RepairStep {
    /// Drop vertices that belong to no face (the original Stanford bunny has 1,113).
    Unreferenced,
    /// Merge vertices with identical coordinates (or within a tolerance): welds triangle soups
    /// and STL-like files.
    DuplicateVertices,
    /// Drop faces that repeat a vertex or have (numerically) zero area.
    Degenerate,
    /// Drop later copies of faces with the same three vertices.
    DuplicateFaces,
    /// Orient every orientable component consistently.
    Orient,
    /// Every step above.
    All,
}

impl RepairStep {
    /// The step that carries out a remedy (`None` for a remedy that is not a repair: reading
    /// polygons, scaling).
    pub fn for_remedy(remedy: Remedy) -> Option<Self> {
        match remedy {
            Remedy::DropUnreferencedVertices => Some(RepairStep::Unreferenced),
            Remedy::DropDegenerateFaces => Some(RepairStep::Degenerate),
            Remedy::DropDuplicateFaces => Some(RepairStep::DuplicateFaces),
            Remedy::OrientFaces => Some(RepairStep::Orient),
            Remedy::TriangulatePolygons | Remedy::ScaleDown => None,
        }
    }
}

wfem_base::registry! {
    RepairStep as "repair" {
        RepairStep::Unreferenced = RepairStep::Unreferenced => "unreferenced":
            "drop vertices that belong to no face (the original Stanford bunny has 1,113)",
        RepairStep::DuplicateVertices = RepairStep::DuplicateVertices => "duplicate-vertices" ["weld"]:
            "merge vertices with identical coordinates (or within the weld tolerance): welds triangle soups and STL files",
        RepairStep::Degenerate = RepairStep::Degenerate => "degenerate":
            "drop faces that repeat a vertex or have (numerically) zero area",
        RepairStep::DuplicateFaces = RepairStep::DuplicateFaces => "duplicate-faces":
            "drop later copies of faces with the same three vertices",
        RepairStep::Orient = RepairStep::Orient => "orient":
            "orient every orientable component consistently (L and B do not depend on it)",
        RepairStep::All = RepairStep::All => "all":
            "every repair above",
    }
}

impl RepairStep {
    /// The options of a list of steps; `weld_tolerance` is the merge tolerance of
    /// [`RepairStep::DuplicateVertices`] (relative to the bounding-box diagonal).
    pub fn options(steps: &[RepairStep], weld_tolerance: f64) -> RepairOptions {
        let has = |s: RepairStep| steps.contains(&s) || steps.contains(&RepairStep::All);
        RepairOptions {
            merge_duplicate_vertices: has(RepairStep::DuplicateVertices).then_some(weld_tolerance),
            drop_degenerate_faces: has(RepairStep::Degenerate),
            drop_duplicate_faces: has(RepairStep::DuplicateFaces),
            orient_faces: has(RepairStep::Orient),
            drop_unreferenced_vertices: has(RepairStep::Unreferenced),
        }
    }
}

/// What [`repair`] changed.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RepairReport {
    /// For each old vertex, its index in the repaired mesh (`None` if dropped). A merged
    /// vertex maps to the index of the vertex it was merged into.
    pub vertex_map: Vec<Option<u32>>,
    /// For each old face, its index in the repaired mesh (`None` if dropped).
    pub face_map: Vec<Option<u32>>,
    /// Number of vertices merged into another vertex.
    pub merged_vertices: usize,
    /// Number of unreferenced vertices dropped.
    pub dropped_vertices: usize,
    /// Old indices of all dropped faces, ascending.
    pub dropped_faces: Vec<usize>,
    /// Old indices of faces dropped as degenerate (repeated index or zero area), ascending.
    pub dropped_degenerate_faces: Vec<usize>,
    /// Old indices of faces dropped as duplicates, ascending.
    pub dropped_duplicate_faces: Vec<usize>,
    /// Old indices of faces whose orientation was flipped, ascending.
    pub flipped_faces: Vec<usize>,
    /// Components that could not be oriented (with `orient_faces`).
    pub non_orientable_components: usize,
}

impl RepairReport {
    /// `true` if the repaired mesh equals the input.
    pub fn is_unchanged(&self) -> bool {
        self.merged_vertices == 0
            && self.dropped_vertices == 0
            && self.dropped_faces.is_empty()
            && self.flipped_faces.is_empty()
    }

    /// One line per change made.
    pub fn summary(&self) -> String {
        if self.is_unchanged() {
            let mut s = "repair: nothing changed".to_string();
            if self.non_orientable_components > 0 {
                s.push_str(&format!(
                    " ({} non-orientable components left as they are)",
                    self.non_orientable_components
                ));
            }
            return s;
        }
        let first = |v: &[usize]| {
            let shown: Vec<String> = v.iter().take(5).map(|x| x.to_string()).collect();
            let ell = if v.len() > 5 { ", …" } else { "" };
            format!("{}{ell}", shown.join(", "))
        };
        let mut lines = vec!["repair:".to_string()];
        if self.merged_vertices > 0 {
            lines.push(format!(
                "  merged {}",
                counted(self.merged_vertices, "duplicate vertex", "duplicate vertices")
            ));
        }
        if !self.dropped_degenerate_faces.is_empty() {
            lines.push(format!(
                "  dropped {} ({})",
                counted(
                    self.dropped_degenerate_faces.len(),
                    "degenerate face",
                    "degenerate faces"
                ),
                first(&self.dropped_degenerate_faces)
            ));
        }
        if !self.dropped_duplicate_faces.is_empty() {
            lines.push(format!(
                "  dropped {} ({})",
                counted(self.dropped_duplicate_faces.len(), "duplicate face", "duplicate faces"),
                first(&self.dropped_duplicate_faces)
            ));
        }
        if !self.flipped_faces.is_empty() {
            lines.push(format!(
                "  flipped {} ({})",
                counted(self.flipped_faces.len(), "face", "faces"),
                first(&self.flipped_faces)
            ));
        }
        if self.non_orientable_components > 0 {
            lines.push(format!(
                "  left {} as they are",
                counted(
                    self.non_orientable_components,
                    "non-orientable component",
                    "non-orientable components"
                )
            ));
        }
        if self.dropped_vertices > 0 {
            lines.push(format!(
                "  dropped {}",
                counted(self.dropped_vertices, "unreferenced vertex", "unreferenced vertices")
            ));
        }
        lines.join("\n")
    }
}

/// Applies the repairs turned on in `opts` and reports what changed.
///
/// ```
/// use mesh_fem::validate::{repair, RepairOptions, validate};
/// use mesh_fem::{MeshError, TriMesh};
/// let p = vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [1., 1., 0.], [5., 5., 5.]];
/// let mesh = TriMesh::new(p, vec![[0, 1, 2], [2, 1, 3]])?;
/// let opts = RepairOptions { drop_unreferenced_vertices: true, ..Default::default() };
/// let (fixed, report) = repair(&mesh, &opts)?;
/// assert_eq!(report.vertex_map, vec![Some(0), Some(1), Some(2), Some(3), None]);
/// assert!(validate(&fixed).is_usable());
/// println!("{}", report.summary()); // "repair:\n  dropped 1 unreferenced vertex"
/// # Ok::<(), MeshError>(())
/// ```
///
/// Faces keep their relative order, vertices too (merged vertices take the index of the
/// vertex they merged into). Runs in O((V + F) log(V + F)).
///
/// # Errors
/// * [`MeshError::InvalidRepairOption`] for a negative or non-finite merge tolerance.
/// * [`MeshError::Empty`] if the repairs remove every face.
pub fn repair(mesh: &TriMesh, opts: &RepairOptions) -> Result<(TriMesh, RepairReport), MeshError> {
    let n = mesh.n_vertices();
    let positions = mesh.positions();
    let mut report = RepairReport::default();

    // 1. Merge duplicate vertices: `rep[v]` is the vertex v merges into (itself if kept).
    let rep: Vec<u32> = match opts.merge_duplicate_vertices {
        None => (0..n as u32).collect(),
        Some(tol) => {
            if !(tol >= 0.0 && tol.is_finite()) {
                return Err(MeshError::InvalidRepairOption {
                    option: "merge_duplicate_vertices",
                    message: format!("tolerance must be finite and ≥ 0, got {tol}"),
                });
            }
            let absolute = tol * bbox_diagonal(positions);
            if !absolute.is_finite() {
                return Err(MeshError::InvalidRepairOption {
                    option: "merge_duplicate_vertices",
                    message: format!("tolerance {tol} times the bounding-box diagonal is not a finite number"),
                });
            }
            merge_representatives(positions, absolute)
        }
    };
    report.merged_vertices = rep.iter().enumerate().filter(|&(v, &r)| r as usize != v).count();
    let mut faces: Vec<[u32; 3]> = mesh
        .faces()
        .iter()
        .map(|f| [rep[f[0] as usize], rep[f[1] as usize], rep[f[2] as usize]])
        .collect();
    // `alive[f]`: old face f is still in the mesh.
    let mut alive = vec![true; faces.len()];

    // 2. Degenerate faces.
    if opts.drop_degenerate_faces {
        let degenerate: Vec<bool> = faces
            .par_iter()
            .map(|&[a, b, c]| {
                a == b
                    || b == c
                    || a == c
                    || is_degenerate_triangle([positions[a as usize], positions[b as usize], positions[c as usize]])
            })
            .collect();
        for (f, &d) in degenerate.iter().enumerate() {
            if d {
                alive[f] = false;
                report.dropped_degenerate_faces.push(f);
            }
        }
    }

    // 3. Duplicate faces (among the faces still alive).
    if opts.drop_duplicate_faces {
        let live: Vec<usize> = (0..faces.len()).filter(|&f| alive[f]).collect();
        let live_faces: Vec<[u32; 3]> = live.iter().map(|&f| faces[f]).collect();
        let mut dups: Vec<usize> = duplicate_faces(&live_faces)
            .into_iter()
            .map(|(copy, _)| live[copy])
            .collect();
        dups.sort_unstable();
        for &f in &dups {
            alive[f] = false;
        }
        report.dropped_duplicate_faces = dups;
    }

    // 4. Orientation (topology of the faces still alive, on the merged vertices).
    if opts.orient_faces {
        let live: Vec<usize> = (0..faces.len()).filter(|&f| alive[f]).collect();
        let live_faces: Vec<[u32; 3]> = live.iter().map(|&f| faces[f]).collect();
        let topo = Topology::new(n, &live_faces);
        for (i, &flip) in topo.face_flip.iter().enumerate() {
            if flip {
                let f = live[i];
                faces[f].swap(1, 2);
                report.flipped_faces.push(f);
            }
        }
        report.non_orientable_components = topo.component_non_orientable.iter().filter(|&&x| x).count();
    }

    // 5. Compact: keep merged representatives, drop unreferenced vertices if asked.
    let mut used = vec![false; n];
    for (f, face) in faces.iter().enumerate() {
        if alive[f] {
            for &v in face {
                used[v as usize] = true;
            }
        }
    }
    let mut new_index = vec![NONE; n];
    let mut new_positions = Vec::with_capacity(n);
    for v in 0..n {
        let is_rep = rep[v] as usize == v;
        if !is_rep {
            continue;
        }
        if opts.drop_unreferenced_vertices && !used[v] {
            report.dropped_vertices += 1;
            continue;
        }
        new_index[v] = new_positions.len() as u32;
        new_positions.push(positions[v]);
    }
    report.vertex_map = (0..n)
        .map(|v| {
            let i = new_index[rep[v] as usize];
            (i != NONE).then_some(i)
        })
        .collect();
    let mut new_faces = Vec::with_capacity(faces.len());
    report.face_map = vec![None; faces.len()];
    for (f, face) in faces.iter().enumerate() {
        if alive[f] {
            report.face_map[f] = Some(new_faces.len() as u32);
            new_faces.push(face.map(|v| new_index[v as usize]));
        } else {
            report.dropped_faces.push(f);
        }
    }
    let repaired = TriMesh::new(new_positions, new_faces)?;
    Ok((repaired, report))
}

/// For each vertex, the earlier kept vertex it merges into (itself if kept): the nearest
/// kept vertex within distance `tol`, found through a hash grid of cell size `tol`.
fn merge_representatives(positions: &[[f64; 3]], tol: f64) -> Vec<u32> {
    let n = positions.len();
    let mut rep: Vec<u32> = (0..n as u32).collect();
    if tol <= 0.0 || tol.is_nan() {
        // Exact coordinates (−0.0 and +0.0 are the same point).
        let key = |p: &[f64; 3]| p.map(|c| if c == 0.0 { 0u64 } else { c.to_bits() });
        let mut first: HashMap<[u64; 3], u32> = HashMap::with_capacity(n);
        for (v, p) in positions.iter().enumerate() {
            rep[v] = *first.entry(key(p)).or_insert(v as u32);
        }
        return rep;
    }
    let cell = |p: &[f64; 3]| p.map(|c| (c / tol).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::with_capacity(n);
    for (v, p) in positions.iter().enumerate() {
        let c = cell(p);
        let mut best: Option<(f64, u32)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&[
                        c[0].saturating_add(dx),
                        c[1].saturating_add(dy),
                        c[2].saturating_add(dz),
                    ]) {
                        for &r in list {
                            let d = norm(sub(positions[r as usize], *p));
                            if d <= tol && best.is_none_or(|(bd, br)| d < bd || (d == bd && r < br)) {
                                best = Some((d, r));
                            }
                        }
                    }
                }
            }
        }
        match best {
            Some((_, r)) => rep[v] = r,
            None => grid.entry(c).or_default().push(v as u32),
        }
    }
    rep
}
