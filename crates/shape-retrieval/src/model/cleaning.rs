//! The cleaning steps a shape goes through before it is described (beyond the paper):
//! [`Smoothing`], [`Despiking`], [`Denoising`], [`HoleFilling`], [`TopologyRepair`], and the
//! [`Refinement`] of coarse meshes last; their order is [`super::DescriptorSettings::shape`]'s.

use crate::{check, RetrievalError};
use faer::Mat;
use mesh_fem::{AssemblyParams, FemOperators, Laplacian, TriMesh};
use serde::{Deserialize, Serialize};

// The tuned defaults of the retrieval cleaning policy (measured on the dev sets; the repairs of
// mesh-repair take every bound explicitly).

/// Default largest perimeter of a hole that [`mesh_repair::holes::fill_holes`] closes, in units of `√A` (A the
/// area of the mesh). A hole left by the loss of one vertex and its ring on a mesh of n
/// vertices has a perimeter of about `8√(A/n)`, 0.1 `√A` at 5K vertices. On the data of
/// `cargo xtask shrec` every hole is closed at this bound and none more at 20 `√A`: cuts
/// through TOSCA limbs and torsos (the `holes` class) have rims of 0.2–3.1 `√A`, clusters of
/// touching micro holes up to 3.8 `√A`, and the rims above 3 pass through a vertex twice, so
/// they are closed as their shorter simple loops. A flat open patch never qualifies: by the
/// isoperimetric inequality its rim is at least `2√π ≈ 3.54` `√A`.
pub const DEFAULT_MAX_HOLE_PERIMETER: f64 = 3.0;

/// Default threshold of [`mesh_repair::filter::despike`]: a vertex is a spike when it lies more than this many local
/// edge lengths away from the centroid of its neighbours. On smooth surfaces the distance is a
/// small fraction of an edge (about κh²/2 for curvature κ and edge length h). On the 71 TOSCA
/// shapes (5K vertices) at most 3 vertices of a shape exceed 3 (the sharpest single-vertex
/// tips), while 86–100 % of the spikes of the synthetic shot noise (±5 mean edge lengths
/// along the normal) do.
pub const DEFAULT_SPIKE_THRESHOLD: f64 = 3.0;

/// Default bound of [`mesh_repair::handles::cut_handles`]: cycles up to `0.35 √A` are cut. Measured with
/// [`mesh_repair::handles::short_handle_cycle`]: the tubes of the synthetic handles class (shrec-bench, 5K-vertex
/// TOSCA shapes, 1–5 tubes) are 0.07–0.32 √A around (one of 120 at 0.39); the bridges that
/// simplification left on 12 of the 600 SHREC'11 500-face shapes 0.03–0.27 √A; real handles
/// are longer: a torus (odedstein `torus.obj`) 0.50 √A, the CAD rocker arm 0.64 √A.
pub const DEFAULT_MAX_HANDLE_LENGTH: f64 = 0.35;

/// Heat-kernel smoothing of the embedding before anything is computed (beyond the paper): the
/// vertex positions are replaced by `K_t x`, the wFEM heat kernel (Eq. (6)) applied to the three
/// coordinate functions, with `t = c·A` (A = 1ᵀB1, so the smoothing is scale invariant and does
/// not depend on the resolution). This is implicit fairing with the exact kernel: the
/// high-frequency part of the geometry (additive noise, isolated spikes) decays like
/// `e^{−λt}` while the shape's large scales are kept. Evaluated by the fast exact path of
/// [`wfem_heat::method::Method::Fast`] (one sparse Cholesky).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Smoothing {
    /// c in `t = c·A` (> 0).
    pub time: f64,
}

impl Smoothing {
    /// The mesh with positions `K_t x`, `t = c·A`, and the same faces (cotangent Laplacian).
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for c ≤ 0, [`RetrievalError::Mesh`] /
    /// [`RetrievalError::Heat`] from assembly and the kernel, and [`RetrievalError::Mesh`] if the
    /// smoothed positions do not form a valid mesh.
    pub fn apply(&self, mesh: &TriMesh) -> Result<TriMesh, RetrievalError> {
        self.apply_with(mesh, Laplacian::default())
    }

    /// [`Self::apply`] with the kernel of the given Laplacian.
    pub(crate) fn apply_with(&self, mesh: &TriMesh, laplacian: Laplacian) -> Result<TriMesh, RetrievalError> {
        check::positive("smoothing time", self.time)?;
        EmbeddingFlow::new(mesh, laplacian)?.mesh_at(mesh, self.time)
    }

