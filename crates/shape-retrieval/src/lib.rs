//! # shape-retrieval
//!
//! Heat kernel shape descriptors (HKS, scale-invariant HKS), feature points, bags of
//! features and retrieval metrics on top of [`wfem_heat`].
//!
//! Descriptors are computed from a truncated spectrum of the generalized eigenproblem
//! `L φ_k = λ_k B φ_k`, `ΦᵀBΦ = I` (paper, Eq. (4)), with L the cotangent stiffness
//! (symmetric positive semidefinite, positive diagonal) and B the mass matrix, given as plain
//! inputs ([`Spectrum`]), so any eigensolver can feed them:
//!
//! * [`hks`]: heat kernel signature in the kernel-value and operator-diagonal conventions,
//!   scaled and scale-normalized variants;
//! * [`exact`]: the HKS without eigen truncation (the kernel's diagonal by selected inversion) and the
//!   per-time choice between it and the truncated sum ([`HksMethod`], default auto);
//! * [`sihks`]: the scale-invariant HKS of Bronstein & Kokkinos;
//! * [`kmeans`](mod@kmeans), [`bof`]: vocabularies, soft-assigned (spatially sensitive) bags of features;
//! * [`retrieval`]: ranking, average precision, mAP, precision/recall;
//! * [`collection`]: a collection described or indexed in parallel, with progress, its
//!   unusable shapes left out and reported (or fatal);
//! * [`eval`](mod@eval): a labelled collection evaluated leave-one-out (mAP, NN, tiers,
//!   E-measure, DCG, per class, confused pairs);
//! * [`descriptor`]: from a mesh to DHK1–DHK3, SI-HKS and the SHK1/SHK2 feature points;
//! * [`features`]: feature points (local maxima), their repeatability, and robustness of
//!   dense descriptors.

#![warn(missing_docs)]
// Robustness (issue #8): no unwrap()/expect() on user-controlled data in library code; the few
// justified ones carry `#[allow]` and an `// invariant:` comment (checked by tests/no_unwrap.rs).
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

pub mod bof;
mod check;
pub mod collection;
pub mod descriptor;
pub mod distance;
mod error;
pub mod eval;
pub mod exact;
pub mod features;
pub mod global;
pub mod hks;
pub mod kmeans;
pub mod limits;
pub mod mesh_hks;
pub mod model;
mod output;
pub mod retrieval;
pub mod sihks;
pub mod spatial;
pub mod standardize;
pub mod store;

pub use bof::{vertex_areas, Assignment, Vocabulary, VocabularyParams};
pub use descriptor::{
    dense_descriptor, sparse_features, Descriptor, DescriptorParams, FeatureDetector, ShapeDescriptors,
    DEFAULT_EIGENPAIRS,
};
pub use distance::{chi_squared_distance, l1_distance, pairwise_distances, pairwise_l1, BagDistance};
pub use error::RetrievalError;
pub use exact::{
    exact_signature, signature_by_method, truncation_bound, truncation_estimate, HksMethod, HksSource,
    DEFAULT_TRUNCATION_TOL,
};
pub use features::{descriptor_distance, local_maxima, repeatability, DistanceOracle, FeatureSet, RepeatabilityReport};
pub use hks::{
    heat_kernel_signature, heat_trace, HeatKernelSignature, HksParams, Spectrum, SpectrumNormalization, TimeSampling,
    DEFAULT_NUM_TIMES,
};
pub use kmeans::{kmeans, KmeansParams, KmeansReport};
pub use mesh_hks::{mesh_hks, operators_hks, HksStep, MeshHks, MeshHksParams};
pub use model::{
    AsShape, BagSettings, Denoising, DescriptorSettings, DescriptorSpec, Despiking, GlobalSignature, HoleFilling,
    IndexEntry, Ranked, RetrievalIndex, RetrievalSettings, ShapeFeatures, ShapeRef, ShapeSignature, Smoothing,
    TopologyRepair, TrainingInfo, TrainingParams, VertexWeights, VocabularyModel,
};
pub use model::{DEFAULT_AREA_CAP, DEFAULT_MAX_COHERENCE, DEFAULT_TARGET_ROUGHNESS, DEFAULT_WORDS};
pub use output::check_index_output;
pub use retrieval::{average_precision, evaluate, precision_recall, rank, RetrievalReport};
pub use sihks::{scale_invariant_hks, MeshLengths, SihksParams, TimeUnit};
pub use standardize::Standardizer;
pub use store::{index_from_settings, index_settings, IndexStore, JsonFile, VocabularyStore};
