//! The recorded settings: [`DescriptorSettings`] (cleaning, eigenpairs, descriptor),
//! [`BagSettings`], [`TrainingParams`] and all of them together, [`RetrievalSettings`].

use super::{
    AsShape, Denoising, Despiking, GlobalSignature, HoleFilling, Refinement, ShapeRef, Smoothing, TopologyRepair,
    VertexWeights, DEFAULT_AREA_CAP,
};
use crate::bof::Assignment;
use crate::descriptor::{Descriptor, DescriptorParams, ShapeDescriptors};
use crate::distance::BagDistance;
use crate::spatial::SpatialBag;
use crate::{check, RetrievalError};
use mesh_fem::cloud::PointCloud;
use mesh_fem::{Laplacian, TriMesh};
use serde::{Deserialize, Serialize};

/// How a shape's vertices are described: the Laplacian, the cleaning, the eigenpairs and the
/// dense descriptor. A vocabulary is only meaningful for descriptors computed with the same
/// settings, so they are stored with it.
///
/// **Point clouds** ([`Self::shape`] of a [`mesh_fem::cloud::PointCloud`]) always get the robust
/// Laplacian of their neighbourhoods ([`ShapeDescriptors::from_cloud`]), whatever
/// [`Self::laplacian`] says, and of the cleaning steps only those that need no faces apply:
/// despiking (on the neighbourhood mesh's adjacency; the operators are then rebuilt from the
/// moved points) and a fixed smoothing (`K_t x` with the cloud's own operators, rebuilt
/// likewise). Denoising, hole filling and topology repair are mesh repairs — roughness and
/// coherence are measured across faces, holes are rims of faces, pinches and handles are
/// properties of a triangulation — and are skipped for clouds, which have none of these
/// (the settings stay what they are, so a collection may mix meshes and clouds).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DescriptorSettings {
    /// Number k of eigenpairs (default 100).
    pub eigenpairs: usize,
    /// The Laplacian of meshes ([`mesh_fem::Laplacian`], recorded by its name): the cotangent L
    /// (the default, paper Eq. (3)) or the robust intrinsic Delaunay L of the tufted cover, for
    /// non-manifold or badly triangulated collections; either way L is symmetric positive
    /// semidefinite. A missing field reads as the cotangent L (what files written before the
    /// choice existed were computed with). Point clouds always use the robust construction.
    #[serde(with = "wfem_base::serde_name")]
    pub laplacian: Laplacian,
    /// The descriptor (default SI-HKS, area time unit).
    pub descriptor: Descriptor,
    /// Optional smoothing of the embedding by a fixed time, after despiking, denoising and
    /// hole filling (default: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub smoothing: Option<Smoothing>,
    /// Removal of isolated spikes first (default: on, threshold 3; `null` turns it off). As
    /// every field, a missing one takes the default, so a vocabulary or index written before
    /// this option existed is queried with it; on shapes without spikes it changes nothing.
    pub despiking: Option<Despiking>,
    /// Denoising as much as needed, after the spikes and before hole filling and any fixed
    /// smoothing (default: on, target roughness 0.1; `null` turns it off). A missing field
    /// takes the default, as for `despiking`; smooth shapes are left unchanged.
    pub denoising: Option<Denoising>,
    /// Hole filling after denoising and before any fixed smoothing (default: on, rims up to
    /// 3 √A; `null` turns it off). Unlike the other steps, **a missing field reads as off**:
    /// a vocabulary or index written before hole filling existed holds bags of unfilled
    /// shapes, and its queries must be described alike. Closed shapes are left unchanged.
    #[serde(default)]
    pub hole_filling: Option<HoleFilling>,
    /// Repair of topological noise after hole filling: pinches split, then thin handles
    /// removed (default: on, handle cycles up to 0.35 √A; `null` turns it off). **A missing
    /// field reads as off**, as for `hole_filling`. Manifold shapes of genus 0 are left
    /// unchanged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub topology_repair: Option<TopologyRepair>,
    /// Refinement of coarse meshes, the last step (default: on, 20 vertices per eigenpair;
    /// `null` turns it off). **A missing field reads as off**, as for `hole_filling`: files
    /// written before it existed were described without it. Point clouds are not refined.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refinement: Option<Refinement>,
}

impl Default for DescriptorSettings {
    fn default() -> Self {
        Self {
            eigenpairs: crate::descriptor::DEFAULT_EIGENPAIRS,
            laplacian: Laplacian::default(),
            descriptor: Descriptor::default(),
            smoothing: None,
            despiking: Some(Despiking::default()),
            denoising: Some(Denoising::default()),
            hole_filling: Some(HoleFilling::default()),
            topology_repair: Some(TopologyRepair::default()),
            refinement: Some(Refinement::default()),
        }
    }
}