    /// The positions `K_t x`, `t = c·A`, of a shape whose operators are given (a point cloud's).
    pub(crate) fn positions(
        &self,
        operators: &FemOperators,
        positions: &[[f64; 3]],
    ) -> Result<Vec<[f64; 3]>, RetrievalError> {
        check::positive("smoothing time", self.time)?;
        EmbeddingFlow::from_operators(operators, positions)?.positions_at(self.time)
    }
}

/// The heat flow of a shape's embedding: `K_t x` for the three coordinate functions, `t = c·A`,
/// by the fast exact path of the wFEM kernel (one factorization per time). Shared by
/// [`Smoothing`] and [`Denoising`].
struct EmbeddingFlow {
    kernel: wfem_heat::HeatKernel,
    area: f64,
    x: Mat<f64>,
}

impl EmbeddingFlow {
    /// The flow of a mesh with its operators of `laplacian`.
    fn new(mesh: &TriMesh, laplacian: Laplacian) -> Result<Self, RetrievalError> {
        let ops = mesh_fem::assemble(
            mesh,
            &AssemblyParams {
                laplacian,
                ..Default::default()
            },
        )?;
        Self::from_operators(&ops, mesh.positions())
    }

    fn from_operators(ops: &FemOperators, positions: &[[f64; 3]]) -> Result<Self, RetrievalError> {
        check::same("positions vs operators", ops.n(), positions.len())?;
        let area: f64 = crate::bof::vertex_areas(ops.mass.as_ref()).iter().sum();
        let kernel = wfem_heat::HeatKernel::new(
            ops,
            wfem_heat::HeatParams {
                mass: mesh_fem::Mass::Consistent,
                method: wfem_heat::method::Method::Fast(Default::default()),
            },
        )?;
        let x = Mat::from_fn(positions.len(), 3, |i, j| positions[i][j]);
        Ok(Self { kernel, area, x })
    }

    /// The positions `K_t x`, `t = c·A`.
    fn positions_at(&self, c: f64) -> Result<Vec<[f64; 3]>, RetrievalError> {
        let y = self.kernel.apply_many(self.x.as_ref(), c * self.area)?;
        Ok((0..y.nrows()).map(|i| [y[(i, 0)], y[(i, 1)], y[(i, 2)]]).collect())
    }

    /// `mesh` with positions `K_t x`, `t = c·A`, and the same faces.
    fn mesh_at(&self, mesh: &TriMesh, c: f64) -> Result<TriMesh, RetrievalError> {
        Ok(TriMesh::new(self.positions_at(c)?, mesh.faces().to_vec())?)
    }
}

/// Removal of isolated spikes (shot noise) before anything is computed (beyond the paper): a
/// vertex farther than `threshold` local edge lengths from the centroid of its neighbours is put
/// back as the harmonic fill of its neighbours ([`mesh_repair::filter::despike`]). A spike changes
/// the heat kernel around it at every small time and adds a few very large vertex areas, so a
/// handful of spikes moves a shape's bag towards every other spiky shape; a mesh without
/// spikes is left unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Despiking {
    /// The threshold, in local edge lengths (> 0).
    pub threshold: f64,
}

impl Default for Despiking {
    fn default() -> Self {
        Self {
            threshold: DEFAULT_SPIKE_THRESHOLD,
        }
    }
}

/// Denoising by the heat kernel, as much as the shape needs (beyond the paper): a shape whose
/// [`mesh_repair::filter::roughness`] is above `roughness` **and** whose height coherence
/// ([`mesh_repair::filter::surface_noise`]) is below `max_coherence` has its positions replaced by
/// `K_t x` (as [`Smoothing`]) with the smallest `t = c·A` on a doubling ladder (c = 10⁻⁶,
/// 2·10⁻⁶, …, at most 10⁻²) that brings the roughness down to `roughness`; any other shape is
/// left unchanged. Additive noise raises the roughness of every vertex and makes the heights of
/// neighbours independent, so a noisy copy of a shape is smoothed back towards the clean one,
/// while clean shapes keep all their detail (a fixed smoothing time for every shape costs the
/// clean ones their small scales).
///
/// The coherence gate keeps coarse clean meshes as they are: on ~250-vertex meshes the
/// curvature changes from one edge to the next, so half of the SHREC'11 shapes read as rough
/// (0.1–0.18) and the roughness alone smoothed them, shrinking thin limbs (SHREC'11 mAP 0.943
/// with it, 0.980 without denoising; `cargo xtask real-eval`, docs/RETRIEVAL-RESULTS.md). Their
/// heights stay coherent (≥ 0.16), those of noisy shapes do not (≤ 0.02 from 0.2 mean edge
/// lengths of noise on).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Denoising {
    /// The target roughness, in edge lengths (> 0).
    pub roughness: f64,
    /// Shapes whose height coherence is at least this are never denoised (in (−1, 1]; `None`:
    /// no gate, the roughness alone decides — what files written before the gate hold).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_coherence: Option<f64>,
}

