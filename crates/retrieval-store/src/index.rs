//! shape-retrieval's [`RetrievalIndex`] in one SQLite store: the index settings (vocabulary,
//! z-score statistics, bag settings; [`shape_retrieval::store::index_settings`]) as one metadata
//! entry, and every shape's signature — its bag followed by its global signature — as one
//! vector. This is the default index file of `wfem retrieval build/query/add`.
//!
//! * [`IndexStore`] (load/save a whole index) — saving builds the file under a temporary name
//!   and renames it into place, so a reader sees the old index or the new one;
//! * [`SqliteIndex::search`] — a query scans the stored vectors in parallel with the index's
//!   own distance (χ² or L1 plus the fused global term) and returns the k nearest, without
//!   loading the index into memory;
//! * [`SqliteIndex::append`] — new shapes are added in one transaction, with the stored
//!   settings, without rebuilding anything.
//!
//! Vectors are stored as `f32`: a bag loaded back is renormalised to sum 1 when its sum is
//! within the rounding of `f32` (1e−4), and otherwise refused like a hand-edited JSON bag.

use crate::check::{CheckReport, Damage};
use crate::{Entry, Store, StoreError, StoreParams};
use shape_retrieval::model::{IndexEntry, RetrievalIndex, ShapeSignature};
use shape_retrieval::store::{index_from_settings, index_settings, IndexStore};
use shape_retrieval::RetrievalError;
use std::path::{Path, PathBuf};
use wfem_base::tempfiles::{self, TempPath};

/// Metadata key of the index settings.
pub const SETTINGS_KEY: &str = "wfem-retrieval-index";

/// A retrieval index stored in a SQLite file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SqliteIndex {
    path: PathBuf,
}

/// One answer of [`SqliteIndex::search`].
#[derive(Clone, Debug, PartialEq)]
pub struct IndexHit {
    /// Position of the shape in insertion order.
    pub id: u64,
    /// Its name (the file as given to `build`/`add`).
    pub name: String,
    /// Its distance to the query.
    pub distance: f64,
}

impl SqliteIndex {
    /// The index at `path` (nothing is read or written yet).
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self { path: path.into() }
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn storage(&self, e: impl std::fmt::Display) -> RetrievalError {
        RetrievalError::Storage {
            path: self.path.clone(),
            reason: e.to_string(),
        }
    }

    /// A store error as the model's: damage stays typed ([`RetrievalError::CorruptIndex`]),
    /// the rest is [`RetrievalError::Storage`].
    fn store_error(&self, e: StoreError) -> RetrievalError {
        match e {
            StoreError::CorruptIndex { path, record, reason } => RetrievalError::CorruptIndex { path, record, reason },
            e => self.storage(e),
        }
    }

    /// Opens the store read-only and reads its settings: an index with the stored vocabulary
    /// and bag settings and no entries (to compute query signatures with), and the store.
    ///
    /// # Errors
    /// [`RetrievalError::CorruptIndex`] (a metadata entry does not match its checksum, or the
    /// chunk table is inconsistent), [`RetrievalError::Storage`] (not a store, no settings),
    /// [`RetrievalError::InvalidModel`].
    pub fn open(&self) -> Result<(RetrievalIndex, Store), RetrievalError> {
        let store = Store::open_readonly(&self.path).map_err(|e| self.store_error(e))?;
        let settings = self.settings(&store)?;
        Ok((settings, store))
    }

    fn settings(&self, store: &Store) -> Result<RetrievalIndex, RetrievalError> {
        let text = store
            .meta(SETTINGS_KEY)
            .map_err(|e| self.store_error(e))?
            .ok_or_else(|| self.storage("a vector store, but not a wfem retrieval index (no settings)"))?;
        let text = String::from_utf8(text).map_err(|_| self.storage("the index settings are not UTF-8"))?;
        let index = index_from_settings(&text, Vec::new()).map_err(|e| self.located(e))?;
        // A hand-edited size must not start an eigensolve or a vocabulary of any size.
        shape_retrieval::limits::check_sizes(
            index.vocabulary().descriptor().eigenpairs,
            index.vocabulary().vocabulary().size(),
        )?;
        let width =
            index.bags().bag_len(index.vocabulary().vocabulary().size()) + index.bags().global.map_or(0, |g| g.len());
        if store.dimension() != width {
            return Err(self.storage(format!(
                "vectors of {} values, the settings describe {width}",
                store.dimension()
            )));
        }
        Ok(index)
    }

