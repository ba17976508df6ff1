/// Failures of descriptor computation and retrieval.
/// Serialized (serde) as `{"Variant": {field: value}}`, which is how the Python package builds
/// its exceptions.
#[derive(Debug, thiserror::Error, serde::Serialize)]
#[non_exhaustive]
pub enum RetrievalError {
    /// An error from the heat kernel.
    #[error(transparent)]
    Heat(#[from] wfem_heat::HeatError),
    /// An error from mesh assembly or a mesh algorithm.
    #[error(transparent)]
    Mesh(#[from] mesh_fem::MeshError),

    // ---- shape-retrieval (descriptors, vocabularies, retrieval metrics) ----
    /// Two inputs that must agree in one dimension do not.
    #[error("{what}: expected {expected}, got {actual}")]
    DimensionMismatch {
        /// Which quantity disagrees (e.g. "eigenvectors columns vs eigenvalues").
        what: &'static str,
        /// The size implied by the other input.
        expected: usize,
        /// The size found.
        #[serde(rename = "found")]
        actual: usize,
    },
    /// An input that must not be empty is empty.
    #[error("{what} is empty")]
    Empty {
        /// Which input is empty.
        what: &'static str,
    },
    /// An input holds a NaN or an infinity.
    #[error("{what} holds a non-finite value at index {index}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Flat index (row-major for matrices: `row · ncols + col`) of the first bad value.
        index: usize,
    },
    /// An option given beside a descriptor's name that belongs to other descriptors (it is
    /// refused, not ignored; [`crate::descriptor::Descriptor::with_options`]). Front ends name
    /// the option their way (`--tau-min`, `tau_min=`).
    #[error("option `{option}` applies to descriptor {} only, not to {descriptor}", owners.join(", "))]
    MisplacedOption {
        /// The option ([`crate::descriptor::DescriptorOptions`] field name, e.g. `tau_min`).
        option: &'static str,
        /// The descriptor it was given to.
        descriptor: &'static str,
        /// The descriptors that take it.
        owners: Vec<&'static str>,
    },
    /// A descriptor whose times depend on the collection's scale (DHK1, DHK2, area-HKS) was
    /// asked to index a collection without its times.
    #[error("descriptor {descriptor} has no default times (they depend on the collection's scale): give them")]
    MissingTimes {
        /// The descriptor.
        descriptor: &'static str,
    },
    /// A scalar parameter is outside its valid range.
    #[error("parameter `{name}` = {value} is invalid: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What is required of it.
        reason: &'static str,
    },
    /// An eigenvalue is negative beyond round-off (L must be positive semidefinite).
    #[error("eigenvalue {index} = {value} is negative (L is positive semidefinite, so λ ≥ 0)")]
    NegativeEigenvalue {
        /// Its index in the given spectrum.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The operator-diagonal convention needs the mass matrix B (or BX), and none was given.
    #[error(
        "the operator-diagonal HKS convention needs the mass matrix: call Spectrum::with_mass or with_mass_eigenvectors"
    )]
    MassRequired,
    /// Every eigenvalue is (numerically) zero, so no automatic time range exists.
    #[error("the spectrum has no nonzero eigenvalue, so no automatic time range exists")]
    NoNonzeroEigenvalue,
    /// A signature value is not positive where a logarithm is needed (SI-HKS).
    #[error("signature value {value} at vertex {vertex}, time {time} is not positive, so its logarithm is undefined")]
    NonPositiveSignature {
        /// The vertex.
        vertex: usize,
        /// The diffusion time.
        #[serde(rename = "t")]
        time: f64,
        /// The offending value.
        value: f64,
    },
    /// Fewer descriptors (points) than requested clusters / words.
    #[error(
        "{n_points} descriptors are too few for {k} clusters (words): train on more shapes or ask for fewer words"
    )]
    TooFewDescriptors {
        /// Number of descriptors given.
        n_points: usize,
        /// Number of clusters requested.
        k: usize,
    },
    /// A vertex index is out of range.
    #[error("{what}: vertex {index} is out of range for {n_vertices} vertices")]
    VertexOutOfRange {
        /// Which input holds the index.
        what: &'static str,
        /// The index.
        #[serde(rename = "vertex")]
        index: usize,
        /// The number of vertices.
        n_vertices: usize,
    },
    /// A descriptor whose norm is zero was used as a normaliser.
    #[error("the descriptor of vertex {vertex} is zero, so the relative distance is undefined")]
    ZeroDescriptor {
        /// The vertex.
        vertex: usize,
    },
    /// No item qualifies for an average (e.g. no feature has a ground-truth correspondence).
    #[error("nothing to average: {what}")]
    NothingToAverage {
        /// What was being averaged.
        what: &'static str,
    },
    /// A distance oracle returned a negative or non-finite value.
    #[error("distance between vertices {from} and {to} is {value}, not a finite non-negative number")]
    InvalidDistance {
        /// First vertex.
        #[serde(rename = "source")]
        from: u32,
        /// Second vertex.
        #[serde(rename = "target")]
        to: u32,
        /// The value returned.
        value: f64,
    },
    /// A descriptor dimension has no spread over the training set, so it cannot be z-scored.
    #[error("descriptor dimension {dimension} is constant ({value}) over the training descriptors, so it cannot be z-scored")]
    ConstantDimension {
        /// The dimension (column).
        dimension: usize,
        /// Its constant value.
        value: f64,
    },
    /// A histogram bin is negative where a distance needs histograms (χ²).
    #[error("{what} has a negative bin {value} at index {index}")]
    NegativeBin {
        /// Which input.
        what: &'static str,
        /// The bin.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A failure on one named shape of a collection.
    #[error("{name}: {source}")]
    Shape {
        /// The shape (e.g. its file).
        name: String,
        /// The failure (in the message, not serialized).
        #[serde(skip)]
        source: Box<RetrievalError>,
    },
    /// No shape of a collection could be described (each is named with its reason).
    #[error("none of the {shapes} shapes could be used: {reasons}")]
    NothingUsable {
        /// How many shapes were given.
        shapes: usize,
        /// `name: reason` of each, separated by `; `.
        reasons: String,
    },
    /// A time window in units of the surface area was asked for, and the area is not known.
    #[error("the time window is in units of the surface area: call Spectrum::with_area")]
    AreaRequired,
    /// A time unit of the mean edge length was asked for where only a spectrum is known.
    #[error("the times are in units of the mean edge length squared, which a spectrum does not know: use the area or an absolute unit")]
    EdgeLengthRequired,
    /// A vocabulary or index (built here or read from storage) is inconsistent.
    #[error("invalid {what}: {reason}")]
    InvalidModel {
        /// Which artifact (`index`, `vocabulary`).
        what: &'static str,
        /// What is wrong, naming the field (e.g. the entry and the bin).
        reason: String,
    },
    /// A label file or a class rule cannot give a shape its class.
    #[error("{location}: {reason}")]
    Labels {
        /// The label file and line, or the shape's path.
        location: String,
        /// What is wrong.
        reason: String,
    },
    /// Reading or writing a stored vocabulary or index failed.
    #[error("{}: {reason}", path.display())]
    Storage {
        /// The file.
        path: std::path::PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// A stored index is damaged or was edited: a record does not match its checksum, or
    /// contradicts the file's invariants (retrieval-store's `StoreError::CorruptIndex`).
    /// Nothing read from it is used.
    #[error("{}: corrupt index: {record}: {reason}", path.display())]
    CorruptIndex {
        /// The file.
        path: std::path::PathBuf,
        /// The damaged record (`metadata "KEY"`, `shape ID ("NAME")`, `chunk C (shapes A to
        /// B)`, …).
        record: String,
        /// What does not match.
        reason: String,
    },
    /// No indexed shape, or more than one, answers to a name (`query --id`).
    #[error("{reason}")]
    UnknownShape {
        /// The name asked for.
        name: String,
        /// Why it does not name one shape, with the candidates.
        reason: String,
    },
}
