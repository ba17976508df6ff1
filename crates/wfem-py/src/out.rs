//! Rust values to new C-ordered NumPy arrays (outputs; no checks, so no errors: the module
//! every other one may use).

use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Mat, MatRef};
use mesh_fem::TriMesh;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;

/// A faer matrix as a new (rows × cols) array.
pub fn mat_out<'py>(py: Python<'py>, m: MatRef<'_, f64>) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// Several n × k matrices as one (T, n, k) array.
pub fn mats_out<'py>(py: Python<'py>, ms: &[Mat<f64>], n: usize, k: usize) -> Bound<'py, PyArray3<f64>> {
    Array3::from_shape_fn((ms.len(), n, k), |(t, i, j)| ms[t][(i, j)]).into_pyarray(py)
}

/// A vector as a new 1-D array.
pub fn vec_out<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    v.into_pyarray(py)
}

/// A mesh as (V (n, 3) float64, F (m, 3) int64) arrays.
pub fn mesh_out<'py>(py: Python<'py>, mesh: &TriMesh) -> (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>) {
    let p = mesh.positions();
    let f = mesh.faces();
    let v = Array2::from_shape_fn((p.len(), 3), |(i, j)| p[i][j]).into_pyarray(py);
    let f = Array2::from_shape_fn((f.len(), 3), |(i, j)| i64::from(f[i][j])).into_pyarray(py);
    (v, f)
}
/// CSC arrays (indptr, indices, data) of a faer matrix, one entry per stored value. The index
/// arrays are int32 when every index fits (what scipy would convert them to, so it keeps them
/// as they are), int64 otherwise.
pub type SparseOut<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyArray1<f64>>,
    (usize, usize),
);

/// The index arrays of a CSC pattern (indptr, indices), int32 when nnz fits.
fn index_arrays<'py>(
    py: Python<'py>,
    sym: SymbolicSparseColMatRef<'_, usize>,
) -> (Bound<'py, PyAny>, Bound<'py, PyAny>) {
    let nnz: usize = (0..sym.ncols()).map(|j| sym.col_range(j).len()).sum();
    fn gather<T: numpy::Element>(
        sym: SymbolicSparseColMatRef<'_, usize>,
        nnz: usize,
        cast: impl Fn(usize) -> T,
    ) -> (Vec<T>, Vec<T>) {
        let mut indptr = Vec::with_capacity(sym.ncols() + 1);
        let mut indices = Vec::with_capacity(nnz);
        indptr.push(cast(0));
        for j in 0..sym.ncols() {
            indices.extend(sym.row_idx()[sym.col_range(j)].iter().map(|&i| cast(i)));
            indptr.push(cast(indices.len()));
        }
        (indptr, indices)
    }
    if nnz.max(sym.nrows()).max(sym.ncols()) <= i32::MAX as usize {
        // invariant: every index and offset is at most nnz or n, checked to fit just above.
        let (indptr, indices) = gather(sym, nnz, |i| i as i32);
        (indptr.into_pyarray(py).into_any(), indices.into_pyarray(py).into_any())
    } else {
        let (indptr, indices) = gather(sym, nnz, |i| i as i64);
        (indptr.into_pyarray(py).into_any(), indices.into_pyarray(py).into_any())
    }
}

/// A faer matrix as CSC arrays for `scipy.sparse.csc_matrix((data, indices, indptr), shape)`.
pub fn sparse_out<'py>(py: Python<'py>, a: SparseColMatRef<'_, usize, f64>) -> SparseOut<'py> {
    let sym = a.symbolic();
    let mut data = Vec::with_capacity(a.val().len());
    for j in 0..a.ncols() {
        data.extend_from_slice(&a.val()[sym.col_range(j)]);
    }
    let (indptr, indices) = index_arrays(py, sym);
    (indptr, indices, data.into_pyarray(py), (a.nrows(), a.ncols()))
}

/// [`sparse_out`] of an owned matrix: its values move into the array without a copy when the
/// columns are stored one after the other (as assembled matrices are).
pub fn sparse_out_owned<'py>(py: Python<'py>, a: SparseColMat<usize, f64>) -> SparseOut<'py> {
    let compact = a.symbolic().col_nnz().is_none();
    if !compact {
        return sparse_out(py, a.as_ref());
    }
    let (indptr, indices) = index_arrays(py, a.symbolic());
    let shape = (a.nrows(), a.ncols());
    let (_, values) = a.into_parts();
    (indptr, indices, values.into_pyarray(py), shape)
}