    fn located(&self, e: RetrievalError) -> RetrievalError {
        match e {
            RetrievalError::Storage { reason, .. } => self.storage(reason),
            other => other,
        }
    }

    /// The `k` indexed shapes nearest to `query` under the index's distance, nearest first
    /// (ties by insertion order): an exact parallel scan of the store.
    ///
    /// # Errors
    /// The query's checks ([`RetrievalIndex::distance`] against a stored shape);
    /// [`RetrievalError::Storage`] for store errors.
    pub fn search(
        &self,
        settings: &RetrievalIndex,
        store: &Store,
        query: &ShapeSignature,
        k: usize,
    ) -> Result<Vec<IndexHit>, RetrievalError> {
        // Validate the query once against the first stored shape (or a copy of itself).
        let first = match store.vector(0).map_err(|e| self.store_error(e))? {
            Some(row) => signature(settings, &row),
            None => return Ok(Vec::new()),
        };
        settings.distance(query, &first)?;
        thread_local! {
            // One f64 copy of the current row per scanning thread (no allocation per row).
            static ROW: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
        }
        let words = settings.vocabulary().vocabulary().size();
        let hits = store
            .search_checked(k, |row| {
                // A bag is a histogram: a negative bin (a tampered file) would make χ² zero
                // between different bags, so it is refused, naming the shape.
                if let Some(i) = row[..words.min(row.len())].iter().position(|&x| x < 0.0) {
                    return Err(format!("bag bin {i} is {}; bags are non-negative histograms", row[i]));
                }
                Ok(ROW.with(|buffer| {
                    let mut buffer = buffer.borrow_mut();
                    buffer.clear();
                    buffer.extend(row.iter().map(|&x| f64::from(x)));
                    settings.row_distance(query, &buffer)
                }))
            })
            .map_err(|e| self.store_error(e))?;
        Ok(hits
            .into_iter()
            .map(|h| IndexHit {
                id: h.id,
                name: h.name,
                distance: h.distance,
            })
            .collect())
    }

    /// The `k` indexed shapes nearest to the stored shape that `name` names
    /// ([`shape_retrieval::model::resolve_name`]: its stored name, file name or stem), itself
    /// left out: a query by an indexed shape from its stored signature, nothing described.
    /// Returns the shape's stored name and the hits.
    ///
    /// # Errors
    /// [`RetrievalError::UnknownShape`], and those of [`Self::search`].
    pub fn search_stored(
        &self,
        settings: &RetrievalIndex,
        store: &Store,
        name: &str,
        k: usize,
    ) -> Result<(String, Vec<IndexHit>), RetrievalError> {
        let shapes = store.shapes().map_err(|e| self.store_error(e))?;
        let i = shape_retrieval::model::resolve_name(shapes.iter().map(|s| s.name.as_str()), name)?;
        let id = shapes[i].id;
        let row = store
            .vector(id)
            .map_err(|e| self.store_error(e))?
            .ok_or_else(|| self.storage(format!("shape {id} ({}) has no stored vector", shapes[i].name)))?;
        let query = signature(settings, &row);
        let mut hits = self.search(settings, store, &query, k.saturating_add(1))?;
        hits.retain(|h| h.id != id);
        hits.truncate(k);
        Ok((shapes[i].name.clone(), hits))
    }

