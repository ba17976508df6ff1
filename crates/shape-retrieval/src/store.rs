//! Storage of vocabularies and indexes, kept apart from the model ([`crate::model`]).
//!
//! [`IndexStore`] / [`VocabularyStore`] are the two small interfaces a backend implements;
//! [`JsonFile`] is the one backend here: one pretty-printed JSON document per artifact, written
//! atomically ([`mesh_fem::io::write_atomic`]) with 17 significant digits (serde_json's
//! shortest round-trip form), so a stored model reads back bit-identical.
//!
//! Reading validates everything before a model exists: the format tag and version, the settings,
//! finite numbers, consistent dimensions (words vs descriptor vs z-score statistics, bags vs
//! words, global signatures vs settings), bags that are histograms (values in [0, 1] summing
//! to 1). A file that fails any check is refused with [`RetrievalError::InvalidModel`] or
//! [`RetrievalError::Storage`] naming the culprit, so a query never prints `inf` or `NaN`.

use crate::bof::Vocabulary;
use crate::model::{
    BagSettings, DescriptorSettings, IndexEntry, RetrievalIndex, ShapeSignature, TrainingParams, TrainingReport,
    VocabularyModel,
};
use crate::standardize::Standardizer;
use crate::RetrievalError;
use faer::Mat;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Format tag of a stored vocabulary.
pub const VOCABULARY_FORMAT: &str = "wfem-retrieval-vocabulary";
/// Format tag of a stored index.
pub const INDEX_FORMAT: &str = "wfem-retrieval-index";
/// Version of both formats (bumped on any incompatible change).
pub const FORMAT_VERSION: u32 = 1;

/// A place a [`RetrievalIndex`] can be saved to and loaded from.
pub trait IndexStore {
    /// Reads and validates an index.
    ///
    /// # Errors
    /// [`RetrievalError::Storage`] (unreadable, not this format) or
    /// [`RetrievalError::InvalidModel`] (inconsistent content).
    fn load_index(&self) -> Result<RetrievalIndex, RetrievalError>;

    /// Writes an index (atomically: a reader sees the old or the new one, never a mixture).
    ///
    /// # Errors
    /// [`RetrievalError::Storage`].
    fn save_index(&self, index: &RetrievalIndex) -> Result<(), RetrievalError>;
}

/// A place a [`VocabularyModel`] can be saved to and loaded from.
pub trait VocabularyStore {
    /// Reads and validates a vocabulary.
    ///
    /// # Errors
    /// As [`IndexStore::load_index`].
    fn load_vocabulary(&self) -> Result<VocabularyModel, RetrievalError>;

    /// Writes a vocabulary atomically.
    ///
    /// # Errors
    /// [`RetrievalError::Storage`].
    fn save_vocabulary(&self, vocabulary: &VocabularyModel) -> Result<(), RetrievalError>;
}

/// One JSON document on disk.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct JsonFile {
    path: PathBuf,
}

impl JsonFile {
    /// The file at `path` (nothing is read or written yet).
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self { path: path.into() }
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn storage(&self, reason: impl Into<String>) -> RetrievalError {
        RetrievalError::Storage {
            path: self.path.clone(),
            reason: reason.into(),
        }
    }

    fn read<T: for<'de> Deserialize<'de>>(&self, format: &str) -> Result<T, RetrievalError> {
        // Regular files only: a FIFO or device would block or never end.
        let bytes = mesh_fem::io::read_regular_file(&self.path).map_err(|e| self.storage(e.to_string()))?;
        let text = String::from_utf8(bytes).map_err(|_| self.storage("not UTF-8 text"))?;
        // Check the tag first, so that another JSON file gets a clear message.
        let header: Header =
            serde_json::from_str(&text).map_err(|e| self.storage(format!("not a {format} file: {e}")))?;
        if header.format != format {
            return Err(self.storage(format!("is a {:?} file, not a {format} file", header.format)));
        }
        if header.version != FORMAT_VERSION {
            return Err(self.storage(format!(
                "{format} version {} is not supported (this build reads version {FORMAT_VERSION})",
                header.version
            )));
        }
        serde_json::from_str(&text).map_err(|e| self.storage(format!("malformed {format} file: {e}")))
    }

    fn write<T: Serialize>(&self, value: &T) -> Result<(), RetrievalError> {
        let text = serde_json::to_string_pretty(value).map_err(|e| self.storage(e.to_string()))?;
        mesh_fem::io::write_atomic(&self.path, |w| w.write_all(text.as_bytes()))
            .map_err(|e| self.storage(e.to_string()))
    }
}

impl IndexStore for JsonFile {
    fn load_index(&self) -> Result<RetrievalIndex, RetrievalError> {
        self.read::<IndexRecord>(INDEX_FORMAT)?.into_index()
    }

    fn save_index(&self, index: &RetrievalIndex) -> Result<(), RetrievalError> {
        self.write(&IndexRecord::from_index(index))
    }
}

impl VocabularyStore for JsonFile {
    fn load_vocabulary(&self) -> Result<VocabularyModel, RetrievalError> {
        self.read::<VocabularyRecord>(VOCABULARY_FORMAT)?.into_model()
    }

    fn save_vocabulary(&self, vocabulary: &VocabularyModel) -> Result<(), RetrievalError> {
        self.write(&VocabularyRecord::from_model(vocabulary))
    }
}

