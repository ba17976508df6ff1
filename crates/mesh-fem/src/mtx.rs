//! Matrix Market I/O for sparse matrices, and (feature `nalgebra`) conversions to and from
//! `nalgebra-sparse`.
//!
//! * [`write_matrix_market`]: `coordinate real general` (every stored entry) or
//!   `coordinate real symmetric` (the lower triangle, after checking symmetry), values with 17
//!   significant digits so that every `f64` reads back bit for bit; written atomically
//!   (a temporary file in the same folder, then a rename).
//! * [`read_matrix_market`]: `coordinate` files with field `real`, `integer` or `pattern`
//!   (pattern entries are 1) and symmetry `general`, `symmetric` or `skew-symmetric`;
//!   duplicate entries are summed. Every malformed line is reported with its number.
//! * [`write_operators`]: `stiffness.mtx` (L), `mass.mtx` (B), `lumped_mass.mtx` (D).
//!
//! The files are what scipy (`scipy.io.mmread`), MATLAB (`mmread.m`) and libigl read.
//!
//! ```
//! use mesh_fem::mtx::{read_matrix_market, write_operators};
//! use mesh_fem::{assemble, generate, AssemblyParams};
//! let ops = assemble(&generate::icosphere(1), &AssemblyParams::default())?;
//! let dir = std::env::temp_dir().join(format!("mesh-fem-mtx-doc-{}", std::process::id()));
//! write_operators(&dir, &ops)?;
//! let l = read_matrix_market(dir.join("stiffness.mtx"))?;
//! assert_eq!((l.nrows(), l.ncols()), (42, 42));
//! # std::fs::remove_dir_all(&dir).unwrap();
//! # Ok::<(), mesh_fem::MeshError>(())
//! ```

use crate::io::AtomicSet;
use crate::{FemOperators, MeshError};
#[cfg(feature = "nalgebra")]
use faer::sparse::SymbolicSparseColMat;
use faer::sparse::{SparseColMat, Triplet};
use rayon::prelude::*;
use std::io::Write;
use std::path::Path;

