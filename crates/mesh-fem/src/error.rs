use std::path::PathBuf;

/// What fixes a problem of a mesh, for each front end to name in its own words (the command
/// line's `--repair degenerate`, Python's `wfem.repair(…, drop_degenerate_faces=True)`, Rust's
/// `RepairOptions::drop_degenerate_faces`): errors and validation reports carry it as data
/// ([`MeshError::remedy`], `Problem::remedy`) instead of a sentence that names one API.
/// [`Remedy::in_library`] is how this crate says it (its `Display`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[non_exhaustive]
pub enum Remedy {
    /// Drop vertices that belong to no face or tetrahedron.
    DropUnreferencedVertices,
    /// Drop faces that repeat a vertex or have zero area (tetrahedra of zero volume).
    DropDegenerateFaces,
    /// Drop later copies of faces with the same vertices.
    DropDuplicateFaces,
    /// Orient the faces (tetrahedra) consistently.
    OrientFaces,
    /// Read polygons fan-triangulated.
    TriangulatePolygons,
    /// Scale the coordinates down.
    ScaleDown,
}

impl Remedy {
    /// The option of this crate that does it (`RepairOptions::orient_faces`).
    pub fn in_library(self) -> &'static str {
        match self {
            Remedy::DropUnreferencedVertices => "RepairOptions::drop_unreferenced_vertices",
            Remedy::DropDegenerateFaces => "RepairOptions::drop_degenerate_faces",
            Remedy::DropDuplicateFaces => "RepairOptions::drop_duplicate_faces",
            Remedy::OrientFaces => "RepairOptions::orient_faces",
            Remedy::TriangulatePolygons => "LoadOptions::triangulate_polygons (fan triangulation)",
            Remedy::ScaleDown => "scale the mesh down (TriMesh::scaled)",
        }
    }
}

impl std::fmt::Display for Remedy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.in_library())
    }
}

