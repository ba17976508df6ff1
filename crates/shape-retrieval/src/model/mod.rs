//! Shape retrieval as a model: settings → vocabulary → index → queries.
//!
//! The pipeline (Shape Google, Bronstein et al. ACM TOG 30(1) 2011, on the wFEM kernel of the
//! paper's Eq. (6)):
//!
//! 1. **Dense descriptor** p(x) per vertex ([`Descriptor`](crate::descriptor::Descriptor)), from the k smallest eigenpairs
//!    of (L, B) (Eq. (4), truncated as in Eq. (8)). Default: SI-HKS with times in units of the
//!    surface area, exactly scale invariant ([`crate::sihks`]).
//! 2. **Vocabulary** ([`VocabularyModel`]): the descriptors of a training set are z-scored per
//!    dimension ([`Standardizer`](crate::standardize::Standardizer), statistics kept with the vocabulary) and quantised by k-means
//!    into V words with a soft-assignment width σ ([`Vocabulary`](crate::bof::Vocabulary)).
//! 3. **Bag** of a shape: `f = Θᵀ w / Σ w` with the soft assignment Θ (n × V) of its z-scored
//!    descriptors and vertex weights w ([`VertexWeights`]; default the areas `B·1` capped at 3
//!    medians), a histogram
//!    summing to 1.
//! 4. **Global signature** (optional fusion, [`GlobalSignature`]): the Shape-DNA
//!    `g_i = ln(λ_i A)`, i = 1 … m, of the same spectrum (A = 1ᵀB1), scale invariant.
//! 5. **Distance** between shapes X, Y: `d(X, Y) = d_bag(f_X, f_Y) + w_g · (1/m) Σ_i |g_i(X) − g_i(Y)|`
//!    with d_bag = L1 or χ² ([`BagDistance`](crate::distance::BagDistance)).
//!
//! [`RetrievalIndex`] holds the vocabulary, the bag settings and one entry (bag + global
//! signature) per indexed shape. A query costs one descriptor computation (one eigensolve) and
//! an O(N·V) scan of the entries: nothing the index holds is recomputed. Storage lives in
//! [`crate::store`]; this module has no file format.
//!
//! Training the vocabulary on the indexed collection itself is *optimistic* (the words are fit
//! to exactly the shapes that are then retrieved); train on disjoint shapes
//! ([`VocabularyModel::train`] on another set) to measure generalisation.
//!
//! One file per part, every type re-exported here: `shape` (what is described: a mesh or a
//! point cloud, [`ShapeRef`], [`AsShape`]), `cleaning`
//! (the steps before a shape is described: [`Despiking`], [`Denoising`], [`HoleFilling`],
//! [`TopologyRepair`], [`Smoothing`], [`Refinement`]), `weights` ([`VertexWeights`]), `global_signature`
//! ([`GlobalSignature`]), `settings` ([`DescriptorSettings`] — which also prepares a shape —,
//! [`BagSettings`], [`TrainingParams`], [`RetrievalSettings`]), `vocabulary` ([`ShapeFeatures`],
//! [`VocabularyModel`]) and `index` ([`RetrievalIndex`] and its entries).

mod cleaning;
mod global_signature;
mod index;
mod settings;
mod shape;
mod vocabulary;
mod weights;

pub use cleaning::{
    Denoising, Despiking, HoleFilling, Refinement, Smoothing, TopologyRepair, DEFAULT_MAX_COHERENCE,
    DEFAULT_MAX_HANDLE_LENGTH, DEFAULT_MAX_HOLE_PERIMETER, DEFAULT_SPIKE_THRESHOLD, DEFAULT_TARGET_ROUGHNESS,
    DEFAULT_VERTICES_PER_EIGENPAIR,
};
pub use global_signature::GlobalSignature;
pub use index::{resolve_name, IndexEntry, Ranked, RetrievalIndex, ShapeSignature, DEFAULT_RESULTS};
pub use settings::{BagSettings, DescriptorSettings, RetrievalSettings, TrainingParams, DEFAULT_WORDS};
pub use shape::{AsShape, ShapeRef};
/// The descriptor with its parameters, by its former name (it was a type of its own beside a
/// registry of bare names; now [`crate::descriptor::Descriptor`] is both).
#[deprecated(note = "use shape_retrieval::descriptor::Descriptor, which now carries the parameters")]
pub type DescriptorSpec = crate::descriptor::Descriptor;
#[allow(deprecated)]
pub use vocabulary::{ShapeFeatures, TrainingInfo, TrainingReport, VocabularyModel};
pub use weights::{VertexWeights, DEFAULT_AREA_CAP};