/// Default target of [`Denoising`]: above the roughness of every TOSCA shape (0.016–0.069 over
/// the 71 poses) and of the same shapes decimated to 10 % (≤ 0.088), at that of additive noise
/// of 0.1 mean edge lengths (0.10–0.11), below that of stronger noise (0.18 at 0.2).
pub const DEFAULT_TARGET_ROUGHNESS: f64 = 0.1;

/// Default coherence gate of [`Denoising`]: between the noisy TOSCA shapes (≤ 0.02 from 0.2
/// mean edge lengths of noise on; −0.07 … 0.17 at 0.1, where denoising changes no retrieval
/// number) and the coarse clean SHREC'11 shapes (≥ 0.16; TOSCA ≥ 0.40).
pub const DEFAULT_MAX_COHERENCE: f64 = 0.1;

impl Default for Denoising {
    fn default() -> Self {
        Self {
            roughness: DEFAULT_TARGET_ROUGHNESS,
            max_coherence: Some(DEFAULT_MAX_COHERENCE),
        }
    }
}

impl Denoising {
    /// Whether a mesh is denoised: rough and (with a gate) incoherent.
    pub fn applies_to(&self, mesh: &TriMesh) -> bool {
        let noise = mesh_repair::filter::surface_noise(mesh);
        noise.roughness > self.roughness && self.max_coherence.is_none_or(|c| noise.coherence < c)
    }

    /// The mesh, smoothed as much as needed (or unchanged), with the cotangent Laplacian.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for a target ≤ 0 or a gate outside (−1, 1],
    /// [`RetrievalError::Mesh`] / [`RetrievalError::Heat`] from assembly and the kernel, and
    /// [`RetrievalError::Mesh`] if the smoothed positions do not form a valid mesh.
    pub fn apply(&self, mesh: &TriMesh) -> Result<TriMesh, RetrievalError> {
        self.apply_with(mesh, Laplacian::default())
    }

    /// [`Self::apply`] with the kernel of the given Laplacian.
    pub(crate) fn apply_with(&self, mesh: &TriMesh, laplacian: Laplacian) -> Result<TriMesh, RetrievalError> {
        self.validate()?;
        if !self.applies_to(mesh) {
            return Ok(mesh.clone());
        }
        let flow = EmbeddingFlow::new(mesh, laplacian)?;
        let mut c = DENOISING_FIRST_TIME;
        loop {
            let smoothed = flow.mesh_at(mesh, c)?;
            if c >= DENOISING_LAST_TIME || mesh_repair::filter::roughness(&smoothed) <= self.roughness {
                return Ok(smoothed);
            }
            c *= 2.0;
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for a target ≤ 0 or a gate outside (−1, 1].
    pub fn validate(&self) -> Result<(), RetrievalError> {
        check::positive("target roughness", self.roughness)?;
        match self.max_coherence {
            Some(c) if !(c > -1.0 && c <= 1.0) => Err(RetrievalError::InvalidParameter {
                name: "largest coherence denoised",
                value: c,
                reason: "must be in (−1, 1]",
            }),
            _ => Ok(()),
        }
    }
}

/// Hole filling (beyond the paper): every hole whose rim is at most `max_perimeter · √A` long
/// is closed by a smooth patch ([`mesh_repair::holes::fill_holes`]; rims of touching holes are
/// split and closed one by one) before the shape is described. The patch changes the
/// operators — the heat no longer reflects at the rim of a hole the intact shape does not
/// have — but its vertices are not described: descriptors, weights and the cap of
/// [`VertexWeights::CappedArea`](super::VertexWeights::CappedArea) are taken over the shape's own vertices only. Closed shapes
/// are left unchanged. Measured on the synthetic SHREC'10 data (docs/SHREC-RESULTS.md, outside
/// vocabulary, area weights): micro holes at strength ≤ 5 from 0.61 to 0.91 mAP, and the
/// cumulative ≤ 5 from 76.9 to 86.6 %.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoleFilling {
    /// The longest rim closed, in units of √A (> 0).
    pub max_perimeter: f64,
}

impl Default for HoleFilling {
    fn default() -> Self {
        Self {
            max_perimeter: DEFAULT_MAX_HOLE_PERIMETER,
        }
    }
}

/// Repair of topological noise (beyond the paper), once holes are filled: first every pinched
/// vertex — where two parts were welded at a point or along an edge — is split into one
/// vertex per sheet ([`mesh_repair::handles::unweld`]); then, on a closed shape of genus > 0,
/// every thin handle — a non-separating cycle of length at most
/// `max_handle · √A` — is removed with its tube and the openings closed
/// ([`mesh_repair::handles::cut_handles`]), shortest first. A tube glued between two parts that
/// touch (scans and simplifications leave them; the synthetic `handles` class makes them)
/// then no longer carries heat between them. Copies, patches and the removed tubes are not
/// described. Manifold shapes of genus 0 (nearly all) are left as they are; real handles are
/// longer than the bound (a torus 0.50 √A). Pinches are split after the holes are filled
/// because holes touching at a vertex are closed one by one as the simple loops of their
/// common rim, whereas splitting the vertex first joins them into one rim around both (a chain
/// of touching micro holes becomes a rim too long to close).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TopologyRepair {
    /// The longest handle cycle removed, in units of √A (> 0).
    pub max_handle: f64,
}