fn io_err(path: &Path, source: std::io::Error) -> MeshError {
    MeshError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn mm_err(path: &Path, message: impl Into<String>) -> MeshError {
    MeshError::MatrixMarket {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Writes `matrix` to `path` in Matrix Market coordinate format.
///
/// With `symmetric = true` the header says `symmetric` and only entries with row ≥ column are
/// written; the matrix must then be square and symmetric up to a relative 1e-12 of its largest
/// entry (assembly order can change the last bit of a sum). Explicitly stored zeros are
/// written too (the file keeps the sparsity pattern). Values carry 17 significant digits.
///
/// # Errors
/// [`MeshError::MatrixMarket`] for a NaN or infinite entry (naming it), or if `symmetric` is
/// asked for a non-square or non-symmetric matrix (naming the first asymmetric entry);
/// [`MeshError::Io`] if the file cannot be written.
pub fn write_matrix_market(
    path: impl AsRef<Path>,
    matrix: &SparseColMat<usize, f64>,
    symmetric: bool,
) -> Result<(), MeshError> {
    let mut set = AtomicSet::new();
    stage_matrix_market(&mut set, path.as_ref(), matrix, symmetric)?;
    set.commit()
}

/// The checks of [`write_matrix_market`], and its file staged in `set` (not yet renamed onto
/// `path`).
fn stage_matrix_market(
    set: &mut AtomicSet,
    path: &Path,
    matrix: &SparseColMat<usize, f64>,
    symmetric: bool,
) -> Result<(), MeshError> {
    let entries = sorted_entries(matrix);
    if let Some(&(i, j, v)) = entries.iter().find(|e| !e.2.is_finite()) {
        return Err(mm_err(
            path,
            format!("entry ({i}, {j}) is {v} (0-based); refusing to write a non-finite value"),
        ));
    }
    if symmetric {
        check_symmetric(path, matrix.nrows(), matrix.ncols(), &entries)?;
    }
    let kept: Vec<(usize, usize, f64)> = entries.into_iter().filter(|&(i, j, _)| !symmetric || i >= j).collect();
    set.stage(path, |w| {
        writeln!(
            w,
            "%%MatrixMarket matrix coordinate real {}",
            if symmetric { "symmetric" } else { "general" }
        )?;
        writeln!(w, "% written by mesh-fem {}", env!("CARGO_PKG_VERSION"))?;
        writeln!(w, "{} {} {}", matrix.nrows(), matrix.ncols(), kept.len())?;
        // The lines are formatted in parallel, a bounded batch at a time, and written in order.
        for batch in kept.chunks(LINES_PER_BATCH) {
            let texts: Vec<Vec<u8>> = batch
                .par_chunks(LINES_PER_TASK)
                .map(|lines| {
                    let mut text = Vec::with_capacity(lines.len() * 40);
                    for &(i, j, v) in lines {
                        // `{:e}` prints the shortest decimal that reads back as the same f64.
                        let _ = writeln!(text, "{} {} {:e}", i + 1, j + 1, v);
                    }
                    text
                })
                .collect();
            for text in &texts {
                w.write_all(text)?;
            }
        }
        Ok(())
    })
}

/// Lines formatted per parallel task, and per batch held in memory, by the Matrix Market writer.
const LINES_PER_TASK: usize = 1 << 14;
const LINES_PER_BATCH: usize = 1 << 20;

/// All stored entries `(row, col, value)`, by column then row (duplicates, if a matrix has
/// any, are summed).
fn sorted_entries(matrix: &SparseColMat<usize, f64>) -> Vec<(usize, usize, f64)> {
    let m = matrix.as_ref();
    let mut out = Vec::with_capacity(m.compute_nnz());
    for j in 0..matrix.ncols() {
        let start = out.len();
        for (&i, &v) in m.row_idx_of_col_raw(j).iter().zip(m.val_of_col(j)) {
            out.push((i, j, v));
        }
        let col = &mut out[start..];
        col.sort_by_key(|e| e.0);
        // Merge duplicates within the column.
        let mut w = start;
        for r in start..out.len() {
            if w > start && out[w - 1].0 == out[r].0 {
                out[w - 1].2 += out[r].2;
            } else {
                out[w] = out[r];
                w += 1;
            }
        }
        out.truncate(w);
    }
    out
}

fn check_symmetric(path: &Path, nrows: usize, ncols: usize, entries: &[(usize, usize, f64)]) -> Result<(), MeshError> {
    if nrows != ncols {
        return Err(mm_err(
            path,
            format!("a symmetric file needs a square matrix, got {nrows} × {ncols}"),
        ));
    }
    let scale = entries.iter().fold(0.0f64, |m, e| m.max(e.2.abs()));
    let tol = 1e-12 * scale;
    // Keys (col, row) of the entries and of the transposed entries, both sorted; walking them
    // together compares a_ij with a_ji (a missing entry counts as zero).
    let a: Vec<((usize, usize), f64)> = entries.iter().map(|&(i, j, v)| ((j, i), v)).collect();
    // The transposed keys sorted by (row, col): a counting sort by row, stable, so the columns
    // stay increasing within a row (the entries come by column).
    let mut first = vec![0usize; nrows + 1];
    for &(i, _, _) in entries {
        first[i + 1] += 1;
    }
    for r in 0..nrows {
        first[r + 1] += first[r];
    }
    let mut b: Vec<((usize, usize), f64)> = vec![((0, 0), 0.0); entries.len()];
    for &(i, j, v) in entries {
        b[first[i]] = ((i, j), v);
        first[i] += 1;
    }
    let (mut p, mut q) = (0, 0);
    while p < a.len() || q < b.len() {
        use std::cmp::Ordering::*;
        let order = match (a.get(p), b.get(q)) {
            (Some(x), Some(y)) => x.0.cmp(&y.0),
            (Some(_), None) => Less,
            _ => Greater,
        };
        let (key, va, vb) = match order {
            Equal => (a[p].0, a[p].1, b[q].1),
            Less => (a[p].0, a[p].1, 0.0),
            Greater => (b[q].0, 0.0, b[q].1),
        };
        if order != Greater {
            p += 1;
        }
        if order != Less {
            q += 1;
        }
        let close = (va - vb).abs() <= tol;
        if !close {
            let (j, i) = key;
            return Err(mm_err(
                path,
                format!("matrix is not symmetric: entry ({i}, {j}) = {va} but ({j}, {i}) = {vb} (0-based)"),
            ));
        }
    }
    Ok(())
}

/// Largest column count [`read_matrix_market`] accepts regardless of the number of entries
/// (beyond it a file needs at least one entry per 64 columns).
const MAX_EMPTY_COLUMNS: usize = 1 << 24;

/// Reads a Matrix Market `coordinate` file into a faer sparse matrix.
///
/// Accepts field `real`, `integer` or `pattern` and symmetry `general`, `symmetric`
/// (lower triangle stored, mirrored on reading) or `skew-symmetric`; duplicate entries are
/// summed. Comment (`%`) and blank lines are skipped.
///
/// # Errors
/// [`MeshError::Io`] if the file cannot be read; [`MeshError::MatrixMarket`] for an
/// unsupported header (e.g. `array` or `complex`) or a wrong entry count;
/// [`MeshError::MatrixMarketLine`] naming the line of a malformed size line or entry
/// (unparsable numbers, indices out of range, an upper-triangle entry in a symmetric file,
/// a non-finite value, more than 2^24 columns with fewer than one entry per 64 columns).
pub fn read_matrix_market(path: impl AsRef<Path>) -> Result<SparseColMat<usize, f64>, MeshError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| io_err(path, e))?;
    let line_err = |line: usize, message: String| MeshError::MatrixMarketLine {
        path: path.to_path_buf(),
        line,
        message,
    };
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));

    let (_, header) = lines.next().ok_or_else(|| mm_err(path, "the file is empty"))?;
    let words: Vec<String> = header.split_whitespace().map(str::to_ascii_lowercase).collect();
    if words.len() != 5 || words[0] != "%%matrixmarket" || words[1] != "matrix" {
        return Err(line_err(
            1,
            format!("expected a header `%%MatrixMarket matrix coordinate real general`, got {header:?}"),
        ));
    }
    if words[2] != "coordinate" {
        return Err(mm_err(
            path,
            format!("only the coordinate format is supported, not {:?}", words[2]),
        ));
    }
    let pattern = match words[3].as_str() {
        "real" | "double" | "integer" => false,
        "pattern" => true,
        other => {
            return Err(mm_err(
                path,
                format!("unsupported field {other:?} (real, integer or pattern)"),
            ))
        }
    };
    #[derive(PartialEq)]
    enum Sym {
        General,
        Symmetric,
        Skew,
    }
    let sym = match words[4].as_str() {
        "general" => Sym::General,
        "symmetric" => Sym::Symmetric,
        "skew-symmetric" => Sym::Skew,
        other => {
            return Err(mm_err(
                path,
                format!("unsupported symmetry {other:?} (general, symmetric or skew-symmetric)"),
            ))
        }
    };

    let mut content = lines.filter(|(_, l)| {
        let t = l.trim_start();
        !t.is_empty() && !t.starts_with('%')
    });
    let (size_line, size) = content
        .next()
        .ok_or_else(|| mm_err(path, "the size line `rows cols entries` is missing"))?;
    let dims: Vec<usize> = size
        .split_whitespace()
        .map(|w| w.parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|e| line_err(size_line, format!("bad size line {size:?}: {e}")))?;
    let [nrows, ncols, nnz] = dims[..] else {
        return Err(line_err(
            size_line,
            format!("the size line needs `rows cols entries`, got {size:?}"),
        ));
    };
    if sym != Sym::General && nrows != ncols {
        return Err(line_err(
            size_line,
            format!("a symmetric matrix must be square, got {nrows} × {ncols}"),
        ));
    }

    // The announced count is untrusted: reserve no more than the file can hold (an entry
    // line takes at least 4 bytes).
    let cap = nnz.min(text.len() / 4 + 1);
    let mut triplets: Vec<Triplet<usize, usize, f64>> =
        Vec::with_capacity(if sym == Sym::General { cap } else { 2 * cap });
    let mut count = 0usize;
    for (ln, l) in content {
        count += 1;
        if count > nnz {
            return Err(line_err(ln, format!("more entries than the {nnz} announced")));
        }
        let mut it = l.split_whitespace();
        let mut index = |what: &str, bound: usize| -> Result<usize, MeshError> {
            let w = it
                .next()
                .ok_or_else(|| line_err(ln, format!("missing {what} index in {l:?}")))?;
            let i: usize = w.parse().map_err(|_| line_err(ln, format!("bad {what} index {w:?}")))?;
            if i == 0 || i > bound {
                return Err(line_err(ln, format!("{what} index {i} is outside 1..={bound}")));
            }
            Ok(i - 1)
        };
        let i = index("row", nrows)?;
        let j = index("column", ncols)?;
        let v = if pattern {
            1.0
        } else {
            let w = it
                .next()
                .ok_or_else(|| line_err(ln, format!("missing value in {l:?}")))?;
            let v: f64 = w.parse().map_err(|_| line_err(ln, format!("bad value {w:?}")))?;
            if !v.is_finite() {
                return Err(line_err(ln, format!("non-finite value {w:?}")));
            }
            v
        };
        if it.next().is_some() {
            return Err(line_err(ln, format!("too many fields in {l:?}")));
        }
        if sym != Sym::General && i < j {
            return Err(line_err(
                ln,
                format!("entry ({}, {}) is above the diagonal in a symmetric file", i + 1, j + 1),
            ));
        }
        if sym == Sym::Skew && i == j {
            return Err(line_err(ln, "diagonal entry in a skew-symmetric file".to_string()));
        }
        triplets.push(Triplet::new(i, j, v));
        if i != j {
            match sym {
                Sym::General => {}
                Sym::Symmetric => triplets.push(Triplet::new(j, i, v)),
                Sym::Skew => triplets.push(Triplet::new(j, i, -v)),
            }
        }
    }
    if count != nnz {
        return Err(mm_err(
            path,
            format!("the size line announces {nnz} entries but the file has {count}"),
        ));
    }
    // A column pointer array is allocated for every column; refuse absurd dimensions that a
    // corrupt size line could ask for instead of exhausting memory.
    if ncols > MAX_EMPTY_COLUMNS.max(64 * nnz) {
        return Err(line_err(
            size_line,
            format!("{ncols} columns for {nnz} entries: refusing to allocate a matrix that sparse"),
        ));
    }
    SparseColMat::try_new_from_triplets(nrows, ncols, &triplets)
        .map_err(|e| mm_err(path, format!("cannot build the matrix: {e:?}")))
}

