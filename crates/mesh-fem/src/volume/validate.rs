//! What is wrong with a tetrahedral mesh, named by its culprit, and the explicit repairs.

use super::{signed_volume, tet_quality, TetMesh};
use crate::graph::UnionFind;
use crate::MeshError;
use rayon::prelude::*;

/// Quality below which a tetrahedron is a sliver (reported, not fatal).
pub const SLIVER_QUALITY: f64 = 0.01;

/// One problem of a tetrahedral mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum VolumeProblem {
    /// Tetrahedra with a negative signed volume (mixed orientation): harmless for the
    /// operators (they use |T|), repaired by `orient`.
    Inverted {
        /// How many.
        count: usize,
        /// The first one.
        first: usize,
    },
    /// A tetrahedron of (numerically) zero volume: fatal; repaired by `degenerate` (dropped).
    Flat {
        /// The tetrahedron.
        tet: usize,
        /// Its vertices.
        vertices: [u32; 4],
    },
    /// Vertices in no tetrahedron: fatal (the mass would be singular); repaired by
    /// `unreferenced`.
    Unreferenced {
        /// How many.
        count: usize,
        /// The first one.
        first: usize,
    },
    /// A triangle shared by more than two tetrahedra (overlapping elements): fatal.
    NonManifoldFace {
        /// Its vertices.
        vertices: [u32; 3],
        /// How many tetrahedra share it.
        tets: usize,
    },
    /// Several connected components (a warning: each is solved separately).
    Components {
        /// How many.
        count: usize,
    },
    /// Nearly flat tetrahedra (quality below 0.01): a warning, they assemble.
    Slivers {
        /// How many.
        count: usize,
        /// The worst one.
        worst: usize,
        /// Its quality.
        quality: f64,
    },
}

impl VolumeProblem {
    /// Whether the operators cannot be assembled with it.
    pub fn is_fatal(&self) -> bool {
        matches!(
            self,
            VolumeProblem::Flat { .. } | VolumeProblem::Unreferenced { .. } | VolumeProblem::NonManifoldFace { .. }
        )
    }
}

impl std::fmt::Display for VolumeProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            VolumeProblem::Inverted { count, first } => write!(
                f,
                "{count} tetrahedra have a negative orientation (the first: {first}); the operators use |T|, --repair orient reorients them"
            ),
            VolumeProblem::Flat { tet, vertices } => write!(
                f,
                "tetrahedron {tet} (vertices {vertices:?}) has zero volume; --repair degenerate drops such tetrahedra"
            ),
            VolumeProblem::Unreferenced { count, first } => write!(
                f,
                "{count} vertices belong to no tetrahedron (the first: {first}); --repair unreferenced drops them"
            ),
            VolumeProblem::NonManifoldFace { vertices, tets } => {
                write!(f, "triangle {vertices:?} is a face of {tets} tetrahedra (overlapping elements)")
            }
            VolumeProblem::Components { count } => write!(f, "{count} connected components (each is solved separately)"),
            VolumeProblem::Slivers { count, worst, quality } => write!(
                f,
                "{count} slivers (quality below {SLIVER_QUALITY}); the worst, tetrahedron {worst}, has quality {quality:.2e}"
            ),
        }
    }
}

/// What [`validate_volume`] found, with the numbers `wfem info` prints.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeReport {
    /// Vertices.
    pub n_vertices: usize,
    /// Tetrahedra.
    pub n_tets: usize,
    /// Σ|T|.
    pub volume: f64,
    /// Boundary triangles.
    pub n_boundary_faces: usize,
    /// Vertices on the boundary.
    pub n_boundary_vertices: usize,
    /// Euler characteristic V − E + F of the boundary surface.
    pub boundary_euler: i64,
    /// Connected components c of the boundary surface (1 for a solid ball; a hollow shell has 2).
    pub n_boundary_components: usize,
    /// Total genus g of the boundary surface, `(2c − χ)/2` (0 for a ball, 1 for a solid torus),
    /// when the boundary is a closed 2-manifold (every edge on exactly two boundary triangles);
    /// `None` otherwise (then χ does not determine it).
    pub boundary_genus: Option<i64>,
    /// Connected components of the tetrahedra.
    pub n_components: usize,
    /// Smallest and median quality 6√2|V|/ℓ³_rms.
    pub quality: (f64, f64),
    /// The tetrahedron of the smallest quality.
    pub worst_tet: usize,
    /// Every problem, fatal ones first.
    pub problems: Vec<VolumeProblem>,
}

impl VolumeReport {
    /// The first fatal problem as an error.
    ///
    /// # Errors
    /// [`MeshError::Invalid`] naming the problem.
    pub fn into_result(self) -> Result<(), MeshError> {
        match self.problems.into_iter().find(VolumeProblem::is_fatal) {
            Some(p) => Err(MeshError::Invalid { reason: p.to_string() }),
            None => Ok(()),
        }
    }

