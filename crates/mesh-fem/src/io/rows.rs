//! A large matrix written row by row to an `.npy` file (float64, C order) that is too big to
//! hold in memory — an n × n distance matrix — atomically and resumably.
//!
//! The rows go to a partial file beside the target (`.NAME.partial`), with a small record
//! (`.NAME.partial.json`) of its shape and of a key that names the computation; [`RowFile::finish`]
//! flushes it to disk and renames it onto the target, so the target is either absent (or the
//! previous file) or complete. After an interrupt or a crash, [`RowFile::open`] with the same
//! shape and key continues after the last whole row; a partial file of another computation is
//! replaced.

use crate::MeshError;
use std::fs::{File, OpenOptions};
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Values converted to bytes and written at a time by [`RowFile::append`] (64 KB).
const APPEND_CHUNK: usize = 8192;

/// An `.npy` matrix being written row by row (see the module docs).
#[derive(Debug)]
pub struct RowFile {
    target: PathBuf,
    partial: PathBuf,
    record: PathBuf,
    file: File,
    n_rows: usize,
    n_cols: usize,
    rows_done: usize,
}

/// The NPY 1.0 header of an `n_rows × n_cols` float64 C-order array, padded to 64 bytes.
fn header(n_rows: usize, n_cols: usize) -> Vec<u8> {
    let dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({n_rows}, {n_cols}), }}");
    let unpadded = 10 + dict.len() + 1;
    let pad = (64 - unpadded % 64) % 64;
    let len = (dict.len() + pad + 1) as u16;
    let mut h = b"\x93NUMPY\x01\x00".to_vec();
    h.extend_from_slice(&len.to_le_bytes());
    h.extend_from_slice(dict.as_bytes());
    h.extend(std::iter::repeat_n(b' ', pad));
    h.push(b'\n');
    h
}

fn io(path: &Path, e: std::io::Error) -> MeshError {
    MeshError::Io {
        path: path.to_path_buf(),
        source: e,
    }
}

/// `dir/.name.suffix` for `dir/name`.
fn beside(target: &Path, suffix: &str) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    target.with_file_name(format!(".{name}{suffix}"))
}

impl RowFile {
    /// Opens the partial file of `target` for an `n_rows × n_cols` matrix of the computation
    /// named `key`: resumed after its last whole row if it holds the same shape and key, started
    /// anew otherwise.
    ///
    /// # Errors
    /// [`MeshError::RowFile`] for an empty shape or one whose size overflows;
    /// [`MeshError::Io`] when the folder is not writable or the target is a directory.
    pub fn open(target: &Path, n_rows: usize, n_cols: usize, key: &str) -> Result<Self, MeshError> {
        if n_rows == 0 || n_cols == 0 || n_rows.checked_mul(n_cols).and_then(|x| x.checked_mul(8)).is_none() {
            return Err(MeshError::RowFile {
                path: target.to_path_buf(),
                reason: format!("a {n_rows} × {n_cols} matrix cannot be written"),
            });
        }
        if target.is_dir() {
            return Err(io(
                target,
                std::io::Error::new(std::io::ErrorKind::InvalidInput, "the output is a directory"),
            ));
        }
        let (partial, record) = (beside(target, ".partial"), beside(target, ".partial.json"));
        let stamp = format!("{{\"key\": {}, \"shape\": [{n_rows}, {n_cols}]}}", show_json(key));
        let head = header(n_rows, n_cols);
        let row_bytes = (8 * n_cols) as u64;
        let same = std::fs::read_to_string(&record).is_ok_and(|r| r == stamp);
        let existing = std::fs::metadata(&partial)
            .ok()
            .filter(|m| m.is_file())
            .map(|m| m.len());
        let rows_done = match (same, existing) {
            (true, Some(len)) if len >= head.len() as u64 => ((len - head.len() as u64) / row_bytes) as usize,
            _ => usize::MAX,
        };
        let file = if rows_done == usize::MAX {
            // A fresh start: the record first, so a later resume knows what the rows are.
            std::fs::write(&record, &stamp).map_err(|e| io(&record, e))?;
            let mut f = File::create(&partial).map_err(|e| io(&partial, e))?;
            f.write_all(&head).map_err(|e| io(&partial, e))?;
            f
        } else {
            let mut f = OpenOptions::new()
                .write(true)
                .open(&partial)
                .map_err(|e| io(&partial, e))?;
            let keep = head.len() as u64 + rows_done as u64 * row_bytes;
            f.set_len(keep).map_err(|e| io(&partial, e))?;
            f.seek(SeekFrom::End(0)).map_err(|e| io(&partial, e))?;
            f
        };
        Ok(Self {
            target: target.to_path_buf(),
            partial,
            record,
            file,
            n_rows,
            n_cols,
            rows_done: if rows_done == usize::MAX {
                0
            } else {
                rows_done.min(n_rows)
            },
        })
    }

    /// Rows already written (by this or an earlier, interrupted run).
    pub fn rows_done(&self) -> usize {
        self.rows_done
    }

    /// The partial file (what stays behind for a resume).
    pub fn partial_path(&self) -> &Path {
        &self.partial
    }

    /// Appends whole rows (`values.len()` a multiple of the row length).
    ///
    /// # Errors
    /// [`MeshError::RowFile`] for a partial row or more rows than the shape; [`MeshError::Io`].
    pub fn append(&mut self, values: &[f64]) -> Result<(), MeshError> {
        if values.len() % self.n_cols != 0 || self.rows_done + values.len() / self.n_cols > self.n_rows {
            return Err(MeshError::RowFile {
                path: self.target.clone(),
                reason: format!(
                    "{} values are not whole rows of {} within the {} rows left",
                    values.len(),
                    self.n_cols,
                    self.n_rows - self.rows_done
                ),
            });
        }
        // A small buffer reused chunk by chunk: appending a block of rows never holds a second
        // copy of it in memory.
        let mut bytes = Vec::with_capacity(8 * APPEND_CHUNK);
        for chunk in values.chunks(APPEND_CHUNK) {
            bytes.clear();
            for v in chunk {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
            self.file.write_all(&bytes).map_err(|e| io(&self.partial, e))?;
        }
        self.rows_done += values.len() / self.n_cols;
        Ok(())
    }

    /// Flushes the complete matrix to disk and renames it onto the target.
    ///
    /// # Errors
    /// [`MeshError::RowFile`] if rows are missing; [`MeshError::Io`].
    pub fn finish(self) -> Result<PathBuf, MeshError> {
        if self.rows_done != self.n_rows {
            return Err(MeshError::RowFile {
                path: self.target.clone(),
                reason: format!(
                    "{} of {} rows written; the matrix is not complete",
                    self.rows_done, self.n_rows
                ),
            });
        }
        self.file.sync_all().map_err(|e| io(&self.partial, e))?;
        std::fs::rename(&self.partial, &self.target).map_err(|e| io(&self.target, e))?;
        let _ = std::fs::remove_file(&self.record);
        if let Some(dir) = self.target.parent().filter(|d| !d.as_os_str().is_empty()) {
            if let Ok(d) = File::open(dir) {
                let _ = d.sync_all();
            }
        }
        Ok(self.target)
    }
}

/// A JSON string literal.
fn show_json(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}