impl Default for TopologyRepair {
    fn default() -> Self {
        Self {
            max_handle: DEFAULT_MAX_HANDLE_LENGTH,
        }
    }
}

/// Refinement of coarse meshes (beyond the paper), the last step before the eigensolve: a mesh
/// with fewer than `vertices_per_eigenpair · k` vertices (k the eigenpairs) has every triangle
/// split into four at its edge midpoints ([`mesh_fem::refine::split_faces`]), again until it
/// has that many. The surface is exactly the same, but its first k eigenpairs are computed with
/// enough degrees of freedom; the shape is still described at its own vertices only (the
/// midpoints are not described, as the patches of [`HoleFilling`]), so its bag weighs the same
/// points as before.
///
/// Without it the descriptors depend on the resolution: the 100th eigenfunction of a 500-vertex
/// mesh has five vertices per wavelength, so a copy of a shape resampled to 10 % of its vertices
/// looks like another shape, and a collection that mixes resolutions is ranked by resolution
/// (measured: the SHREC'10 protocol's `sampling` class at strength 5 from 0.835 to 0.924; on
/// SHREC'11's 250-vertex meshes mAP 0.9896 → 0.9904; docs/RETRIEVAL-RESULTS.md). Meshes with
/// enough vertices are left unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Refinement {
    /// The fewest vertices per eigenpair the eigenbasis is computed with (in (0, 100]: with the
    /// largest eigenpair count, 1,000, a mesh is refined to at most 400,000 vertices).
    pub vertices_per_eigenpair: f64,
}

/// Default of [`Refinement`]: 20 vertices per eigenpair (2,000 for the default 100 pairs), so a
/// 250-vertex SHREC'11 mesh is described on 4,000 vertices and a 5,000-vertex TOSCA shape as
/// it is.
pub const DEFAULT_VERTICES_PER_EIGENPAIR: f64 = 20.0;

impl Default for Refinement {
    fn default() -> Self {
        Self {
            vertices_per_eigenpair: DEFAULT_VERTICES_PER_EIGENPAIR,
        }
    }
}

impl Refinement {
    /// The mesh split until it has at least `vertices_per_eigenpair · eigenpairs` vertices (its
    /// own vertices first and unchanged), or `None` if it already has them.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for a factor outside (0, 100].
    pub fn apply(&self, mesh: &TriMesh, eigenpairs: usize) -> Result<Option<TriMesh>, RetrievalError> {
        self.validate()?;
        let wanted = self.vertices_per_eigenpair * eigenpairs as f64;
        if mesh.n_vertices() as f64 >= wanted {
            return Ok(None);
        }
        let mut fine = mesh_fem::refine::split_faces(mesh);
        while (fine.n_vertices() as f64) < wanted {
            fine = mesh_fem::refine::split_faces(&fine);
        }
        Ok(Some(fine))
    }

    /// Checks the factor.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for a factor outside (0, 100].
    pub fn validate(&self) -> Result<(), RetrievalError> {
        let v = self.vertices_per_eigenpair;
        if v > 0.0 && v <= 100.0 {
            Ok(())
        } else {
            Err(RetrievalError::InvalidParameter {
                name: "vertices per eigenpair",
                value: v,
                reason: "must be in (0, 100]",
            })
        }
    }
}

/// The ladder of [`Denoising`]: c from 10⁻⁶ (well below an edge: a 5K-vertex shape has
/// ℓ̄² ≈ 4·10⁻⁴ A) doubling up to at most 10⁻².
const DENOISING_FIRST_TIME: f64 = 1e-6;
const DENOISING_LAST_TIME: f64 = 1e-2;