    /// Appends shapes whose signatures were computed with `opened` (the settings of
    /// [`SqliteIndex::open`], e.g. by [`RetrievalIndex::describe`]) in one transaction;
    /// nothing else is rewritten.
    ///
    /// The stored settings must still be `opened`'s and the file the one opened here: an
    /// index rebuilt or replaced meanwhile (another vocabulary) is refused rather than given
    /// bags it cannot compare.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidModel`] for a signature that does not fit the settings;
    /// [`RetrievalError::Storage`] (settings changed, file replaced, a name already indexed,
    /// store errors).
    pub fn append(&self, opened: &RetrievalIndex, entries: &[IndexEntry]) -> Result<(), RetrievalError> {
        let mut store = Store::open(&self.path).map_err(|e| self.store_error(e))?;
        let settings = self.settings(&store)?;
        if index_settings(&settings).map_err(|e| self.located(e))?
            != index_settings(opened).map_err(|e| self.located(e))?
        {
            return Err(self.storage(
                "the index was rebuilt with other settings since these shapes were described; nothing was added",
            ));
        }
        // The same checks as a loaded index, on the new entries.
        index_from_settings(
            &index_settings(&settings).map_err(|e| self.located(e))?,
            entries.to_vec(),
        )?;
        let rows: Vec<Vec<f64>> = entries.iter().map(row).collect();
        let batch: Vec<Entry<'_>> = entries
            .iter()
            .zip(&rows)
            .map(|(e, r)| Entry::new(&e.name, "", r))
            .collect();
        store.add(&batch).map_err(|e| self.store_error(e))?;
        Ok(())
    }
}

impl SqliteIndex {
    /// Verifies the whole index file and reports every damaged record
    /// ([`Store::check_with`]): each record against its checksum and the file's invariants,
    /// the stored settings as a model (they parse, their sizes are within bounds and they
    /// describe the stored vectors' width), and every stored bag as a histogram (no negative
    /// bin). A version 1 file (no checksums) is reported as unchecked.
    ///
    /// # Errors
    /// [`RetrievalError::Storage`] only when nothing can be checked (not a store, unreadable).
    pub fn check(&self) -> Result<CheckReport, RetrievalError> {
        let settings = Store::open_readonly(&self.path)
            .map_err(|e| self.store_error(e))
            .and_then(|store| self.settings(&store));
        let words = settings
            .as_ref()
            .ok()
            .map(|s| s.bags().bag_len(s.vocabulary().vocabulary().size()));
        let mut report = Store::check_with(&self.path, &|_, row| {
            let bag = &row[..words.unwrap_or(0).min(row.len())];
            bag.iter()
                .position(|&x| x < 0.0)
                .map(|i| format!("bag bin {i} is {}; bags are non-negative histograms", bag[i]))
        })
        .map_err(|e| self.store_error(e))?;
        match settings {
            // Damage of the store is in the report already.
            Ok(_) | Err(RetrievalError::CorruptIndex { .. }) => {}
            Err(e) => report.damage.push(Damage {
                record: format!("metadata {SETTINGS_KEY:?}"),
                reason: match e {
                    RetrievalError::Storage { reason, .. } => reason,
                    e => e.to_string(),
                },
            }),
        }
        Ok(report)
    }

    /// Adds checksums to an index of format version 1 in place ([`Store::upgrade`]): its
    /// structure and values are checked first, and an index with damage is refused.
    ///
    /// # Errors
    /// [`RetrievalError::CorruptIndex`] for damage; [`RetrievalError::Storage`].
    pub fn upgrade(&self) -> Result<(), RetrievalError> {
        Store::upgrade(&self.path).map_err(|e| self.store_error(e))?;
        Ok(())
    }
}

/// A stored vector as a signature: the bag (renormalised when within f32 rounding of sum 1)
/// and the global part.
fn signature(settings: &RetrievalIndex, row: &[f32]) -> ShapeSignature {
    let v = settings
        .bags()
        .bag_len(settings.vocabulary().vocabulary().size())
        .min(row.len());
    let mut bag: Vec<f64> = row[..v].iter().map(|&x| f64::from(x)).collect();
    let sum: f64 = bag.iter().sum();
    if (sum - 1.0).abs() <= 1e-4 && sum > 0.0 {
        bag.iter_mut().for_each(|x| *x /= sum);
    }
    ShapeSignature {
        bag,
        global: row[v..].iter().map(|&x| f64::from(x)).collect(),
    }
}