/// The settings of an index — its vocabulary and bag settings, without the entries — as one
/// JSON document, for a store that keeps the entries itself (retrieval-store's SQLite file
/// keeps them as vectors). Read back with [`index_from_settings`].
///
/// # Errors
/// [`RetrievalError::Storage`] if serialization fails.
pub fn index_settings(index: &RetrievalIndex) -> Result<String, RetrievalError> {
    let mut record = IndexRecord::from_index(index);
    record.entries.clear();
    serde_json::to_string(&record).map_err(|e| RetrievalError::Storage {
        path: PathBuf::new(),
        reason: e.to_string(),
    })
}

/// An index from the text of [`index_settings`] and its entries, validated exactly like a JSON
/// index file (tags, version, settings, every bag and global signature).
///
/// # Errors
/// [`RetrievalError::Storage`] for text that is not index settings of this version;
/// [`RetrievalError::InvalidModel`] as [`IndexStore::load_index`].
pub fn index_from_settings(text: &str, entries: Vec<IndexEntry>) -> Result<RetrievalIndex, RetrievalError> {
    let storage = |reason: String| RetrievalError::Storage {
        path: PathBuf::new(),
        reason,
    };
    let header: Header = serde_json::from_str(text).map_err(|e| storage(format!("not index settings: {e}")))?;
    if header.format != INDEX_FORMAT || header.version != FORMAT_VERSION {
        return Err(storage(format!(
            "settings tagged {:?} version {}, expected {INDEX_FORMAT:?} version {FORMAT_VERSION}",
            header.format, header.version
        )));
    }
    let mut record: IndexRecord =
        serde_json::from_str(text).map_err(|e| storage(format!("malformed index settings: {e}")))?;
    record.entries = entries
        .into_iter()
        .map(|e| EntryRecord {
            name: e.name,
            bag: e.signature.bag,
            global: e.signature.global,
        })
        .collect();
    record.into_index()
}

#[derive(Deserialize)]
struct Header {
    format: String,
    version: u32,
}

/// The stored form of a [`VocabularyModel`].
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct VocabularyRecord {
    format: String,
    version: u32,
    descriptor: DescriptorSettings,
    training: TrainingParams,
    info: TrainingReport,
    standardizer: Option<StandardizerRecord>,
    words: Vec<Vec<f64>>,
    sigma: f64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct StandardizerRecord {
    mean: Vec<f64>,
    std: Vec<f64>,
}

impl VocabularyRecord {
    fn from_model(v: &VocabularyModel) -> Self {
        let w = v.vocabulary().words();
        Self {
            format: VOCABULARY_FORMAT.into(),
            version: FORMAT_VERSION,
            descriptor: v.descriptor().clone(),
            training: *v.training(),
            info: v.info().clone(),
            standardizer: v.standardizer().map(|z| StandardizerRecord {
                mean: z.mean().to_vec(),
                std: z.std().to_vec(),
            }),
            words: (0..w.nrows())
                .map(|i| (0..w.ncols()).map(|j| w[(i, j)]).collect())
                .collect(),
            sigma: v.vocabulary().sigma(),
        }
    }

    fn into_model(self) -> Result<VocabularyModel, RetrievalError> {
        let invalid = |reason: String| RetrievalError::InvalidModel {
            what: "vocabulary",
            reason,
        };
        let d = self.words.first().map_or(0, Vec::len);
        if let Some((i, w)) = self.words.iter().enumerate().find(|(_, w)| w.len() != d) {
            return Err(invalid(format!("word {i} has dimension {}, word 0 has {d}", w.len())));
        }
        let words = Mat::from_fn(self.words.len(), d, |i, j| self.words[i][j]);
        let vocabulary = Vocabulary::new(words, self.sigma).map_err(|e| invalid(format!("words: {e}")))?;
        let standardizer = self
            .standardizer
            .map(|z| Standardizer::new(z.mean, z.std))
            .transpose()
            .map_err(|e| invalid(format!("z-score statistics: {e}")))?;
        VocabularyModel::from_parts(self.descriptor, self.training, standardizer, vocabulary, self.info)
    }
}

/// The stored form of a [`RetrievalIndex`].
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct IndexRecord {
    format: String,
    version: u32,
    vocabulary: VocabularyRecord,
    bags: BagSettings,
    entries: Vec<EntryRecord>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct EntryRecord {
    name: String,
    bag: Vec<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    global: Vec<f64>,
}

impl IndexRecord {
    fn from_index(index: &RetrievalIndex) -> Self {
        Self {
            format: INDEX_FORMAT.into(),
            version: FORMAT_VERSION,
            vocabulary: VocabularyRecord::from_model(index.vocabulary()),
            bags: index.bags().clone(),
            entries: index
                .entries()
                .iter()
                .map(|e| EntryRecord {
                    name: e.name.clone(),
                    bag: e.signature.bag.clone(),
                    global: e.signature.global.clone(),
                })
                .collect(),
        }
    }

    fn into_index(self) -> Result<RetrievalIndex, RetrievalError> {
        if self.vocabulary.format != VOCABULARY_FORMAT {
            return Err(RetrievalError::InvalidModel {
                what: "index",
                reason: format!("its vocabulary is tagged {:?}", self.vocabulary.format),
            });
        }
        let vocabulary = self.vocabulary.into_model()?;
        let entries = self
            .entries
            .into_iter()
            .map(|e| IndexEntry {
                name: e.name,
                signature: ShapeSignature {
                    bag: e.bag,
                    global: e.global,
                },
            })
            .collect();
        RetrievalIndex::from_parts(vocabulary, self.bags, entries)
    }
}
