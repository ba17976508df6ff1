//! What a full check of a store found ([`Store::check`](crate::Store::check)): every damaged
//! record, named, and whether the file could be verified at all.
//!
//! A store of format version 2 keeps a CRC-32 of every record — each metadata entry (key and
//! value), each shape row (id, name, text) and each vector chunk (its number, row count and
//! bytes). Opening a store verifies the metadata; every read verifies what it reads (a scan,
//! each chunk it scans); a check verifies everything and reports all it finds instead of
//! stopping at the first. CRC-32 detects every error of one to three bits in a record and
//! every burst of up to 32 bits; other random damage goes unnoticed with probability 2⁻³².
//! It guards against damage and stray edits, not against someone who recomputes checksums.

use std::path::PathBuf;

/// One damaged record (the fields of [`StoreError::CorruptIndex`](crate::StoreError::CorruptIndex)).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Damage {
    /// The record: `metadata "KEY"`, `shape ID ("NAME")`, `chunk C (shapes A to B)`,
    /// `the chunk table`, or `the file` (SQLite's own structure).
    pub record: String,
    /// What does not match.
    pub reason: String,
}

/// The outcome of [`Store::check`](crate::Store::check).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CheckReport {
    /// The file.
    pub path: PathBuf,
    /// Its format version.
    pub version: u32,
    /// Whether its records carry checksums (format version 2). A version 1 file is checked
    /// for its structure and finite values only: its contents cannot be verified, and
    /// [`CheckReport::is_verified`] is false even when nothing was found.
    pub checksums: bool,
    /// Metadata entries checked.
    pub metadata: usize,
    /// Shapes checked.
    pub shapes: usize,
    /// Vector chunks checked.
    pub chunks: usize,
    /// Every damaged record found (empty: none).
    pub damage: Vec<Damage>,
}

impl CheckReport {
    /// Nothing is damaged and everything was verified against its checksum.
    pub fn is_verified(&self) -> bool {
        self.checksums && self.damage.is_empty()
    }

    /// One line per finding, then a summary line (what `wfem retrieval check` prints).
    pub fn to_text(&self) -> String {
        let mut out = String::new();
        for d in &self.damage {
            out.push_str(&format!(
                "{}: damaged: {}: {}\n",
                self.path.display(),
                d.record,
                d.reason
            ));
        }
        let counted = format!(
            "{} metadata entries, {} shapes, {} vector chunks",
            self.metadata, self.shapes, self.chunks
        );
        let summary = match (self.damage.len(), self.checksums) {
            (0, true) => format!("{}: intact: {counted} verified", self.path.display()),
            (0, false) => format!(
                "{}: unchecked: format version {} has no checksums; its structure and values are sound ({counted}), \
                 its contents cannot be verified (upgrade it with `wfem retrieval check --upgrade`)",
                self.path.display(),
                self.version
            ),
            (n, _) => format!(
                "{}: DAMAGED: {n} damaged record{} among {counted}",
                self.path.display(),
                if n == 1 { "" } else { "s" }
            ),
        };
        out.push_str(&summary);
        out.push('\n');
        out
    }
}