fn row(e: &IndexEntry) -> Vec<f64> {
    e.signature.bag.iter().chain(&e.signature.global).copied().collect()
}

fn sibling(path: &Path, suffix: &str) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(suffix);
    PathBuf::from(s)
}

impl IndexStore for SqliteIndex {
    fn load_index(&self) -> Result<RetrievalIndex, RetrievalError> {
        let (settings, store) = self.open()?;
        let shapes = store.shapes().map_err(|e| self.store_error(e))?;
        let vectors = store.vectors().map_err(|e| self.store_error(e))?;
        let dim = store.dimension();
        let entries = shapes
            .into_iter()
            .zip(vectors.chunks_exact(dim))
            .map(|(s, row)| IndexEntry {
                name: s.name,
                signature: signature(&settings, row),
            })
            .collect();
        index_from_settings(&index_settings(&settings).map_err(|e| self.located(e))?, entries)
            .map_err(|e| self.located(e))
    }

    fn save_index(&self, index: &RetrievalIndex) -> Result<(), RetrievalError> {
        let settings = index_settings(index).map_err(|e| self.located(e))?;
        let width =
            index.bags().bag_len(index.vocabulary().vocabulary().size()) + index.bags().global.map_or(0, |g| g.len());
        let name = self.path.file_name().ok_or_else(|| self.storage("no file name"))?;
        crate::store::regular_or_absent(&self.path).map_err(|e| self.store_error(e))?;
        // The whole index is built in a private folder beside it (`.NAME.tmp-PID-N`, with
        // SQLite's journals: removed when dropped, on a signal, or after a kill by the next
        // writer of this path; wfem_base::tempfiles), then renamed into place.
        let folder = TempPath::dir(&self.path).map_err(|e| self.storage(e))?;
        let tmp = folder.path().join(name);
        let build = || -> Result<(), StoreError> {
            let mut store = Store::create(&tmp, &StoreParams::new(width), true)?;
            store.set_meta(SETTINGS_KEY, settings.as_bytes())?;
            let rows: Vec<Vec<f64>> = index.entries().iter().map(row).collect();
            let batch: Vec<Entry<'_>> = index
                .entries()
                .iter()
                .zip(&rows)
                .map(|(e, r)| Entry::new(&e.name, "", r))
                .collect();
            store.add(&batch)?;
            // Closing the last connection checkpoints the log: one self-contained file.
            drop(store);
            // The rename happens under the replaced store's write lock, so an `append` to it
            // either commits before (and is replaced, as asked) or sees the new file and
            // refuses (StoreError::Replaced): the two never interleave.
            let lock = Store::lock_for_replace(&self.path)?;
            let renamed =
                tempfiles::while_locked(|| std::fs::rename(&tmp, &self.path)).map_err(|source| StoreError::Io {
                    path: self.path.clone(),
                    source,
                });
            drop(lock);
            renamed
        };
        let result = build();
        drop(folder);
        result.map_err(|e| self.store_error(e))?;
        // A shared-memory index left by readers of the replaced file must not describe this one.
        let _ = std::fs::remove_file(sibling(&self.path, "-shm"));
        Ok(())
    }
}

/// shape-retrieval's bag distances as scan metrics (the one formula, `BagDistance::of_pairs`).
impl crate::metric::Metric for shape_retrieval::distance::BagDistance {
    #[inline]
    fn eval(&self, query: &[f64], row: &[f32]) -> f64 {
        self.of_pairs(query.iter().zip(row).map(|(&a, &b)| (a, f64::from(b))))
    }

    fn checks_values(&self) -> bool {
        *self == shape_retrieval::distance::BagDistance::ChiSquared
    }

    fn refuse(&self, value: f64) -> Option<&'static str> {
        (self.checks_values() && value < 0.0).then_some("is negative; chi-squared compares histograms")
    }
}