/// Writes the operators of `ops` into the folder `dir` (created if missing):
/// `stiffness.mtx` (L, symmetric positive semidefinite — the negative of libigl's
/// `cotmatrix`), `mass.mtx` (consistent B) and `lumped_mass.mtx` (D, its diagonal only),
/// all `coordinate real symmetric` (paper, Eq. (3) and Eq. (7)). The three files are written
/// to temporary files first and renamed together: after a failure none of them has changed.
///
/// # Errors
/// [`MeshError::Io`] if the folder or a file cannot be written.
pub fn write_operators(dir: impl AsRef<Path>, ops: &FemOperators) -> Result<(), MeshError> {
    let dir = dir.as_ref();
    std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;
    let n = ops.lumped_diagonal.len();
    let diagonal: Vec<Triplet<usize, usize, f64>> = ops
        .lumped_diagonal
        .iter()
        .enumerate()
        .map(|(i, &d)| Triplet::new(i, i, d))
        .collect();
    let d = SparseColMat::try_new_from_triplets(n, n, &diagonal)
        .map_err(|e| mm_err(dir, format!("cannot build the lumped mass: {e:?}")))?;
    // All three files are staged first and renamed together, so a failure (disk full, a
    // target that is a directory, …) leaves the folder as it was: no partial set of files.
    let mut set = AtomicSet::new();
    for (name, matrix) in [
        ("stiffness.mtx", &ops.stiffness),
        ("mass.mtx", &ops.mass),
        ("lumped_mass.mtx", &d),
    ] {
        stage_matrix_market(&mut set, &dir.join(name), matrix, true)?;
    }
    set.commit()
}

