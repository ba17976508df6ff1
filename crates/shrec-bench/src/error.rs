//! Failures of the benchmark: generation, mesh surgery, evaluation.

use shape_retrieval::RetrievalError;

/// Errors of the SHREC'10-style benchmark.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BenchError {
    /// A mesh routine failed (reading, writing, building a mesh, assembly).
    #[error(transparent)]
    Mesh(#[from] mesh_fem::MeshError),
    /// A heat-kernel routine failed (kernel, eigenpairs, decomposition).
    #[error(transparent)]
    Heat(#[from] wfem_heat::HeatError),
    /// A per-vertex mask does not have one entry per vertex.
    #[error("the vertex mask has {len} entries, but the mesh has {n_vertices} vertices")]
    MaskLength {
        /// Number of mask entries given.
        len: usize,
        /// Number of vertices of the mesh.
        n_vertices: usize,
    },
    /// A vertex index given as input (source vertex, pair to weld) does not exist.
    #[error("vertex index {index} is out of range: the mesh has {n_vertices} vertices")]
    VertexIndex {
        /// The offending index.
        index: u32,
        /// Number of vertices of the mesh.
        n_vertices: usize,
    },
    /// A generated mesh failed validation.
    #[error("{shape} {class} strength {strength}: invalid output: {reason}")]
    InvalidOutput {
        /// Base shape name.
        shape: String,
        /// Transformation class.
        class: String,
        /// Strength 1…5.
        strength: u8,
        /// What is wrong.
        reason: String,
    },
    /// A bad command-line or API argument (names the argument and the allowed values).
    #[error("{0}")]
    Argument(String),
    /// Writing or reading the manifest failed.
    #[error("manifest: {0}")]
    Json(#[from] serde_json::Error),
    /// A descriptor, vocabulary or metric failed on a named shape.
    #[error("{shape}: {source}")]
    Retrieval {
        /// The shape file (or "vocabulary …", "collection").
        shape: String,
        /// The failure.
        source: RetrievalError,
    },
    /// A bad ground-truth file, manifest entry or data folder.
    #[error("{0}")]
    Data(String),
}

impl BenchError {
    /// Wraps a retrieval failure with the shape it happened on.
    pub fn retrieval(shape: impl Into<String>) -> impl FnOnce(RetrievalError) -> BenchError {
        let shape = shape.into();
        move |source| BenchError::Retrieval { shape, source }
    }
}