impl DescriptorSettings {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] for k < 2 (a descriptor needs a nonzero eigenvalue)
    /// and those of [`Descriptor::validate`].
    pub fn validate(&self) -> Result<(), RetrievalError> {
        if self.eigenpairs < 2 {
            return Err(RetrievalError::InvalidParameter {
                name: "eigenpairs",
                value: self.eigenpairs as f64,
                reason: "must be at least 2",
            });
        }
        if let Some(s) = &self.smoothing {
            check::positive("smoothing time", s.time)?;
        }
        if let Some(d) = &self.despiking {
            check::positive("spike threshold", d.threshold)?;
        }
        if let Some(d) = &self.denoising {
            d.validate()?;
        }
        if let Some(h) = &self.hole_filling {
            check::positive("largest hole perimeter", h.max_perimeter)?;
        }
        if let Some(t) = &self.topology_repair {
            check::positive("longest handle cycle", t.max_handle)?;
        }
        if let Some(r) = &self.refinement {
            r.validate()?;
        }
        self.descriptor.validate()
    }

    /// Cleans a shape and assembles its operators for these settings (no eigensolve yet): a
    /// mesh with [`Self::laplacian`] after the cleaning steps, a point cloud as the type docs
    /// say.
    ///
    /// # Errors
    /// [`RetrievalError::Mesh`] if a cleaning step or assembly fails, and those of
    /// [`Self::validate`].
    pub fn shape(&self, shape: &impl AsShape) -> Result<ShapeDescriptors, RetrievalError> {
        self.validate()?;
        match shape.as_shape() {
            ShapeRef::Mesh(mesh) => self.mesh_shape(mesh),
            ShapeRef::Cloud(cloud) => self.cloud_shape(cloud),
        }
    }

    /// The descriptor options of these settings: the eigensolver at
    /// [`crate::descriptor::RETRIEVAL_EIGEN_TOLERANCE`].
    fn params(&self) -> DescriptorParams {
        DescriptorParams {
            eigenpairs: self.eigenpairs,
            eigen: wfem_heat::spectral::EigenParams {
                tol: crate::descriptor::RETRIEVAL_EIGEN_TOLERANCE,
                ..Default::default()
            },
            ..Default::default()
        }
    }

    /// [`Self::shape`] of a mesh.
    fn mesh_shape(&self, mesh: &TriMesh) -> Result<ShapeDescriptors, RetrievalError> {
        // The cleaning steps, in order; each one that is on replaces the mesh. Every step that
        // adds vertices appends them, so the shape's own vertices stay the first `described`.
        let mut mesh = std::borrow::Cow::Borrowed(mesh);
        let mut described = mesh.n_vertices();
        if let Some(d) = &self.despiking {
            mesh = std::borrow::Cow::Owned(mesh_repair::filter::despike(&mesh, d.threshold)?.mesh);
        }
        // Denoising measures the roughness of the shape itself, so it comes before the
        // patches (smooth by construction) could dilute it.
        if let Some(d) = &self.denoising {
            mesh = std::borrow::Cow::Owned(d.apply_with(&mesh, self.laplacian)?);
        }
        if let Some(h) = &self.hole_filling {
            mesh = std::borrow::Cow::Owned(mesh_repair::holes::fill_holes(&mesh, h.max_perimeter)?.mesh);
        }
        // Pinches are split once holes are filled: holes touching at a vertex are closed one
        // by one as the simple loops of their common rim, while splitting that vertex first
        // would join them into one rim around both — a chain of touching micro holes into a
        // rim too long to close (a cat with 160 of them kept a 310-edge hole and 8 islands).
        // Handles are found on closed shapes, so after the holes are filled too.
        if let Some(t) = &self.topology_repair {
            let unwelded = mesh_repair::handles::unweld(&mesh);
            if !unwelded.copies.is_empty() {
                mesh = std::borrow::Cow::Owned(unwelded.mesh);
            }
            let cut = mesh_repair::handles::cut_handles(&mesh, t.max_handle)?;
            if !cut.cut.is_empty() {
                // The tubes' vertices are gone: the shape's own vertices are the kept ones.
                described -= cut.removed.iter().filter(|&&v| (v as usize) < described).count();
                mesh = std::borrow::Cow::Owned(cut.mesh);
            }
        }
        if let Some(s) = &self.smoothing {
            mesh = std::borrow::Cow::Owned(s.apply_with(&mesh, self.laplacian)?);
        }
        // The midpoints are appended: the described vertices stay the first ones.
        if let Some(fine) = self
            .refinement
            .map(|r| r.apply(&mesh, self.eigenpairs))
            .transpose()?
            .flatten()
        {
            mesh = std::borrow::Cow::Owned(fine);
        }
        ShapeDescriptors::with_laplacian(&mesh, self.laplacian, &self.params())?.described_only(described)
    }

    /// [`Self::shape`] of a point cloud: despiking and smoothing only (type docs), each
    /// followed by a new assembly when it moved a point.
    fn cloud_shape(&self, cloud: &PointCloud) -> Result<ShapeDescriptors, RetrievalError> {
        let params = self.params();
        let mut shape = ShapeDescriptors::from_cloud(cloud, &params)?;
        if let Some(d) = &self.despiking {
            let despiked = mesh_repair::filter::despike(shape.mesh(), d.threshold)?;
            if !despiked.moved.is_empty() {
                // The given normals stay (a spike's own normal was as wrong as its position).
                let moved = PointCloud::new(despiked.mesh.positions().to_vec(), cloud.normals().map(<[_]>::to_vec))?;
                shape = ShapeDescriptors::from_cloud(&moved, &params)?;
            }
        }
        if let Some(s) = &self.smoothing {
            let positions = s.positions(shape.operators(), shape.mesh().positions())?;
            // Smoothed points have new tangent planes: their normals are estimated again.
            shape = ShapeDescriptors::from_cloud(&PointCloud::new(positions, None)?, &params)?;
        }
        Ok(shape)
    }
}