/// Everything that can go wrong between a file on disk and the FEM operators.
///
/// Each variant names the culprit (file, line, face or vertex) so that a user can find it.
/// Serialized (serde) as `{"Variant": {field: value}}`, which is how the Python package builds
/// its exceptions: `kind` is the variant, the fields are the exception's attributes.
#[derive(Debug, thiserror::Error, serde::Serialize)]
#[non_exhaustive]
pub enum MeshError {
    /// The mesh has no vertices or no faces.
    #[error("the mesh is empty ({n_vertices} vertices, {n_faces} faces)")]
    Empty {
        /// Number of vertices found.
        n_vertices: usize,
        /// Number of faces found.
        n_faces: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate {position:?}")]
    NonFiniteCoordinate {
        /// Vertex index (0-based).
        vertex: usize,
        /// Its position as read.
        position: [f64; 3],
    },
    /// A face refers to a vertex that does not exist.
    #[error("face {face} uses vertex {index}, but the mesh has {n_vertices} vertices")]
    IndexOutOfRange {
        /// Face index (0-based).
        face: usize,
        /// The offending vertex index (0-based).
        index: u32,
        /// Number of vertices of the mesh.
        n_vertices: usize,
    },
    /// The whole mesh has zero (or non-finite) area.
    #[error("the mesh has total area {area}: zero or not a finite number, so there is no usable geometry")]
    DegenerateMesh {
        /// Total area found.
        area: f64,
    },
    /// A face repeats a vertex index.
    #[error("{}; fix: {}", repeated(*.face, .vertices), Remedy::DropDegenerateFaces)]
    RepeatedIndex {
        /// Face index.
        face: usize,
        /// Its vertex indices.
        vertices: Vec<u32>,
    },
    /// A face has zero area.
    #[error("{}; fix: {}", zero_area(*.face, .vertices), Remedy::DropDegenerateFaces)]
    DegenerateFace {
        /// Face index.
        face: usize,
        /// Its vertex indices.
        vertices: [u32; 3],
    },
    /// A polygon with more than three corners was found and fan triangulation was not enabled.
    #[error("{}; fix: {}", polygon(.path, *.face, *.corners), Remedy::TriangulatePolygons)]
    Polygon {
        /// File read.
        path: PathBuf,
        /// Face index in the file (0-based).
        face: usize,
        /// Number of corners.
        corners: usize,
    },
    /// A vertex belongs to no face.
    #[error("{}; fix: {}", unreferenced(*.vertex), Remedy::DropUnreferencedVertices)]
    UnreferencedVertex {
        /// Vertex index.
        vertex: usize,
    },
    /// The file extension names no supported format.
    #[error("{path}: unknown mesh format {extension:?} (supported: .obj, .ply, .off, .stl)")]
    UnknownFormat {
        /// File read.
        path: PathBuf,
        /// The extension found (empty if none).
        extension: String,
    },
    /// The file could not be parsed.
    #[error("{path}:{line}: {message}")]
    Parse {
        /// File read.
        path: PathBuf,
        /// 1-based line (0 for binary formats or when unknown).
        line: usize,
        /// What was wrong.
        #[serde(rename = "reason")]
        message: String,
    },
    /// An operating-system I/O error.
    #[error("{path}: {source}")]
    Io {
        /// File involved.
        path: PathBuf,
        /// The underlying error.
        #[source]
        #[serde(rename = "errno", serialize_with = "errno")]
        source: std::io::Error,
    },
    /// The validation found a problem that makes the mesh unusable for the requested work.
    #[error("mesh is unusable: {reason}")]
    Invalid {
        /// Human-readable summary naming the culprit.
        reason: String,
    },
    /// A Matrix Market file could not be read or written, or holds the wrong matrix.
    #[error("{path}: matrix market: {message}")]
    MatrixMarket {
        /// File involved.
        path: PathBuf,
        /// What was wrong.
        #[serde(rename = "reason")]
        message: String,
    },
    // ===== morse.rs: critical points and persistence (appended by branch `morse`) =====
    /// A per-vertex scalar field does not have one value per vertex.
    #[error("the scalar field has {len} values, but the mesh has {n_vertices} vertices")]
    ScalarFieldLength {
        /// Number of values given.
        len: usize,
        /// Number of vertices of the mesh.
        n_vertices: usize,
    },
    /// A per-vertex scalar field holds a NaN or infinite value.
    #[error("the scalar field value at vertex {vertex} is {value}, not a finite number")]
    NonFiniteScalarField {
        /// Vertex index (0-based).
        vertex: usize,
        /// The offending value.
        value: f64,
    },
    // ===== end of morse.rs block =====
    // ---- Variants added by the mesh I/O work (branch `io`); keep this block together. ----
    /// A face in a mesh file names a negative vertex index (or an OBJ relative index that
    /// points before the first vertex).
    #[error("{path}:{line}: face {face} uses the negative vertex index {index}")]
    NegativeIndex {
        /// File read.
        path: PathBuf,
        /// 1-based line (0 for binary formats).
        line: usize,
        /// Face index in the file (0-based).
        face: usize,
        /// The index as written in the file.
        index: i64,
    },
    /// A per-vertex field has the wrong number of values.
    #[error("{path}: field {name:?} has {found} values, but the mesh has {expected} vertices")]
    FieldLength {
        /// File read or written.
        path: PathBuf,
        /// Field name (the file name for a field file being read).
        name: String,
        /// Number of values required (the number of vertices).
        expected: usize,
        /// Number of values found.
        found: usize,
    },
    /// A per-vertex field holds a NaN or infinite value.
    #[error("{path}: field {name:?} has the non-finite value {value} at vertex {vertex}")]
    NonFiniteValue {
        /// File read or written.
        path: PathBuf,
        /// Field name (the file name for a field file being read).
        name: String,
        /// Vertex index (0-based).
        vertex: usize,
        /// The value found.
        value: f64,
    },
    // ---- end of the I/O block ----

    // ---- variants added by the validate/stats/mtx work (branch `validate`) ----
    /// A repair option has an invalid value.
    #[error("invalid repair option {option}: {message}")]
    InvalidRepairOption {
        /// The option's name.
        option: &'static str,
        /// What was wrong.
        #[serde(rename = "reason")]
        message: String,
    },
    /// A line of a Matrix Market file could not be parsed.
    #[error("{path}:{line}: matrix market: {message}")]
    MatrixMarketLine {
        /// File read.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What was wrong.
        #[serde(rename = "reason")]
        message: String,
    },
    // ---- end of variants added by the validate/stats/mtx work ----

    // ---- variants added by the robust Laplacian and point-cloud work (branch `robust-points`) ----
    /// A numeric parameter is out of its range.
    #[error("parameter {name} = {value} is invalid: expected {expected}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range, in words.
        expected: &'static str,
    },
    /// The intrinsic triangulation became numerically degenerate (a triangle of zero or
    /// non-finite area), e.g. with mollification turned off on a mesh with a flat face.
    #[error("intrinsic triangle {triangle} has edge lengths {lengths:?}, not a valid triangle; use a mollification factor > 0")]
    DegenerateIntrinsicTriangle {
        /// Triangle of the intrinsic triangulation.
        triangle: usize,
        /// Its three edge lengths.
        lengths: [f64; 3],
    },
    /// The intrinsic Delaunay flips did not finish within their bound (a safety net against
    /// rounding cycles; not expected to happen).
    #[error("intrinsic Delaunay flipping did not finish after {flips} flips on {n_edges} edges")]
    FlipLimit {
        /// Flips done.
        flips: usize,
        /// Edges of the triangulation.
        n_edges: usize,
    },
    /// A point cloud has too few points.
    #[error("the point cloud has {n_points} points; at least {minimum} are needed")]
    TooFewPoints {
        /// Points found.
        n_points: usize,
        /// The minimum.
        minimum: usize,
    },
    /// A point's coordinate or normal is NaN or infinite.
    #[error("point {point} has a non-finite {what} {position:?}")]
    NonFinitePoint {
        /// Point index (0-based).
        point: usize,
        /// The offending vector as read.
        position: [f64; 3],
        /// "coordinate" or "normal".
        what: &'static str,
    },
    /// The normals of a point cloud are not one per point.
    #[error("the point cloud has {expected} points but {found} normals")]
    NormalsLength {
        /// Normals given.
        found: usize,
        /// Points.
        expected: usize,
    },
    /// Two points of a cloud have identical coordinates.
    #[error("point {point} has the same coordinates as point {duplicate_of}; merge duplicate points first (repair duplicate-vertices)")]
    DuplicatePoint {
        /// The later point.
        point: usize,
        /// The earlier point with the same coordinates.
        duplicate_of: usize,
    },
    /// A point of a cloud is in no local triangle.
    #[error("point {point} is in no local triangle: its {n_neighbours} nearest neighbours are collinear with it or project onto it; use more neighbours or drop the point")]
    DegenerateNeighbourhood {
        /// Point index (0-based).
        point: usize,
        /// Neighbours used.
        n_neighbours: usize,
    },
    // ---- end of the robust Laplacian and point-cloud block ----
    /// A per-element field does not have one value per element.
    #[error("the field has {found} vectors, but the mesh has {expected} elements")]
    ElementFieldLength {
        /// Vectors given.
        found: usize,
        /// Elements of the mesh.
        expected: usize,
    },
    /// A tetrahedron names a vertex that does not exist.
    #[error("tetrahedron {tet} uses vertex {index}, but the mesh has {n_vertices} vertices")]
    TetIndexOutOfRange {
        /// Tetrahedron index.
        tet: usize,
        /// The index found.
        index: u32,
        /// Number of vertices.
        n_vertices: usize,
    },
    /// A tetrahedron of (numerically) zero volume: its gradients are undefined.
    #[error("tetrahedron {tet} (vertices {vertices:?}) has zero volume ({volume:e}); --repair degenerate drops such tetrahedra")]
    DegenerateTet {
        /// Tetrahedron index.
        tet: usize,
        /// Its vertices.
        vertices: [u32; 4],
        /// Its signed volume.
        volume: f64,
    },
    /// A volume mesh file could not be parsed.
    #[error("{path}: line {line}: {message}")]
    VolumeParse {
        /// File read.
        path: PathBuf,
        /// 1-based line (0 for binary data).
        line: usize,
        /// What is wrong.
        #[serde(rename = "reason")]
        message: String,
    },
    /// A row-by-row matrix file ([`crate::io::rows`]) cannot take what it was given.
    #[error("{path}: {reason}")]
    RowFile {
        /// The target file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A vertex given by the caller (a source, a query vertex) is not a vertex of the mesh.
    #[error("{what} {index} is out of range: the mesh has {n_vertices} vertices (0 to {last})", last = n_vertices.saturating_sub(1))]
    VertexOutOfRange {
        /// What the vertex was given as ("source", "vertex").
        what: &'static str,
        /// The index given.
        index: u64,
        /// Number of vertices of the mesh.
        n_vertices: usize,
    },
}

/// The problem of [`MeshError::Polygon`], without its remedy.
fn polygon(path: &std::path::Path, face: usize, corners: usize) -> String {
    format!("{}: face {face} has {corners} corners", path.display())
}

/// The problem of [`MeshError::RepeatedIndex`], without its remedy.
fn repeated(face: usize, vertices: &[u32]) -> String {
    format!("face {face} repeats a vertex (vertices {vertices:?})")
}

/// The problem of [`MeshError::DegenerateFace`], without its remedy.
fn zero_area(face: usize, vertices: &[u32; 3]) -> String {
    format!("face {face} has zero area (vertices {vertices:?})")
}

/// The problem of [`MeshError::UnreferencedVertex`], without its remedy.
fn unreferenced(vertex: usize) -> String {
    format!("vertex {vertex} belongs to no face or tetrahedron")
}

impl MeshError {
    /// What fixes this error, when a repair or an option does.
    pub fn remedy(&self) -> Option<Remedy> {
        match self {
            MeshError::Polygon { .. } => Some(Remedy::TriangulatePolygons),
            MeshError::UnreferencedVertex { .. } => Some(Remedy::DropUnreferencedVertices),
            MeshError::RepeatedIndex { .. } | MeshError::DegenerateFace { .. } => Some(Remedy::DropDegenerateFaces),
            _ => None,
        }
    }

    /// The message with its remedy named by `fix` (a front end's words for [`Remedy`]); the
    /// `Display` form is `message_with(&|r| r.in_library().to_string())`.
    pub fn message_with(&self, fix: &dyn Fn(Remedy) -> String) -> String {
        let Some(remedy) = self.remedy() else {
            return self.to_string();
        };
        let problem = match self {
            MeshError::Polygon { path, face, corners } => polygon(path, *face, *corners),
            MeshError::UnreferencedVertex { vertex } => unreferenced(*vertex),
            MeshError::RepeatedIndex { face, vertices } => repeated(*face, vertices),
            MeshError::DegenerateFace { face, vertices } => zero_area(*face, vertices),
            other => return other.to_string(),
        };
        format!("{problem}; fix: {}", fix(remedy))
    }
}

/// An I/O error as its operating-system error number (`None` when it has none): the field
/// `errno` of the error's serialized form (what the Python exceptions carry).
fn errno<S: serde::Serializer>(e: &std::io::Error, s: S) -> Result<S::Ok, S::Error> {
    serde::Serialize::serialize(&e.raw_os_error(), s)
}