    /// The warnings (problems that do not stop the assembly).
    pub fn warnings(&self) -> impl Iterator<Item = &VolumeProblem> {
        self.problems.iter().filter(|p| !p.is_fatal())
    }
}

/// The four faces of a tetrahedron [a, b, c, d], oriented outward for a positive one.
fn faces_of(t: [u32; 4]) -> [[u32; 3]; 4] {
    let [a, b, c, d] = t;
    [[b, c, d], [a, d, c], [a, b, d], [a, c, b]]
}

/// Every face of every tetrahedron, keyed by its sorted vertices, sorted by key: (key, tet, face
/// oriented outward).
fn keyed_faces(mesh: &TetMesh) -> Vec<([u32; 3], usize, [u32; 3])> {
    let mut all: Vec<([u32; 3], usize, [u32; 3])> = (0..mesh.n_tets())
        .into_par_iter()
        .flat_map_iter(|t| {
            let positive = mesh.signed_volume(t) >= 0.0;
            faces_of(mesh.tets()[t]).into_iter().map(move |f| {
                let f = if positive { f } else { [f[0], f[2], f[1]] };
                let mut key = f;
                key.sort_unstable();
                (key, t, f)
            })
        })
        .collect();
    all.par_sort_unstable_by_key(|x| (x.0, x.1));
    all
}

/// The boundary surface: the faces of exactly one tetrahedron, oriented outward (computed from
/// the tetrahedra, never taken from a file's triangles).
pub fn boundary_faces(mesh: &TetMesh) -> Vec<[u32; 3]> {
    let all = keyed_faces(mesh);
    let mut out = Vec::new();
    let mut i = 0;
    while i < all.len() {
        let mut j = i + 1;
        while j < all.len() && all[j].0 == all[i].0 {
            j += 1;
        }
        if j - i == 1 {
            out.push(all[i].2);
        }
        i = j;
    }
    out
}

/// Validates a tetrahedral mesh (see [`VolumeProblem`]).
pub fn validate_volume(mesh: &TetMesh) -> VolumeReport {
    let n = mesh.n_vertices();
    let m = mesh.n_tets();
    let volumes: Vec<f64> = (0..m).into_par_iter().map(|t| mesh.signed_volume(t)).collect();
    let qualities: Vec<f64> = (0..m).into_par_iter().map(|t| tet_quality(mesh.corners(t))).collect();
    let mut problems = Vec::new();
    if let Some(t) = (0..m).find(|&t| super::tet_element(mesh.corners(t)).is_none()) {
        problems.push(VolumeProblem::Flat {
            tet: t,
            vertices: mesh.tets()[t],
        });
    }
    let mut used = vec![false; n];
    mesh.tets().iter().flatten().for_each(|&v| used[v as usize] = true);
    let unused: Vec<usize> = (0..n).filter(|&v| !used[v]).collect();
    if let Some(&first) = unused.first() {
        problems.push(VolumeProblem::Unreferenced {
            count: unused.len(),
            first,
        });
    }
    let all = keyed_faces(mesh);
    let (mut boundary, mut i) = (Vec::new(), 0);
    while i < all.len() {
        let mut j = i + 1;
        while j < all.len() && all[j].0 == all[i].0 {
            j += 1;
        }
        match j - i {
            1 => boundary.push(all[i].2),
            2 => {}
            k => {
                if !problems
                    .iter()
                    .any(|p| matches!(p, VolumeProblem::NonManifoldFace { .. }))
                {
                    problems.push(VolumeProblem::NonManifoldFace {
                        vertices: all[i].0,
                        tets: k,
                    });
                }
            }
        }
        i = j;
    }
    let inverted: Vec<usize> = (0..m).filter(|&t| volumes[t] < 0.0).collect();
    if let Some(&first) = inverted.first() {
        problems.push(VolumeProblem::Inverted {
            count: inverted.len(),
            first,
        });
    }
    let mut uf = UnionFind::new(n);
    for t in mesh.tets() {
        for k in 1..4 {
            uf.union(t[0], t[k]);
        }
    }
    let mut roots: Vec<u32> = (0..n as u32)
        .filter(|&v| used[v as usize])
        .map(|v| uf.find(v))
        .collect();
    roots.sort_unstable();
    roots.dedup();
    if roots.len() > 1 {
        problems.push(VolumeProblem::Components { count: roots.len() });
    }
    let slivers: Vec<usize> = (0..m).filter(|&t| qualities[t] < SLIVER_QUALITY).collect();
    if !slivers.is_empty() {
        let worst = slivers
            .iter()
            .copied()
            .min_by(|&a, &b| qualities[a].total_cmp(&qualities[b]))
            .unwrap_or(0);
        problems.push(VolumeProblem::Slivers {
            count: slivers.len(),
            worst,
            quality: qualities[worst],
        });
    }
    problems.sort_by_key(|p| !p.is_fatal());
    let mut sorted = qualities.clone();
    sorted.sort_unstable_by(f64::total_cmp);
    let boundary_vertices = {
        let mut v: Vec<u32> = boundary.iter().flatten().copied().collect();
        v.sort_unstable();
        v.dedup();
        v.len()
    };
    let mut edge_uses: Vec<[u32; 2]> = boundary
        .iter()
        .flat_map(|f| (0..3).map(move |k| [f[k].min(f[(k + 1) % 3]), f[k].max(f[(k + 1) % 3])]))
        .collect();
    edge_uses.sort_unstable();
    // A closed 2-manifold boundary has every edge on exactly two of its triangles.
    let closed = edge_uses.chunk_by(|a, b| a == b).all(|uses| uses.len() == 2);
    edge_uses.dedup();
    let edges = edge_uses.len();
    let mut sheets = UnionFind::new(n);
    for f in &boundary {
        sheets.union(f[0], f[1]);
        sheets.union(f[0], f[2]);
    }
    let mut boundary_roots: Vec<u32> = boundary.iter().map(|f| sheets.find(f[0])).collect();
    boundary_roots.sort_unstable();
    boundary_roots.dedup();
    let euler = boundary_vertices as i64 - edges as i64 + boundary.len() as i64;
    let twice_genus = 2 * boundary_roots.len() as i64 - euler;
    // A pinched vertex (two sheets touching at a point) keeps every edge manifold but breaks
    // χ = Σ(2 − 2g): an odd or negative 2g gives it away.
    let genus = (closed && twice_genus >= 0 && twice_genus % 2 == 0).then_some(twice_genus / 2);
    let worst_tet = (0..m)
        .min_by(|&a, &b| qualities[a].total_cmp(&qualities[b]))
        .unwrap_or(0);
    VolumeReport {
        n_vertices: n,
        n_tets: m,
        volume: volumes.iter().map(|v| v.abs()).sum(),
        n_boundary_faces: boundary.len(),
        n_boundary_vertices: boundary_vertices,
        boundary_euler: euler,
        n_boundary_components: boundary_roots.len(),
        boundary_genus: genus,
        n_components: roots.len(),
        quality: (
            sorted.first().copied().unwrap_or(0.0),
            sorted.get(m / 2).copied().unwrap_or(0.0),
        ),
        worst_tet,
        problems,
    }
}