/// How bags are made and compared (everything after the vocabulary).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BagSettings {
    /// Vertex weights of the bag (default `CappedArea { factor: 3 }`).
    pub weights: VertexWeights,
    /// How descriptors are spread over the words (default normalised, Shape Google).
    pub assignment: Assignment,
    /// Distance between bags (default χ²).
    pub distance: BagDistance,
    /// Optional fusion with the Shape-DNA (default: none).
    pub global: Option<GlobalSignature>,
    /// Spatially sensitive bags ([`crate::spatial`]): the bag becomes `[½ f, ½ F]`, the plain
    /// bag and the heat flow between words (or groups of words). Default off: with
    /// [`DEFAULT_WORDS`] words the plain bags do as well on the dev sets at 1/65 of the size
    /// (docs/RETRIEVAL-RESULTS.md). A missing field reads as off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spatial: Option<SpatialBag>,
}

impl Default for BagSettings {
    fn default() -> Self {
        Self {
            weights: VertexWeights::CappedArea {
                factor: DEFAULT_AREA_CAP,
            },
            assignment: Assignment::Normalized,
            distance: BagDistance::default(),
            global: None,
            spatial: None,
        }
    }
}

impl BagSettings {
    /// Checks the parameters against the number of eigenpairs k.
    ///
    /// # Errors
    /// Those of [`VertexWeights::validate`] and [`GlobalSignature::validate`].
    pub fn validate(&self, eigenpairs: usize) -> Result<(), RetrievalError> {
        self.weights.validate()?;
        if let Some(g) = &self.global {
            g.validate(eigenpairs)?;
        }
        if let Some(s) = &self.spatial {
            s.validate()?;
        }
        Ok(())
    }

    /// The length of a bag for V words: V, plus G(G+1)/2 with spatial bags over G classes
    /// ([`SpatialBag::classes`]).
    pub fn bag_len(&self, words: usize) -> usize {
        words + self.spatial.map_or(0, |s| SpatialBag::bins(s.classes(words)))
    }
}

/// Every user-selectable setting of `build`: the descriptor, the vocabulary training and the bags.
/// Deserialises from partial JSON (missing fields take their defaults).
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RetrievalSettings {
    /// Eigenpairs and dense descriptor.
    pub descriptor: DescriptorSettings,
    /// Vocabulary training.
    pub training: TrainingParams,
    /// Bags and distances.
    pub bags: BagSettings,
}

/// Options of [`VocabularyModel::train`](super::VocabularyModel::train).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrainingParams {
    /// Number of words V (default [`DEFAULT_WORDS`]).
    pub words: usize,
    /// Seed of k-means++ and of the training subsample (default 0).
    pub seed: u64,
    /// Lloyd iterations (default 300).
    pub max_iter: usize,
    /// Train k-means on at most this many pooled descriptors (seeded subsample; default 50 000).
    pub max_training_points: usize,
    /// z-score the descriptor dimensions before quantisation (default `true`).
    pub standardize: bool,
}

/// Default vocabulary size: 512 words (Shape Google: 48). Finer words tell apart classes made
/// of similar parts (spiders, octopus and ants; the TOSCA humans) on every dev set
/// (docs/RETRIEVAL-RESULTS.md, plain bags, 3 k-means seeds): SHREC'11 mAP 0.990 against 0.986
/// for the previous default (96 words with spatially sensitive bags), NN 1.0, spiders
/// 0.89–0.90 against 0.83–0.85; the SHREC'10 protocol with the handles class 98.6 / 97.2 /
/// 94.8 / 92.1 / 87.2 against 99.1 / 96.1 / 93.3 / 90.8 / 85.9; TOSCA-76 0.996–0.997 both.
/// 1024 words lose TOSCA (0.994).
pub const DEFAULT_WORDS: usize = 512;

impl Default for TrainingParams {
    fn default() -> Self {
        Self {
            words: DEFAULT_WORDS,
            seed: 0,
            max_iter: 300,
            max_training_points: 50_000,
            standardize: true,
        }
    }
}
