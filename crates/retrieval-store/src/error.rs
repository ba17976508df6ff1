use std::path::PathBuf;

/// Failures of the retrieval store. Each variant names the file and the culprit (shape name,
/// chunk, index) so a user can find it.
/// Serialized (serde) as `{"Variant": {field: value}}`, which is how the Python package builds
/// its exceptions.
#[derive(Debug, thiserror::Error, serde::Serialize)]
#[non_exhaustive]
pub enum StoreError {
    /// SQLite reported an error (I/O, locking, a full disk, a corrupt page).
    #[error("{path}: {source}")]
    Sqlite {
        /// The store file.
        path: PathBuf,
        /// SQLite's error.
        #[source]
        #[serde(skip)]
        source: rusqlite::Error,
    },
    /// An operating-system error outside SQLite (creating or renaming the file).
    #[error("{path}: {source}")]
    Io {
        /// The file involved.
        path: PathBuf,
        /// The underlying error.
        #[source]
        #[serde(rename = "errno", serialize_with = "errno")]
        source: std::io::Error,
    },
    /// The file is not a store of this format (another SQLite database, or not SQLite).
    #[error("{path} is not a wfem retrieval store: {reason}")]
    NotAStore {
        /// The file.
        path: PathBuf,
        /// What was missing or wrong.
        reason: String,
    },
    /// The store was written by an incompatible version of this crate.
    #[error("{path}: store format version {found} is not supported (this build reads version {supported})")]
    UnsupportedVersion {
        /// The file.
        path: PathBuf,
        /// Version found in the file.
        found: u32,
        /// Version this build reads.
        supported: u32,
    },
    /// The file already exists and overwriting was not asked for.
    #[error("{path} already exists (pass overwrite to replace it)")]
    Exists {
        /// The file.
        path: PathBuf,
    },
    /// The file cannot be replaced safely: its write-ahead log is not empty, so another
    /// process has it open or a writer crashed and it was not opened since.
    #[error(
        "{path} is in use or was not closed cleanly ({wal} is not empty); open it once to recover, or close its users"
    )]
    InUse {
        /// The file.
        path: PathBuf,
        /// The non-empty write-ahead log.
        wal: PathBuf,
    },
    /// A vector does not have the store's dimension.
    #[error("vector of shape {name:?} has {found} values, but the store holds vectors of {expected}")]
    Dimension {
        /// The shape's name.
        name: String,
        /// The store's dimension.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A vector value is NaN, infinite or outside the range of f32 (the stored precision).
    #[error("vector of shape {name:?} has the value {value} at index {index}: not a finite f32")]
    NonFinite {
        /// The shape's name.
        name: String,
        /// Index of the value in the vector.
        index: usize,
        /// The value given.
        value: f64,
    },
    /// A shape name is already in the store (or repeated in one batch).
    #[error("shape name {name:?} is already in the store")]
    DuplicateName {
        /// The repeated name.
        name: String,
    },
    /// A shape name is empty.
    #[error("shape {index} of the batch has an empty name")]
    EmptyName {
        /// Position in the batch.
        index: usize,
    },
    /// A parameter is out of range.
    #[error("invalid parameter {name}: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// What is required.
        reason: String,
    },
    /// The file is damaged or was edited behind the store's back: a record's checksum does
    /// not match its contents, or the stored rows contradict the store's invariants. Nothing
    /// read from such a record is used.
    #[error("{path}: corrupt index: {record}: {reason}")]
    CorruptIndex {
        /// The file.
        path: PathBuf,
        /// The damaged record: `metadata "KEY"`, `shape ID ("NAME")`, `chunk C (shapes A to
        /// B)`, or `the chunk table` / `the file` for the structure.
        record: String,
        /// What does not match.
        reason: String,
    },
    /// A write to a store of an older format, which has no checksums: such a file is read (as
    /// unchecked) but not written to, so that it never holds records that cannot be verified.
    #[error(
        "{path} is a store of format version {version}, which has no checksums: it is read as unchecked, not written to; \
         upgrade it in place first (`wfem retrieval check --upgrade`, Python `VectorStore.upgrade`)"
    )]
    NoChecksums {
        /// The file.
        path: PathBuf,
        /// Its format version.
        version: u32,
    },
    /// A read-only store whose write-ahead log holds committed changes that cannot be read
    /// with it (the log is read when the shared-memory index can be created, or else in
    /// exclusive mode; both failed): the file alone would be an older state, so it is not read.
    #[error(
        "{path}: its log {wal} holds committed changes that cannot be read here ({reason}); fold the log in by \
         opening the index once where its folder is writable (e.g. `wfem retrieval check`), or copy both files there"
    )]
    UnreadableLog {
        /// The file.
        path: PathBuf,
        /// The non-empty write-ahead log.
        wal: PathBuf,
        /// SQLite's error.
        reason: String,
    },
    /// The path is a directory, FIFO, socket or device, not a store file.
    #[error("{path} is {kind}, not a store file")]
    NotAFile {
        /// The path.
        path: PathBuf,
        /// What it is ("a directory", "a FIFO", …).
        #[serde(rename = "reason")]
        kind: &'static str,
    },
    /// The store file was replaced (e.g. by a `build` of the same path) after this writer
    /// opened it: nothing was written.
    #[error("{path} was replaced by another process since it was opened; nothing was added (open it again)")]
    Replaced {
        /// The file.
        path: PathBuf,
    },
    /// A stored vector cannot be used by the distance (e.g. a negative bin for χ²).
    #[error("{path}: stored shape {id}: {reason}")]
    InvalidRow {
        /// The file.
        path: PathBuf,
        /// The shape's id.
        id: u64,
        /// What is wrong with it.
        reason: String,
    },
    /// A read would need more memory than can be allocated.
    #[error("{path}: {what} do not fit in memory")]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// What was to be read.
        #[serde(rename = "reason")]
        what: String,
    },
    /// The distance function returned NaN for a stored shape (a query must never rank NaN).
    #[error("the distance to shape {id} is not a number")]
    NanDistance {
        /// The shape's id.
        id: u64,
    },
}

/// An I/O error as its operating-system error number (`None` when it has none): the field
/// `errno` of the error's serialized form (what the Python exceptions carry).
fn errno<S: serde::Serializer>(e: &std::io::Error, s: S) -> Result<S::Ok, S::Error> {
    serde::Serialize::serialize(&e.raw_os_error(), s)
}
