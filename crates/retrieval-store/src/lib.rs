//! # retrieval-store
//!
//! The on-disk form of a wfem retrieval index: one embedded SQLite file (SQLite compiled in,
//! no system library) holding
//!
//! * **metadata** as key → blob pairs ([`Store::meta`], [`Store::set_meta`]): the index
//!   settings and the vocabulary (shape-retrieval's JSON, [`index`]); the [`Store`] layer only
//!   stores them;
//! * **shapes**: an id (0, 1, 2, … in insertion order), a unique name and a free-form text
//!   (e.g. the mesh path and its class);
//! * **vectors**, one per shape, all of the store's dimension (a bag of features, possibly
//!   followed by a global signature), as little-endian `f32` in **chunks** of
//!   [`StoreParams::chunk_rows`] consecutive shapes, so that a scan reads a few hundred large
//!   contiguous blobs instead of a million small rows.
//!
//! [`Store::search`] is an exact top-k scan: every worker thread (rayon) opens its own
//! read-only connection and takes chunks from a shared counter; each keeps a local top-k and
//! the results are merged, ties broken by id, so the answer does not depend on the number of
//! threads. With 48 words a million shapes is 192 MB of f32, scanned in a fraction of a second
//! on two cores (`cargo bench -p retrieval-store`, docs/BENCHMARKS.md).
//!
//! **Durability.** The file is in WAL mode with `synchronous = FULL`: [`Store::add`] is one
//! transaction, so after it returns the shapes survive a crash of the process (and of the
//! machine), and a crash during it leaves the store exactly as before
//! (`tests/it/store.rs` kills a writer mid-transaction). Readers never block the writer and
//! see only committed shapes; since shapes are only appended, a scan planned on a snapshot
//! reads the same rows from any connection.
//!
//! The store knows no model: a scan takes any [`metric::Metric`] (or a closure, [`Store::search`]).
//! With the feature **`index`** (off by default, so that a store user compiles no heat
//! stack), `index::SqliteIndex` stores shape-retrieval's `RetrievalIndex` this way (its
//! `IndexStore` for SQLite): the default index file of `wfem retrieval`.
//!
//! ```
//! use retrieval_store::metric::StandardMetric;
//! use retrieval_store::{Entry, Store, StoreParams};
//! let dir = tempfile::tempdir()?;
//! let mut store = Store::create(&dir.path().join("index.sqlite"), &StoreParams::new(3), false)?;
//! store.set_meta("settings", br#"{"words": 3}"#)?;
//! store.add(&[
//!     Entry::new("a", "", &[1.0, 0.0, 0.0]),
//!     Entry::new("b", "", &[0.0, 1.0, 0.0]),
//! ])?;
//! let hits = store.search_metric(&[0.9, 0.1, 0.0], 1, &StandardMetric::L1)?;
//! assert_eq!(hits[0].name, "a");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

pub mod check;
mod error;
#[cfg(feature = "index")]
pub mod index;
pub mod metric;
mod store;

pub use error::StoreError;
pub use store::{
    Entry, Hit, ShapeRow, Store, StoreParams, DEFAULT_CHUNK_ROWS, FORMAT, FORMAT_VERSION, MAX_CHUNK_BYTES,
    MAX_DIMENSION,
};