/// Converts a faer sparse matrix to `nalgebra_sparse::CscMatrix` (same entries; row indices
/// sorted and duplicates summed, as nalgebra requires). Feature `nalgebra`.
#[cfg(feature = "nalgebra")]
#[allow(clippy::expect_used)]
pub fn to_nalgebra_csc(matrix: &SparseColMat<usize, f64>) -> nalgebra_sparse::CscMatrix<f64> {
    let entries = sorted_entries(matrix);
    let mut col_offsets = vec![0usize; matrix.ncols() + 1];
    for &(_, j, _) in &entries {
        col_offsets[j + 1] += 1;
    }
    for j in 0..matrix.ncols() {
        col_offsets[j + 1] += col_offsets[j];
    }
    let row_indices = entries.iter().map(|e| e.0).collect();
    let values = entries.iter().map(|e| e.2).collect();
    nalgebra_sparse::CscMatrix::try_from_csc_data(matrix.nrows(), matrix.ncols(), col_offsets, row_indices, values)
        // invariant: `sorted_entries` yields sorted, deduplicated, in-range CSC data.
        .expect("sorted, deduplicated, in-range CSC data is valid")
}

/// Converts a faer sparse matrix to `nalgebra_sparse::CsrMatrix`. Feature `nalgebra`.
#[cfg(feature = "nalgebra")]
pub fn to_nalgebra_csr(matrix: &SparseColMat<usize, f64>) -> nalgebra_sparse::CsrMatrix<f64> {
    nalgebra_sparse::CsrMatrix::from(&to_nalgebra_csc(matrix))
}

/// Converts an `nalgebra_sparse::CscMatrix` to a faer sparse matrix (same entries). Feature
/// `nalgebra`.
#[cfg(feature = "nalgebra")]
pub fn from_nalgebra_csc(matrix: &nalgebra_sparse::CscMatrix<f64>) -> SparseColMat<usize, f64> {
    let (col_offsets, row_indices, values) = matrix.csc_data();
    // nalgebra guarantees sorted, unique, in-range row indices per column, which is exactly
    // faer's invariant, so the checked constructor cannot fail.
    let symbolic = SymbolicSparseColMat::new_checked(
        matrix.nrows(),
        matrix.ncols(),
        col_offsets.to_vec(),
        None,
        row_indices.to_vec(),
    );
    SparseColMat::new(symbolic, values.to_vec())
}