/// What [`repair_volume`] changed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VolumeRepair {
    /// Tetrahedra reoriented (`orient`).
    pub flipped: usize,
    /// Flat tetrahedra dropped (`degenerate`).
    pub dropped_tets: usize,
    /// Vertices dropped (`unreferenced`).
    pub dropped_vertices: usize,
    /// For every vertex of the input, its index in the repaired mesh (`None`: dropped).
    pub vertex_map: Vec<Option<u32>>,
}

/// Explicit repairs: `orient` makes every signed volume positive, `degenerate` drops flat
/// tetrahedra, `unreferenced` drops vertices in no tetrahedron (renumbering the rest in order).
///
/// # Errors
/// [`MeshError::Empty`] when nothing is left.
pub fn repair_volume(
    mesh: &TetMesh,
    orient: bool,
    degenerate: bool,
    unreferenced: bool,
) -> Result<(TetMesh, VolumeRepair), MeshError> {
    let mut report = VolumeRepair::default();
    let mut tets = Vec::with_capacity(mesh.n_tets());
    for t in 0..mesh.n_tets() {
        let mut tet = mesh.tets()[t];
        if degenerate && super::tet_element(mesh.corners(t)).is_none() {
            report.dropped_tets += 1;
            continue;
        }
        if orient && signed_volume(mesh.corners(t)) < 0.0 {
            tet.swap(0, 1);
            report.flipped += 1;
        }
        tets.push(tet);
    }
    let n = mesh.n_vertices();
    let mut map: Vec<Option<u32>> = (0..n as u32).map(Some).collect();
    let mut positions = mesh.positions().to_vec();
    if unreferenced {
        let mut used = vec![false; n];
        tets.iter().flatten().for_each(|&v| used[v as usize] = true);
        let mut next = 0u32;
        positions.clear();
        for v in 0..n {
            if used[v] {
                map[v] = Some(next);
                positions.push(mesh.positions()[v]);
                next += 1;
            } else {
                map[v] = None;
                report.dropped_vertices += 1;
            }
        }
        for t in &mut tets {
            for v in t.iter_mut() {
                // invariant: every vertex of a kept tetrahedron is used, so it is mapped.
                *v = map[*v as usize].unwrap_or(0);
            }
        }
    }
    report.vertex_map = map;
    Ok((TetMesh::new(positions, tets)?, report))
}
